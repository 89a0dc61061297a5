"""``cleatfmu rig``: write one virtual-rig recording and its truth file."""

from __future__ import annotations

from . import params as P

__all__ = ["add_parser"]


def run(args) -> int:
    if args.list_params:
        print(P.describe())
        return 0
    if args.output is None:
        from ..errors import InputError
        raise InputError("-o", "an output stem DIR/NAME is required")
    from .generate import run_rig, write_run  # the solver stack loads only when the rig runs

    overrides = P.parse_assignments(args.param)
    if args.speed is not None:
        overrides["speed_kmh"] = args.speed
    rig_run = run_rig(P.parse_effects(args.effect), overrides, seed=args.seed)
    csv_path, truth_path = write_run(rig_run, args.output, value_decimals=args.decimals)
    print(csv_path)
    print(csv_path.with_suffix(".json"))
    print(truth_path)
    return 0


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "rig", help="simulate a tractor crossing the cleat: a recording with known truth",
        description="Virtual cleat-test rig. Writes DIR/NAME.csv + DIR/NAME.json (cleat-recording/1) and "
                    "DIR/NAME.truth.json (the truth, never read by the pipeline). Effects: "
                    + ", ".join(P.EFFECTS) + ".")
    p.add_argument("--effect", action="append", metavar="NAME[,NAME...]",
                   help="physical effect(s) to switch on (default: none, the paper's point-contact model)")
    p.add_argument("--speed", type=float, metavar="KMH", help="driving speed, km/h (default 7)")
    p.add_argument("--seed", type=int, default=0, help="seed of noise and lug phases (default 0)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="override a parameter (repeatable; --list-params shows them)")
    p.add_argument("--decimals", type=int, default=4, choices=range(2, 10), metavar="N",
                   help="decimals of the acceleration in the CSV (default 4)")
    p.add_argument("-o", "--output", metavar="DIR/NAME", help="output stem")
    p.add_argument("--list-params", action="store_true", help="list parameters with defaults and units")
    p.set_defaults(func=run)
