"""``cleatfmu identify REC.csv``: each tire's k and c by the cleat-test paper's method, or the waveform fit.

A thin layer over :func:`identification.identify.graceful.identify_channels`.
"""

from __future__ import annotations

import sys

from .._files import json_text
from ..errors import InputError
from ..recording import TIRES
from .util import add_example_option, normalize_tire, read_recording_arg

__all__ = ["add_parser", "run", "tire_list", "format_table"]


def add_parser(sub) -> None:
    """Register ``cleatfmu identify``."""
    p = sub.add_parser("identify", help="identify tire stiffness k and damping c from a cleat recording",
                       description="Identify k and c of each tire by the cleat-test paper's method "
                                   "(logarithmic decrement for k, exponential fit through the first peak for c).")
    p.add_argument("recording", nargs="?", metavar="REC.csv",
                   help="recording NAME.csv (sidecar NAME.json beside it)")
    add_example_option(p)
    p.add_argument("--tire", action="extend", nargs="+", metavar="TIRE",
                   help="tire channel(s) to identify (FL FR RL RR, any letter case; default: all in the "
                        "recording)")
    p.add_argument("--method", choices=("paper", "waveform"), default="paper",
                   help="paper: log decrement (k) and exponential fit through the first peak (c); "
                        "waveform: least-squares damped-sinusoid fit of the free decay, with 95%% "
                        "confidence intervals (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print JSON (SI units) instead of a table")
    p.add_argument("--cutoff-hz", type=float, default=None,
                   help="low-pass cut-off, Hz (default: 100, or 0.4 x the sampling rate when lower; zero-phase 5th-order Butterworth)")
    p.set_defaults(func=run)


def tire_list(values: list[str] | None) -> list[str] | None:
    """The tires of ``--tire`` (names in any letter case, separated by blanks or commas), or None for all."""
    if not values:
        return None
    out: list[str] = []
    for item in values:
        for name in map(normalize_tire, item.replace(",", " ").split()):
            if name not in TIRES:
                raise InputError("--tire", f"unknown tire {name!r} (allowed: {', '.join(TIRES)})")
            if name not in out:
                out.append(name)
    if not out:
        raise InputError("--tire", "no tire given (FL, FR, RL or RR)")
    return out


def format_table(rec, results) -> str:
    """A Table-4-style text table (SI values shown in the paper's units)."""
    head = (f"{'Tire':<5}{'T/s':>7}{'zeta':>7}{'delta':>7}{'wn/rad/s':>10}{'K/kN/m':>10}"
            f"{'C/kNs/m':>9}{'R2':>6}{'peaks':>6}{'m/kg':>8}")
    lines = [f"Recording {rec.source}: {rec.speed_kmh:.4g} km/h, {rec.sample_rate_hz:.6g} Hz, "
             f"cleat {rec.cleat_height_m * 1e3:.4g} x {rec.cleat_width_m * 1e3:.4g} mm", head, "-" * len(head)]
    for name, r in results.items():
        lines.append(f"{name:<5}{r.T:>7.3f}{r.zeta:>7.3f}{r.delta:>7.3f}{r.omega_n:>10.2f}{r.k / 1e3:>10.2f}"
                     f"{r.c / 1e3:>9.2f}{r.r2:>6.2f}{r.n_peaks:>6d}{r.mass:>8.1f}")
    cis = [(n, r) for n, r in results.items() if hasattr(r, "k_ci")]
    if cis:
        lines.append("95 % confidence intervals (waveform fit):")
        for name, r in cis:
            lines.append(f"{name:<5}K {r.k_ci[0] / 1e3:.2f} .. {r.k_ci[1] / 1e3:.2f} kN/m   "
                         f"C {r.c_ci[0] / 1e3:.3f} .. {r.c_ci[1] / 1e3:.3f} kNs/m")
    return "\n".join(lines)


def run(args) -> int:
    """Run ``cleatfmu identify``; returns 0 (user errors raise InputError)."""
    from ..identify.graceful import Refusal, identify_channels

    rec = read_recording_arg(args)
    results = identify_channels(rec, tire_list(args.tire), cutoff_hz=args.cutoff_hz, method=args.method)
    refused = [r for r in results.values() if isinstance(r, Refusal)]
    identified = {name: r for name, r in results.items() if not isinstance(r, Refusal)}
    if refused and not identified and all(r.fallback is None for r in refused):
        raise InputError(rec.source, f"channel {refused[0].tire}: {refused[0].rule}")
    for r in [*identified.values(), *(r.fallback for r in refused if r.fallback is not None)]:
        if r.warning() is not None:
            print(f"cleatfmu: warning: {rec.source}: {r.warning()}", file=sys.stderr)
    if args.json:
        for r in refused:
            print(f"cleatfmu: warning: {rec.source}: {r.sentence()}", file=sys.stderr)
        doc = {"recording": rec.source, "speed_kmh": rec.speed_kmh,
               "tires": {name: r.to_json() for name, r in results.items()}}
        print(json_text(doc))
    else:
        print(format_table(rec, identified))
        for r in refused:
            print(r.sentence())
    return 0
