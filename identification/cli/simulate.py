"""``cleatfmu simulate TIRE.fmu REC.csv --tire FL``: the tire FMU against the measurement.

``cleatfmu simulate FL.fmu FR.fmu RL.fmu RR.fmu REC.csv --body DIAG.json`` (or
``simulate DIR REC.csv --body DIAG.json``): the four tire FMUs under the
diagnosed body against every channel
(:func:`identification.fmu.tractor_cosim.simulate_tractor`).
"""

from __future__ import annotations

from pathlib import Path

from .util import add_example_option, check_output, choose_tire, read_recording_arg, recording_name_arg
from ..errors import InputError
from .._files import json_text

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
    lines.extend(f"  warning: {w}" for w in cmp.warnings)
    return "\n".join(lines)


_KINDS = {"corners": "four independent corners", "sides": "one half-tractor per side (pitch)",
          "axles": "one axle pair per axle (roll)", "rigid": "rigid tractor (heave, pitch, roll)",
          "pivot": "rigid tractor with a pivoting front axle"}


def _tractor_text(sim, verbose: bool = False) -> str:
    from ..model.fitting import TIRE_EFFECTS
    from ..fmu.tractor_cosim import UNEXPLAINED_RATIO
    from ..model.fitting import LOCAL_RATIO, LOCAL_SPAN_S

    body, pb = sim.body, sim.problem
    t = pb.rec.time_s[pb.window]
    indices = ", ".join(f"{name.replace('_', ' ')} {body[name]:.3f}" for name in
                        ("pitch_index", "roll_index", "pivot_index") if body[name] is not None)
    lines = [f"{sim.recording}: four tire FMUs co-simulated under the body vs the measurement "
             f"(both low-pass {pb.cutoff_hz:g} Hz; step {sim.step_s * 1e3:.4g} ms; window {t[0]:.3f}-{t[-1]:.3f} s)",
             f"  body ({body['document']}): {_KINDS.get(body['kind'], body['kind'])}"
             + (f"; {indices}" if indices else "")
             + f"; tire effects {', '.join(e for e in body['effects'] if e in TIRE_EFFECTS) or 'none'}"]
    diagnosed = body.get("diagnosed_recording")
    if diagnosed and Path(str(diagnosed)).name != Path(sim.recording).name:
        lines.append(f"  note: the body and arrivals were diagnosed from {diagnosed}, not from this recording")
    lines.append("  tire  NRMSE  noise-only  residual/noise")
    bad = []
    for tire in sim.channels:
        ratio = sim.residual_to_noise(tire)
        test = sim.residual_test(tire)
        verdict = "at the noise floor" if test["at_noise"] else \
            f"NOT EXPLAINED: residual {ratio:.1f}x the noise (> {UNEXPLAINED_RATIO:g}x)" \
            if ratio > UNEXPLAINED_RATIO else \
            (f"NOT EXPLAINED: residual {test['worst_span_to_noise']:.1f}x the noise over "
             f"{test['worst_span_s'][0]:.2f}-{test['worst_span_s'][1]:.2f} s (> {LOCAL_RATIO:g}x)")
        if sim.unexplained(tire):
            bad.append(tire)
        lines.append(f"  {tire:<4}{sim.nrmse[tire]:7.2%}{sim.noise_nrmse[tire]:11.2%}{ratio:11.2f}   {verdict}  "
                     f"[{sim.fmus[tire].name}]")
    if bad:
        lines.append(f"  the model does not explain the data in {', '.join(bad)}: the residual there is more than "
                     f"{UNEXPLAINED_RATIO:g}x the noise, or {LOCAL_RATIO:g}x over {LOCAL_SPAN_S:g} s")
    else:
        lines.append("  the model explains every channel to within the noise")
    if verbose:
        lines.append(f"  time: {sim.seconds:.1f} s")
    return "\n".join(lines)


