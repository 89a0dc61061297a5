"""Output-error fit of a whole-tractor model to all channels at once, with honest intervals.

The residual stacks every channel's low-passed prediction minus its low-passed
measurement over the diagnosis window, each divided by that channel's noise
RMS.  ``scipy.optimize.least_squares`` (Levenberg-Marquardt, positive
parameters on a log scale) minimises it.  95 % intervals: the sandwich
covariance of the estimates under serially correlated residuals (the
low-passed noise is correlated over several samples, a misfit over many
periods; each channel's autocovariance, Parzen-tapered, up to the lag where
the residual's autocorrelation has died out), Student's t; a positive parameter's
interval is built on its logarithm.  The final fits also check the grid step
(``step_check``): the estimates move to the half step's, and the move widens
the interval; and they check the model in the impacts against the free decay
(:func:`impact_weight_shift`): the estimates' move when the impacts weigh a
tenth widens the interval too, so a model wrong in the impact (a cleat edge,
a footprint, a sensor chain it does not know) does not leave an interval that
only white noise would justify.

The intervals hold *if the model is right*.  :func:`unexplained` measures what
the model leaves: the residual energy beyond the noise floor, its share of the
signal, and the window where it sits.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from ..identify.waveform import long_run_variance_ratio
from ..recording.condition import line_fit, refine_line
from .joint_jacobian import FAILED, GroupedJacobian, channel_dependence
from ..model.fitting import LOCAL_RATIO, SIGNED, UNEXPLAINED_RATIO, TractorFitModel, residual_test


def _exp(x: float) -> float:
    """exp without overflow (a log-parameter far out of range maps to a huge, finite value)."""
    return math.exp(min(float(x), 700.0))


__all__ = ["TractorFit", "fit_tractor", "sse_of", "unexplained", "sandwich_covariance", "correlation_lag",
           "residual_correlation_lag",
           "UNEXPLAINED_RATIO"]

#: Largest half-step move (log scale for positive parameters) applied to the estimates.
MAX_STEP_SHIFT = 0.02
#: The impact-weight check: the impacts (onset - lead until the tire has rolled over the cleat and this
#: footprint) weigh this much of the free decay (:func:`impact_weight_shift`).
IMPACT_WEIGHT = 0.1
IMPACT_LEAD_S = 0.02
IMPACT_FOOTPRINT_M = 0.45
_DIFF_STEP = {"arrival": 2e-5, "stagger": 2e-5, "lug_phase": 1e-3, "lug_amplitude": 1e-3}


@dataclass(frozen=True, eq=False)
class TractorFit:
    """A fitted whole-tractor model."""

    model: TractorFitModel
    params: dict
    ci: dict                   # name -> (low, high), 95 %
    sse: dict                  # channel -> Σ residual², (m/s²)², over the window
    nrmse: dict                # channel -> RMS(pred − meas) / RMS(meas)
    prediction: dict           # channel -> low-passed prediction (whole record)
    evaluations: int
    seconds: float
    extra: dict = field(default_factory=dict)

    @property
    def label(self) -> str:
        return self.model.label

    @property
    def in_bounds(self) -> bool:
        return bool(self.extra.get("in_bounds", True))

    def weighted_sse(self) -> float:
        """Σ over channels of SSE / noise²: the fit's objective."""
        pb = self.model.problem
        return float(sum(self.sse[c] / pb.noise[c] ** 2 for c in pb.channels))


def correlation_lag(sample_rate_hz: float, cutoff_hz: float) -> int:
    """Lags (samples) over which the low-passed noise is correlated: four periods of the cut-off."""
    return max(10, int(math.ceil(4.0 * sample_rate_hz / cutoff_hz)))


def _autocovariance(r: np.ndarray) -> np.ndarray:
    """Biased autocovariance of `r` about its mean at lags 0 .. len(r) - 1 (by FFT, zero-padded)."""
    r = r - r.mean()
    nfft = 1 << int(math.ceil(math.log2(2 * r.size)))
    fr = np.fft.rfft(r, nfft)
    return np.fft.irfft(fr * np.conj(fr), nfft)[: r.size] / r.size


