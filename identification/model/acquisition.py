"""The acquisition chain of an accelerometer channel, applied to a model's hub motion.

A recording's sidecar may describe how its channels were acquired
(``"acquisition"``, see :class:`Acquisition`): the hub's kinematic
acceleration a(t) passes, in continuous time,

* an AC-coupling first-order high-pass s / (s + ω_h), and
* an analog Butterworth anti-alias filter of order N at f_aa,

and is then sampled.  The virtual rig applies exactly this chain to its
recordings, and a fitting model must apply it too: a 4th-order anti-alias
filter at a quarter of the sampling rate delays the impact by about 1.7 ms and
rounds it, which a model without the chain absorbs into biased arrivals and
stiffnesses (≈ 0.1 % in k, with intervals that miss the truth).

(The rig has its own implementation of the chain, so that it stays an
independent reference for this one.)

The chain is split into first-order complex modes ż_j = p_j z_j + a(t),
y = Σ Re(ρ_j z_j) + D a (:func:`chain_modes`), and each mode is advanced with
the exact solution for an input that is linear between grid points
(:func:`apply_chain`, first-order hold), with the grid step split wherever the
input jumps.

A model's hub velocity v is linear between its grid points and jumps at the
impulses of point-contact cleat edges (:meth:`identification.model.scheme.Trajectory.velocity_at`);
its acceleration is v̇.  With z_j(t0) = 0, integration by parts gives

    z_j(t) = v(t) − e^{p_j (t − t0)} v(t0) + p_j u_j(t),   u̇_j = p_j u_j + v,

so :func:`sensed_acceleration` filters the velocity (exactly, for that
interpolant) rather than differentiating it.  Without an anti-alias filter
the channel is the mean acceleration over each sample interval.
"""

from __future__ import annotations

import cmath
import functools
import math

import numpy as np

from ..recording.acquisition import Acquisition

__all__ = ["Acquisition", "acquisition_modes", "chain_modes", "hold", "apply_chain", "sensed_acceleration"]

@functools.lru_cache(maxsize=32)
def _modes(aa_order, aa_cutoff_hz, highpass_hz):
    return chain_modes(aa_order, aa_cutoff_hz, highpass_hz)


def acquisition_modes(acquisition: Acquisition):
    """(poles rad/s, residues, direct term) of a recording's acquisition chain (:func:`chain_modes`)."""
    return _modes(acquisition.anti_alias_order, float(acquisition.anti_alias_cutoff_hz),
                  float(acquisition.highpass_hz))


def chain_modes(aa_order: int, aa_cutoff_hz: float, highpass_hz: float):
    """Poles (rad/s), residues and direct term of high-pass × anti-alias filter."""
    poles: list[complex] = []
    res: list[complex] = []
    direct = 1.0
    if aa_order > 0:
        wc = 2 * np.pi * aa_cutoff_hz
        m = np.arange(-aa_order + 1, aa_order, 2)
        p = -np.exp(1j * np.pi * m / (2 * aa_order)) * wc      # Butterworth poles (scipy.signal.buttap order)
        gain = wc ** aa_order
        for j, pj in enumerate(p):
            others = np.delete(p, j)
            rj = gain / np.prod(pj - others)
            if highpass_hz > 0:
                rj *= pj / (pj + 2 * np.pi * highpass_hz)
            poles.append(pj)
            res.append(rj)
        direct = 0.0
        if highpass_hz > 0:
            wh = 2 * np.pi * highpass_hz
            g_aa = gain / np.prod(-wh - p)
            poles.append(-wh)
            res.append(-wh * g_aa)
    elif highpass_hz > 0:
        wh = 2 * np.pi * highpass_hz
        poles.append(-wh)
        res.append(-wh)
    return np.array(poles, dtype=complex), np.array(res, dtype=complex), direct


def hold(p: complex, h: float):
    """E, g0, g1 with z(h) = E z(0) + g0 a(0) + g1 a(h) for ż = p z + a, a linear over [0, h]."""
    if h <= 0:
        return 1.0 + 0j, 0j, 0j
    x = p * h
    if abs(x) < 0.1:         # series of (eˣ − 1)/x and (eˣ − 1 − x)/x², truncation < 1e-15
        s1, s2 = 0j, 0j
        for k in range(12, -1, -1):
            s1 = s1 * x + 1.0 / _FACT[k + 1]
            s2 = s2 * x + 1.0 / _FACT[k + 2]
        e_m1_over_p = h * s1
        g1 = h * s2
    else:
        em1 = cmath.exp(x) - 1.0
        e_m1_over_p = em1 / p
        g1 = (em1 - x) / (p * p * h)
    return cmath.exp(x), e_m1_over_p - g1, g1


_FACT = np.array([float(math.factorial(k)) for k in range(16)])


