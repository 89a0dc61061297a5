"""The free decay of a coupled body: the rigid tractor's modes after the last impact, fitted alone.

Under a rigid tractor a hub does not ring as a corner: each channel holds the body's heave, pitch and roll
modes, and a channel's own waveform fit is no measurement of its tire.  After the last impact the tractor
rolls on flat ground and the body rings freely: M q̈ + Jᵀ C J q̇ + Jᵀ K J q = 0 with the body of
:class:`identification.model.tractor.Body` (J the hub displacement per coordinate, M its masses from the
static loads and the dynamic indices) and K, C the tires' k and c.  Its solution from the state x₀ at the
start of the tail is x(t) = V e^{Λ t} V⁻¹ x₀, and every channel's acceleration is linear in x₀; so x₀ is
solved by linear least squares for every k, c and index tried (variable projection), and only those are
fitted (scipy's Levenberg-Marquardt, on logarithms).

A steady line running through the record (lugs, a road line: the fitted lug frequency where
``periodic_disturbance`` is named, else the line of a channel's quiet stretch) is fitted beside the decay in
its channel, its sine and cosine being linear too.

What this needs of the model is the least: no cleat, footprint, timing or impact, and no acquisition chain
(a filter that every channel shares turns each mode by the same complex gain, which the free x₀ absorbs).
What it cannot hold is a tire whose damping or stiffness depends on the amplitude (friction, a
progressive tire): :func:`amplitude_scales` fits the tail's second half with the tires' k and c scaled
together and reports the scales; a damping or stiffness that changes as the ringing dies is said.

Intervals: the sandwich covariance of the estimates under the residual's own autocorrelation
(:func:`identification.diagnose.joint_fit.sandwich_covariance`, up to the lag where it has died out),
Student's t, on the logarithms, each half-width grown in quadrature by the estimate's move when the tail
starts one period of the slowest mode later (the window shift).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats

from ..model.fitting import axle_of
from ..model.tractor import Body
from ..recording.condition import refine_line
from .joint_fit import LINE_SEARCH_HZ, correlation_lag, impact_spans, residual_correlation_lag, sandwich_covariance

__all__ = ["BodyDecay", "body_decay", "line_frequency", "tail_window", "MIN_TAIL_S", "TAIL_RATE_HZ"]

#: Shortest tail fitted, s.
MIN_TAIL_S = 0.8
#: After the last impact's span, the tail starts this much later, s.
TAIL_MARGIN_S = 0.05
#: The tail is fitted at about this rate (every n-th sample of the low-passed channels): the body's modes lie
#: under 15 Hz.
TAIL_RATE_HZ = 100.0
#: Corner frequencies (Hz) of the front and of the rear tires' extra starting values (every pair; damping
#: ratio 0.1).
START_HZ = (2.2, 3.2, 4.6)
#: Iterations (Jacobians) each start gets before the best is fitted to convergence.
SCAN_ITERATIONS = 12
_INDICES = {"pitch_index": 0.9, "roll_index": 0.6, "pivot_index": 0.1}
_FAILED = 1e3


@dataclass(frozen=True, eq=False)
class BodyDecay:
    """The fit of the body's free decay: values and 95 % intervals of every tire's k and c and the indices."""

    kind: str                  # "rigid", "pivot" or "corners"
    params: dict
    ci: dict
    window: tuple              # (start, end) of the tail, s
    nrmse: float               # RMS(residual) / RMS(signal) over the tail
    residual_to_noise: float   # RMS of the noise-weighted residual
    modes_hz: tuple
    extra: dict = field(default_factory=dict)


def tail_window(problem, final=None) -> tuple[float, float]:
    """(start, end) s of the free decay after the last impact: past every impact span
    (:func:`identification.diagnose.joint_fit.impact_spans`) and, given the final fit, past each fitted arrival
    by the cleat and the footprint, plus :data:`TAIL_MARGIN_S`."""
    rec = problem.rec
    end = max(b for _, b in impact_spans(problem))
    if final is not None:
        arrivals = final.model.arrivals(final.params)
        for tire, a in arrivals.items():
            axle = "front" if tire[0] == "F" else "rear"
            foot = float(final.params.get(f"footprint_{axle}", 0.0))
            end = max(end, a + (rec.cleat_width_m + foot) / rec.speed_m_s)
    return max(end + TAIL_MARGIN_S, float(rec.time_s[0])), float(rec.time_s[-1])


class _Tail:
    """The tail's samples and the linear body's response basis."""

    def __init__(self, problem, start_s: float, end_s: float, kind: str, final=None):
        rec = problem.rec
        self.problem, self.kind = problem, kind
        t = rec.time_s
        lines = {j: f for j, f in enumerate(line_frequency(problem, c, final)[0] for c in problem.channels) if f}
        rate = max(TAIL_RATE_HZ, 4.0 * max(lines.values(), default=0.0))
        stride = max(1, int(rec.sample_rate_hz // rate))
        idx = np.flatnonzero((t >= start_s) & (t <= end_s))[::stride]
        self.rate_hz = rec.sample_rate_hz / stride
        self.tau = t[idx] - t[idx[0]]
        self.sigma = np.array([problem.noise[c] for c in problem.channels])
        self.y = np.concatenate([problem.measured[c][idx] / problem.noise[c] for c in problem.channels])
        self.signal = np.concatenate([problem.measured[c][idx] for c in problem.channels])
        # a steady line (lugs, a road) runs through the tail: its sine and cosine in its channel, beside the decay
        self.lines = {}
        for j, f in lines.items():
            if f < 0.45 * self.rate_hz:
                x = problem.measured[problem.channels[j]][idx]
                self.lines[j] = refine_line(self.tau, x[None, :], f, min(LINE_SEARCH_HZ, 0.5 * f))
        self.names = tuple([f"k_{c}" for c in problem.channels] + [f"c_{c}" for c in problem.channels] +
                           {"corners": [], "rigid": ["pitch_index", "roll_index"],
                            "pivot": ["pitch_index", "roll_index", "pivot_index"]}[kind])

    def matrices(self, theta: dict):
        pb = self.problem
        coupled = self.kind != "corners"
        body = Body(tires=pb.channels, loads_n=tuple(pb.rec.wheel_load_N[c] for c in pb.channels),
                    wheelbase_m=pb.rec.wheelbase_m, pitch=coupled, roll=coupled, pivot=self.kind == "pivot",
                    **{n: theta.get(n, v) for n, v in _INDICES.items()})
        J, mass, _ = body.matrices()
        n = J.shape[1]
        k = np.array([theta[f"k_{c}"] for c in pb.channels])
        c = np.array([theta[f"c_{c}"] for c in pb.channels])
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -(J.T * k) @ J / mass[:, None]
        A[n:, n:] = -(J.T * c) @ J / mass[:, None]
        return J, A

    def design(self, theta: dict, scale_k: float = 1.0, scale_c: float = 1.0):
        """(rows × state) response of the noise-weighted channels to each unit initial state; the poles."""
        theta = dict(theta)
        for name in self.names:
            if name.startswith("k_"):
                theta[name] *= scale_k
            elif name.startswith("c_"):
                theta[name] *= scale_c
        J, A = self.matrices(theta)
        n = J.shape[1]
        with np.errstate(all="ignore"):   # a start far off may hold a growing mode: its rows are then refused
            return self._design(J, A, n)

    def _design(self, J, A, n):
        lam, V = np.linalg.eig(A)
        G = (J @ A[n:, :]) @ V                              # hub acceleration per mode
        E = np.exp(np.outer(lam, self.tau))
        B = np.linalg.solve(V, np.eye(2 * n))               # modal coordinates of each unit state
        cols = np.real(np.einsum("cm,mi,mt->cti", G, B, E))  # channel, time, state
        cols /= self.sigma[:, None, None]
        cols = cols.reshape(-1, 2 * n)
        if self.lines:
            tau = self.tau
            extra = np.zeros((cols.shape[0], 2 * len(self.lines)))
            for i, (j, f) in enumerate(self.lines.items()):
                rows = slice(j * tau.size, (j + 1) * tau.size)
                extra[rows, 2 * i] = np.sin(2 * np.pi * f * tau) / self.sigma[j]
                extra[rows, 2 * i + 1] = np.cos(2 * np.pi * f * tau) / self.sigma[j]
            cols = np.hstack([cols, extra])
        return cols, lam

    def residual(self, theta: dict, rows=None, **scales) -> np.ndarray:
        try:
            D, _ = self.design(theta, **scales)
            y = self.y
            if rows is not None:
                D, y = D[rows], y[rows]
            if not np.all(np.isfinite(D)):
                raise ValueError("a mode grows without bound")
            coef = np.linalg.lstsq(D, y, rcond=None)[0]
            r = D @ coef - y
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            return np.full(self.y.size if rows is None else int(np.sum(rows)), _FAILED)
        return np.where(np.isfinite(r), r, _FAILED)


def line_frequency(problem, tire: str, final=None) -> tuple:
    """(frequency Hz or None, whether it is fitted) of the steady line running through the tire's channel: a
    named ``periodic_disturbance``'s fitted lug frequency of its axle in `final`, else the line of the
    channel's quiet stretch (its periodogram's peak: refine it before use)."""
    f = final.params.get(f"lug_frequency_{axle_of(tire)}") if final is not None else None
    if f:
        return float(f), True
    return (getattr(problem, "steady_lines", {}).get(tire) or {}).get("frequency_hz"), False


def _starts(tail: _Tail, start: dict | None) -> list[dict]:
    pb = tail.problem
    out = []
    if start is not None and all(n in start for n in tail.names if not n.endswith("_index")):
        out.append({n: float(start.get(n, _INDICES.get(n, 1.0))) for n in tail.names})
    for front in START_HZ:
        for rear in START_HZ:
            theta = {}
            for c in pb.channels:
                m, w = pb.rec.mass_kg(c), 2 * math.pi * (front if c[0] == "F" else rear)
                theta[f"k_{c}"], theta[f"c_{c}"] = m * w * w, 2 * 0.1 * m * w
            out.append({n: theta.get(n, _INDICES.get(n)) for n in tail.names})
    return out


def body_decay(problem, *, kind: str = "rigid", start: dict | None = None, final=None) -> BodyDecay | None:
    """Fit a body's free decay to the tail of all four channels.

    Parameters
    ----------
    problem : identification.model.fitting.TractorProblem
        Four channels.
    kind : {"rigid", "pivot", "corners"}
        The rigid tractor, the rigid tractor with a pivoting front axle (``front_axle_pivot``), or four
        independent corners (each channel's own free decay, fitted the same way).
    start : dict, optional
        Starting values (e.g. the joint fit's); the corner frequencies of :data:`START_HZ` are tried too.
    final : TractorFit, optional
        The joint fit, whose arrivals and footprints place the tail's start (:func:`tail_window`).

    Returns
    -------
    BodyDecay or None
        None where the tail is shorter than :data:`MIN_TAIL_S` or the channels are not all four.
    """
    if kind not in ("rigid", "pivot", "corners"):
        raise ValueError(f"kind must be 'rigid', 'pivot' or 'corners', got {kind!r}")
    if len(problem.channels) != 4:
        return None
    start_s, end_s = tail_window(problem, final)
    if end_s - start_s < MIN_TAIL_S:
        return None
    tail = _Tail(problem, start_s, end_s, kind, final)
    names = tail.names

    def fun(x, part=tail):
        return part.residual(dict(zip(names, np.exp(np.clip(x, -700, 700)))))

    best = None
    for theta in _starts(tail, start):   # every start briefly, the best to convergence
        x0 = np.log([theta[n] for n in names])
        sol = optimize.least_squares(fun, x0, method="lm", max_nfev=SCAN_ITERATIONS * (len(names) + 1))
        if best is None or sol.cost < best.cost:
            best = sol
    best = optimize.least_squares(fun, best.x, method="lm", max_nfev=60 * (len(names) + 1))
    x, res = best.x, best.fun
    params = dict(zip(names, np.exp(x)))
    # the initial state's unknowns and the lines', solved linearly
    states = 2 * tail.matrices(params)[0].shape[1] + 2 * len(tail.lines)
    cov, q, lag = _sandwich(tail, best.jac, res, len(names) + states)
    _, lam = tail.design(params)
    shift, shifted = _window_shift(problem, kind, final, fun, x, start_s, end_s, lam)
    ci = {}
    for i, name in enumerate(names):
        var = float(cov[i, i])
        half = math.hypot(q * math.sqrt(var), shift[i]) if var >= 0 and math.isfinite(var) else math.inf
        ci[name] = (math.exp(max(-700.0, x[i] - half)), math.exp(min(700.0, x[i] + half)))
    signal = tail.signal
    weighted = res * np.repeat(tail.sigma, tail.tau.size)
    nrmse = float(np.sqrt(np.mean(weighted ** 2)) / max(np.sqrt(np.mean(signal ** 2)), 1e-12))
    modes = tuple(sorted({round(abs(float(v.imag)) / (2 * math.pi), 3) for v in lam if v.imag > 0}))
    return BodyDecay(kind=kind, params=params, ci=ci, window=(float(start_s), float(end_s)), nrmse=nrmse,
                     residual_to_noise=float(np.sqrt(np.mean(res ** 2))), modes_hz=modes,
                     extra={"lag": lag, "samples": int(tail.tau.size), "window_shift": shift,
                            "shift_measured": shifted,
                            "scales": amplitude_scales(tail, params)})


def _sandwich(tail: _Tail, jac: np.ndarray, res: np.ndarray, unknowns: int):
    """(covariance, Student's t quantile, lag) of estimates from the tail's residual `res` (all its rows, or
    the rows of a part of it, channel by channel): the sandwich up to the lag where the residual's
    autocorrelation has died out (at least the low-passed noise's), scaled to `unknowns` fitted."""
    sizes = [res.size // len(tail.problem.channels)] * len(tail.problem.channels)
    lag = residual_correlation_lag(res, sizes, correlation_lag(tail.rate_hz, tail.problem.cutoff_hz))
    dof = max(1, res.size - unknowns)
    cov = sandwich_covariance(jac, res, sizes, lag) * (res.size / dof)
    return cov, float(stats.t.ppf(0.975, dof)), lag


def _window_shift(problem, kind, final, fun, x, start_s, end_s, lam) -> tuple[np.ndarray, bool]:
    """How far the estimates (logarithms) move when the tail starts one period of the slowest mode later: what
    the impacts' last effects and anything else the free decay does not model pull at the tail's start.  Added
    to each interval's half-width in quadrature (as a corner decay's window shift is).  Returns (moves,
    measured): zeros and False where the shorter tail would be under :data:`MIN_TAIL_S` (a slowest mode near
    0 Hz, an overdamped motion, makes its period longer than any tail)."""
    slowest = min((abs(float(v.imag)) for v in lam if v.imag > 0), default=0.0)
    later = start_s + (2 * math.pi / slowest if slowest > 0 else 0.0)
    if slowest <= 0 or end_s - later < MIN_TAIL_S:
        return np.zeros(x.size), False
    part = _Tail(problem, later, end_s, kind, final)
    sol = optimize.least_squares(lambda v: fun(v, part), x, method="lm", max_nfev=30 * (x.size + 1))
    moved = sol.x - x
    return np.where(np.isfinite(moved), np.abs(moved), 0.0), True


def amplitude_scales(tail: _Tail, params: dict) -> dict:
    """The tires' k and c scaled together (two factors) to fit the tail's second half alone, from the whole
    tail's fit: ``{"k": (value, low, high), "c": (...)}``, 95 %.  A linear tire gives 1 within the interval;
    friction damps the small late ringing more (c > 1), a progressive tire softens it (k < 1)."""
    half = tail.tau >= tail.tau[-1] / 2
    rows = np.tile(half, len(tail.problem.channels))

    def fun(x):
        return tail.residual(params, rows=rows, scale_k=math.exp(x[0]), scale_c=math.exp(x[1]))

    sol = optimize.least_squares(fun, np.zeros(2), method="lm", max_nfev=60)
    cov, q, _ = _sandwich(tail, sol.jac, sol.fun, 2)
    out = {}
    for i, name in enumerate(("k", "c")):
        h = q * math.sqrt(max(float(cov[i, i]), 0.0))
        out[name] = (math.exp(sol.x[i]), math.exp(sol.x[i] - h), math.exp(sol.x[i] + h))
    return out


#: The body's decay counts only where its noise-weighted residual RMS is at most this (more: lugs, a line, a
#: mode it does not have).
MAX_RESIDUAL_TO_NOISE = 3.5
#: Largest high / low ratio of a tire's k or c interval (wider: not determined by the tail; a collapsed damping).
MAX_INTERVAL_RATIO = 4.0
#: Amplitude scales (:func:`amplitude_scales`) a linear tire keeps: k within ±5 %, c within ±25 %, or their
#: intervals holding 1.
K_SCALE_TOL, C_SCALE_TOL = 0.05, 0.25


def why_not(bd: BodyDecay) -> str | None:
    """Why a body's free decay is no measurement of the tires, or None where it is one."""
    if bd.residual_to_noise > MAX_RESIDUAL_TO_NOISE:
        return (f"the body's free decay leaves {bd.residual_to_noise:.1f}x the noise "
                f"(> {MAX_RESIDUAL_TO_NOISE}) over {bd.window[0]:.2f}-{bd.window[1]:.2f} s")
    wide = [n for n in bd.params if n[:2] in ("k_", "c_") and
            not bd.ci[n][1] / max(bd.ci[n][0], 1e-300) <= MAX_INTERVAL_RATIO]
    if wide:
        return f"the body's free decay does not determine {', '.join(wide)}"
    for q, tol, what in (("k", K_SCALE_TOL, "stiffness"), ("c", C_SCALE_TOL, "damping")):
        value, lo, hi = bd.extra["scales"][q]
        if abs(value - 1) > tol and not lo <= 1 <= hi:
            return (f"the tires' {what} changes with the amplitude (x{value:.2f} ({lo:.2f}-{hi:.2f}) in the "
                    f"decay's second half): friction or a progressive tire, which a linear decay does not hold")
    return None
