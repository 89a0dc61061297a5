"""``cleatfmu comfort ACC.csv``: whole-body vibration of an acceleration record by ISO 2631-1.

The record is a CSV file with a header: the first column is time in s
(strictly increasing, uniformly sampled: every step within 1 % of the nominal
step, at least 1 s), every other column an acceleration in m/s² (a
``cleat-recording/1`` CSV qualifies).  Each column is weighted (Wk, Wd, Wf, or
the additional Wc, We, Wj) and evaluated by :func:`identification.comfort.iso2631.comfort`; for Wk and Wd
the daily exposure (8 h unless ``--exposure-h``) is compared with the
whole-body values of EU directive 2002/44/EC.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError
from .._files import json_text
from ..recording.csv_reader import check_uniform_time
from .util import check_output

__all__ = ["add_parser", "run", "read_acceleration_csv", "DEFAULT_EXPOSURE_H"]

#: Daily exposure time assumed for Wk and Wd when none is given, h.
DEFAULT_EXPOSURE_H = 8.0
#: Shortest accepted record, s (the running RMS's integration time).
MIN_DURATION_S = 1.0
_WEIGHTINGS = ("Wk", "Wd", "Wf", "Wc", "We", "Wj")
#: What a weighting without daily-exposure values rates (its error message).
_NO_EXPOSURE = {"Wf": "motion sickness", "Wc": "seat-back", "We": "rotational vibration", "Wj": "recumbent, head"}


def add_parser(subparsers) -> None:
    """Register ``cleatfmu comfort``."""
    p = subparsers.add_parser(
        "comfort", help="whole-body vibration of an acceleration record (ISO 2631-1): a_w, VDV, MTVV, A(8)",
        description="Frequency-weight every acceleration column of a CSV record (ISO 2631-1:1997 Annex A) and "
                    "report the weighted RMS a_w, the vibration dose value VDV, the maximum transient vibration "
                    "value MTVV (1 s running RMS) and the crest factor; for Wk and Wd also the daily exposure "
                    "A(8) and daily VDV against the EU directive 2002/44/EC action and limit values.")
    p.add_argument("acc", metavar="ACC.csv",
                   help="CSV with a header; first column time in s (uniformly sampled), then accelerations in m/s²")
    p.add_argument("--weighting", choices=_WEIGHTINGS, default="Wk",
                   help="Wk vertical, Wd horizontal (x, y), Wf motion sickness; Wc seat-back fore-aft (x), We "
                        "rotational (the columns in rad/s², a_w in rad/s²), Wj vertical under the head, recumbent "
                        "(default: %(default)s)")
    p.add_argument("--column", metavar="NAME", help="evaluate only this column (default: every acceleration column)")
    p.add_argument("--exposure-h", metavar="H",
                   help=f"daily exposure time, h (0 < H <= 24), for A(8) and the daily VDV (default: "
                        f"{DEFAULT_EXPOSURE_H:g} for Wk and Wd; Wf has no exposure values)")
    p.add_argument("--axes", metavar="X,Y,Z",
                   help="rate a seat's three axes: the fore-aft, lateral and vertical columns (weighted Wd, Wd, Wk): "
                        "a_w, VDV, MTVV per axis, the vector sum (k = 1.4, 1.4, 1) and the worst axis's A(8) and "
                        "daily VDV against 2002/44/EC (--weighting and --column do not apply)")
    p.add_argument("--mtvv-window-s", type=float, default=1.0, metavar="TAU",
                   help="integration time of the running RMS whose maximum is MTVV, s; the record must be at least "
                        "this long (ISO 2631-1 recommends 1 s) (default: %(default)s)")
    p.add_argument("--bands", action="store_true",
                   help="also print the one-third-octave band spectrum of each weighted column (always in --json)")
    p.add_argument("--plot", metavar="OUT.png", default=None,
                   help="write the one-third-octave band spectra of the weighted columns as a figure")
    p.add_argument("--json", action="store_true", help="print JSON (SI units) instead of a table")
    p.set_defaults(func=run)


def _exposure_h(text: str | None, weighting: str) -> float | None:
    if text is None:
        return None if weighting in _NO_EXPOSURE else DEFAULT_EXPOSURE_H
    if weighting in _NO_EXPOSURE:
        raise InputError("--exposure-h", f"{weighting} ({_NO_EXPOSURE[weighting]}) has no daily-exposure values; "
                                         f"use Wk or Wd")
    try:
        value = float(text)
    except ValueError:
        raise InputError("--exposure-h", f"{text!r} is not a number") from None
    if not (math.isfinite(value) and 0 < value <= 24):
        raise InputError("--exposure-h", f"a daily exposure time must be > 0 and <= 24 h, got {text}")
    return value


def read_acceleration_csv(path, *, min_duration_s: float = None) -> tuple[list[str], float, dict]:
    """Read and check an acceleration record: its column names, sampling rate (Hz) and columns (m/s²).

    Parameters
    ----------
    path : str or path-like
        CSV with a header; first column time in s, other columns accelerations in m/s².

    Returns
    -------
    names : list of str
        The acceleration columns' names, in file order.
    sample_rate_hz : float
        (n - 1) / (t[-1] - t[0]).
    columns : dict of str to ndarray
        Each acceleration column.

    Raises
    ------
    InputError
        Missing or unreadable file, malformed header or cell, non-finite value,
        time not strictly increasing or not uniformly sampled, record shorter than 1 s.
    """
    import numpy as np

    from .._inputs import parse_number, read_input_text

    path = Path(path)
    lines = read_input_text(path, encoding="utf-8-sig").splitlines()
    if not lines or not lines[0].strip():
        raise InputError(path, "empty file (expected a header 'time,<columns>')")
    header = [h.strip() for h in lines[0].split(",")]
    if len(header) < 2:
        raise InputError(path, "no acceleration column (expected a header 'time,<columns>')")
    if not all(header):
        raise InputError(path, f"empty column name in the header (column {header.index('') + 1})")
    dupes = sorted({h for h in header if header.count(h) > 1})
    if dupes:
        raise InputError(path, f"duplicate column {dupes[0]!r}")
    numbered = [(i + 2, ln) for i, ln in enumerate(lines[1:]) if ln.strip()]
    if len(numbered) < 2:
        raise InputError(path, f"record too short: {len(numbered)} samples")
    for lineno, line in numbered:
        cells = line.split(",")
        if len(cells) != len(header):
            raise InputError(path, f"line {lineno}: expected {len(header)} cells, found {len(cells)}")
    try:
        data = np.loadtxt([ln for _, ln in numbered], delimiter=",", dtype=float, ndmin=2)
    except ValueError:
        for lineno, line in numbered:
            for name, cell in zip(header, line.split(",")):
                try:
                    parse_number(cell)
                except ValueError:
                    raise InputError(path, f"line {lineno}, column {name}: {cell.strip()!r} is not a number") from None
        raise InputError(path, "unreadable numeric data") from None  # pragma: no cover
    if not np.all(np.isfinite(data)):
        row, col = np.argwhere(~np.isfinite(data))[0]
        raise InputError(path, f"line {numbered[row][0]}, column {header[col]}: non-finite value {data[row, col]}")
    t = data[:, 0]
    duration = float(t[-1] - t[0])
    shortest = MIN_DURATION_S if min_duration_s is None else min_duration_s
    if duration < shortest:
        raise InputError(path, f"record too short: {duration:g} s (at least {shortest:g} s needed for the "
                               f"{shortest:g} s running RMS of MTVV; --mtvv-window-s sets it)")
    nominal = check_uniform_time(path, t, line_of=lambda i: numbered[i][0])
    names = header[1:]
    return names, 1.0 / nominal, {name: data[:, j + 1] for j, name in enumerate(names)}


def _fmt(x) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.4g}"


def format_table(path, weighting, results: dict, bands: dict | None = None) -> str:
    """The human-readable report of :func:`run` (`results`: column name -> ComfortResult; `bands`: column name
    -> :class:`~identification.comfort.spectra.ThirdOctave` or None, printed when given)."""
    from ..comfort.iso2631 import (CREST_FACTOR_LIMIT, EU_A8_ACTION_M_S2, EU_A8_LIMIT_M_S2, EU_VDV_ACTION, EU_VDV_LIMIT,
                          MTVV_RATIO_LIMIT, VDV_RATIO_LIMIT)

    first = next(iter(results.values()))
    width = max(8, *(len(n) for n in results))
    lines = [f"{path}: ISO 2631-1 {weighting.name}, {weighting.description}, {first.sample_rate_hz:.6g} Hz, "
             f"{first.duration_s:.4g} s"]
    exposure = first.exposure
    head = f"{'column':<{width}}{'a_w':>9}{'MTVV':>9}{'VDV':>10}{'crest':>7}"
    unit = weighting.unit                                   # rad/s² for the rotational We
    units = f"{'':<{width}}{unit:>9}{unit:>9}{unit.replace('/s²', '/s^1.75'):>10}{'':>7}"
    if exposure is not None:
        head += f"{'A(8)':>9}{'daily VDV':>11}"
        units += f"{'m/s²':>9}{'m/s^1.75':>11}"
    elif first.msdv is not None:
        head += f"{'MSDV':>9}"
        units += f"{'m/s^1.5':>9}"
    lines += [head, units]
    for name, r in results.items():
        row = f"{name:<{width}}{_fmt(r.a_w):>9}{_fmt(r.mtvv):>9}{_fmt(r.vdv):>10}{_fmt(r.crest_factor):>7}"
        if r.exposure is not None:
            row += f"{_fmt(r.exposure.a8):>9}{_fmt(r.exposure.vdv):>11}"
        elif r.msdv is not None:
            row += f"{_fmt(r.msdv):>9}"
        lines.append(row)
    if exposure is not None:
        lines.append(f"daily exposure {exposure.exposure_h:g} h, k = {exposure.k:g}; EU 2002/44/EC: A(8) action "
                     f"{EU_A8_ACTION_M_S2:g} / limit {EU_A8_LIMIT_M_S2:g} m/s², VDV action {EU_VDV_ACTION:g} / "
                     f"limit {EU_VDV_LIMIT:g} m/s^1.75")
        for name, r in results.items():
            lines.append(f"  {name}: A(8) {r.exposure.a8_status.replace('_', ' ')} value, "
                         f"daily VDV {r.exposure.vdv_status.replace('_', ' ')} value")
    for name, r in results.items():
        over = [f"{label} {_fmt(value)} > {limit:g}" for label, value, limit in
                (("crest factor", r.crest_factor, CREST_FACTOR_LIMIT), ("MTVV/a_w", r.mtvv_ratio, MTVV_RATIO_LIMIT),
                 ("VDV/(a_w T^1/4)", r.vdv_ratio, VDV_RATIO_LIMIT)) if value > limit]
        if over:
            lines.append(f"  {name}: {', '.join(over)}: by ISO 2631-1 6.3.3 the weighted RMS alone may "
                         f"underestimate this record (occasional shocks or vibration that varies in time); "
                         f"judge it by MTVV and VDV as well")
    if bands:
        shown = {name: b for name, b in bands.items() if b is not None}
        lines.append(f"one-third-octave bands of the weighted acceleration: RMS {unit} (level dB re 1e-6 {unit})")
        for name in (n for n, b in bands.items() if b is None):
            lines.append(f"  {name}: none (the record is too short or sampled too slowly for the bands)")
        if shown:
            first = next(iter(shown.values()))
            lines.append(f"{'band Hz':>9}" + "".join(f"{name:>20}" for name in shown))
            for i, label in enumerate(first.labels):
                lines.append(f"{label:>9}" + "".join(f"{_fmt(b.rms_m_s2[i]):>12} ({b.level_db[i]:5.1f})"
                                                     for b in shown.values()))
    return "\n".join(lines)


def _three_axes(args) -> int:
    """``cleatfmu comfort --axes X,Y,Z``: the seat's three axes (:mod:`identification.comfort.seat_axes`)."""
    from ..comfort.seat_axes import AXES, three_axis

    cols = [c.strip() for c in args.axes.split(",")]
    if len(cols) != 3 or not all(cols) or len(set(cols)) != 3:
        raise InputError("--axes", f"three different column names X,Y,Z expected, got {args.axes!r}")
    if args.column is not None:
        raise InputError("--column", "does not apply with --axes")
    if args.plot is not None or args.bands:      # (the band spectra are of one weighting's columns)
        raise InputError("--plot" if args.plot is not None else "--bands", "does not apply with --axes")
    exposure_h = _exposure_h(args.exposure_h, "Wk")
    names, fs, columns = read_acceleration_csv(args.acc, min_duration_s=args.mtvv_window_s)
    missing = [c for c in cols if c not in names]
    if missing:
        raise InputError("--axes", f"{args.acc} has no column {missing[0]!r} (columns: {', '.join(names)})")
    if fs < 160.0:
        raise InputError(args.acc, f"sampling rate {fs:.6g} Hz is too low for Wk and Wd: at least 160 Hz needed")
    try:
        r = three_axis(*(columns[c] for c in cols), fs, exposure_h=exposure_h, tau_s=args.mtvv_window_s)
    except InputError as exc:
        raise InputError(args.acc, exc.problem) from None
    doc = {"file": str(args.acc), "columns": dict(zip(AXES, cols)), "sample_rate_hz": fs, **r.to_json()}
    if args.json:
        print(json_text(doc))
        return 0
    lines = [f"{args.acc}: ISO 2631-1 seat, three axes, {fs:.6g} Hz, {r.axes['z'].duration_s:.4g} s",
             f"{'axis':<6}{'column':<12}{'weighting':>10}{'k':>5}{'a_w':>9}{'MTVV':>9}{'VDV':>10}"]
    for a, c in zip(AXES, cols):
        x = r.axes[a]
        lines.append(f"{a:<6}{c:<12}{x.weighting:>10}{doc['axes'][a]['k']:>5g}{_fmt(x.a_w):>9}{_fmt(x.mtvv):>9}"
                     f"{_fmt(x.vdv):>10}")
    lines.append(f"vector sum a_v (k 1.4, 1.4, 1): {_fmt(r.vector_sum_health)} m/s²; with k = 1 (comfort): "
                 f"{_fmt(r.vector_sum_comfort)} m/s²")
    e = doc["exposure"]
    lines.append(f"daily exposure {e['exposure_h']:g} h: A(8) {_fmt(e['a8'])} m/s² on axis {e['a8_axis']} "
                 f"({e['a8_status'].replace('_', ' ')} value; action {e['a8_action']:g} / limit {e['a8_limit']:g}), "
                 f"daily VDV {_fmt(e['vdv'])} m/s^1.75 on axis {e['vdv_axis']} ({e['vdv_status'].replace('_', ' ')} "
                 f"value; {e['vdv_action']:g} / {e['vdv_limit']:g})")
    print("\n".join(lines))
    return 0


