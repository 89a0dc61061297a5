"""Static tire stiffness from a compression test (the cleat-test paper's section 2.2.2, eq. 18).

In a compression test the tire is loaded slowly while its deformation D and
the compression force F are measured; the static stiffness is the slope of
the force–deformation curve, k_static = dF/dD (eq. 18).  Here it is the
least-squares slope of F = k D + F0 over the first loading branch, with a
95 % interval (Student t on n − 2 degrees of freedom), R² and the local
slope dF/dD along the branch: a rubber tire need not be linear (the Mullins
effect, section 2.2.2), and the local slopes show by how much it is not.

The input is a CSV file with a header row naming the columns
``deformation_m`` (or ``deformation_mm``) and ``force_N`` (or ``force_kN``);
other columns are ignored, blank lines and lines starting with ``#`` are
skipped.  Rows are in the order measured: loading, possibly preceded or
followed by unloading.  A loading branch ends where the deformation falls
back from its largest value so far by more than :data:`UNLOADING_TOLERANCE`
of its range (smaller falls are taken as noise) and starts at the smallest
deformation before that largest value; the fit uses the first loading branch
of at least :data:`MIN_POINTS` points that rises by more than that tolerance.
Other rows (unloading, further cycles) are not fitted.  Results are in
SI units (N, m, N/m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["StaticStiffness", "read_compression", "static_stiffness", "static_stiffness_file",
           "UNLOADING_TOLERANCE", "DEFAULT_SEGMENTS", "MIN_POINTS"]

#: Fall of the deformation below its running maximum, as a fraction of the deformation range, that
#: ends the loading branch (smaller falls are taken as measurement noise).
UNLOADING_TOLERANCE = 0.05
#: Default number of intervals (of equal point count) of the loading branch with a local slope each.
DEFAULT_SEGMENTS = 5
#: Fewest points of a loading branch (and of each local-slope interval).
MIN_POINTS = 3

#: Largest deformation (m) and force (N) a compression test's cell may hold: beyond any tire, far within the fit's
#: floating-point range.
_BOUND_M, _BOUND_N = 100.0, 1e9
#: Smallest rise of the deformation on a loading branch, m.
_RESOLUTION_M = 1e-9
#: Accepted column names (lower case) and their factor to SI.
_DEFORMATION = {"deformation_m": 1.0, "deformation_mm": 1e-3}
_FORCE = {"force_n": 1.0, "force_kn": 1e3}


@dataclass(frozen=True, eq=False)
class StaticStiffness:
    """The static stiffness of one compression test.

    Attributes
    ----------
    source : str
        The file (or name) the data came from.
    k_N_per_m : float
        Static stiffness k_static = dF/dD, least-squares slope over the loading branch, N/m.
    k_ci95_N_per_m : tuple of float
        Its 95 % confidence interval, N/m.
    k_se_N_per_m : float
        Its standard error, N/m.
    intercept_N : float
        F0 of the fitted line F = k D + F0, N.
    r2 : float
        Coefficient of determination of the fit.
    residual_std_N : float
        Standard deviation of the residuals (n − 2 degrees of freedom), N.
    deformation_m, force_N : ndarray
        Every row, SI units.
    line_numbers : ndarray
        The file line of each row (1-based; 0 when not read from a file).
    first, stop : int
        The loading branch is rows ``first:stop``.
    local_deformation_m, local_force_N, local_slope_N_per_m, local_se_N_per_m : ndarray
        Local slope dF/dD of consecutive intervals of the loading branch (equal point counts):
        mean deformation and force of the interval, its least-squares slope and standard error.
    local_points : ndarray
        Points in each interval.
    """

    source: str
    k_N_per_m: float
    k_ci95_N_per_m: tuple
    k_se_N_per_m: float
    intercept_N: float
    r2: float
    residual_std_N: float
    deformation_m: np.ndarray
    force_N: np.ndarray
    line_numbers: np.ndarray
    first: int
    stop: int
    local_deformation_m: np.ndarray
    local_force_N: np.ndarray
    local_slope_N_per_m: np.ndarray
    local_se_N_per_m: np.ndarray
    local_points: np.ndarray

    @property
    def n_loading(self) -> int:
        """Points of the loading branch."""
        return self.stop - self.first

    @property
    def local_slope_range(self) -> float:
        """(largest − smallest local slope) / k: 0 for a straight force–deformation curve."""
        return float((self.local_slope_N_per_m.max() - self.local_slope_N_per_m.min()) / self.k_N_per_m)

    def to_json(self) -> dict:
        """A JSON-ready document, SI units."""
        d = self.deformation_m[self.first:self.stop]
        f = self.force_N[self.first:self.stop]
        return {
            "source": self.source,
            "method": "static stiffness k = dF/dD (eq. 18): least-squares slope of the loading branch",
            "k_static_N_per_m": self.k_N_per_m,
            "k_ci95_N_per_m": list(self.k_ci95_N_per_m),
            "k_se_N_per_m": self.k_se_N_per_m,
            "intercept_N": self.intercept_N,
            "r2": self.r2,
            "residual_std_N": self.residual_std_N,
            "n_rows": int(self.deformation_m.size),
            "loading_branch": {"first_line": int(self.line_numbers[self.first]),
                               "last_line": int(self.line_numbers[self.stop - 1]),
                               "n_points": self.n_loading,
                               "deformation_m": [float(d.min()), float(d.max())],
                               "force_N": [float(f.min()), float(f.max())]},
            "n_rows_not_fitted": int(self.deformation_m.size - self.n_loading),
            "local_slopes": [{"deformation_m": float(x), "force_N": float(y), "slope_N_per_m": float(s),
                              "se_N_per_m": float(e), "n_points": int(n)}
                             for x, y, s, e, n in zip(self.local_deformation_m, self.local_force_N,
                                                      self.local_slope_N_per_m, self.local_se_N_per_m,
                                                      self.local_points)],
            "local_slope_range": self.local_slope_range,
        }

    def text(self) -> str:
        """A short report in the paper's units (kN/m, mm, kN)."""
        doc = self.to_json()
        branch = doc["loading_branch"]
        lo, hi = self.k_ci95_N_per_m
        lines = [f"{self.source}: static stiffness by eq. 18, k = dF/dD (least squares over the loading branch)",
                 f"  loading branch: lines {branch['first_line']}-{branch['last_line']} ({self.n_loading} points), "
                 f"deformation {branch['deformation_m'][0] * 1e3:.4g}-{branch['deformation_m'][1] * 1e3:.4g} mm, "
                 f"force {branch['force_N'][0] / 1e3:.4g}-{branch['force_N'][1] / 1e3:.4g} kN"
                 + (f"; {doc['n_rows_not_fitted']} other rows not fitted" if doc["n_rows_not_fitted"] else ""),
                 f"  k_static {self.k_N_per_m / 1e3:.2f} kN/m   95 % interval {lo / 1e3:.2f} .. {hi / 1e3:.2f} kN/m"
                 f"   R2 {self.r2:.4f}",
                 "  local slope dF/dD:  deformation/mm  force/kN  slope/(kN/m)  points"]
        for x, y, s, n in zip(self.local_deformation_m, self.local_force_N, self.local_slope_N_per_m,
                              self.local_points):
            lines.append(f"{x * 1e3:36.3f}{y / 1e3:10.3f}{s / 1e3:14.2f}{n:8d}")
        lines.append(f"  the local slope varies by {self.local_slope_range:.1%} of k_static over the loading branch")
        return "\n".join(lines)


