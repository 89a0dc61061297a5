"""``cleatfmu ride``: the whole tractor on an ISO 8608 road with each tire parameter set, rated at the seat.

The body (rigid or pivoting front axle, dynamic indices) and the sets come
from a whole-tractor recording (:func:`identification.comfort.ride.parameter_sets`);
the ride from :func:`identification.comfort.ride.ride`; the rating is
ISO 2631-1's Wk (vertical) at the seat: on the floor, or with ``--seat PARAMS.json`` on a suspended seat
(:mod:`identification.comfort.seat`).
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
from pathlib import Path

from ..errors import InputError
from .._files import json_text

__all__ = ["add_parser", "run", "DEFAULT_COMPARE", "format_expected", "format_contact", "format_axes", "format_seat"]

DEFAULT_COMPARE = "paper,final"
_CLASSES = ("A", "B", "C", "D", "E")


def add_parser(subparsers) -> None:
    """Register ``cleatfmu ride``."""
    p = subparsers.add_parser(
        "ride", help="the tractor on an ISO 8608 road with each tire parameter set: ISO 2631-1 a_w, VDV at the seat",
        description="Diagnose a whole-tractor recording (body and tires; or take them from --body), then drive that tractor over a random "
                    "ISO 8608 road (two tracks, seeded) once per tire parameter set (--compare) and rate the seat's "
                    "vertical acceleration by ISO 2631-1 (Wk): weighted RMS a_w, VDV, MTVV, crest factor, and the "
                    "daily exposure A(8) against EU directive 2002/44/EC.")
    p.add_argument("recording", metavar="REC.csv", nargs="?", help="a whole-tractor recording (four hubs)")
    p.add_argument("--example", metavar="NAME", help="an embedded recording instead of REC.csv (7kmh, 10kmh)")
    p.add_argument("--road", default=None, type=str.upper, help="ISO 8608 road class, A (best) .. E (default B)")
    p.add_argument("--coherence", choices=("uniform", "class"), default=None,
                   help="coherence of the left and right tracks: uniform, exp(-2 n B) for every class (default), "
                        "or class, measured per class A .. E (Project Chrono's RandomSurfaceTerrain; lower on rough "
                        "roads)")
    p.add_argument("--road-file", metavar="ROAD.csv|ROAD.crg", default=None,
                   help="ride on this road (a road CSV x_m,left_m,right_m or an OpenCRG file) instead of a generated "
                        "one: one ride, the class reported as 'file'")
    p.add_argument("--save-road", metavar="OUT.csv|OUT.crg", default=None,
                   help="write the road ridden (seed's road; both tracks) as a road CSV or an OpenCRG file")
    p.add_argument("--speed-kmh", type=float, default=None, help="driving speed, km/h (default: the recording's)")
    p.add_argument("--duration-s", type=float, default=60.0, help="length of the ride, s (default 60)")
    p.add_argument("--compare", default=DEFAULT_COMPARE,
                   help="parameter sets, comma-separated: paper, waveform, final, static=K (K in N/m, or a "
                        "compression test CSV as for the static command), fmu=DIR (the k, c of the four tire "
                        "FMUs in DIR, *_FL.fmu .. *_RR.fmu, as exported; in a report's fmu/ the recording's), params=FILE (the k, c of an "
                        "'identify --json' file of the four tires), map=FILE (the k, c of a 'cleatfmu map' tire map at the "
                        "ride's speed; outside its tested speeds an extrapolation, warned of); "
                        f"default {DEFAULT_COMPARE})")
    p.add_argument("--body", metavar="DIAG.json", default=None,
                   help="take the body and the final k, c from a 'cleatfmu diagnose --json' document or a report's "
                        "summary.json (its entry of the recording) instead of diagnosing the recording")
    p.add_argument("--seed", type=int, default=1,
                   help="seed of the first road; the other realisations' seeds are derived from it (default 1)")
    p.add_argument("--realisations", type=int, default=None,
                   help="roads of the class to ride (seeds derived from --seed): every rating as its expected "
                        "value, the 95 %% interval of that mean and of a single ride "
                        f"(default {_default_realisations()})")
    p.add_argument("--seat-x-m", type=float, default=None,
                   help="seat position behind the front axle, m (default: 0.85 of the wheelbase)")
    p.add_argument("--seat-y", type=float, default=0.0,
                   help="seat position from the centre line, fraction of the half-track (+ left; default 0)")
    p.add_argument("--tires", choices=("auto", "linear", "lift-off"), default="auto",
                   help="tire law rated: auto (default) rides the linear law and, where a tire would pull "
                        "(tension), the ride again with the law's lift-off option; linear; lift-off. The "
                        "linear law's tension is always counted")
    p.add_argument("--seat-height-m", type=float, default=None,
                   help="seat height above the axles, m, for the seat's fore-aft (pitch) and lateral (roll) "
                        "acceleration (default 0.9)")
    p.add_argument("--seat", metavar="PARAMS.json", default=None,
                   help="rate the occupant on a suspended seat (mass, spring, damper, end stops; see 'cleatfmu seat'): "
                        "the z axis on the seat with its floor values alongside, the SEAT factor and the end-stop "
                        "hits; x and y stay floor values (default: floor values, no seat suspension)")
    p.add_argument("--exposure-h", type=float, default=8.0, help="daily exposure time for A(8), h (default 8)")
    p.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1), help="processes of the diagnosis (default: 2 or the CPU count)")
    p.add_argument("--json", action="store_true", help="print JSON (SI units)")
    p.add_argument("--plot", metavar="OUT.png", help="write the seat's acceleration and a_w, VDV per set")
    p.add_argument("--bands", action="store_true",
                   help="also print the seat's one-third-octave band spectra (x, y Wd; z Wk), expected over the "
                        "roads (always in --json, sets.<name>.expected.third_octave)")
    p.add_argument("--bands-plot", metavar="OUT.png",
                   help="write the seat's expected one-third-octave band spectra (z, Wk) per set as a figure")
    p.add_argument("--enveloping", choices=("diagnosed", "off"), default="diagnosed",
                   help="every set's tires roll with the footprints the diagnosis fitted where it named "
                        "enveloping (the road averaged over each footprint), or ('off') on the point under them "
                        "(default diagnosed)")
    p.add_argument("--ssp", metavar="DIR", help="also write each set's ride as an SSP 1.0 system of native FMUs "
                                                "(body, four tires, road profile): DIR/<set>.ssp")
    p.set_defaults(func=run)


def _default_realisations() -> int:
    from ..comfort.expected import DEFAULT_REALISATIONS
    return DEFAULT_REALISATIONS


def _check(args) -> list:
    from ..comfort.expected import MAX_REALISATIONS

    if args.road_file is not None:
        for option, value in (("--road", args.road), ("--coherence", args.coherence)):
            if value is not None:
                raise InputError(option, "applies to a generated road, not to --road-file")
        if args.realisations not in (None, 1):
            raise InputError("--realisations", "a road file is one road: one realisation")
        args.realisations = 1
    if args.realisations is None:
        args.realisations = _default_realisations()
    if not 1 <= args.realisations <= MAX_REALISATIONS:
        raise InputError("--realisations", f"1 .. {MAX_REALISATIONS} expected, got {args.realisations}")
    if args.seed < 0:
        raise InputError("--seed", f"an integer >= 0 expected, got {args.seed}")
    args.road = "B" if args.road is None else args.road
    args.coherence = "uniform" if args.coherence is None else args.coherence
    if args.road not in _CLASSES:
        raise InputError("--road", f"unknown ISO 8608 class {args.road!r} (A, B, C, D or E)")
    if args.speed_kmh is not None and not (math.isfinite(args.speed_kmh) and 1.0 <= args.speed_kmh <= 60.0):
        raise InputError("--speed-kmh", f"a tractor's ride speed of 1 .. 60 km/h is expected, got {args.speed_kmh:g}")
    if not (math.isfinite(args.duration_s) and 10.0 <= args.duration_s <= 3600.0):
        raise InputError("--duration-s", f"10 .. 3600 s expected, got {args.duration_s:g}")
    if not (math.isfinite(args.exposure_h) and 0 < args.exposure_h <= 24.0):
        raise InputError("--exposure-h", f"0 .. 24 h expected, got {args.exposure_h:g}")
    if not (math.isfinite(args.seat_y) and -1.5 <= args.seat_y <= 1.5):
        raise InputError("--seat-y", f"a fraction of the half-track within ±1.5 is expected, got {args.seat_y:g}")
    if args.seat_x_m is not None and not math.isfinite(args.seat_x_m):
        raise InputError("--seat-x-m", f"a finite position is expected, got {args.seat_x_m:g}")
    if args.seat_height_m is not None and not (math.isfinite(args.seat_height_m) and -1.0 <= args.seat_height_m <= 5.0):
        raise InputError("--seat-height-m", f"-1 .. 5 m above the axles expected, got {args.seat_height_m:g}")
    if args.workers < 1:
        raise InputError("--workers", f"at least 1, got {args.workers}")
    args.seat_model = None
    if args.seat is not None:
        from ..comfort.seat import read_seat
        args.seat_model = read_seat(args.seat)
    from ..comfort.ride import check_set_names

    from .util import recording_name_arg

    return check_set_names(args.compare.split(","), recording=recording_name_arg(args))


def run(args) -> int:
    from .command_line import _recording_arg
    from .util import check_output

    names = _check(args)
    road = None if args.road_file is None else _road_file(args.road_file)
    check_output(args.plot, ".png", "plot")
    check_output(args.bands_plot, ".png", "plot")
    if args.save_road is not None:
        if not args.save_road.lower().endswith((".csv", ".crg")):
            raise InputError(args.save_road, "the road file name must end with .csv or .crg")
        check_output(args.save_road, args.save_road[-4:].lower(), "road")
    if args.ssp is not None:
        from .util import check_folder
        check_folder(args.ssp)
    rec = _recording_arg(args)
    from ..comfort.ride import ride_comparison

    if args.seat_x_m is not None and not -1.0 <= args.seat_x_m <= rec.wheelbase_m + 1.0:
        raise InputError("--seat-x-m", f"the seat must be on the tractor (-1 .. wheelbase + 1 m), got {args.seat_x_m:g}")
    speed = rec.speed_m_s if args.speed_kmh is None else args.speed_kmh / 3.6
    if road is not None and road.length_m < speed * args.duration_s:
        raise InputError(args.road_file, f"the road is {road.length_m:g} m long, shorter than the ride "
                                         f"({speed * args.duration_s:g} m: {speed * 3.6:.3g} km/h for "
                                         f"{args.duration_s:g} s); shorten --duration-s")
    from .util import announce_compilation
    announce_compilation()
    from .._folders import FolderSet
    # --ssp DIR as one set: the earlier systems or the new ones, its other files kept
    with FolderSet(args.ssp, keep_existing=True) if args.ssp is not None else contextlib.nullcontext() as ssp_dir:
        runs, doc = ride_comparison(rec, names, road_class=args.road, seed=args.seed,
                                    speed_m_s=None if args.speed_kmh is None else args.speed_kmh / 3.6,
                                    duration_s=args.duration_s, seat_x_m=args.seat_x_m, seat_y=args.seat_y,
                                    exposure_h=args.exposure_h, workers=args.workers, ssp_dir=ssp_dir,
                                    realisations=args.realisations, tires=args.tires,
                                    seat_height_m=args.seat_height_m, body_doc=args.body, seat=args.seat_model,
                                    road=road if road is not None else {"coherence": args.coherence},
                                    enveloping=args.enveloping == "diagnosed")
        if ssp_dir is not None:
            doc["ssp"] = {name: str(Path(args.ssp) / Path(p).name) for name, p in doc["ssp"].items()}
    if road is not None:
        doc["road"]["file"] = str(args.road_file)
    if args.save_road is not None:
        _save_road(args, road, doc)
    speed, seat_x, how = doc["speed_m_s"], doc["seat"]["x_m"], doc["body"]["source"]
    for name, entry in doc["sets"].items():
        outside = [t for t, v in entry.get("map", {}).items() if v["extrapolation"]]
        if outside:
            print(f"cleatfmu: warning: set {name}: {speed * 3.6:.3g} km/h is outside the map's tested speeds of "
                  f"{', '.join(outside)}: their k, c are extrapolated (held at the nearest node)", file=sys.stderr)
        if entry["expected"]["contact"]["warning"]:
            print(f"cleatfmu: warning: set {name}: {entry['expected']['contact']['warning']}", file=sys.stderr)
    if args.plot:
        from ..report.plots import plot_ride, save_png
        save_png(plot_ride(runs, road_class=doc["road"]["class"], speed_m_s=speed,
                           expected={n: v["expected"] for n, v in doc["sets"].items()}), args.plot)
    if args.bands_plot:
        import numpy as np

        from ..comfort.spectra import ThirdOctave
        from ..report.plots import plot_third_octave, save_png

        spectra = {name: (lambda b: ThirdOctave(np.array(b["centre_hz"]), b["nominal_hz"], np.array(b["rms_m_s2"])))(
            entry["expected"]["third_octave"]["z"]) for name, entry in doc["sets"].items()
            if entry["expected"].get("third_octave")}
        save_png(plot_third_octave(spectra, title=f"seat z (Wk), expected over {doc['road']['realisations']} "
                                                  f"road(s)"), args.bands_plot)
    if args.json:
        print(json_text(doc))
    else:
        what = f"road file {args.road_file} (class file)" if road is not None else \
            f"ISO 8608 class {args.road} road (seed {args.seed}, {args.coherence} track coherence)"
        print(f"{rec.source}: {what}, {speed * 3.6:.3g} km/h, "
              f"{args.duration_s:g} s; {how}; seat {seat_x:.2f} m behind the front axle")
        print(f"{'set':<16}{'k FL/FR/RL/RR kN/m':>24}{'a_w m/s2':>10}{'VDV':>8}{'MTVV':>8}{'A(8)':>8}")
        for name, r in runs.items():
            ks = "/".join(f"{r.k[t] / 1e3:.0f}" for t in r.k)
            a8 = r.comfort.exposure.a8 if r.comfort.exposure else float("nan")
            print(f"{name:<16}{ks:>24}{r.comfort.a_w:>10.3f}{r.comfort.vdv:>8.3f}{r.comfort.mtvv:>8.3f}{a8:>8.3f}")
        footprint = next((r.footprints for r in runs.values() if r.footprints), None)
        if footprint:
            lengths = ", ".join(f"{axle} {v[0]:.2f} m" for axle, v in (
                ("front", [v for t, v in footprint.items() if t.startswith("F")]),
                ("rear", [v for t, v in footprint.items() if t.startswith("R")])) if v)
            print(f"tires: every set's roll with the footprints the diagnosis fitted ({lengths}; enveloping): road "
                  f"waves shorter than a footprint are averaged out (--enveloping off: point contact)")
        print(format_expected(doc))
        print(format_contact(doc))
        print(format_axes(doc))
        if args.seat_model is not None:
            print(format_seat(doc, args.seat))
        if args.bands:
            print(format_bands(doc))
        print(f"seat: {doc['seat']['values']}")
        if args.plot:
            print(f"wrote {args.plot}")
        if args.bands_plot:
            print(f"wrote {args.bands_plot}")
        if args.save_road:
            print(f"wrote {args.save_road}: the road ridden, both tracks")
        for name, path in doc.get("ssp", {}).items():
            print(f"wrote {path}: the ride with set {name} as an SSP 1.0 system of FMUs")
    return 0



def _road_file(path):
    """The road of ``--road-file`` (:mod:`identification.comfort.road_files`), read before the diagnosis."""
    from ..comfort.road_files import read_road

    return read_road(path)


def _save_road(args, road, doc: dict) -> None:
    """Write the road ridden: the file's, or seed's generated road again (same class, length, grid, seed and
    coherence as :func:`~identification.comfort.ride.ride_comparison` drew it: the same heights)."""
    from ..comfort.ride import ROAD_SPACING_M
    from ..comfort.road import road_profile
    from ..comfort.road_files import write_road

    if road is None:
        road = road_profile(args.road, doc["road"]["length_m"], ROAD_SPACING_M, args.seed, coherence=args.coherence)
    write_road(road, args.save_road)


def format_expected(doc: dict) -> str:
    """The expected ratings of a ``ride`` document as text: per set and rating the mean, the interval of
    the mean and the single-ride interval; the a_w from the road PSD against the realisations'."""
    first = next(iter(doc["sets"].values()))["expected"]
    n = first["realisations"]
    if n < 2:
        return "one road: no expected values (--realisations N for N roads)"
    level = f"{first['a_w']['level']:.0%}"
    keys = [k for k in ("a_w", "vdv", "mtvv", "a8") if k in first]
    label = {"a_w": "a_w m/s2", "vdv": "VDV m/s^1.75", "mtvv": "MTVV m/s2", "a8": "A(8) m/s2"}
    lines = [f"expected over {n} roads (seeds derived from {doc['road']['seed']}): mean [{level} interval of the "
             f"mean] ({level} of single rides)",
             f"{'set':<16}" + "".join(f"{label[k]:>34}" for k in keys)]
    for name, entry in doc["sets"].items():
        e = entry["expected"]
        cells = []
        for k in keys:
            s = e[k]
            lo, hi = s["mean_interval"]
            slo, shi = s["single_ride_interval"]
            cells.append(f"{s['mean']:.3f} [{lo:.3f},{hi:.3f}] ({slo:.2f}-{shi:.2f})")
        lines.append(f"{name:<16}" + "".join(f"{c:>34}" for c in cells))
    lines.append("a_w from the road PSD (linear tires): " + ", ".join(
        f"{name} {e['expected']['psd']['a_w']:.3f} (realisations {e['expected']['psd']['monte_carlo_rms_a_w']:.3f}"
        + (", rated with the lift-off law" if e["expected"]["contact"]["lift_off_rides"] else "") + ")"
        for name, e in doc["sets"].items()))
    return "\n".join(lines)


