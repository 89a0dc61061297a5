"""``cleatfmu diagnose REC.csv --tire FL``: what the point-contact model misses, and the extended model."""

from __future__ import annotations

import json
import os

from ..cliutil import check_output, choose_tire
from ..errors import InputError
from ..preprocess import DEFAULT_CUTOFF_HZ

__all__ = ["add_parser", "run_diagnosis"]


def _progress(desc: str):
    """A progress callback drawing a bar on stderr (only on a terminal, after one second)."""
    from tqdm import tqdm
    bar = tqdm(desc=desc, unit="model", delay=1.0, disable=None, leave=False)

    def tick(label):
        bar.set_postfix_str(label[:40], refresh=False)
        bar.update(1)
    return tick, bar


def run_diagnosis(rec, tire: str, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ, fmu_path=None, workers: int = 1,
                  progress=None):
    """Diagnose one tire and measure the gain with the FMUs: (Diagnosis, GainCheck)."""
    from .fmu import measure_gain
    from .select import diagnose

    diag = diagnose(rec, tire, cutoff_hz=cutoff_hz, workers=workers, progress=progress)
    if progress is not None:
        progress("FMU co-simulation")
    try:
        gain = measure_gain(diag, fmu_path)
    except OSError as exc:
        raise InputError(fmu_path, f"cannot write: {exc.strerror or exc}") from None
    return diag, gain


def _text(diag, gain) -> str:
    fin = diag.final
    lines = [f"{diag.tire} of {diag.problem.rec.source}: effects the point-contact model misses: "
             f"{', '.join(diag.effects) or 'none (the baseline explains the data to within noise)'}"]
    for effect in diag.effects:
        lines.append(f"  {effect}: {diag.evidence.get(effect, '')}")
    lines.append(f"  NRMSE (FMU co-simulation with fmpy): point contact {gain.nrmse_before:.2%} -> "
                 f"extended {gain.nrmse_after:.2%}   (fitting model and FMU agree to {gain.agreement:.1e})")
    k_lo, k_hi = fin.ci["k"]
    c_lo, c_hi = fin.ci["c"]
    lines.append(f"  k {fin.params['k'] / 1e3:.2f} kN/m ({k_lo / 1e3:.2f}-{k_hi / 1e3:.2f})   "
                 f"c {fin.params['c'] / 1e3:.3f} kN s/m ({c_lo / 1e3:.3f}-{c_hi / 1e3:.3f})   [95 %]")
    from .models import PARAMETERS
    for name in fin.model.names:
        if name in ("k", "c"):
            continue
        lo, hi = fin.ci[name]
        lines.append(f"  {name:<16}{fin.params[name]:12.5g} {PARAMETERS[name][0]:<6} ({lo:.5g} .. {hi:.5g})")
    timing = ", ".join(f"{label} {sec:.2f} s" for label, sec in diag.timings().items())
    lines.append(f"  time: {diag.seconds:.1f} s diagnosis ({timing}); {gain.seconds:.1f} s FMU gain check")
    return "\n".join(lines)


def run(args) -> int:
    from ..recording import read_recording

    rec = read_recording(args.recording)
    tire = choose_tire(rec, args.tire)
    check_output(args.plot, ".png", "plot")
    check_output(args.fmu, ".fmu", "FMU")
    tick, bar = _progress(f"diagnose {tire}")
    try:
        diag, gain = run_diagnosis(rec, tire, cutoff_hz=args.cutoff_hz, fmu_path=args.fmu, workers=args.workers,
                                   progress=tick)
    finally:
        bar.close()
    if args.plot is not None:
        from ..plots import plot_diagnosis, save_png
        save_png(plot_diagnosis(diag, nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after), args.plot)
    if args.json:
        print(json.dumps(diag.to_json(nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after), indent=2))
    else:
        print(_text(diag, gain))
    return 0


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "diagnose", help="find the effects the point-contact model misses, extend it, measure the gain",
        description="Fit the point-contact model and its extensions (enveloping, lift_off, axle_coupling, "
                    "nonlinear_stiffness, friction_damping, periodic_disturbance) to the measured hub acceleration, "
                    "name the effects by forward selection (BIC plus physical evidence), and measure the gain by "
                    "co-simulating the extended tire FMU(s) with fmpy.")
    p.add_argument("recording", metavar="REC.csv")
    p.add_argument("--tire", metavar="TIRE", help="channel to diagnose (required when the recording has several)")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.add_argument("--fmu", metavar="OUT.fmu",
                   help="write the extended tire FMU (with axle_coupling also OUT_<other tire>.fmu)")
    p.add_argument("--plot", metavar="OUT.png", help="write measured vs point-contact and extended models")
    p.add_argument("--cutoff-hz", type=float, default=DEFAULT_CUTOFF_HZ, help="low-pass cut-off, Hz")
    p.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1),
                   help="processes fitting candidate models in parallel (default: up to 2)")
    p.set_defaults(func=run)
