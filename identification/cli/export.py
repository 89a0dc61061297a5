"""``cleatfmu export PARAMS.json``: identified tire parameters -> a tire FMU, .tir or Chrono tire file.

A thin layer over :func:`identification.fmu.export.export_fmu` and
:func:`identification.fmu.tire_files.export_tire_file`.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..fmu.export import DEFAULT_UNLOADED_RADIUS_M, check_backend, export_fmu, read_identified

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> None:
    """Register ``cleatfmu export``."""
    p = subparsers.add_parser(
        "export", help="build a point-contact tire FMU from identified parameters",
        description="Build an FMI 2.0 or 3.0 co-simulation FMU of the point-contact tire (spring k parallel to "
                    "damper c) whose tunable parameters start at the values identified by 'cleatfmu identify --json'.")
    p.add_argument("params", metavar="PARAMS.json", help="output of 'cleatfmu identify --json'")
    p.add_argument("--tire", metavar="TIRE", help="tire to export, any letter case (required when the file "
                                                  "holds several)")
    p.add_argument("-o", "--output", metavar="FMU", help="FMU file to write; its folder is created if needed "
                                                        "(default: TIRE.fmu in the current directory)")
    p.add_argument("--unloaded-radius-m", type=float, default=None, metavar="R0",
                   help=f"unloaded tire radius, m (default {DEFAULT_UNLOADED_RADIUS_M}, an assumption; "
                        f"it only sets the hub height at which the tire touches the road)")
    p.add_argument("--backend", default="native", metavar="{native,pythonfmu}",
                   help="native: C binaries for Linux, Windows and macOS, no Python needed in the importer; "
                        "pythonfmu: the Python slave (needs Python 3 in the importer) (default: %(default)s)")
    p.add_argument("--accept-out-of-range", action="store_true",
                   help="accept k, c, the corner mass and the unloaded radius outside their plausible ranges for a "
                        "tractor tire (k 10 kN/m-10 MN/m, c 0-100 kN s/m, mass 10-10200 kg, r0 0.1-2 m); they must "
                        "still be finite, k > 0, c >= 0")
    p.add_argument("--fmi-version", type=int, default=2, metavar="{2,3}",
                   help="FMI version of a native FMU: 2 (FMI 2.0) or 3 (FMI 3.0) (default: %(default)s)")
    p.add_argument("--platforms", default=None, metavar="P1,P2",
                   help="comma-separated platforms of a native FMU (default: all; FMI 2.0: linux64,win64,darwin64; "
                        "FMI 3.0: x86_64-linux,aarch64-linux,x86_64-windows,x86_64-darwin,aarch64-darwin)")
    p.add_argument("--format", default="fmu", choices=("fmu", "tir", "chrono-json"),
                   help="fmu (default); tir: an MF-Tyre property file with the vertical stiffness and damping; "
                        "chrono-json: a Chrono tire JSON with them (needs --base)")
    p.add_argument("--base", metavar="FILE", default=None,
                   help="with --format tir or chrono-json: the supplier's .tir or a Chrono tire JSON whose vertical "
                        "stiffness and damping are set; every other byte is kept")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``cleatfmu export``; returns 0 (user errors raise InputError)."""
    import sys

    _, tire, entry = read_identified(args.params, args.tire, accept_out_of_range=args.accept_out_of_range)
    if isinstance(entry.get("warning"), str) and entry["warning"]:
        # identify warned of this tire (its fit shows a coupled body or a misfit): the file carries those values
        print(f"cleatfmu: warning: {args.params}: tire {tire}: the identification warned: {entry['warning']} "
              f"(the exported k and c are its values)", file=sys.stderr)
    if args.format != "fmu" or args.base is not None:
        from ..fmu.tire_files import FORMATS, export_tire_file

        if args.format == "fmu":
            raise InputError("--base", "patches a .tir or a Chrono tire JSON: use it with --format tir or chrono-json")
        output = Path(args.output) if args.output else Path(f"{tire}{FORMATS[args.format]}")
        path, notes = export_tire_file(args.params, output, fmt=args.format, tire=tire, base=args.base,
                                       unloaded_radius_m=args.unloaded_radius_m,
                                       accept_out_of_range=args.accept_out_of_range)
        for note in notes:
            print(f"cleatfmu: warning: {note}", file=sys.stderr)
        print(f"wrote {path}: tire {tire}, stiffness {entry['k']:.6g} N/m, damping {entry['c']:.6g} N.s/m")
        return 0
    output = Path(args.output) if args.output else Path(f"{tire}.fmu")
    platforms = None if args.platforms is None else [p.strip() for p in args.platforms.split(",") if p.strip()]
    check_backend(args.backend, args.fmi_version, platforms)
    path = export_fmu(args.params, output, tire=tire, unloaded_radius_m=args.unloaded_radius_m,
                      backend=args.backend, fmi_version=args.fmi_version, platforms=platforms,
                      accept_out_of_range=args.accept_out_of_range)
    print(f"wrote {path}: tire {tire}, stiffness {entry['k']:.6g} N/m, damping {entry['c']:.6g} N.s/m")
    return 0