def run(args) -> int:
    """``cleatfmu comfort``: returns the exit status; raises InputError for bad input."""
    tau = args.mtvv_window_s
    if not (math.isfinite(tau) and 0.01 <= tau <= 60.0):
        raise InputError("--mtvv-window-s", f"an integration time of 0.01 to 60 s is needed, got {tau:g}")
    if args.plot is not None:
        check_output(args.plot, ".png", "--plot")
    if args.axes is not None:
        return _three_axes(args)
    exposure_h = _exposure_h(args.exposure_h, args.weighting)
    names, fs, columns = read_acceleration_csv(args.acc, min_duration_s=tau)
    if args.column is not None:
        if args.column not in names:
            raise InputError("--column", f"{args.acc} has no column {args.column!r} (columns: {', '.join(names)})")
        names = [args.column]
    from ..comfort.iso2631 import comfort, get_weighting, weight
    from ..comfort.spectra import third_octave

    weighting = get_weighting(args.weighting)
    if fs < 2.0 * weighting.band_hz[1]:
        raise InputError(args.acc, f"sampling rate {fs:.6g} Hz is too low for {weighting.name}: at least "
                                   f"{2.0 * weighting.band_hz[1]:g} Hz needed (twice the {weighting.band_hz[1]:g} Hz "
                                   f"upper end of its frequency range)")
    results, bands = {}, {}
    for name in names:
        try:
            results[name] = comfort(columns[name], fs, weighting, exposure_h=exposure_h, tau_s=tau)
        except InputError as exc:
            raise InputError(args.acc, f"column {name}: {exc.problem}") from None
        try:
            bands[name] = third_octave(weight(columns[name], fs, weighting), fs, low_hz=weighting.band_hz[0],
                                       high_hz=weighting.band_hz[1])
        except InputError:
            bands[name] = None
    if args.plot is not None:
        from ..report.plots import plot_third_octave, save_png

        save_png(plot_third_octave(bands, title=f"{Path(args.acc).name}: {weighting.name}"), args.plot)
    if args.json:
        docs = {name: {**r.to_json(), "unit": weighting.unit, "mtvv_window_s": tau,
                       "third_octave": None if bands[name] is None else bands[name].to_json()}
                for name, r in results.items()}
        if len(names) == 1:
            doc = {"file": str(args.acc), "column": names[0], **docs[names[0]]}
        else:
            doc = {"file": str(args.acc), "weighting": weighting.name, "sample_rate_hz": fs, "channels": docs}
        print(json_text(doc))
    else:
        print(format_table(args.acc, weighting, results, bands if args.bands else None))
    return 0
