"""``cleatfmu map REPORT... -o DIR``: a tire map over speed from reports, as JSON and as FMUs.

A thin layer over :func:`identification.report.tire_map.map_of_reports` (the runs of the reports'
``summary.json``, fitted over speed by :mod:`identification.identify.tire_map`) and
:func:`identification.fmu.tire_map_fmu.export_map_fmu`: writes ``DIR/tire_map.json`` and, per tire mapped,
``DIR/tire_map_<TIRE>.fmu``, all or none.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from ..errors import InputError

__all__ = ["add_parser", "run", "MAP_JSON"]

#: File name of the map document in the output folder.
MAP_JSON = "tire_map.json"


def add_parser(subparsers) -> None:
    """Register ``cleatfmu map``."""
    p = subparsers.add_parser(
        "map", help="k and c of each tire as functions of speed, from reports of runs at several speeds",
        description="Fit each tire's recommended k and c (with their 95 % intervals) from the recordings of one or "
                    "more reports over speed (weighted least squares; linear, a quadratic where the runs demand "
                    "it; a between-run scatter where they disagree beyond their intervals) and write "
                    f"DIR/{MAP_JSON} and, per tire, DIR/tire_map_<TIRE>.fmu: the point-contact tire whose k and c "
                    "follow its input speed, flagging speeds outside the tested range. 'cleatfmu ride --compare "
                    f"map=DIR/{MAP_JSON}' rides the map at the ride's speed.")
    p.add_argument("reports", nargs="+", metavar="REPORT", help="report folders (cleatfmu report -o) or their "
                                                                "summary.json")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="output folder (created with its missing parents)")
    p.add_argument("--tire", action="append", metavar="TIRE", default=None,
                   help="map only this tire (any letter case; repeat for several; default: every tire with runs)")
    p.add_argument("--pressure-kpa", type=float, default=None, metavar="P",
                   help="map only the runs whose sidecar declares this inflation pressure (within 5 %%; needed "
                        "when a tire was tested at several pressures)")
    p.add_argument("--unloaded-radius-m", type=float, default=None, metavar="R0",
                   help="unloaded tire radius of the FMUs, m (default 0.75, an assumption; it only sets the hub "
                        "height at which the tire touches the road)")
    p.add_argument("--no-fmu", action="store_true", help=f"write {MAP_JSON} only")
    p.add_argument("--fmi-version", type=int, default=2, metavar="{2,3}", help="FMI version of the FMUs "
                                                                                 "(default: %(default)s)")
    p.add_argument("--platforms", default=None, metavar="P1,P2",
                   help="comma-separated platforms of the FMUs (default: all)")
    p.add_argument("--json", action="store_true", help=f"print the map document ({MAP_JSON}) instead of a table")
    p.set_defaults(func=run)


def _check(args):
    from ..fmu.export import check_backend
    from ..model.tire_law import value_problem
    from ..recording.plausibility import check_value
    from .util import normalize_tire

    from ..recording import TIRES

    tires = None if args.tire is None else [normalize_tire(t) for t in args.tire]
    for tire in tires or []:
        if tire not in TIRES:
            raise InputError("--tire", f"unknown tire {tire!r} ({', '.join(TIRES)})")
    if args.pressure_kpa is not None and not (math.isfinite(args.pressure_kpa) and args.pressure_kpa > 0):
        raise InputError("--pressure-kpa", f"a pressure > 0 kPa is expected, got {args.pressure_kpa:g}")
    if args.unloaded_radius_m is not None:
        problem = value_problem("unloaded radius", "m", args.unloaded_radius_m, strictly_positive=True) or \
            check_value("unloaded_radius_m", args.unloaded_radius_m, label="unloaded radius")
        if problem:
            raise InputError("--unloaded-radius-m", problem)
    platforms = None if args.platforms is None else [p.strip() for p in args.platforms.split(",") if p.strip()]
    check_backend("native", args.fmi_version, platforms)
    return tires, platforms


def format_map(doc: dict) -> str:
    """The map as text: per tire the tested range, the runs, the degrees and k, c (with their 95 % band) at
    the ends of the tested range."""
    from ..identify.tire_map import map_values

    lines = [f"{'tire':<5}{'tested km/h':>13}{'runs':>6}{'degree k/c':>12}   k kN/m at low, high"
             f"{'':>14}c kN s/m at low, high"]
    for tire, m in doc["tires"].items():
        low, high = m["tested_speed_m_s"]
        ends = [map_values(m, low), map_values(m, high)]
        k = ", ".join(f"{e['k'] / 1e3:.1f} ± {e['k_band'] / 1e3:.1f}" for e in ends)
        c = ", ".join(f"{e['c'] / 1e3:.3f} ± {e['c_band'] / 1e3:.3f}" for e in ends)
        tested = f"{3.6 * low:.3g}-{3.6 * high:.3g}"
        degrees = f"{m['k']['degree']}/{m['c']['degree']}"
        lines.append(f"{tire:<5}{tested:>13}{len(m['runs']):>6}{degrees:>12}   {k:<33}{c}")
    lines.append("outside the tested speeds: extrapolation (k, c of the nearest node), flagged by the FMUs")
    return "\n".join(lines)


def run(args) -> int:
    """Run ``cleatfmu map``; returns 0 (user errors raise InputError)."""
    from .._files import json_text
    from ..fmu.tire_map_fmu import export_map_fmu
    from ..report.tire_map import map_of_reports
    from .util import announce_compilation, write_files

    tires, platforms = _check(args)
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise InputError(out, "is not a directory")
    doc = map_of_reports(args.reports, tires=tires, pressure_kpa=args.pressure_kpa)
    missing = [t for t in (tires or []) if t not in doc["tires"]]
    if missing:
        raise InputError("--tire", f"no map for {', '.join(missing)}: "
                                   + ("; ".join(f"{t}: {doc['skipped'][t]}" for t in missing if t in doc["skipped"])
                                      or "no runs with recommended k and c"))
    from .._folders import FolderSet

    # DIR as one set: the earlier map's files or the new ones (never a mix), its other files kept, one run at a
    # time (a second is refused, naming the first one's pid)
    with FolderSet(out, keep_existing=True) as new:
        written = [out / p.relative_to(new) for p in
                   write_files({new / MAP_JSON: (json_text(doc) + "\n").encode("utf-8")})]
        if not args.no_fmu:
            announce_compilation()
            for tire in doc["tires"]:
                path = export_map_fmu(doc, tire, new / f"tire_map_{tire}.fmu", unloaded_radius_m=args.unloaded_radius_m,
                                      fmi_version=args.fmi_version, platforms=platforms)
                written.append(out / Path(path).relative_to(new))
    for tire, reason in doc["skipped"].items():
        print(f"cleatfmu: warning: tire {tire} not mapped: {reason}", file=sys.stderr)
    if args.json:
        print(json_text(doc))
    else:
        print(format_map(doc))
        for path in written:
            print(f"wrote {path}")
    return 0
