"""``cleatfmu rig``: write one virtual-rig recording and its truth file.

Without ``-o`` the files go to the current directory (with ``-o`` naming an
existing folder: to that folder) under a name made of the run's settings,
``rig_<effects>_<speed>kmh_seed<seed>`` (``rig_baseline_7kmh_seed0`` with no
effect); a ``_2``, ``_3`` ... is appended rather than overwrite an earlier
run's files.  ``-o DIR/NAME`` creates DIR if needed.  The paths written are
printed.
"""

from __future__ import annotations

from pathlib import Path

from .._files import check_folder
from ..rig import params as P

__all__ = ["add_parser", "default_stem"]

#: Suffixes of the three files of a run.
_SUFFIXES = (".csv", ".json", ".truth.json")


def default_stem(effects, speed_kmh: float, seed: int, folder=".") -> Path:
    """The output stem of a run given no ``-o``: a new name in `folder` that no existing file uses.

    Parameters
    ----------
    effects : sequence of str
        The run's effects (none: ``baseline``).
    speed_kmh : float
        Its driving speed, km/h.
    seed : int
        Its seed.
    folder : path-like
        Where the files go (default: the current directory).

    Returns
    -------
    Path
        ``folder/rig_<effects joined by +>_<speed>kmh_seed<seed>``, with ``_2``, ``_3`` ... appended when
        a file of that name exists.
    """
    effects = [e for e in P.EFFECTS if e in effects] + [e for e in effects if e not in P.EFFECTS]
    base = f"rig_{'+'.join(effects) or 'baseline'}_{speed_kmh:g}kmh_seed{seed}".replace("/", "_")
    folder = Path(folder)
    stem, n = folder / base, 1
    while any(stem.with_name(stem.name + s).exists() for s in _SUFFIXES):
        n += 1
        stem = folder / f"{base}_{n}"
    return stem


def _tire_names_upper(assignments: dict[str, str]) -> dict[str, str]:
    """``--param`` keys and channel lists with the tire names in upper case (``tire.fl.k_N_m`` = ``tire.FL.k_N_m``)."""
    out = {}
    for key, value in assignments.items():
        parts = key.split(".")
        if len(parts) == 3 and parts[0] == "tire":
            key = ".".join((parts[0], parts[1].upper(), parts[2]))
        if key in ("sensor.channels", "sensor.flipped"):
            value = value.upper()
        out[key] = value
    return out


def _write(rig_run, stem: Path, decimals: int):
    """:func:`write_run` into a folder created as needed (inside the command's
    :class:`~identification._files.OutputFolders` block: a folder created here goes again if the run fails)."""
    from .._files import make_folders
    from ..errors import InputError
    from ..rig.generate import write_run

    make_folders(stem.parent)
    try:
        return write_run(rig_run, stem, value_decimals=decimals)
    except OSError as exc:
        raise InputError(stem, f"cannot write: {exc.strerror or exc}") from None


def _check_options(args) -> None:
    """Refuse a ``--speed`` that is no finite number in its plausible range, and a negative ``--seed``."""
    import math

    from ..errors import InputError

    if args.speed is not None:
        if not (math.isfinite(args.speed) and args.speed > 0):
            raise InputError("--speed", f"must be a finite number > 0 km/h, got {args.speed!r}")
        low, high, what = P.RANGES["speed_kmh"]
        if not low <= args.speed <= high:
            raise InputError("--speed", f"speed {args.speed:.6g} km/h is outside the plausible range "
                                        f"{low:.6g}-{high:.6g} km/h ({what})")
    if args.seed < 0:
        raise InputError("--seed", f"must be >= 0, got {args.seed}")


def run(args) -> int:
    """Run ``cleatfmu rig``; returns 0 (user errors raise InputError)."""

    if args.list_params:
        print(P.describe())
        return 0
    into_folder = args.output is not None and Path(args.output).is_dir()
    if args.output is not None and not into_folder:
        check_folder(Path(args.output).parent)
    from ..rig.generate import run_rig  # the solver stack loads only when the rig runs

    _check_options(args)
    overrides = _tire_names_upper(P.parse_assignments(args.param))
    if args.speed is not None:
        overrides["speed_kmh"] = args.speed
    effects = P.parse_effects(args.effect)
    rig_run = run_rig(effects, overrides, seed=args.seed)
    if args.output is None or into_folder:
        stem = default_stem(effects, rig_run.recording.speed_kmh, args.seed, args.output or ".")
    else:
        stem = Path(args.output)
    csv_path, truth_path = _write(rig_run, stem, args.decimals)
    print(csv_path)
    print(csv_path.with_suffix(".json"))
    print(truth_path)
    return 0


def add_parser(subparsers) -> None:
    """Register ``cleatfmu rig``."""
    p = subparsers.add_parser(
        "rig", help="simulate a tractor crossing the cleat: a recording with known truth",
        description="Virtual cleat-test rig. Writes DIR/NAME.csv + DIR/NAME.json (cleat-recording/1) and "
                    "DIR/NAME.truth.json (the truth, never read by the pipeline), and prints their paths. Effects: "
                    + ", ".join(P.EFFECTS) + ".")
    p.add_argument("--effect", action="append", metavar="NAME[,NAME...]",
                   help="physical effect(s) to switch on (default: none, the paper's point-contact model)")
    p.add_argument("--speed", type=float, metavar="KMH",
                   help=f"driving speed, km/h (default {P.PARAMS['speed_kmh'].default:g})")
    p.add_argument("--seed", type=int, default=0, help="seed of noise and lug phases (default %(default)s)")
    p.add_argument("--param", action="append", metavar="KEY=VALUE",
                   help="override a parameter (repeatable; --list-params shows them; tire names in any "
                        "letter case)")
    p.add_argument("--decimals", type=int, default=4, choices=range(2, 10), metavar="N",
                   help="decimals of the acceleration in the CSV, 2 .. 9 (default %(default)s)")
    p.add_argument("-o", "--output", metavar="DIR/NAME",
                   help="output stem; DIR is created if needed; an existing folder: the default name in it "
                        "(default: rig_EFFECTS_SPEEDkmh_seedSEED in the current directory, e.g. "
                        "rig_baseline_7kmh_seed0, with _2, _3 ... appended rather than overwrite existing files)")
    p.add_argument("--list-params", action="store_true", help="list parameters with defaults and units")
    p.set_defaults(func=run)