def read_compression(path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Deformation (m), force (N) and file line of every row of a compression-test CSV.

    Parameters
    ----------
    path : str or path-like
        The CSV (see the module docstring for its columns).

    Returns
    -------
    deformation_m, force_N, line_numbers : ndarray

    Raises
    ------
    InputError
        A missing or unreadable file, missing or ambiguous columns, a short row, a
        non-numeric or non-finite cell.
    """
    from .._inputs import parse_number, read_input_text

    path = Path(path)
    text = read_input_text(path, encoding="utf-8-sig")
    numbered = [(i + 1, ln) for i, ln in enumerate(text.splitlines())
                if ln.strip() and not ln.lstrip().startswith("#")]
    if not numbered:
        raise InputError(path, "empty file (expected a header 'deformation_m,force_N')")
    head = numbered[0][1]
    sep = max(",;\t", key=head.count) if any(c in head for c in ",;\t") else ","
    header = [h.strip() for h in head.split(sep)]
    lower = [h.lower() for h in header]

    def column(choices: dict, what: str) -> tuple[int, float]:
        found = [(lower.index(name), scale) for name, scale in choices.items() if name in lower]
        names = " or ".join(n.replace("_n", "_N").replace("_kn", "_kN") for n in choices)
        if not found:
            raise InputError(path, f"no {what} column (expected {names}; found {', '.join(header)})")
        if len(found) > 1 or any(lower.count(name) > 1 for name in choices):
            raise InputError(path, f"more than one {what} column ({names}): give one")
        return found[0]

    i_d, s_d = column(_DEFORMATION, "deformation")
    i_f, s_f = column(_FORCE, "force")
    rows = numbered[1:]
    deformation = np.empty(len(rows))
    force = np.empty(len(rows))
    for r, (lineno, line) in enumerate(rows):
        cells = line.split(sep)
        if len(cells) != len(header):
            raise InputError(path, f"line {lineno}: expected {len(header)} cells, found {len(cells)}")
        for out, i, scale, bound in ((deformation, i_d, s_d, _BOUND_M), (force, i_f, s_f, _BOUND_N)):
            try:
                value = parse_number(cells[i])
            except ValueError:
                raise InputError(path, f"line {lineno}, column {header[i]}: {cells[i].strip()!r} is not a number") \
                    from None
            if not math.isfinite(value):
                raise InputError(path, f"line {lineno}, column {header[i]}: non-finite value {cells[i].strip()}")
            if abs(value * scale) > bound:      # (its square would overflow the fit)
                raise InputError(path, f"line {lineno}, column {header[i]}: {cells[i].strip()} is beyond any "
                                       f"compression test (|deformation| <= {_BOUND_M:g} m, |force| <= {_BOUND_N:g} N)")
            out[r] = value
    return deformation * s_d, force * s_f, np.array([n for n, _ in rows], dtype=int)


def _loading_branch(deformation: np.ndarray) -> tuple[int, int] | None:
    """Rows ``first:stop`` of the first loading branch (see the module docstring), or None."""
    tol = UNLOADING_TOLERANCE * float(deformation.max() - deformation.min())
    start = 0
    while start < deformation.size:
        d = deformation[start:]
        falls = np.flatnonzero(d < np.maximum.accumulate(d) - tol)
        end = int(falls[0]) if falls.size else d.size
        top = int(np.argmax(d[:end]))
        first = int(np.argmin(d[:top + 1]))
        if top + 1 - first >= MIN_POINTS and d[top] - d[first] > tol:
            return start + first, start + top + 1
        start += end
    return None


def _line_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Slope, intercept, standard error of the slope and residual sum of squares of y = a x + b."""
    xm, ym = x.mean(), y.mean()
    sxx = float(np.sum((x - xm) ** 2))
    slope = float(np.sum((x - xm) * (y - ym)) / sxx)
    intercept = float(ym - slope * xm)
    ssr = float(np.sum((y - slope * x - intercept) ** 2))
    se = math.sqrt(ssr / (x.size - 2) / sxx) if x.size > 2 else math.nan
    return slope, intercept, se, ssr


def static_stiffness(deformation_m, force_N, *, source: str = "compression test", segments: int = DEFAULT_SEGMENTS,
                     line_numbers=None) -> StaticStiffness:
    """The static stiffness k = dF/dD of a compression test (eq. 18).

    Parameters
    ----------
    deformation_m, force_N : array_like
        Rows of the test in the order measured, m and N.
    source : str, optional
        Name used in errors and in the result.
    segments : int, optional
        Intervals of the loading branch with a local slope each (default
        :data:`DEFAULT_SEGMENTS`; fewer when the branch has fewer than 3 points per interval).
    line_numbers : array_like of int, optional
        File line of each row (for the report).

    Returns
    -------
    StaticStiffness

    Raises
    ------
    InputError
        Fewer than :data:`MIN_POINTS` rows or loading points, non-finite values, a deformation
        that does not increase on the loading branch, a stiffness that is not positive.
    """
    d = np.asarray(deformation_m, dtype=float)
    f = np.asarray(force_N, dtype=float)
    if d.ndim != 1 or d.shape != f.shape:
        raise InputError(source, "deformation and force must be two 1-D arrays of the same length")
    if d.size < MIN_POINTS:
        raise InputError(source, f"{d.size} rows: at least {MIN_POINTS} are needed")
    if not (np.all(np.isfinite(d)) and np.all(np.isfinite(f))):
        raise InputError(source, "deformation and force must be finite numbers")
    if isinstance(segments, bool) or not isinstance(segments, (int, np.integer)) or segments < 1:
        raise InputError("segments", f"must be an integer >= 1, got {segments!r}")
    lines = np.zeros(d.size, dtype=int) if line_numbers is None else np.asarray(line_numbers, dtype=int)
    if np.ptp(d) == 0:
        raise InputError(source, "the deformation does not vary: no loading branch")
    branch = _loading_branch(d)
    if branch is None:
        raise InputError(source, f"the deformation does not increase over {MIN_POINTS} points or more on any "
                                 "loading branch")
    first, stop = branch
    x, y = d[first:stop], f[first:stop]
    if not np.ptp(x) > _RESOLUTION_M:     # (a range of 1e-290 m: its squares underflow to 0)
        raise InputError(source, f"the deformation rises by {np.ptp(x):.3g} m on the loading branch: less than "
                                 f"{_RESOLUTION_M:g} m, no compression test")
    k, intercept, se, ssr = _line_fit(x, y)
    if not k > 0:
        raise InputError(source, f"the force does not increase with the deformation on the loading branch "
                                 f"(slope {k:.6g} N/m): no positive stiffness")
    from scipy.special import stdtrit

    q = float(stdtrit(x.size - 2, 0.975))
    sst = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - ssr / sst
    order = np.argsort(x, kind="stable")
    parts = np.array_split(order, max(1, min(segments, x.size // MIN_POINTS)))
    parts = [p for p in parts if np.ptp(x[p]) > 0] or [order]
    local = np.array([(x[p].mean(), y[p].mean(), *_line_fit(x[p], y[p])[::2], p.size) for p in parts])
    return StaticStiffness(source=str(source), k_N_per_m=k, k_ci95_N_per_m=(k - q * se, k + q * se),
                           k_se_N_per_m=se, intercept_N=intercept, r2=r2,
                           residual_std_N=math.sqrt(ssr / (x.size - 2)), deformation_m=d, force_N=f,
                           line_numbers=lines, first=first, stop=stop,
                           local_deformation_m=local[:, 0], local_force_N=local[:, 1],
                           local_slope_N_per_m=local[:, 2], local_se_N_per_m=local[:, 3],
                           local_points=local[:, 4].astype(int))


def static_stiffness_file(path, *, segments: int = DEFAULT_SEGMENTS) -> StaticStiffness:
    """:func:`static_stiffness` of a compression-test CSV (see :func:`read_compression`)."""
    d, f, lines = read_compression(path)
    return static_stiffness(d, f, source=str(path), segments=segments, line_numbers=lines)