def residual_correlation_lag(residual: np.ndarray, sizes, floor: int, *, level: float = 0.1,
                             max_share: float = 0.25) -> int:
    """The lag (samples) beyond which every block's residual autocorrelation stays under `level`.

    A residual that is the low-passed noise decorrelates within a few periods of the cut-off (`floor`);
    one that holds what the model gets wrong (a misfit ringing at the tire's mode) stays correlated over
    many periods.  The sandwich covariance must span that correlation to hold the misfit's effect on the
    estimates: the lag is the largest over the blocks, at least `floor`, at most `max_share` of a block.
    """
    lag_out = floor
    row = 0
    for size in sizes:
        r = residual[row:row + size]
        row += size
        if size < 8:
            continue
        acov = _autocovariance(r)
        if acov[0] <= 0:
            continue
        above = np.flatnonzero(np.abs(acov[: max(2, int(max_share * size))] / acov[0]) > level)
        if above.size:
            lag_out = max(lag_out, int(above[-1]) + 1)
    return lag_out


def sandwich_covariance(jac: np.ndarray, residual: np.ndarray, sizes, max_lag: int) -> np.ndarray:
    """Covariance of least-squares estimates under serially correlated residuals (a HAC sandwich).

    ``A⁻¹ M A⁻¹`` with ``A = JᵀJ`` and ``M = Σ_blocks Σ_h γ(h) Σ_i J_iᵀ J_{i+h}``:
    each block of rows (a channel) has its own residual autocovariance γ,
    estimated up to `max_lag` and tapered by a Parzen window (which keeps M
    positive semi-definite).  ``M`` is computed in the frequency domain.  For
    white residuals it reduces to ``s² A⁻¹``.

    Parameters
    ----------
    jac : ndarray, shape (n, p)
        Jacobian of the stacked residual.
    residual : ndarray, shape (n,)
        Stacked residual at the solution.
    sizes : sequence of int
        Rows per block, in order; they sum to n.
    max_lag : int
        Truncation lag of the autocovariance, samples.
    """
    p = jac.shape[1]
    meat = np.zeros((p, p))
    row = 0
    for size in sizes:
        J, r = jac[row:row + size], residual[row:row + size]
        row += size
        if size == 0:
            continue
        lag = min(max_lag, size - 1)
        nfft = 1 << int(math.ceil(math.log2(2 * size)))
        acov = _autocovariance(r)[: lag + 1]
        u = np.arange(lag + 1) / (lag + 1)
        parzen = np.where(u <= 0.5, 1 - 6 * u ** 2 + 6 * u ** 3, 2 * (1 - u) ** 3)
        kernel = np.zeros(nfft)
        kernel[: lag + 1] = acov * parzen
        kernel[nfft - lag:] = (acov * parzen)[1:][::-1]
        spectrum = np.fft.rfft(kernel).real           # the tapered autocovariance's spectrum
        fj = np.fft.rfft(J, nfft, axis=0)
        weights = np.full(fj.shape[0], 2.0)
        weights[0] = 1.0
        if nfft % 2 == 0:
            weights[-1] = 1.0
        meat += ((fj.conj() * (weights * spectrum)[:, None]).T @ fj).real / nfft
    bread = np.linalg.pinv(jac.T @ jac)
    return bread @ meat @ bread


def impact_spans(problem) -> list:
    """[start, end] (s) of every impact: from its onset less :data:`IMPACT_LEAD_S` until the tire has rolled
    over the cleat and a generous footprint, (cleat width + :data:`IMPACT_FOOTPRINT_M`) / speed."""
    rec = problem.rec
    length = (rec.cleat_width_m + IMPACT_FOOTPRINT_M) / rec.speed_m_s
    return [(float(t) - IMPACT_LEAD_S, float(t) + length) for t in problem.onsets.values()]