def format_contact(doc: dict) -> str:
    """The tires' contact of a ``ride`` document as text: per set the linear law's tension and, where the
    lift-off law ran, the share of the ride each tire was off the ground (means over the roads)."""
    lines = []
    for name, entry in doc["sets"].items():
        c = entry["expected"]["contact"]
        tension = " ".join(f"{t} {v:.2%}" for t, v in c["tension_share"].items())
        line = f"{name}: linear tires in tension {tension} of the ride"
        if any(v > 0 for v in c["tension_share"].values()):
            pull = max(c["largest_pull"].values())
            longest = max(c["longest_tension_s"].values())
            line += f" (longest {longest * 1e3:.0f} ms, largest pull {pull:.2f} x the static load)"
        if c["lift_off_rides"]:
            lost = " ".join(f"{t} {v:.2%}" for t, v in c["lost_contact_share"].items())
            line += f"; lift-off law on {c['lift_off_rides']} of {c['rides']} roads: off the ground {lost}"
            if any(v > 0 for v in c["lost_contact_share"].values()):
                times = " ".join(f"{t} {v:.1f}" for t, v in c["lost_contact_episodes"].items())
                line += (f", {times} times per road, at most {max(c['longest_lost_contact_s'].values()) * 1e3:.0f} "
                         f"ms at a time")
        lines.append(line)
    return "\n".join(lines)


