"""``cleatfmu diagnose REC.csv --tire FL``: what the point-contact model misses, and the extended model."""

from __future__ import annotations

import contextlib
import os
import sys
import time

from .util import (add_example_option, announce_compilation, check_folder, check_output, choose_tire,
                       read_recording_arg, write_files)
from ..errors import InputError
from ..diagnose.joint_evidence import interval_text
from ..diagnose.wording import line_sentence, percent
from ..diagnose.run import diagnosis_warnings, run_tractor_diagnosis
from .._files import json_text, temp_prefix

__all__ = ["add_parser", "run"]


class _Lines:
    """Progress as plain lines on stderr: ``cleatfmu: diagnose: <elapsed> s: <stage>``."""

    def __init__(self, desc: str):
        self.desc, self.start, self.count = desc, time.perf_counter(), 0

    def __call__(self, label: str) -> None:
        self.count += 1
        print(f"cleatfmu: {self.desc}: {time.perf_counter() - self.start:6.1f} s: step {self.count}: {label}",
              file=sys.stderr, flush=True)

    def close(self) -> None:
        print(f"cleatfmu: {self.desc}: {time.perf_counter() - self.start:6.1f} s: done", file=sys.stderr, flush=True)


def _progress(desc: str, *, long: bool = False):
    """A progress callback and its closer: a bar on stderr on a terminal (after one second; at once for a long
    recording), else for a long recording one plain line per stage on stderr, else nothing."""
    from tqdm import tqdm

    if long and not _is_terminal(sys.stderr):
        lines = _Lines(desc)
        return lines, lines
    bar = tqdm(desc=desc, unit="model", delay=0.0 if long else 1.0, disable=None, leave=False)

    def tick(label):
        bar.set_postfix_str(label[:40], refresh=False)
        bar.update(1)
    return tick, bar


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


#: A 95 % interval whose half-width exceeds this share of the value says the data do not determine it.
UNDETERMINED_SHARE = 0.5


def _interval(value: float, ci, scale: float, fmt: str) -> str:
    """``(low-high)`` in the display unit, or ``(not determined by the data)`` when the 95 % interval's
    half-width exceeds :data:`UNDETERMINED_SHARE` of the value (its bounds are then no usable number)."""
    import math

    lo, hi = ci
    if not (math.isfinite(lo) and math.isfinite(hi)) or (hi - lo) / 2 > UNDETERMINED_SHARE * abs(value):
        return "(not determined by the data)"
    return f"({lo / scale:{fmt}}-{hi / scale:{fmt}})"


def _tractor_text(diag, gain, verbose: bool = False) -> str:
    doc = diag.to_json(nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after)
    body = doc["body"]
    rec = diag.problem.rec
    lines = [f"{rec.source}: effects the four-corner model misses: {doc['summary']}"]
    if rec.record_span_s is not None:
        lines.append(f"  analysed {rec.time_s[0]:.3f}-{rec.time_s[-1]:.3f} s of the {rec.record_span_s[0]:.3f}-"
                     f"{rec.record_span_s[1]:.3f} s record (the cleat impacts and their free decay)")
    if rec.decimated_from_hz is not None:
        lines.append(f"  analysed at {rec.sample_rate_hz:.6g} Hz, decimated from {rec.decimated_from_hz:.6g} Hz")
    for effect in diag.effects:
        lines.append(f"  {effect}: {diag.evidence.get(effect, '')}")
    for name in ("pitch_index", "roll_index"):
        if body[name]:
            lines.append(f"  {name:<12} {interval_text(body[name]['value'], *body[name]['ci'])}")
    speed = body["speed_m_s"]
    lines.append(f"  front axle   {body['front_axle']}; speed {speed['sidecar'] * 3.6:.2f} km/h (sidecar)"
                 + (f", {speed['from_delay'] * 3.6:.2f} km/h from the front/rear delay" if speed["from_delay"] else ""))
    for tire, t in doc["tires"].items():
        left = t["unexplained"]
        flag = (f"above the noise floor: residual {left['residual_to_noise']:.1f}x the noise"
                + (f" ({left['worst_span_to_noise']:.1f}x over {left['worst_span'][0]:.2f}-{left['worst_span'][1]:.2f} s)"
                   if "worst_span" in left else "") +
                f", {percent(left['share'])} % of the signal energy left, in {left['window'][0]:.3f}-"
                f"{left['window'][1]:.3f} s" if left else "residual at the noise floor")
        if left and left.get("steady_line"):
            flag += "; " + line_sentence(left["steady_line"])
        lines.append(f"  {tire}: k {t['k'] / 1e3:.1f} kN/m {_interval(t['k'], t['k_ci'], 1e3, '.1f')}  "
                     f"c {t['c'] / 1e3:.3f} kN s/m {_interval(t['c'], t['c_ci'], 1e3, '.3f')}  "
                     f"NRMSE {t['nrmse_before']:.1%} -> {t['nrmse_after']:.1%} (noise {t['noise_nrmse']:.1%}): {flag}")
    lines.append(f"  95 % intervals: {doc['intervals']}")
    check = "the final model's FMUs cannot start (see the warning)" if gain.agreement is None else \
        "gives the fitting model's hub accelerations bit for bit" if gain.agreement == 0.0 else \
        f"agrees with the fitting model to {gain.agreement:.1e} of the largest hub acceleration"
    lines.append(f"  FMU co-simulation (fmpy, one FMU per tire): {check}"
                 + (f"; {diag.seconds:.1f} s diagnosis, {gain.seconds:.1f} s FMU gain check" if verbose else ""))
    return "\n".join(lines)


