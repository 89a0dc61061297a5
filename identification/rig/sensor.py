"""Sensor and acquisition chain of the virtual rig.

The hub's kinematic acceleration a(t) (gravity is a constant the AC coupling
removes) passes, in continuous time,

* an AC-coupling first-order high-pass s / (s + ω_h), and
* an analog Butterworth anti-alias filter of order N at f_aa,

is sampled at f_s, gets white noise and, optionally, quantization.

The analog chain is applied exactly: it is split into first-order complex
modes ż_j = p_j z_j + a(t), y = Σ Re(ρ_j z_j) + D a, and each mode is advanced
with the exact solution for an input that is linear between grid points
(first-order hold on a grid of ``oversample`` points per sample).  Where the
acceleration jumps (road steps, contact changes) the grid step is split at the
jump, and the impulses of a point-contact road step (a hub velocity jump Δv is
an acceleration impulse Δv δ(t)) enter each mode as z_j += Δv.  The remaining
error is the first-order-hold error of the smooth parts, O(h²).
"""

from __future__ import annotations

import numpy as np
from scipy import signal

__all__ = ["chain_modes", "apply_chain"]


def chain_modes(aa_order: int, aa_cutoff_hz: float, highpass_hz: float):
    """Poles (rad/s), residues and direct term of high-pass × anti-alias filter."""
    poles: list[complex] = []
    res: list[complex] = []
    direct = 1.0
    if aa_order > 0:
        wc = 2 * np.pi * aa_cutoff_hz
        _, p, k = signal.buttap(aa_order)
        p = p * wc
        gain = k * wc ** aa_order
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


def _hold(p: complex, h: float):
    """E, g0, g1 with z(h) = E z(0) + g0 a(0) + g1 a(h) for ż = p z + a, a linear."""
    if h <= 0:
        return 1.0 + 0j, 0j, 0j
    x = p * h
    if abs(x) < 1e-3:
        e_m1_over_p = h * (1 + x / 2 + x * x / 6 + x ** 3 / 24)
        g1 = h * (0.5 + x / 6 + x * x / 24 + x ** 3 / 120)
    else:
        em1 = np.expm1(x)
        e_m1_over_p = em1 / p
        g1 = (em1 - x) / (p * p * h)
    return np.exp(x), e_m1_over_p - g1, g1


def apply_chain(acc: np.ndarray, t0: float, h: float, cuts, poles, residues, direct: float) -> np.ndarray:
    """Exact response of the analog chain on the grid t0 + j h.

    Parameters
    ----------
    acc : ndarray (channels, n)
        Acceleration at the grid nodes (right-hand value at a jump), m/s².
    t0, h : float
        Grid origin and step, s.
    cuts : list of (t, a_before, a_after, velocity_jump)
        Jumps and impulses inside the grid, in time order (see
        :func:`identification.rig.solver.hub_acceleration_on_grid`).
    poles, residues, direct
        From :func:`chain_modes`.

    Returns
    -------
    ndarray (channels, n)
        Filtered acceleration at the nodes, m/s² (zero initial state).
    """
    ch, n = acc.shape
    out = direct * acc.astype(float)
    if poles.size == 0:
        return out
    # Group the cuts by the grid cell (t_k, t_k+1] that holds them.
    cells: dict[int, list] = {}
    for cut in cuts:
        k = int(np.ceil((cut[0] - t0) / h - 1e-7)) - 1
        if 0 <= k < n - 1:
            cells.setdefault(k, []).append(cut)
    order = sorted(cells)
    for p, rho in zip(poles, residues):
        e, g0, g1 = _hold(p, h)
        b, a = np.array([g1, g0]), np.array([1.0, -e])
        z = np.zeros(ch, dtype=complex)
        traj = np.empty((ch, n), dtype=complex)
        start = 0
        for k in order + [n - 1]:
            # Uniform stretch start..k: lfilter with the state carried in.
            seg = acc[:, start:k + 1]
            zi = (z - g1 * seg[:, 0])[:, None]
            traj[:, start:k + 1], _ = signal.lfilter(b, a, seg, axis=1, zi=zi)
            if k == n - 1:
                break
            z = traj[:, k].copy()
            t_prev, a_prev = t0 + k * h, acc[:, k]
            for t_cut, a_before, a_after, jump in cells[k]:
                dt = max(0.0, t_cut - t_prev)
                e1, h0, h1 = _hold(p, dt)
                z = e1 * z + h0 * a_prev + h1 * a_before + jump
                t_prev, a_prev = t_cut, a_after
            e1, h0, h1 = _hold(p, max(0.0, t0 + (k + 1) * h - t_prev))
            z = e1 * z + h0 * a_prev + h1 * acc[:, k + 1]
            traj[:, k + 1] = z
            start = k + 1
        out += np.real(rho * traj)
    return out