def _chain(x, t0, h, cut_cell, cut_t, cut_before, cut_after, cut_jump, poles, residues, start_weights):
    """Σ Re(ρ_j z_j − w_j e^{p_j (t − t0)} x(t0)) at the nodes for one input `x` (see :func:`apply_chain`).

    Cuts sorted by time; `start_weights` w_j (zero for a plain chain) forget the
    start's value at each pole's rate (:func:`sensed_acceleration`).
    """
    n = x.size
    out = np.zeros(n)
    for m in range(poles.size):
        p, rho, w = poles[m], residues[m], start_weights[m]
        e, g0, g1 = hold(p, h)
        z = 0j
        c = 0
        decay = w * x[0]
        out[0] -= decay.real
        for k in range(n - 1):
            if c < cut_cell.size and cut_cell[c] == k:
                t_prev, a_prev = t0 + k * h, x[k]
                while c < cut_cell.size and cut_cell[c] == k:
                    e1, h0, h1 = hold(p, max(0.0, cut_t[c] - t_prev))
                    z = e1 * z + h0 * a_prev + h1 * cut_before[c] + cut_jump[c]
                    t_prev, a_prev = cut_t[c], cut_after[c]
                    c += 1
                e1, h0, h1 = hold(p, max(0.0, t0 + (k + 1) * h - t_prev))
                z = e1 * z + h0 * a_prev + h1 * x[k + 1]
            else:
                z = e * z + g0 * x[k] + g1 * x[k + 1]
            decay = decay * e
            out[k + 1] += (rho * z).real - decay.real
    return out


_COMPILED: dict = {}


def _chain_kernel():
    """:func:`_chain` compiled with numba, on first use (importing numba is a start-up cost that commands
    not filtering anything, like ``export``, do not pay); plain Python without numba."""
    global hold
    if "chain" not in _COMPILED:
        try:
            import numba  # noqa: F401 - without it, plain Python

            from .._compile import njit
        except ImportError:   # pragma: no cover - numba is a dependency
            _COMPILED["chain"] = _chain
        else:
            hold = njit()(hold)
            _COMPILED["chain"] = njit()(_chain)
    return _COMPILED["chain"]


def apply_chain(acc: np.ndarray, t0: float, h: float, cuts, poles, residues, direct: float,
                start_weights=None) -> np.ndarray:
    """Exact response of the analog chain on the grid t0 + j h (zero initial state).

    Parameters
    ----------
    acc : ndarray (channels, n)
        Input at the grid nodes (right-hand value at a jump).
    t0, h : float
        Grid origin and step, s.
    cuts : list of (t, before, after, jump)
        Jumps of the input (value just before and after t) and impulses
        (``jump``: the integral of a Dirac at t) inside the grid, in time
        order; ``before``, ``after`` and ``jump`` are scalars or one value per
        channel.
    poles, residues, direct
        From :func:`chain_modes`.
    start_weights : ndarray, optional
        w_j: subtract Re(w_j e^{p_j (t − t0)}) times the first node's value.

    Returns
    -------
    ndarray (channels, n)
        The chain's output at the nodes.
    """
    acc = np.asarray(acc, dtype=float)
    ch, n = acc.shape
    out = direct * acc if direct else np.zeros_like(acc)
    if poles.size == 0:
        return out
    kept = []
    for cut in cuts:   # the grid cell (t_k, t_k+1] that holds each cut
        k = int(np.ceil((cut[0] - t0) / h - 1e-7)) - 1
        if 0 <= k < n - 1:
            kept.append((k, cut))
    cell = np.array([k for k, _ in kept], dtype=np.int64)
    times = np.array([float(c[0]) for _, c in kept])
    poles = np.asarray(poles, dtype=complex)
    residues = np.asarray(residues, dtype=complex)
    weights = np.zeros(poles.size, dtype=complex) if start_weights is None else \
        np.asarray(start_weights, dtype=complex)
    for i in range(ch):
        vals = [np.array([float(np.broadcast_to(c[j], (ch,))[i]) for _, c in kept]) for j in (1, 2, 3)]
        out[i] += _chain_kernel()(np.ascontiguousarray(acc[i]), float(t0), float(h), cell, times, *vals, poles, residues,
                         weights)
    return out


def sensed_acceleration(traj, tire: int, time_s, sample_rate_hz: float, acquisition: Acquisition | None):
    """What the accelerometer of one tire records at `time_s` for a model trajectory, m/s².

    Parameters
    ----------
    traj : identification.model.scheme.Trajectory
        The model's hub motion (its grid should hold the sample times).
    tire : int
        Row of the tire in `traj`.
    time_s : ndarray
        Sample times, s.
    sample_rate_hz : float
    acquisition : Acquisition or None
        The chain; without an anti-alias filter (or None) the mean
        acceleration over each sample interval.
    """
    t = np.asarray(time_s, dtype=float)
    if acquisition is None or not acquisition.anti_alias_order:
        return traj.mean_acceleration(tire, t, 1.0 / sample_rate_hz)
    poles, residues, direct = acquisition_modes(acquisition)
    grid = traj.time_s
    t0, h = float(grid[0]), float(traj.step_s)
    jumps: dict = {}
    for t_edge, jump in traj.impulses[tire]:
        jumps[float(t_edge)] = jumps.get(float(t_edge), 0.0) + float(jump)
    edges = sorted(jumps)
    v = traj.velocity_at(tire, np.concatenate([grid, edges]))
    cuts = [(t_edge, v_after - jumps[t_edge], v_after, 0.0) for t_edge, v_after in zip(edges, v[grid.size:])]
    v = v[:grid.size]
    y = apply_chain(v[None, :], t0, h, cuts, poles, residues * poles, 0.0, start_weights=residues)[0]
    y += np.real(residues.sum()) * v
    return np.interp(t, grid, y)
