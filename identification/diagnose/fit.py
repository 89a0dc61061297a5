"""Output-error identification: fit a model's parameters to the measured hub acceleration.

The residual is the low-passed prediction minus the low-passed measurement
over the diagnosis window (the whole waveform, impact included), divided by
the measurement's noise RMS; for ``axle_coupling`` the other axle's channel is
appended.  ``scipy.optimize.least_squares`` (trust-region reflective, bounded
Levenberg-Marquardt on log-transformed positive parameters) minimises it
from starting values taken from the waveform identification and the previous
model.  95 % confidence intervals use the Jacobian at the solution,
s² (JᵀJ)⁻¹, inflated by the residuals' long-run variance ratio and scaled by
Student's t; for a positive parameter the interval is built on its logarithm
(so it stays positive and may be asymmetric).  A solution outside the model's
physical bounds is reported as such (:attr:`Fit.in_bounds`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from ..waveform import long_run_variance_ratio
from .models import Model

__all__ = ["Fit", "fit_model", "scan_arrival", "sse_at"]

#: Default relative step of the numerical Jacobian, per parameter.
_DIFF_STEP = {"arrival": 2e-5, "lug_phase": 1e-3}


@dataclass(frozen=True, eq=False)
class Fit:
    """A fitted model."""

    model: Model
    params: dict
    ci: dict                      # name -> (low, high), 95 %
    sse: float                    # Σ residual² of the tire's channel, (m/s²)²
    n: int                        # samples in the tire's window
    nrmse: float                  # RMS(pred − meas) / RMS(meas) over the tire's window
    prediction: np.ndarray        # low-passed predicted acceleration of the tire (whole record)
    other_prediction: np.ndarray | None
    evaluations: int
    seconds: float
    extra: dict = field(default_factory=dict)

    @property
    def label(self) -> str:
        return self.model.label

    @property
    def in_bounds(self) -> bool:
        """All fitted parameters inside the model's physical bounds."""
        return bool(self.extra.get("in_bounds", True))


def _nrmse(pred, meas, window) -> float:
    return float(np.sqrt(np.mean((pred - meas)[window] ** 2)) / np.sqrt(np.mean(meas[window] ** 2)))


def _exp(x: float) -> float:
    """exp without overflow (a log-parameter far out of range maps to a huge, finite value)."""
    return math.exp(min(float(x), 700.0))


#: Parameters that may take either sign (the others are fitted as logarithms).
_SIGNED = {"arrival", "lug_amplitude", "lug_phase"}


def fit_model(model: Model, start: dict, *, fixed: dict | None = None, budget: int = 200,
              step_s: float | None = None) -> Fit:
    """Fit `model` from `start` (name -> value for every parameter).

    Parameters
    ----------
    model : Model
    start : dict
        Starting values (missing names raise KeyError).
    fixed : dict, optional
        Parameters held at a value (not fitted).
    budget : int
        Model evaluations allowed, the finite-difference Jacobian's included
        (about budget / (parameters + 1) iterations).
    step_s : float, optional
        Step of the model (default: the problem's).
    """
    t0 = time.perf_counter()
    pb = model.problem
    fixed = dict(fixed or {})
    free = [n for n in model.names if n not in fixed]
    logs = [n not in _SIGNED for n in free]
    lo, hi = model.bounds(start)
    x0 = np.array([math.log(min(max(start[n], lo[n], 1e-12), hi[n])) if lg else start[n]
                   for n, lg in zip(free, logs)], dtype=float)
    window = pb.window
    meas = pb.measured[window]
    other_meas = pb.other_sig.filtered_m_s2[window] if "axle_coupling" in model.effects else None
    noise = pb.noise
    count = [0]

    def theta_of(x):
        return {**fixed, **{n: (_exp(v) if lg else float(v)) for n, v, lg in zip(free, x, logs)}}

    size = int(window.sum()) * (2 if other_meas is not None else 1)

    def residual(x):
        count[0] += 1
        try:
            pred, other = model.predict(theta_of(x), step_s=step_s)
        except (ValueError, OverflowError, ZeroDivisionError, FloatingPointError):
            return np.full(size, 1e6)   # a parameter set the model cannot run: far from any solution
        r = (pred[window] - meas) / noise
        if other is not None:
            r = np.concatenate([r, (other[window] - other_meas) / max(pb.other_sig.noise_m_s2, 1e-6)])
        return r

    diff = np.array([_DIFF_STEP.get(n, 1e-4) if not lg else 1e-4 for n, lg in zip(free, logs)])
    sol = optimize.least_squares(residual, x0, method="lm", diff_step=diff,
                                 max_nfev=max(3, budget // (len(free) + 1)))
    params = theta_of(sol.x)
    pred, other = model.predict(params, step_s=step_s)
    res_t = pred[window] - pb.measured[window]
    n = int(window.sum())
    J = sol.jac * noise
    dof = max(1, sol.fun.size - len(free))
    s2 = float(np.sum((sol.fun * noise) ** 2)) / dof
    infl = long_run_variance_ratio(res_t)
    cov = np.linalg.pinv(J.T @ J) * s2 * infl
    q = float(stats.t.ppf(0.975, dof))
    ci = {}
    for i, (name, lg) in enumerate(zip(free, logs)):
        half = q * math.sqrt(max(0.0, float(cov[i, i])))
        ci[name] = (_exp(sol.x[i] - half), _exp(sol.x[i] + half)) if lg else \
            (params[name] - half, params[name] + half)
    for name, value in fixed.items():
        ci[name] = (value, value)
    if "lug_phase" in params:   # report the phase in (-pi, pi]
        wrapped = math.pi - (math.pi - params["lug_phase"]) % (2 * math.pi)
        shift = wrapped - params["lug_phase"]
        params["lug_phase"] = wrapped
        ci["lug_phase"] = (ci["lug_phase"][0] + shift, ci["lug_phase"][1] + shift)
    in_bounds = all(lo[n] <= params[n] <= hi[n] for n in free)
    return Fit(model=model, params=params, ci=ci, sse=float(res_t @ res_t), n=n,
               nrmse=_nrmse(pred, pb.measured, window), prediction=pred, other_prediction=other,
               evaluations=count[0], seconds=time.perf_counter() - t0,
               extra={"variance_inflation": infl, "in_bounds": in_bounds, "step_s": step_s or pb.step_s})


def sse_at(model: Model, theta: dict, step_s: float | None = None) -> float:
    """Residual energy of the tire's channel over the window for given parameters, (m/s²)²."""
    pb = model.problem
    pred, _ = model.predict(theta, step_s=step_s)
    r = (pred - pb.measured)[pb.window]
    return float(r @ r)


def scan_arrival(model: Model, theta: dict, *, half_width_s: float = 0.02, points: int = 21,
                 step_s: float | None = None) -> float:
    """The arrival time (s) within ±half_width of theta's that fits best, the rest held.

    The impact is a sharp feature: a gradient search started a few ms off can
    settle on a neighbouring minimum, so the fit starts from this scan.
    """
    pb = model.problem
    window = pb.window
    meas = pb.measured[window]
    best, best_sse = theta["arrival"], math.inf
    for shift in np.linspace(-half_width_s, half_width_s, points):
        trial = dict(theta, arrival=theta["arrival"] + shift)
        pred, _ = model.predict(trial, step_s=step_s)
        sse = float(np.sum((pred[window] - meas) ** 2))
        if sse < best_sse:
            best, best_sse = trial["arrival"], sse
    return best