def run(args) -> int:
    """Run ``cleatfmu diagnose``; returns 0 (user errors raise InputError).

    Every output file (``--fmu``, ``--fmu-dir``, ``--plot``) is written at the end, all together or none;
    ``--fmu-dir`` as one set (:class:`identification._folders.FolderSet`, its other files kept): the folder
    holds the earlier FMUs or the new ones, a killed run's temporary files go beside it, not to $TMPDIR.
    """
    from ..recording.plausibility import check_option

    check_option("--workers", args.workers)
    check_output(args.plot, ".png", "plot", create=False)
    check_output(args.fmu, ".fmu", "FMU", create=False)
    if args.fmu_dir is not None:
        check_folder(args.fmu_dir)
    rec = read_recording_arg(args)
    tire = choose_tire(rec, args.tire) if args.tire is not None or len(rec.tires) == 1 else None
    if args.fmu is not None and tire is None:
        raise InputError("--fmu", "names one tire's FMU: use it with --tire, or --fmu-dir for every tire")
    from ..recording.window import decimate, focus, is_long, window_json

    long = is_long(rec)
    rec = decimate(focus(rec, cutoff_hz=args.cutoff_hz), cutoff_hz=args.cutoff_hz)
    long = long or rec.decimated_from_hz is not None
    keep_fmus = args.fmu is not None or args.fmu_dir is not None
    announce_compilation()
    from .._folders import FolderSet
    # --fmu-dir as one set: the earlier FMUs or the new ones, never a mix (a plain `with`: an interrupt that
    # ends __enter__ leaves nothing, one after it reaches __exit__)
    with FolderSet(args.fmu_dir, keep_existing=True) if args.fmu_dir is not None else contextlib.nullcontext() \
            as new_dir:
        diag, gain, files = _diagnose_into(args, rec, tire, long, keep_fmus, new_dir)
        write_files(files)
    if args.json:
        doc = diag.tire_json(tire, nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after) if tire else \
            diag.to_json(nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after)
        if gain.note:
            doc["nrmse_before_note"] = gain.note
        if gain.final_note:
            doc["nrmse_after_note"] = gain.final_note
        if window_json(diag.problem.rec) is not None:    # the conditioning with the signs the fit chose
            doc["analysis_window"] = window_json(diag.problem.rec)
        print(json_text(doc))
    else:
        print(_tractor_text(diag, gain, args.verbose))
    return 0


def _diagnose_into(args, rec, tire, long: bool, keep_fmus: bool, new_dir) -> tuple:
    """Run the diagnosis; the files to write (``--fmu``, ``--plot``; ``--fmu-dir``'s FMUs go to `new_dir`,
    the folder's new set)."""
    import tempfile
    from pathlib import Path

    tick, bar = _progress(f"diagnose {tire or 'tractor'}", long=long)
    with tempfile.TemporaryDirectory(prefix=temp_prefix("fmus")) as tmp:
        try:
            diag, gain = run_tractor_diagnosis(rec, cutoff_hz=args.cutoff_hz, fmu_dir=tmp if keep_fmus else None,
                                               workers=args.workers, progress=tick)
        finally:
            bar.close()
        for line in diagnosis_warnings(diag, gain):
            print(f"cleatfmu: warning: {rec.source}: {line}", file=sys.stderr)
        files = {}
        if args.fmu is not None:
            own = next(p for p in gain.fmu_paths if p.stem.endswith(f"_{tire}"))
            files[Path(args.fmu)] = own.read_bytes()
        if new_dir is not None:
            files.update({Path(new_dir) / p.name: p.read_bytes() for p in gain.fmu_paths})
    if args.plot is not None:
        from ..report.plots import plot_tractor_diagnosis, png_bytes
        files[Path(args.plot)] = png_bytes(plot_tractor_diagnosis(diag, nrmse_before=gain.nrmse_before,
                                                                  nrmse_after=gain.nrmse_after))
    return diag, gain, files


def add_parser(subparsers) -> None:
    """Register ``cleatfmu diagnose``."""
    p = subparsers.add_parser(
        "diagnose", help="diagnose the whole tractor: every tire jointly under one body, the effects the "
                         "point-contact model misses, the extended model, the gain",
        description="Fit all channels jointly: four point-contact corners, then the rigid tractor (heave, pitch, roll; "
                    "rigid or pivoting front axle) and the tire-side extensions (enveloping, lift_off, "
                    "nonlinear_stiffness, friction_damping, periodic_disturbance), named by forward selection (BIC "
                    "plus physical evidence); say what is left unexplained; measure the gain by co-simulating one "
                    "extended tire FMU per wheel with fmpy.  Output folders are created if needed; the output "
                    "files are written together at the end, or none of them.")
    p.add_argument("recording", metavar="REC.csv", nargs="?", help="the recording (or --example NAME)")
    add_example_option(p)
    p.add_argument("--tire", metavar="TIRE", help="print one tire's result (per-tire JSON shape), from the joint "
                                                  "fit; any letter case")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.add_argument("--fmu", metavar="OUT.fmu", help="with --tire: write that tire's extended FMU")
    p.add_argument("--fmu-dir", metavar="DIR", help="write one extended tire FMU per tire into DIR "
                                                    "(REC_FL.fmu .. REC_RR.fmu)")
    p.add_argument("--plot", metavar="OUT.png", help="write measured vs the corners and the final model, per channel")
    p.add_argument("--cutoff-hz", type=float, default=None,
                   help="low-pass cut-off, Hz (default: 100, or 0.4 x the sampling rate when lower)")
    p.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1),
                   help="processes fitting candidate models in parallel (default: 2, or 1 on a one-core machine)")
    p.add_argument("-v", "--verbose", action="store_true", help="also print the time taken (text output)")
    p.set_defaults(func=run)
