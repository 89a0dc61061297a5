"""``cleatfmu seat [PARAMS.json]``: a suspended seat's SEAT factor on ISO 5007's input classes.

The seat (:func:`identification.comfort.seat.read_seat`, or the default seat) on a random floor record of
each agricultural tractor input class, rated by ISO 2631-1 (Wk): the SEAT factor in the time domain (end
stops included) beside the linear seat's from the class's PSD (:func:`identification.comfort.seat.class_seat_factor`).
"""

from __future__ import annotations

import math

from ..errors import InputError
from .._files import json_text

__all__ = ["add_parser", "run"]

_CLASSES = ("I", "II", "III")


def add_parser(subparsers) -> None:
    """Register ``cleatfmu seat``."""
    p = subparsers.add_parser(
        "seat", help="a suspended seat's SEAT factor on ISO 5007's input classes of agricultural tractors",
        description="Step a suspended seat (mass, linear spring and damper, end stops) on a random floor "
                    "acceleration of each ISO 5007 input spectral class of agricultural wheeled tractors (I up "
                    "to 3600 kg, II 3600-6500 kg, III over 6500 kg) and give its SEAT factor a_w(seat) / "
                    "a_w(floor), both Wk-weighted (ISO 2631-1): in the time domain, end stops included, and for "
                    "the linear seat from the class's PSD, with the seat's natural frequency, damping ratio and "
                    "end-stop hits.  The class spectra are those of the HVLab HRV Toolbox's reading of ISO "
                    "5007:2003 (8-pole Butterworth bands), not checked against the standard's text.")
    p.add_argument("params", metavar="PARAMS.json", nargs="?", default=None,
                   help="the seat: a JSON object with mass_kg, stiffness_N_per_m, damping_N_s_per_m, travel_m, "
                        "end_stop_stiffness_N_per_m (a key left out takes the default seat's value; default: a "
                        "passive seat of 90 kg, 1.6 Hz, damping ratio 0.3, travel +-50 mm)")
    p.add_argument("--class", dest="input_class", metavar="CLASS", type=str.upper, default=None,
                   help="ISO 5007 input class I, II or III (default: all three)")
    p.add_argument("--duration-s", type=float, default=120.0, help="length of the random floor record rated, s "
                                                                    "(default 120)")
    p.add_argument("--seed", type=int, default=1, help="seed of the random floor record (default 1)")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.input_class is not None and args.input_class not in _CLASSES + ("1", "2", "3"):
        raise InputError("--class", f"unknown ISO 5007 input class {args.input_class!r} (I, II or III)")
    if not (math.isfinite(args.duration_s) and 10.0 <= args.duration_s <= 3600.0):
        raise InputError("--duration-s", f"10 .. 3600 s expected, got {args.duration_s:g}")
    if args.seed < 0:
        raise InputError("--seed", f"an integer >= 0 expected, got {args.seed}")
    from ..comfort.seat import DEFAULT_SEAT, ISO5007_SOURCE, class_seat_factor, read_seat

    seat = DEFAULT_SEAT if args.params is None else read_seat(args.params)
    names = _CLASSES if args.input_class is None else (args.input_class,)
    rows = [class_seat_factor(seat, name, duration_s=args.duration_s, seed=args.seed) for name in names]
    if args.json:
        print(json_text({"seat": seat.to_json(), "source": args.params or "default seat",
                         "input_spectra": ISO5007_SOURCE, "classes": rows}))
        return 0
    print(f"seat ({args.params or 'default seat'}): {seat.mass_kg:g} kg, k {seat.stiffness_N_per_m:g} N/m, "
          f"c {seat.damping_N_s_per_m:g} N s/m, travel +-{seat.travel_m * 1e3:g} mm, end stops "
          f"{seat.end_stop_stiffness_N_per_m:g} N/m")
    print(f"natural frequency {seat.natural_frequency_hz:.2f} Hz, damping ratio {seat.damping_ratio:.2f}")
    print(f"{'class':<7}{'tractor mass':<17}{'input rms':>10}{'floor a_w':>10}{'seat a_w':>10}{'SEAT':>8}"
          f"{'SEAT linear':>13}{'end-stop hits':>15}")
    for r in rows:
        stops = r["end_stops"]
        print(f"{r['class']:<7}{r['tractor_mass']:<17}{r['input_rms']:>10.3f}{r['floor_a_w']:>10.3f}"
              f"{r['seat_a_w']:>10.3f}{r['seat_factor']:>8.3f}{r['seat_factor_linear']:>13.3f}"
              f"{stops['hits']:>6d} ({stops['share']:.2%})")
    print(f"a_w in m/s2 (ISO 2631-1 Wk); SEAT = a_w(seat) / a_w(floor) on {args.duration_s:g} s of floor "
          f"(seed {args.seed}), end stops included; SEAT linear: the linear seat from the class's PSD")
    print(f"input spectra: {ISO5007_SOURCE}")
    return 0
