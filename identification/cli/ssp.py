"""``cleatfmu ssp``: the diagnosed whole tractor as an SSP 1.0 system of native FMUs (body + four tires).

The same inputs as the whole-tractor ``simulate``: four tire FMUs (or their
folder), the recording and the ``diagnose --json`` document of the body.  The
system is the model record those make (:func:`identification.fmu.tractor_cosim.tractor_from_fmus`),
written by :func:`identification.fmu.ssp.write_tractor_ssp`; ``--check`` runs it in
fmpy and libcosim against the project's master.
"""

from __future__ import annotations

from dataclasses import replace

from .util import add_example_option, check_output, read_recording_arg, recording_name_arg, write_files
from ..errors import InputError
from .._files import json_text, temp_prefix

__all__ = ["point_contact_as_builtin", "run", "add_parser"]


def point_contact_as_builtin(record):
    """The record with every point-contact cleat (a road input) carried by the tire itself (``footprint 0``).

    An FMU system has no road FMU: a tire that saw the rectangular cleat as a
    road input gets it as its built-in cleat under the contact point.  The
    damper's impulse c H at each edge (the road rate of the point-contact
    input) is then not applied; returns (record, converted tires).
    """
    cleat = record.cleat
    laws, converted = [], []
    for i, (tire, law) in enumerate(zip(record.tires, record.laws)):
        if cleat.height_m > 0.0 and not record.builtin_cleat(i):
            law = {**law, "cleat_height": float(cleat.height_m), "cleat_width": float(cleat.width_m),
                   "footprint_length": 0.0, "cleat_x": 0.0}
            converted.append(tire)
        laws.append(law)
    return replace(record, laws=tuple(laws)), converted


def run(args) -> int:
    """Run ``cleatfmu ssp``; returns 0 (user errors raise InputError)."""
    from ..comfort.ride import SEAT_X_FRACTION
    from .simulate import _inputs
    from ..fmu.simulate_inputs import tractor_fmu_paths
    from ..fmu.ssp import write_tractor_ssp
    from ..fmu.tractor_cosim import tractor_from_fmus

    fmus, recording = _inputs(args)
    args.recording = recording
    paths = tractor_fmu_paths(fmus, recording=recording_name_arg(args))
    check_output(args.output, ".ssp", "SSP")
    rec = read_recording_arg(args)
    model, pb, theta, paths, record, body, settings, source = tractor_from_fmus(paths, rec, args.body)
    record, converted = point_contact_as_builtin(record)
    start, h, n = model.grid(record)
    if args.stop_s is not None and not args.stop_s > start:
        raise InputError("--stop-s", f"must be after the start {start:.6g} s, got {args.stop_s}")
    stop = start + (n - 1) * h if args.stop_s is None else float(args.stop_s)
    seat_x = body.wheelbase_m * SEAT_X_FRACTION if args.seat_x_m is None else float(args.seat_x_m)
    from pathlib import Path
    import tempfile

    with tempfile.TemporaryDirectory(prefix=temp_prefix("ssp")) as tmp:
        staged = Path(tmp) / (Path(args.output).stem + ".ssp")   # (the writer takes .ssp, the option any case)
        try:
            write_tractor_ssp(staged, record, start_s=start, stop_s=stop, step_s=h, seat_x_m=seat_x,
                              seat_y=args.seat_y, name=Path(args.output).stem,
                              description=f"Whole tractor of '{Path(rec.source).name}' ({body.kind} body, "
                                          f"{', '.join(settings['tire_effects'] + settings['body_effects'])})")
        except ValueError as exc:
            raise InputError(args.body, str(exc)) from None
        check = None
        if args.check:
            import sys

            from ..fmu.ssp_run import check_ssp
            libcosim = libcosim_available()
            if not libcosim:
                print("cleatfmu: warning: --check: libcosimpy is not installed (pip install 'cleatfmu[libcosim]'): the "
                      "archive is checked in fmpy only", file=sys.stderr)
            check = check_ssp(staged, record, start_s=start, step_s=h, stop_s=stop, seat_x_m=seat_x,
                              seat_y=args.seat_y, libcosim=libcosim)
        write_files({Path(args.output): staged.read_bytes()})
    doc = {"ssp": str(args.output), "start_s": start, "stop_s": stop, "step_s": h, "body": body.kind,
           "seat_x_m": seat_x, "seat_y": args.seat_y, "point_contact_as_builtin": converted, "check": check}
    if args.json:
        print(json_text(doc))
        return _status(check)
    print(f"wrote {args.output}: body ({body.kind}) + four extended tire FMUs, SSP 1.0; "
          f"default experiment {start:.4g}-{stop:.4g} s, step {h * 1e3:.4g} ms")
    if converted:
        print(f"  tires {', '.join(converted)}: the point-contact cleat is carried by the tire (no road FMU); "
              f"the damper's edge impulse c H is not applied")
    if check:
        from ..fmu.ssp_run import AGREEMENT
        for host, dev in check.items():
            if host.startswith("exchange"):
                print(f"  the exchange itself: the parallel (fixed-step) master's one-step force delay moves the "
                      f"hubs and the seat by {dev:.2e} of their motion from the sequential one")
            else:
                print(f"  {host}: largest deviation from the project's master {dev:.2e} of the motion  "
                      + ("OK" if dev <= AGREEMENT else f"DIFFERS (more than {AGREEMENT:g})"))
    return _status(check)


