"""A tire map: each tire's k and c as smooth functions of speed, from runs at several speeds.

The inputs are plain numbers per run and tire: the speed, the run's k and c with their 95 % intervals (a
report's recommended values), the static wheel load and, where the sidecar declares it, the inflation
pressure.  Per tire and quantity (k, c separately):

* **fit** - weighted least squares of a polynomial in speed (m/s) on the runs' values, each weighted by
  1 / sigma_i^2 with sigma_i = (high - low) / (2 x 1.96) of its interval;
* **degree** - linear by default (a constant when the runs cover two distinct speeds: a fit never has
  more terms than distinct speeds - 1, so that at least one degree of freedom judges it); the next power
  is added, up to a quadratic, while the rule allows one more term, the runs' intervals reject the lower
  degree (its weighted residual sum above the chi-square 95 % quantile of its degrees of freedom) and an
  F-test at 5 % on the weighted residual sums (residual variance from the larger model) finds the new
  term significant;
* **between-run scatter** - when the residuals exceed the intervals (weighted residual sum above its
  degrees of freedom) a between-run variance tau^2 is added to every run's sigma_i^2 and the fit repeated,
  tau^2 chosen so that the weighted residual sum equals its degrees of freedom (Paule-Mandel);
* **band** - the 95 % prediction band 1.96 sqrt(x(v) C x(v)' + tau^2), C the fit's covariance
  (X' W X)^-1 with those weights: where a new run at speed v is expected.

The map is evaluated from nodes: the fitted curve at a grid over the tested speed range and at the tested
speeds, interpolated linearly between them and held at the first or last node outside (``numpy.interp``),
as the map FMU does.  The tested range is the runs' lowest to highest speed; a value outside it is an
extrapolation and is flagged.  Wheel loads and inflation pressures are stated (their tested ranges), not
fitted: the runs of one tire must share one inflation pressure (within 5 %).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["FORMAT", "Z95", "MAX_DEGREE", "CurveFit", "fit_curve", "fit_map", "read_map", "map_values",
           "check_map", "map_set"]

FORMAT = "cleatfmu-tire-map/1"
#: Two-sided 95 % quantile of the normal distribution.
Z95 = 1.959963984540054
#: Highest power of speed a map fits (a quadratic).
MAX_DEGREE = 2
#: Significance level of the tests that admit the next power.
TEST_LEVEL = 0.05
#: Grid nodes over the tested range (the tested speeds are nodes too).
GRID_NODES = 9
#: Runs of one tire whose inflation pressures differ by more than this fraction are not mapped together.
PRESSURE_TOLERANCE = 0.05
RULE = ("weighted least squares in speed (m/s), weights 1/sigma^2 from each run's 95 % interval; linear "
        "(a constant with two distinct speeds), never more terms than distinct speeds - 1; the next power up "
        "to a quadratic when the intervals reject the lower degree (chi-square test at 5 %) and an F-test at "
        "5 % finds the new term significant; a between-run variance tau^2 added when "
        "the residuals exceed the intervals (Paule-Mandel); 95 % prediction band 1.96 sqrt(x C x' + tau^2)")


@dataclass(frozen=True)
class CurveFit:
    """A polynomial in speed fitted to runs, with its covariance and between-run scatter.

    Attributes
    ----------
    coefficients : ndarray
        Ascending powers of speed (m/s): value = sum_j b_j v^j.
    covariance : ndarray
        Covariance of the coefficients.
    scatter : float
        Between-run standard deviation tau (0: the runs' intervals explain the residuals), in the value's unit.
    chi2 : float
        Weighted residual sum with the runs' own intervals.
    dof : int
        Runs minus coefficients.
    residuals : ndarray
        Run value minus fit, per run.
    """

    coefficients: np.ndarray
    covariance: np.ndarray
    scatter: float
    chi2: float
    dof: int
    residuals: np.ndarray

    @property
    def degree(self) -> int:
        return len(self.coefficients) - 1

    def value(self, speed_m_s) -> np.ndarray:
        """The fitted value at `speed_m_s`."""
        return _design(np.asarray(speed_m_s, dtype=float), self.degree) @ self.coefficients

    def band(self, speed_m_s) -> np.ndarray:
        """Half width of the 95 % prediction band at `speed_m_s`."""
        x = _design(np.asarray(speed_m_s, dtype=float), self.degree)
        return Z95 * np.sqrt(np.einsum("...i,ij,...j->...", x, self.covariance, x) + self.scatter ** 2)


def _design(v: np.ndarray, degree: int) -> np.ndarray:
    return np.stack([v ** j for j in range(degree + 1)], axis=-1)


def _wls(v, y, var, degree):
    """Coefficients, covariance and residuals of the weighted fit with variances `var`."""
    x = _design(v, degree)
    w = 1.0 / var
    normal = x.T @ (x * w[:, None])
    cov = np.linalg.inv(normal)
    beta = cov @ (x.T @ (w * y))
    return beta, cov, y - x @ beta


def _scatter(v, y, var, degree, dof) -> float:
    """tau^2 >= 0 with sum r^2 / (var + tau^2) = dof after refitting with those weights (0 if already below)."""
    def excess(tau2):
        _, _, r = _wls(v, y, var + tau2, degree)
        return float(np.sum(r * r / (var + tau2))) - dof

    if dof < 1 or excess(0.0) <= 0.0:
        return 0.0
    high = float(np.max(var)) + float(np.var(y)) + 1e-300
    while excess(high) > 0.0:
        high *= 4.0
    low = 0.0
    for _ in range(200):
        mid = 0.5 * (low + high)
        if excess(mid) > 0.0:
            low = mid
        else:
            high = mid
        if high - low <= 1e-12 * high:
            break
    return high


def fit_curve(speed_m_s, value, low, high) -> CurveFit:
    """Fit one quantity of one tire over speed (see the module's rule).

    Parameters
    ----------
    speed_m_s, value, low, high : array_like
        Per run: speed (m/s), value and its 95 % interval.

    Raises
    ------
    ValueError
        Fewer than two distinct speeds, or values and intervals that are not finite with low <= value <= high.
    """
    from scipy.stats import chi2 as chi2_dist, f as f_dist

    v, y = np.asarray(speed_m_s, dtype=float), np.asarray(value, dtype=float)
    lo, hi = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    if not all(np.all(np.isfinite(a)) for a in (v, y, lo, hi)) or np.any(lo > hi):
        raise ValueError("every run needs a finite value and interval low <= high")
    distinct = np.unique(v).size
    if distinct < 2:
        raise ValueError(f"a map needs runs at two distinct speeds at least (got {distinct})")
    sigma = (hi - lo) / (2.0 * Z95)
    var = np.maximum(sigma, 1e-9 * np.maximum(np.abs(y), 1e-300)) ** 2
    max_terms = min(distinct - 1, MAX_DEGREE + 1)
    degree = min(1, max_terms - 1)
    while degree + 2 <= max_terms:
        _, _, r_lo = _wls(v, y, var, degree)
        _, _, r_hi = _wls(v, y, var, degree + 1)
        s_lo, s_hi, dof_hi = float(np.sum(r_lo ** 2 / var)), float(np.sum(r_hi ** 2 / var)), v.size - degree - 2
        if s_lo <= chi2_dist.ppf(1 - TEST_LEVEL, dof_hi + 1):
            break       # the runs' own intervals accept the lower degree
        if dof_hi < 1 or s_hi <= 0.0 or (s_lo - s_hi) / (s_hi / dof_hi) <= f_dist.ppf(1 - TEST_LEVEL, 1, dof_hi):
            break       # the next power is not significant
        degree += 1
    dof = v.size - degree - 1
    tau2 = _scatter(v, y, var, degree, dof)
    beta, cov, r = _wls(v, y, var + tau2, degree)
    return CurveFit(coefficients=beta, covariance=cov, scatter=math.sqrt(tau2), chi2=float(np.sum(r * r / var)),
                    dof=dof, residuals=r)


def _nodes(speeds: np.ndarray) -> np.ndarray:
    grid = np.linspace(speeds.min(), speeds.max(), GRID_NODES)
    nodes = np.unique(np.concatenate([grid, np.unique(speeds)]))
    keep = np.concatenate([[True], np.diff(nodes) > 1e-9 * nodes[-1]])
    return nodes[keep]


def _tire_map(tire: str, runs: list, source) -> dict:
    speeds = np.array([r["speed_m_s"] for r in runs], dtype=float)
    pressures = [r.get("inflation_pressure_Pa") for r in runs]
    known = [p for p in pressures if p is not None]
    if known and (len(known) < len(runs) or max(known) > (1 + PRESSURE_TOLERANCE) * min(known)):
        shown = ", ".join("?" if p is None else f"{p / 1e3:g}" for p in pressures)
        raise InputError(source, f"tire {tire}: the runs are at different inflation pressures ({shown} kPa): map "
                                 f"one pressure at a time (--pressure-kpa)")
    loads = [r["wheel_load_N"] for r in runs]
    out = {"runs": runs, "tested_speed_m_s": [float(speeds.min()), float(speeds.max())],
           "wheel_load_N": [float(min(loads)), float(max(loads))],
           "inflation_pressure_Pa": [float(min(known)), float(max(known))] if known else None}
    nodes = _nodes(speeds)
    out["nodes"] = {"speed_m_s": nodes.tolist()}
    for q, unit in (("k", "N/m"), ("c", "N.s/m")):
        fit = fit_curve(speeds, [r[q] for r in runs], [r[f"{q}_ci"][0] for r in runs],
                        [r[f"{q}_ci"][1] for r in runs])
        out[q] = {"unit": unit, "degree": fit.degree, "coefficients": fit.coefficients.tolist(),
                  "covariance": fit.covariance.tolist(), "scatter": fit.scatter, "chi2": fit.chi2, "dof": fit.dof,
                  "residuals": fit.residuals.tolist()}
        out["nodes"][q] = fit.value(nodes).tolist()
        out["nodes"][f"{q}_band"] = fit.band(nodes).tolist()
        lowest = min(out["nodes"][q])
        if lowest < 0.0 or (q == "k" and lowest == 0.0):
            raise InputError(source, f"tire {tire}: the fitted {q} is {'negative' if lowest < 0 else 'zero'} "
                                     f"within the tested speeds ({lowest:g} {unit}): no map")
    return out


def fit_map(runs, *, source=None, values: str = "") -> dict:
    """The tire map document (``cleatfmu-tire-map/1``, SI units) of `runs`.

    Parameters
    ----------
    runs : iterable of dict
        One per run and tire: ``recording``, ``tire``, ``speed_m_s``, ``k``, ``k_ci`` (low, high), ``c``,
        ``c_ci``, ``wheel_load_N`` and ``inflation_pressure_Pa`` (None where not declared).
    source : str, optional
        Where the runs come from, for messages and the document.
    values : str
        Which values the runs carry (stated in the document).

    Returns
    -------
    dict
        ``tires``: per tire the runs, the tested speed range (m/s), the wheel loads' and inflation
        pressures' ranges, per quantity (k, c) the fit (degree, coefficients in ascending powers of speed,
        covariance, scatter, chi2, dof, residuals) and the ``nodes`` (speed, k, c and their 95 % band half
        widths) the map is evaluated from; ``skipped``: the tires with runs at fewer than two speeds.

    Raises
    ------
    InputError
        No tire has runs at two distinct speeds, or a tire's runs differ in inflation pressure.
    """
    by_tire: dict = {}
    for r in runs:
        by_tire.setdefault(r["tire"], []).append(dict(r))
    tires, skipped = {}, {}
    for tire in sorted(by_tire):
        runs_t = sorted(by_tire[tire], key=lambda r: r["speed_m_s"])
        distinct = len({r["speed_m_s"] for r in runs_t})
        if distinct < 2:
            skipped[tire] = f"runs at {distinct} speed(s): a map needs two distinct speeds at least"
            continue
        tires[tire] = _tire_map(tire, runs_t, source)
    if not tires:
        raise InputError(source, "no tire has runs at two distinct speeds or more: nothing to map"
                         + (f" ({'; '.join(f'{t}: {m}' for t, m in skipped.items())})" if skipped else ""))
    return {"format": FORMAT, "source": source, "values": values, "rule": RULE, "level": 0.95,
            "outside": "k and c are held at the first or last node: an extrapolation, flagged",
            "tires": tires, "skipped": skipped}


def map_values(tire_map: dict, speed_m_s: float) -> dict:
    """k, c and their 95 % band half widths of one tire's map at `speed_m_s` (nodes interpolated linearly,
    held outside), and whether that is an extrapolation (outside the tested speeds)."""
    nodes = tire_map["nodes"]
    low, high = tire_map["tested_speed_m_s"]
    out = {q: float(np.interp(speed_m_s, nodes["speed_m_s"], nodes[q])) for q in ("k", "c", "k_band", "c_band")}
    return {**out, "speed_m_s": float(speed_m_s), "extrapolation": not low <= speed_m_s <= high}


def check_map(doc, source) -> dict:
    """`doc` checked as a tire map document (InputError naming `source` otherwise); returns it."""
    def bad(problem):
        raise InputError(source, f"not a cleatfmu tire map ({FORMAT}): {problem}")

    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        bad(f"format must be {FORMAT!r}")
    tires = doc.get("tires")
    if not isinstance(tires, dict) or not tires:
        bad("no tires")
    for tire, m in tires.items():
        try:
            nodes = m["nodes"]
            v, k, c = (np.asarray(nodes[q], dtype=float) for q in ("speed_m_s", "k", "c"))
            kb, cb = (np.asarray(nodes[q], dtype=float) for q in ("k_band", "c_band"))
            low, high = (float(x) for x in m["tested_speed_m_s"])
        except (KeyError, TypeError, ValueError):
            bad(f"tire {tire}: nodes (speed_m_s, k, c, k_band, c_band) and tested_speed_m_s needed")
        if v.ndim != 1 or v.size < 1 or any(a.shape != v.shape for a in (k, c, kb, cb)):
            bad(f"tire {tire}: one k, c and band per node speed needed")
        if not all(np.all(np.isfinite(a)) for a in (v, k, c, kb, cb)) or not math.isfinite(low + high):
            bad(f"tire {tire}: every number must be finite")
        if np.any(np.diff(v) <= 0) or np.any(k <= 0) or np.any(c < 0) or not low <= high:
            bad(f"tire {tire}: node speeds must increase, k > 0, c >= 0, tested range low <= high")
    return doc


def read_map(path) -> dict:
    """Read and check a tire map file (``cleatfmu map`` output)."""
    from .._inputs import read_json_file

    return check_map(read_json_file(path), path)


def map_set(path, speed_m_s: float | None, tires) -> tuple:
    """k and c of `tires` from the map file `path` at `speed_m_s` (None: only check that the map has them).

    Returns
    -------
    (dict, dict, dict)
        k per tire (N/m), c per tire (N s/m), and per tire :func:`map_values` (bands, extrapolation).
    """
    doc = read_map(path)
    missing = [t for t in tires if t not in doc["tires"]]
    if missing:
        raise InputError(path, f"the map has no tire {', '.join(missing)} (it maps {', '.join(doc['tires'])})")
    if speed_m_s is None:
        return {}, {}, {}
    values = {t: map_values(doc["tires"][t], speed_m_s) for t in tires}
    return {t: v["k"] for t, v in values.items()}, {t: v["c"] for t, v in values.items()}, values