def _plot_tractor(sim):
    """Every channel: measured vs co-simulated (both low-passed) over the diagnosis window."""
    from ..report.plots import figure, finish_channel_axis, finish_channel_figure

    pb = sim.problem
    t, w = pb.rec.time_s, pb.window
    n = len(pb.channels)
    fig, axes = figure(n, 1, size=(10.0, 2.3 * n + 0.8), sharex=True, squeeze=False)
    for ax, ch in zip(axes[:, 0], pb.channels):
        ax.plot(t[w], pb.measured[ch][w], color="C0", lw=1.0, label=f"{ch} measured (low-pass)")
        ax.plot(t[w], sim.predicted[ch][w], color="C3", lw=0.8,
                label=f"FMU co-simulation, NRMSE {sim.nrmse[ch]:.1%} (noise {sim.noise_nrmse[ch]:.1%})")
        finish_channel_axis(ax, pb.measured[ch][w])
    return finish_channel_figure(fig, axes, f"{pb.rec.source}: four tire FMUs under the body ({sim.body['kind']})")


def _save_plot(fig, path) -> None:
    from ..report.plots import png_bytes
    from .util import write_files

    write_files({path: png_bytes(fig)})


def _inputs(args) -> tuple[list[str], str | None]:
    """The FMU paths and the recording path of the command line (None with ``--example``)."""
    paths = list(args.fmu) + ([args.recording] if args.recording is not None else [])
    if args.example is not None:
        if paths and str(paths[-1]).lower().endswith(".csv"):
            raise InputError("--example", "give either a recording or --example, not both")
        return paths, None
    if len(paths) < 2:
        raise InputError(None, "give the FMU(s) and then the recording REC.csv (or --example NAME)")
    return paths[:-1], paths[-1]


def _focus(rec, args):
    """`rec`, or for a long recording its impact window (:func:`identification.recording.window.focus`, noted on stderr)."""
    from ..recording.window import focus

    return focus(rec, cutoff_hz=args.cutoff_hz)


def _with_window(doc: dict, rec) -> dict:
    """The ``--json`` document, with ``"analysis_window"`` for a long recording analysed on its impact window."""
    from ..recording.window import window_json

    if window_json(rec) is not None:
        doc["analysis_window"] = window_json(rec)
    return doc


def _run_tractor(args) -> int:
    from ..fmu.simulate_inputs import tractor_fmu_paths
    from ..fmu.tractor_cosim import simulate_tractor

    if args.tire is not None:
        raise InputError("--tire", "the whole-tractor form compares all four channels; --tire is for one FMU")
    if args.method is not None:
        raise InputError("--method", "re-identification applies to one FMU, not to the whole-tractor form")
    paths = tractor_fmu_paths(args.fmu, recording=recording_name_arg(args))
    if args.body is None:
        raise InputError("--body", "the whole-tractor form (four FMUs or a directory) needs the body and the "
                                   "arrivals: give --body DIAG.json, a 'cleatfmu diagnose REC.csv --json' document")
    rec = _focus(read_recording_arg(args), args)
    check_output(args.plot, ".png", "plot")
    sim = simulate_tractor(paths, rec, args.body, cutoff_hz=args.cutoff_hz, step_s=args.max_step_s)
    if args.plot is not None:
        _save_plot(_plot_tractor(sim), args.plot)
    print(json_text(_with_window(sim.to_json(), rec)) if args.json else _tractor_text(sim, args.verbose))
    return 0