def libcosim_available() -> bool:
    """Whether the Open Simulation Platform's Python package (libcosimpy, in the ``test`` extra) is installed."""
    import importlib.util

    return importlib.util.find_spec("libcosimpy") is not None


def _status(check) -> int:
    from ..fmu.ssp_run import AGREEMENT

    if check and any(dev > AGREEMENT for host, dev in check.items() if not host.startswith("exchange")):
        return 1
    return 0


def add_parser(subparsers) -> None:
    """Register ``cleatfmu ssp``."""
    p = subparsers.add_parser(
        "ssp", help="the diagnosed tractor as an SSP 1.0 system: a native body FMU and four tire FMUs",
        description="Package four tire FMUs under the body a whole-tractor diagnosis found (its --json document) "
                    "as an SSP 1.0 archive: a native body FMU (the diagnosed body: the rigid tractor with heave, "
                    "pitch, roll and a rigid or pivoting front axle, half tractors or corners; hub and seat "
                    "outputs), four native extended tire FMUs with the cleat in the system's "
                    "road coordinates, the connections and the default experiment over the diagnosis window.  "
                    "--check runs it in fmpy and libcosim against the project's master (exit 1 if a host "
                    "deviates by more than 1e-6 of the motion).")
    p.add_argument("fmu", metavar="FMU", nargs="+", help="the four tire FMUs (FL FR RL RR) or their folder")
    p.add_argument("recording", metavar="REC.csv", nargs="?", help="the recording (or --example NAME)")
    add_example_option(p, bare=False)
    p.add_argument("--body", metavar="DIAG.json", required=True,
                   help="the 'cleatfmu diagnose REC.csv --json' document (body and arrivals), or a report's "
                        "summary.json (its entry of the recording)")
    p.add_argument("-o", "--output", metavar="OUT.ssp", required=True, help="the SSP file to write")
    p.add_argument("--seat-x-m", type=float, default=None,
                   help="seat position behind the front axle, m (default: 0.85 wheelbase)")
    p.add_argument("--seat-y", type=float, default=0.0,
                   help="seat position from the centre line, fraction of the half-track, + left (default 0)")
    p.add_argument("--stop-s", type=float, default=None, help="stop time of the default experiment, s "
                                                              "(default: the end of the diagnosis window)")
    p.add_argument("--check", action="store_true",
                   help="run the SSP in fmpy (both exchanges) and libcosim and compare with the project's master")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.set_defaults(func=run)