def impact_weight_shift(model: TractorFitModel, jac: np.ndarray, fun: np.ndarray) -> np.ndarray:
    """How far the estimates move when the impacts weigh :data:`IMPACT_WEIGHT` of the rest (first order).

    The free decay after an impact needs little of the model (the tire on flat ground); the impact needs
    all of it (the cleat's shape, the footprint, the sensor chain).  A model that is right fits both
    alike, and the move is at the noise's scale; one that is wrong in the impact pulls the estimates
    there, and the move measures that pull.  One Gauss-Newton step from the solution of the evenly
    weighted fit on the re-weighted residual (the Jacobian at hand: no model run).  The move is added
    to each interval in quadrature, so the interval holds both weightings' estimates.
    """
    pb = model.problem
    t = pb.rec.time_s[pb.window]
    weight = np.ones(t.size)
    for a, b in impact_spans(pb):
        weight[(t >= a) & (t <= b)] = IMPACT_WEIGHT
    weight = np.tile(weight, len(pb.channels))
    if weight.size != fun.size or not np.all(np.isfinite(jac)):
        return np.zeros(jac.shape[1])
    step = -np.linalg.lstsq(jac * weight[:, None], fun * weight, rcond=None)[0]
    return np.where(np.isfinite(step), step, 0.0)


def _residual_parts(model: TractorFitModel, pred: dict):
    pb = model.problem
    w = pb.window
    return {c: (pred[c] - pb.measured[c])[w] for c in pb.channels}


def sse_of(model: TractorFitModel, theta: dict, step_s: float | None = None) -> float:
    """Noise-weighted residual energy Σ SSE_c / σ_c² for parameters `theta`."""
    pb = model.problem
    parts = _residual_parts(model, model.predict(theta, step_s=step_s))
    return float(sum(float(r @ r) / pb.noise[c] ** 2 for c, r in parts.items()))


