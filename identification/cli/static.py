"""``cleatfmu static COMPRESSION.csv``: static tire stiffness from a compression test (eq. 18).

See :mod:`identification.identify.static` for the input format and the method.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import InputError
from .._files import json_text

__all__ = ["add_parser", "run"]

#: Number of local-slope intervals by default (identification.identify.static.DEFAULT_SEGMENTS, repeated here so that
#: building the parser imports no numpy).
_SEGMENTS = 5


def _write_plot(result, path) -> None:
    """Draw the plot and write it atomically (temporary file in the target folder, then os.replace)."""
    from .._files import atomic_write_bytes
    from ..report.plots import png_bytes
    from ..report.plots import plot_static

    data = png_bytes(plot_static(result))
    path = Path(path)
    try:
        os.makedirs(path.parent if str(path.parent) else ".", exist_ok=True)
        atomic_write_bytes({path: data})
    except OSError as exc:
        raise InputError(path, f"cannot write: {exc.strerror or exc}") from None


def run(args) -> int:
    """Run ``cleatfmu static``; returns the exit status (user errors raise InputError)."""
    from ..identify.static import static_stiffness_file

    if args.plot is not None:
        if not str(args.plot).lower().endswith(".png"):
            raise InputError(args.plot, "the plot file name must end with .png")
        if os.path.isdir(args.plot):
            raise InputError(args.plot, "is a directory (give OUT.png)")
    if args.segments < 1:
        raise InputError("--segments", f"must be >= 1, got {args.segments}")
    result = static_stiffness_file(args.compression, segments=args.segments)
    if args.plot is not None:
        _write_plot(result, args.plot)
    print(json_text(result.to_json()) if args.json else result.text())
    return 0


def add_parser(subparsers) -> None:
    """Register ``cleatfmu static`` (``set_defaults(func=run)``)."""
    p = subparsers.add_parser(
        "static", help="static tire stiffness k = dF/dD from a compression test (force-deformation curve)",
        description="Static stiffness of a tire from a compression test, by the cleat-test paper's eq. 18: "
                    "k_static = dF/dD, the least-squares slope of force against deformation over the first "
                    "loading branch (unloading rows are not fitted), with its 95 % interval, R2 and the local "
                    "slope along the branch (non-linearity, e.g. the Mullins effect).  The CSV has a header naming "
                    "deformation_m (or deformation_mm) and force_N (or force_kN); other columns are ignored.")
    p.add_argument("compression", metavar="COMPRESSION.csv", help="the compression test's rows, in measured order")
    p.add_argument("--json", action="store_true", help="print JSON (SI units) instead of text (default: text)")
    p.add_argument("--plot", metavar="OUT.png", default=None,
                   help="write force vs deformation with the fitted line and the local slopes; the folder is "
                        "created if needed (default: no plot)")
    p.add_argument("--segments", type=int, default=_SEGMENTS, metavar="N",
                   help="intervals of the loading branch with a local slope each (default: %(default)s)")
    p.set_defaults(func=run)