def format_bands(doc: dict) -> str:
    """The seat's expected one-third-octave band spectra of a ``ride`` document as text: per axis (x, y Wd;
    z Wk) a row per band, a column per set, RMS level in dB re 1e-6 m/s²."""
    sets = {name: e["expected"]["third_octave"] for name, e in doc["sets"].items()
            if e["expected"].get("third_octave")}
    if not sets:
        return "one-third-octave bands: none (the ride is too short for the lowest band)"
    lines = [f"seat's one-third-octave bands, expected over {doc['road']['realisations']} road(s): RMS level, "
             f"dB re 1e-6 m/s2"]
    for axis, weighting in (("z", "Wk"), ("x", "Wd"), ("y", "Wd")):
        first = next(iter(sets.values()))[axis]
        lines.append(f"  {axis} ({weighting})  Hz " + "".join(f"{name[:12]:>13}" for name in sets))
        for i, label in enumerate(first["nominal_hz"]):
            levels = [b[axis]["level_db_re_1e-6_m_s2"][i] for b in sets.values()]
            lines.append(f"  {label:>10}    " + "".join(f"{'-' if v is None else f'{v:.1f}':>13}" for v in levels))
    return "\n".join(lines)


def format_axes(doc: dict) -> str:
    """The seat's three axes of a ``ride`` document as text (expected values over the roads): a_w per axis
    (x, y Wd; z Wk), the vector sum (k 1.4, 1.4, 1) and the worst axis's A(8) against 2002/44/EC."""
    from ..comfort.iso2631 import EU_A8_ACTION_M_S2, EU_A8_LIMIT_M_S2

    seat = doc["seat"]
    lines = [f"seat's three axes ({seat['height_m']:g} m above the axles; expected a_w, m/s2): x, y Wd, z Wk; "
             f"vector sum with k = 1.4, 1.4, 1"]
    for name, entry in doc["sets"].items():
        e = entry["expected"]
        line = (f"{name}: x {e['x_a_w']['mean']:.3f}, y {e['y_a_w']['mean']:.3f}, z {e['z_a_w']['mean']:.3f}, "
                f"vector sum {e['vector_sum_health']['mean']:.3f}")
        if "a8_worst_axis" in e:
            a8 = e["a8_worst_axis"]["mean"]
            status = "above the limit" if a8 > EU_A8_LIMIT_M_S2 else "above the action value" \
                if a8 > EU_A8_ACTION_M_S2 else "below the action value"
            line += (f"; A(8) {a8:.3f} on axis {entry['three_axes']['exposure']['a8_axis']} "
                     f"({status}, {EU_A8_ACTION_M_S2:g} / {EU_A8_LIMIT_M_S2:g})")
        lines.append(line)
    return "\n".join(lines)