def run(args) -> int:
    """Run ``cleatfmu simulate``; returns 0 (user errors raise InputError)."""
    from ..recording.preprocess import DEFAULT_CUTOFF_HZ
    from ..fmu.validation import DEFAULT_MAX_STEP_S, simulate_recording

    check_output(args.plot, ".png", "plot", create=False)
    if args.max_step_s is not None:
        from ..recording.plausibility import check_option

        check_option("--max-step-s", args.max_step_s)
        # without --cutoff-hz the cut-off is at most DEFAULT_CUTOFF_HZ: a step too coarse for it is too coarse
        cutoff = DEFAULT_CUTOFF_HZ if args.cutoff_hz is None else args.cutoff_hz
        if cutoff > 0 and args.max_step_s > 0.4 / cutoff:   # a NaN cut-off: refused later
            raise InputError("--max-step-s", f"{args.max_step_s:g} s is too coarse for the low-pass at "
                                             f"{cutoff:g} Hz: the co-simulation must sample at 2.5 x the "
                                             f"cut-off or faster (a step of at most {0.4 / cutoff:.3g} s)")
    args.fmu, args.recording = _inputs(args)
    if len(args.fmu) > 1 or Path(args.fmu[0]).is_dir():
        return _run_tractor(args)
    if args.body is not None:
        raise InputError("--body", "applies to the whole-tractor form (four FMUs or a directory), not to one FMU")
    rec = read_recording_arg(args)
    tire = choose_tire(rec, args.tire)
    rec = _focus(rec, args)
    check_output(args.plot, ".png", "plot")
    step = args.max_step_s if args.max_step_s is not None else DEFAULT_MAX_STEP_S
    cmp = simulate_recording(args.fmu[0], rec, tire, cutoff_hz=args.cutoff_hz, max_step_s=step,
                             method=args.method or "paper")
    if args.plot is not None:
        from ..report.plots import plot_comparison
        _save_plot(plot_comparison(cmp), args.plot)
    print(json_text(_with_window(cmp.to_json(), rec)) if args.json else _text(cmp, rec))
    return 0


def add_parser(subparsers) -> None:
    """Register ``cleatfmu simulate``."""
    p = subparsers.add_parser(
        "simulate", help="co-simulate a tire FMU (or all four under the body) over a recording's cleat and compare "
                         "with the measurement",
        description="One FMU: run the tire FMU with fmpy under the corner mass W/g over the recording's cleat, "
                    "sample the hub acceleration on the recording's time base, and report NRMSE, R2, re-identified "
                    "k and c, decay rates and where (impact, free decay, other axle) the simulation is wrong.  "
                    "Four FMUs (FL FR RL RR, or a directory holding *_FL.fmu .. *_RR.fmu as 'diagnose --fmu-dir' "
                    "writes them, or a report's fmu/ whose <recording>_FL.fmu .. are taken) with --body DIAG.json: run them under the body of a whole-tractor diagnosis "
                    "('diagnose --json') and report, per channel, the NRMSE against the measurement, the noise-only "
                    "NRMSE and their ratio.  The recording is the last path, or an embedded one with --example.")
    p.add_argument("fmu", metavar="FMU", nargs="+",
                   help="one tire FMU, four (FL FR RL RR: matched by a _FL.fmu .. _RR.fmu suffix, else in that "
                        "order), or one directory holding them")
    p.add_argument("recording", metavar="REC.csv", nargs="?",
                   help="the recording (the last path; omit it with --example)")
    add_example_option(p, bare=False)
    p.add_argument("--tire", metavar="TIRE", help="one FMU: channel to compare, any letter case (required when "
                                                  "the recording has several)")
    p.add_argument("--body", metavar="DIAG.json",
                   help="four FMUs: the body and arrivals, a 'cleatfmu diagnose REC.csv --json' document or a "
                        "report's summary.json (its entry of the recording)")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.add_argument("--plot", metavar="OUT.png", help="write measured vs simulated acceleration (one FMU: with "
                                                     "decay curves; four: every channel); the folder is created "
                                                     "if needed")
    p.add_argument("--method", choices=("paper", "waveform"), default=None,
                   help="one FMU: method to re-identify k and c from the simulated acceleration (default: paper)")
    p.add_argument("--cutoff-hz", type=float, default=None,
                   help="low-pass cut-off, Hz (default: 100, or 0.4 x the sampling rate when lower)")
    p.add_argument("--max-step-s", type=float, default=None, metavar="H",
                   help="largest co-simulation step, s (default 2.5e-4 for one FMU, 1e-3 for four, as diagnose)")
    p.add_argument("-v", "--verbose", action="store_true", help="four FMUs: also print the time taken")
    p.set_defaults(func=run, trailing="fmu")