def fit_tractor(model: TractorFitModel, start: dict, *, fixed: dict | None = None, budget: int = 300,
                step_s: float | None = None, step_check: bool = False) -> TractorFit:
    """Fit `model` from `start` (every parameter named); `fixed` parameters are held.

    With `step_check` the model is also run at half the step at the solution:
    the estimates move by the resulting first-order shift (the fit at the
    finer step) and each interval's half-width grows by that shift in
    quadrature, so the grid's own error is inside the interval.  The
    prediction, residuals and NRMSE are those of the moved estimates at the
    fitted step (what their FMUs give).
    """
    t0 = time.perf_counter()
    pb = model.problem
    fixed = dict(fixed or {})
    free = [n for n in model.names if n not in fixed]
    logs = [n.rsplit("_", 1)[0] not in SIGNED and n not in SIGNED for n in free]
    lo, hi = model.bounds(start)
    x0 = np.array([math.log(min(max(start[n], lo[n], 1e-12), hi[n])) if lg else float(start[n])
                   for n, lg in zip(free, logs)])
    w = pb.window
    scale = np.concatenate([np.full(int(w.sum()), pb.noise[c]) for c in pb.channels])
    meas = np.concatenate([pb.measured[c][w] for c in pb.channels])
    count = [0]

    def theta_of(x):
        return {**fixed, **{n: (_exp(v) if lg else float(v)) for n, v, lg in zip(free, x, logs)}}

    def residual(x):
        count[0] += 1
        try:
            pred = model.predict(theta_of(x), step_s=step_s)
        except (ValueError, OverflowError, ZeroDivisionError, FloatingPointError, np.linalg.LinAlgError):
            return np.full(meas.size, FAILED)
        r = (np.concatenate([pred[c][w] for c in pb.channels]) - meas) / scale
        return np.where(np.isfinite(r), r, FAILED)

    diff = np.array([1e-4 if lg else _DIFF_STEP.get(n.rsplit("_", 1)[0] if n not in _DIFF_STEP else n, 1e-4)
                     for n, lg in zip(free, logs)])
    dependence = channel_dependence(model, free) if free else None
    grouped = GroupedJacobian(residual, diff, dependence, int(w.sum())) if dependence is not None else None
    if free:
        # independent tires: their columns differenced together, the same Jacobian from fewer runs
        how = dict(fun=grouped.value, jac=grouped) if grouped and len(grouped.groups) < len(free) else \
            dict(fun=residual, diff_step=diff)
        sol = optimize.least_squares(x0=x0, method="lm", max_nfev=max(3, budget // (len(free) + 1)), **how)
        x, jac, fun = sol.x, sol.jac, sol.fun
    else:
        x, jac, fun = x0, np.zeros((meas.size, 0)), residual(x0)
    params = theta_of(x)
    failed = False
    try:
        pred = model.predict(params, step_s=step_s)
    except (ValueError, OverflowError, ZeroDivisionError, FloatingPointError, np.linalg.LinAlgError):
        x, params = x0, theta_of(x0)       # the solver left the model's domain: report the start, out of bounds
        fun = residual(x0)
        pred = model.predict(params, step_s=step_s)
        failed = True
    parts = _residual_parts(model, pred)
    shift = np.zeros(len(free))
    if step_check and free and not failed:
        # the estimates' move when the step is halved, to first order: one Gauss-Newton step on the change
        fine = model.predict(params, step_s=(step_s or model.default_step_s()) / 2)
        change = np.concatenate([(fine[c] - pred[c])[w] for c in pb.channels]) / scale
        shift = -np.linalg.lstsq(jac, change, rcond=None)[0]
    weight_shift = np.zeros(len(free))
    if step_check and free and not failed:
        weight_shift = impact_weight_shift(model, jac, fun)
    dof = max(1, fun.size - len(free))
    infl = float(np.mean([long_run_variance_ratio(parts[c]) for c in pb.channels]))
    sizes = [int(w.sum())] * len(pb.channels)
    noise_lag = correlation_lag(pb.rec.sample_rate_hz, pb.cutoff_hz)
    lag = residual_correlation_lag(fun, sizes, noise_lag)
    cov = sandwich_covariance(jac, fun, sizes, noise_lag) * (fun.size / dof)
    if lag > noise_lag and free:
        # the residual stays correlated beyond the noise's lags (a misfit): each variance is the larger of the
        # two lags' (a longer lag can also sum negative lobes), the correlations are the noise lag's
        var = np.diag(cov).copy()
        longer = np.diag(sandwich_covariance(jac, fun, sizes, lag)) * (fun.size / dof)
        with np.errstate(divide="ignore", invalid="ignore"):
            grow = np.where(var > 0, np.sqrt(np.maximum(longer, var) / var), 1.0)
        grow = np.where(np.isfinite(grow), grow, 1.0)
        cov = cov * np.outer(grow, grow)
    # a parameter the residual does not depend on (a damping collapsed to zero) is not known to be anything:
    # its interval is unbounded, not the zero width a pseudo-inverse gives it
    norms = np.sqrt(np.sum(jac ** 2, axis=0)) if free else np.zeros(0)
    blind = norms <= 1e-9 * (float(norms.max()) if norms.size else 0.0)
    cov[blind, :] = cov[:, blind] = 0.0
    cov[blind, blind] = math.inf
    q = float(stats.t.ppf(0.975, dof))
    moved = bool(np.any(shift != 0.0) and np.all(np.abs(shift) <= MAX_STEP_SHIFT))
    if moved:   # a larger move is no first-order correction: widen only
        x = x + shift
    params = theta_of(x)
    if moved:   # the prediction (and its residual) of the parameters reported, as their FMUs will give it
        pred = model.predict(params, step_s=step_s)
        parts = _residual_parts(model, pred)
    ci = {}
    for i, (name, lg) in enumerate(zip(free, logs)):
        half = q * math.sqrt(max(0.0, float(cov[i, i])) + float(shift[i]) ** 2 + float(weight_shift[i]) ** 2)
        ci[name] = (_exp(x[i] - half), _exp(x[i] + half)) if lg else (params[name] - half, params[name] + half)
    for name, value in fixed.items():
        ci[name] = (value, value)
    for name in [n for n in params if n.startswith("lug_phase")]:
        wrapped = math.pi - (math.pi - params[name]) % (2 * math.pi)
        turn = wrapped - params[name]
        params[name] = wrapped
        ci[name] = (ci[name][0] + turn, ci[name][1] + turn)
    in_bounds = not failed and all(lo[n] <= params[n] <= hi[n] for n in free)
    sse = {c: float(r @ r) for c, r in parts.items()}
    nrmse = {c: float(np.sqrt(np.mean(parts[c] ** 2)) / np.sqrt(np.mean(pb.measured[c][w] ** 2)))
             for c in pb.channels}
    return TractorFit(model=model, params=params, ci=ci, sse=sse, nrmse=nrmse, prediction=pred,
                      evaluations=count[0], seconds=time.perf_counter() - t0,
                      extra={"variance_inflation": infl, "in_bounds": in_bounds, "lag": lag, "weight_shift": weight_shift, "step_s": step_s or model.default_step_s(),
                             "free": free, "covariance": cov, "logs": logs, "step_shift": shift})


def unexplained(problem, prediction: dict, channel: str, *, ratio: float = UNEXPLAINED_RATIO):
    """What a model leaves unexplained in one channel, or None when its residual is at the noise floor: its RMS
    within `ratio` times the noise RMS over the window and within
    :data:`~identification.model.fitting.LOCAL_RATIO` times it over every stretch of
    :data:`~identification.model.fitting.LOCAL_SPAN_S` (:func:`~identification.model.fitting.residual_test`).

    Returns ``{"share", "window", "residual_to_noise", "worst_span_to_noise", "worst_span"}``: the residual
    energy beyond the noise as a share of the signal energy over the diagnosis window, the time span [s, s]
    holding the middle 80 % of that excess energy, the RMS over the noise RMS, and the same over the worst
    stretch with that stretch [s, s]; and ``"steady_line"`` where a steady line of the channel's quiet stretch makes up
    over :data:`LINE_SHARE` of the residual (:func:`residual_line`).
    """
    w = problem.window
    t = problem.rec.time_s[w]
    meas = problem.measured[channel][w]
    r = (prediction[channel] - problem.measured[channel])[w]
    sigma = problem.noise[channel]
    test = residual_test(r, sigma, problem.rec.sample_rate_hz, t)
    if test["residual_to_noise"] <= ratio and test["worst_span_to_noise"] <= LOCAL_RATIO:
        return None
    excess = np.clip(r ** 2 - sigma ** 2, 0.0, None)
    cum = np.cumsum(excess)
    total = float(cum[-1]) if cum.size else 0.0
    if total <= 0:
        return None
    a = int(np.searchsorted(cum, 0.1 * total))
    b = int(np.searchsorted(cum, 0.9 * total))
    share = (float(np.sum(r ** 2)) - sigma ** 2 * r.size) / float(np.sum(meas ** 2))
    out = {"share": float(max(share, 0.0)), "window": [float(t[a]), float(t[min(b, t.size - 1)])],
           "residual_to_noise": test["residual_to_noise"], "worst_span_to_noise": test["worst_span_to_noise"],
           "worst_span": test["worst_span_s"]}
    line = problem.steady_lines.get(channel)
    if line and line.get("frequency_hz"):
        found = residual_line(t, r, float(line["frequency_hz"]))
        if found["share_of_residual"] > LINE_SHARE:
            out["steady_line"] = found
    return out


#: A steady line is named in what a model leaves when it makes up over this share of the residual's energy.
LINE_SHARE = 0.25
#: Half-width of the search for a steady line's frequency in the residual around its quiet stretch's
#: periodogram peak, Hz (a stretch of a few tenths of a second resolves a few Hz).
LINE_SEARCH_HZ = 2.0


def residual_line(time_s, residual, frequency_hz: float) -> dict:
    """The steady line in a residual near `frequency_hz`: ``{"frequency_hz", "amplitude_m_s2",
    "share_of_residual"}``.

    The frequency of the largest least-squares sinusoid within :data:`LINE_SEARCH_HZ` of `frequency_hz`
    (at most half of it), as the conditioning finds an engine line's
    (:func:`identification.recording.condition.refine_line`); its amplitude, and its energy as a share of
    the residual's.
    """
    t = np.asarray(time_s, dtype=float)
    r = np.asarray(residual, dtype=float)[None, :]
    f = refine_line(t, r, frequency_hz, min(LINE_SEARCH_HZ, 0.5 * frequency_hz))
    coef, energy = line_fit(t, r, f)
    total = float(np.sum(r * r))
    return {"frequency_hz": f, "amplitude_m_s2": float(math.hypot(*coef[0, 0])),
            "share_of_residual": energy / total if total > 0 else 0.0}