def format_seat(doc: dict, source: str = "") -> str:
    """The suspended seat of a ``ride --seat`` document as text: the seat, then per set the occupant's and the
    floor's z a_w, the SEAT factor and the end-stop hits (expected values over the roads)."""
    seat = doc["seat"]["suspension"]
    lines = [f"suspended seat{' ' + source if source else ''}: {seat['mass_kg']:g} kg, natural frequency "
             f"{seat['natural_frequency_hz']:.2f} Hz, damping ratio {seat['damping_ratio']:.2f}, travel "
             f"+-{seat['travel_m'] * 1e3:g} mm (expected values; z a_w in m/s2)"]
    iso = doc["seat"]["iso5007"]
    lines.append(f"on ISO 5007 class {iso['class']} ({iso['tractor_mass']}; the wheel loads give "
                 f"{iso['tractor_mass_kg']:.0f} kg): SEAT {iso['seat_factor']:.3f} (linear seat "
                 f"{iso['seat_factor_linear']:.3f}), end-stop hits {iso['end_stops']['hits']}")
    for name, entry in doc["sets"].items():
        e = entry["expected"]
        linear = e["psd"]["seat_factor_linear"]      # None on a road file (no PSD)
        linear = "none" if linear is None else f"{linear:.3f}"
        lines.append(f"{name}: seat {e['a_w']['mean']:.3f}, floor {e['floor_a_w']['mean']:.3f}, SEAT "
                     f"{e['seat_factor']['mean']:.3f} (linear seat from the road PSD "
                     f"{linear}), end-stop hits {e['end_stop_hits']['mean']:.3g} per "
                     f"ride ({e['end_stop_share']['mean']:.2%} of the time)")
    return "\n".join(lines)
