"""``cleatfmu simulate TIRE.fmu REC.csv --tire FL``: the tire FMU against the measurement."""

from __future__ import annotations

import json

from .cliutil import check_output, choose_tire
from .errors import InputError
from .preprocess import DEFAULT_CUTOFF_HZ

__all__ = ["add_parser"]


def _text(cmp, rec) -> str:
    lines = [f"{cmp.tire} of {rec.source}: co-simulated tire FMU vs measurement (both low-pass "
             f"{cmp.measured_signal.cutoff_hz:g} Hz; alignment {cmp.alignment_s * 1e3:+.2f} ms, "
             f"step {cmp.cosim.step_s * 1e3:.4g} ms)",
             f"  NRMSE {cmp.nrmse:.2%}   R2 {cmp.r2:.4f}",
             f"  FMU:           k {cmp.k_fmu / 1e3:9.2f} kN/m   c {cmp.c_fmu / 1e3:7.3f} kN s/m",
             f"  re-identified: k {cmp.k_reidentified / 1e3:9.2f} kN/m   c {cmp.c_reidentified / 1e3:7.3f} kN s/m"
             f"   ({cmp.method} method, from the simulated acceleration)",
             f"  decay rate: measured {cmp.decay_rate_measured:.3f} 1/s, simulated {cmp.decay_rate_simulated:.3f} 1/s",
             "  window        from/s   to/s   NRMSE  err/noise  share of misfit"]
    for name, w in cmp.windows.items():
        lines.append(f"  {name:<12}{w.start_s:7.3f}{w.end_s:7.3f}{w.nrmse:8.1%}{w.error_to_noise:10.1f}"
                     f"{w.misfit_share:12.0%}")
    lines.append(f"  the simulation is most wrong in the {cmp.worst_window} window")
    return "\n".join(lines)


def run(args) -> int:
    from .recording import read_recording
    from .validation import DEFAULT_MAX_STEP_S, simulate_recording

    rec = read_recording(args.recording)
    tire = choose_tire(rec, args.tire)
    check_output(args.plot, ".png", "plot")
    step = args.max_step_s if args.max_step_s is not None else DEFAULT_MAX_STEP_S
    if not step > 0:
        raise InputError("--max-step-s", f"must be > 0, got {step}")
    cmp = simulate_recording(args.fmu, rec, tire, cutoff_hz=args.cutoff_hz, max_step_s=step, method=args.method)
    if args.plot is not None:
        from .plots import plot_comparison, save_png
        try:
            save_png(plot_comparison(cmp), args.plot)
        except OSError as exc:
            raise InputError(args.plot, f"cannot write: {exc.strerror or exc}") from None
    print(json.dumps(cmp.to_json(), indent=2) if args.json else _text(cmp, rec))
    return 0


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "simulate", help="co-simulate a tire FMU over a recording's cleat and compare with the measurement",
        description="Run the tire FMU with fmpy under the corner mass W/g over the recording's cleat, sample the "
                    "hub acceleration on the recording's time base, and report NRMSE, R2, re-identified k and c, "
                    "decay rates and where (impact, free decay, other axle) the simulation is wrong.")
    p.add_argument("fmu", metavar="TIRE.fmu")
    p.add_argument("recording", metavar="REC.csv")
    p.add_argument("--tire", metavar="TIRE", help="channel to compare (required when the recording has several)")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.add_argument("--plot", metavar="OUT.png", help="write measured vs simulated acceleration with decay curves")
    p.add_argument("--method", choices=("paper", "waveform"), default="paper",
                   help="method to re-identify k and c from the simulated acceleration (default: %(default)s)")
    p.add_argument("--cutoff-hz", type=float, default=DEFAULT_CUTOFF_HZ, help="low-pass cut-off, Hz")
    p.add_argument("--max-step-s", type=float, default=None, metavar="H",
                   help="largest co-simulation step, s (default 2.5e-4)")
    p.set_defaults(func=run)
