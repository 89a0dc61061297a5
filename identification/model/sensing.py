"""What a model's accelerometers show after the analysis low-pass: every channel in one compiled pass.

The reference, channel by channel, is
:func:`identification.model.acquisition.sensed_acceleration` (the hub motion through
the acquisition chain, or the mean acceleration over each sample interval
without an anti-alias filter) followed by
:func:`identification.recording.preprocess.lowpass` (:func:`sensed_lowpassed_reference`).
:func:`sensed_lowpassed` computes the same for all channels at once with numba
kernels (Python only packs the impulses into arrays):

* the hub velocity is reconstructed as
  :meth:`identification.model.scheme.Trajectory.velocity_at` does (linear between
  grid points, jumping at the impulses), the jumps summed by prefix sums;
* the chain's modes are advanced side by side (:func:`_chain_rows`, the
  recursion of :func:`identification.model.acquisition.apply_chain` with the
  velocity form of :func:`~identification.model.acquisition.sensed_acceleration`);
* the zero-phase low-pass filters all channels side by side
  (:func:`_filtfilt_rows`: odd extension, steady-state initial conditions and
  the section-by-section recursion of ``scipy.signal.sosfilt``, forward then
  backward, as the fast path of :func:`~identification.recording.preprocess.lowpass`).

The two agree to round-off (tested ≤ 1e-12 relative over every model effect,
with and without a chain).  Without numba the reference is used.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from . import acquisition
from .acquisition import acquisition_modes, sensed_acceleration
from ..recording.preprocess import FILTER_ORDER, lowpass, lowpass_design
from .kernels import drop_stale_cache

__all__ = ["sensed_lowpassed", "sensed_lowpassed_reference", "sensed_accelerations"]

try:   # pragma: no cover - numba is a dependency; without it the reference is used
    import numba

    from .._compile import njit
except ImportError:   # pragma: no cover
    numba = None


def sensed_lowpassed_reference(traj, time_s, sample_rate_hz: float, acquisition_chain, *, cutoff_hz: float,
                               order: int = FILTER_ORDER, tires: int | None = None) -> np.ndarray:
    """What each channel shows after the low-pass, channel by channel with the public functions, m/s².

    Parameters
    ----------
    traj : identification.model.scheme.Trajectory
        The model's hub motion.
    time_s : ndarray
        Sample times, s.
    sample_rate_hz : float
        Sampling rate of the recording, Hz.
    acquisition_chain : identification.model.acquisition.Acquisition or None
        The recording's acquisition chain.
    cutoff_hz : float
        Cut-off of the zero-phase low-pass, Hz.
    order : int
        Butterworth order of one pass.
    tires : int, optional
        How many rows of `traj`, from the first (default all).

    Returns
    -------
    ndarray (tires, samples)
    """
    return np.array([lowpass(sensed_acceleration(traj, i, time_s, sample_rate_hz, acquisition_chain),
                             sample_rate_hz=sample_rate_hz, cutoff_hz=cutoff_hz, order=order)
                     for i in range(traj.hub_vz_m_s.shape[0] if tires is None else tires)])


def sensed_lowpassed(traj, time_s, sample_rate_hz: float, acquisition_chain, *, cutoff_hz: float,
                     order: int = FILTER_ORDER, tires: int | None = None) -> np.ndarray:
    """:func:`sensed_lowpassed_reference` in one compiled pass (same parameters and result), m/s².

    Raises
    ------
    identification.errors.InputError
        If the cut-off is not below the Nyquist frequency.
    """
    t = np.asarray(time_s, dtype=float)
    sos, zi, edge = lowpass_design(sample_rate_hz=sample_rate_hz, cutoff_hz=cutoff_hz, order=order)
    if numba is None or t.ndim != 1 or t.size <= edge:   # pragma: no cover - numba is a dependency
        return sensed_lowpassed_reference(traj, t, sample_rate_hz, acquisition_chain, cutoff_hz=cutoff_hz,
                                          order=order, tires=tires)
    raw = sensed_accelerations(traj, t, sample_rate_hz, acquisition_chain, tires=tires)
    return _filtfilt_rows(raw, sos, zi, edge)


def sensed_accelerations(traj, time_s, sample_rate_hz: float, acquisition_chain, *,
                         tires: int | None = None) -> np.ndarray:
    """:func:`identification.model.acquisition.sensed_acceleration` of the first `tires` rows (default all), m/s².

    Parameters as :func:`sensed_lowpassed_reference`; without an anti-alias
    filter (or `acquisition_chain` None), the mean acceleration over each
    sample interval 1 / `sample_rate_hz`.

    Returns
    -------
    ndarray (tires, samples)
    """
    t = np.asarray(time_s, dtype=float)
    nt = traj.hub_vz_m_s.shape[0] if tires is None else tires
    v = np.ascontiguousarray(traj.hub_vz_m_s[:nt], dtype=float)
    grid = np.ascontiguousarray(traj.time_s, dtype=float)
    counts = [len(traj.impulses[i]) for i in range(nt)]
    ptr = np.zeros(nt + 1, dtype=np.int64)
    ptr[1:] = np.cumsum(counts)
    flat = np.array([p for i in range(nt) for p in traj.impulses[i]], dtype=float).reshape(-1, 2)
    edge_t, edge_j = np.ascontiguousarray(flat[:, 0]), np.ascontiguousarray(flat[:, 1])
    h = float(traj.step_s)
    if acquisition_chain is None or not acquisition_chain.anti_alias_order:
        return _mean_rows(v, grid, h, ptr, edge_t, edge_j, t, 1.0 / sample_rate_hz)
    poles, residues, fold, direct = _folded_modes(acquisition_chain)
    return _chain_rows(v, grid, h, ptr, edge_t, edge_j, t, poles, residues * poles, residues, fold, direct)


@functools.lru_cache(maxsize=32)
def _folded_modes(acquisition_chain):
    """The chain's modes with each conjugate pair folded into one (its real part counted twice).

    Returns (poles, residues, fold, direct): fold 2 for a kept complex pole, 1
    for a real one; direct = Re Σ residues over all modes.
    """
    poles, residues, _ = acquisition_modes(acquisition_chain)
    keep, fold, dropped = [], [], set()
    for j, (p, r) in enumerate(zip(poles, residues)):
        if j in dropped:
            continue
        pair = [k for k in range(j + 1, poles.size) if k not in dropped and p.imag != 0
                and abs(poles[k] - p.conjugate()) <= 1e-12 * abs(p)
                and abs(residues[k] - r.conjugate()) <= 1e-12 * abs(r)]
        if pair:
            dropped.add(pair[0])
        keep.append(j)
        fold.append(2.0 if pair else 1.0)
    return (poles[keep].copy(), residues[keep].copy(), np.array(fold), float(np.real(residues.sum())))


def _locate(xp, x, j):
    """j with xp[j] <= x < xp[j+1] (−1 below xp[0], n − 1 at or above xp[-1]), walking from the guess j."""
    n = xp.size
    j = min(max(j, -1), n - 1)
    while j + 1 < n and xp[j + 1] <= x:
        j += 1
    while j >= 0 and xp[j] > x:
        j -= 1
    return j


def _interp_at(xp, fp, x, j):
    """``np.interp(x, xp, fp)`` with x in [xp[j], xp[j+1]) (:func:`_locate`): numpy's formula."""
    if j < 0:
        return fp[0]
    if j >= xp.size - 1 or xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    return slope * (x - xp[j]) + fp[j]


def _guess(xp, x):
    """A first guess of :func:`_locate` (xp a uniform grid)."""
    if xp.size < 2:
        return 0
    g = math.floor((x - xp[0]) / (xp[1] - xp[0]))
    return int(min(max(g, -1.0), xp.size - 1.0))


def _cells(grid, time_s, offset):
    """:func:`_locate` of each time + `offset`, walking from one to the next."""
    out = np.empty(time_s.size, dtype=np.int64)
    j = _guess(grid, time_s[0] + offset) if time_s.size else 0
    for s in range(time_s.size):
        j = _locate(grid, time_s[s] + offset, j)
        out[s] = j
    return out


def _smooth(v, grid, h, te, je):
    """The velocity without its jumps (:meth:`~identification.model.scheme.Trajectory.velocity_at`'s ``smooth``).

    Each impulse (t_e, j_e) takes j_e off the grid points after t_e, half of it
    off a point within half a step of t_e.
    """
    n = grid.size
    out = v.copy()
    d = np.zeros(n + 1)
    for e in range(te.size):
        lo = np.searchsorted(grid, te[e] - h)
        hi = np.searchsorted(grid, te[e] + h)
        for k in range(lo, hi):
            after = grid[k] - te[e]
            if abs(after) < 0.5 * h:
                out[k] -= je[e] * 0.5
            elif after > 0:
                out[k] -= je[e]
        d[hi] += je[e]
    c = 0.0
    for k in range(n):
        c += d[k]
        out[k] -= c
    return out


def _impulse_sums(te, je):
    """Impulse times sorted (stable), prefix sums of their jumps (Σ_{t_e <= x} j_e = cum[count]), the order."""
    order = np.arange(te.size)
    for i in range(1, te.size):   # a stable insertion sort (a tire's few impulses; numba's mergesort costs
        o, j = order[i], i        # more to compile than the whole chain)
        while j > 0 and te[order[j - 1]] > te[o]:
            order[j] = order[j - 1]
            j -= 1
        order[j] = o
    ts = te[order]
    cum = np.zeros(te.size + 1)
    for i in range(te.size):
        cum[i + 1] = cum[i] + je[order[i]]
    return ts, cum, order


def _count_at_or_before(ts, x, c):
    """How many of the sorted times `ts` are <= x, walking from the guess c."""
    while c < ts.size and ts[c] <= x:
        c += 1
    while c > 0 and ts[c - 1] > x:
        c -= 1
    return c


def _mean_rows(v, grid, h, ptr, edge_t, edge_j, time_s, interval_s):
    """Mean acceleration over each sample interval of every row (no anti-alias filter)."""
    nt, ns = v.shape[0], time_s.size
    out = np.empty((nt, ns))
    half = interval_s / 2
    up, down = _cells(grid, time_s, half), _cells(grid, time_s, -half)
    for i in range(nt):
        te, je = edge_t[ptr[i]:ptr[i + 1]], edge_j[ptr[i]:ptr[i + 1]]
        smooth = _smooth(v[i], grid, h, te, je)
        ts, cum, _ = _impulse_sums(te, je)
        c_up = c_down = 0
        for s in range(ns):
            x_up, x_down = time_s[s] + half, time_s[s] - half
            c_up = _count_at_or_before(ts, x_up, c_up)
            c_down = _count_at_or_before(ts, x_down, c_down)
            a = _interp_at(grid, smooth, x_up, up[s]) + cum[c_up]
            b = _interp_at(grid, smooth, x_down, down[s]) + cum[c_down]
            out[i, s] = (a - b) / interval_s
    return out


def _grid_velocity(v, grid, h, te, je):
    """The velocity on the grid and its cuts for :func:`identification.model.acquisition.apply_chain`.

    Returns x (with the jumps of the impulses at or before each point) and, at
    the distinct impulse times inside the grid (jumps merged): their cell, time
    and the velocity just before and after.
    """
    n, t0 = grid.size, grid[0]
    smooth = _smooth(v, grid, h, te, je)
    ts, cum, order = _impulse_sums(te, je)
    x = np.empty(n)
    c = 0
    for k in range(n):
        c = _count_at_or_before(ts, grid[k], c)
        x[k] = smooth[k] + cum[c]
    cell, t, before, after = np.empty(ts.size, dtype=np.int64), np.empty(ts.size), np.empty(ts.size), \
        np.empty(ts.size)
    nc = e = 0
    while e < ts.size:
        t_e, jump = ts[e], je[order[e]]
        e += 1
        while e < ts.size and ts[e] == t_e:
            jump += je[order[e]]
            e += 1
        v_after = _interp_at(grid, smooth, t_e, _locate(grid, t_e, _guess(grid, t_e))) \
            + cum[_count_at_or_before(ts, t_e, e)]
        k = int(math.ceil((t_e - t0) / h - 1e-7)) - 1
        if 0 <= k < n - 1:
            cell[nc], t[nc], before[nc], after[nc] = k, t_e, v_after - jump, v_after
            nc += 1
    return x, cell[:nc], t[:nc], before[:nc], after[:nc]


def _chain_rows(v, grid, h, ptr, edge_t, edge_j, time_s, poles, rho, weights, fold, direct):
    """Every row's velocity through the chain (modes side by side), interpolated at the samples.

    Per row: :func:`identification.model.acquisition.sensed_acceleration`, i.e.
    :func:`identification.model.acquisition.apply_chain` of the velocity x with
    residues ρ_j = r_j p_j, start weights w_j = r_j and cuts at the (merged)
    impulse times, plus Re Σ r_j times x.  Each mode carries one state
    ζ_j = ρ_j z_j − w_j e^{p_j (t − t0)} x(t0), which the hold advances like
    z_j (ζ_j(t0) = −w_j x(t0)); y = Σ fold_j Re ζ_j (fold 2 for a complex
    pole standing for its conjugate too, :func:`_folded_modes`).
    """
    nt, n = v.shape
    ns, nm = time_s.size, poles.size
    t0 = grid[0]
    e_h = np.empty(nm, dtype=np.complex128)
    g0_h = np.empty(nm, dtype=np.complex128)
    g1_h = np.empty(nm, dtype=np.complex128)
    for m in range(nm):
        e_h[m], g0_h[m], g1_h[m] = _hold(poles[m], h)
        g0_h[m] *= rho[m]
        g1_h[m] *= rho[m]
    cell_of_sample = _cells(grid, time_s, 0.0)
    out = np.empty((nt, ns))
    y = np.empty(n)
    zeta = np.empty(nm, dtype=np.complex128)
    for i in range(nt):
        x, cut_cell, cut_t, cut_before, cut_after = _grid_velocity(v[i], grid, h, edge_t[ptr[i]:ptr[i + 1]],
                                                                   edge_j[ptr[i]:ptr[i + 1]])
        nc = cut_cell.size
        y0 = direct * x[0]
        for m in range(nm):
            zeta[m] = -weights[m] * x[0]
            y0 += fold[m] * zeta[m].real
        y[0] = y0
        c = 0
        for k in range(n - 1):
            if c < nc and cut_cell[c] == k:
                c_end = c
                for m in range(nm):
                    p, r = poles[m], rho[m]
                    t_prev, a_prev = t0 + k * h, x[k]
                    c_end = c
                    zm = zeta[m]
                    while c_end < nc and cut_cell[c_end] == k:
                        e1, h0, h1 = _hold(p, max(0.0, cut_t[c_end] - t_prev))
                        zm = e1 * zm + r * (h0 * a_prev + h1 * cut_before[c_end])
                        t_prev, a_prev = cut_t[c_end], cut_after[c_end]
                        c_end += 1
                    e1, h0, h1 = _hold(p, max(0.0, t0 + (k + 1) * h - t_prev))
                    zeta[m] = e1 * zm + r * (h0 * a_prev + h1 * x[k + 1])
                c = c_end
            else:
                xk, xk1 = x[k], x[k + 1]
                for m in range(nm):
                    zeta[m] = e_h[m] * zeta[m] + g0_h[m] * xk + g1_h[m] * xk1
            yk = direct * x[k + 1]
            for m in range(nm):
                yk += fold[m] * zeta[m].real
            y[k + 1] = yk
        for s in range(ns):
            out[i, s] = _interp_at(grid, y, time_s[s], cell_of_sample[s])
    return out


def _filtfilt_rows(x, sos, zi, edge):
    """Zero-phase filter of every row: ``lowpass``'s fast path, the rows side by side.

    Odd extension by `edge` samples at both ends, steady-state initial
    conditions `zi` (``sosfilt_zi``) scaled by the first value of each pass,
    and scipy's ``sosfilt`` recursion (transposed direct form II per section).
    The rows go four at a time (the last group padded with a copy of its first
    row), section after section over the whole extended signal, their states in
    scalars: four independent recursions in flight, with the same operations in
    the same order per row as ``sosfilt``.  Every :data:`FLUSH_EVERY` samples a
    section's states below :data:`FLUSH_BELOW` in sum are set to zero: a
    model's prediction is exactly zero before its impact, and the backward
    pass's states decay through that stretch into subnormal numbers, whose
    arithmetic is some hundred times slower (measured: the filter 3.7x faster
    on a 2 kHz recording); what that changes stays under 1e-200 m/s².
    """
    ch, n = x.shape
    m = n + 2 * edge
    ns = sos.shape[0]
    out = np.empty((ch, n))
    ext = np.empty((m, 4))
    for c0 in range(0, ch, 4):
        w = min(4, ch - c0)
        for j in range(4):
            c = c0 + j if j < w else c0
            for k in range(edge):
                ext[k, j] = 2 * x[c, 0] - x[c, edge - k]
                ext[edge + n + k, j] = 2 * x[c, n - 1] - x[c, n - 2 - k]
            for k in range(n):
                ext[edge + k, j] = x[c, k]
        for backward in range(2):
            first = m - 1 if backward else 0
            xa, xb, xc, xd = ext[first, 0], ext[first, 1], ext[first, 2], ext[first, 3]
            for s in range(ns):
                b0, b1, b2, a1, a2 = sos[s, 0], sos[s, 1], sos[s, 2], sos[s, 4], sos[s, 5]
                za0, za1 = zi[s, 0] * xa, zi[s, 1] * xa
                zb0, zb1 = zi[s, 0] * xb, zi[s, 1] * xb
                zc0, zc1 = zi[s, 0] * xc, zi[s, 1] * xc
                zd0, zd1 = zi[s, 0] * xd, zi[s, 1] * xd
                for k in range(m):
                    if k % FLUSH_EVERY == 0:
                        za0, za1 = _flushed(za0, za1)
                        zb0, zb1 = _flushed(zb0, zb1)
                        zc0, zc1 = _flushed(zc0, zc1)
                        zd0, zd1 = _flushed(zd0, zd1)
                    i = m - 1 - k if backward else k
                    ext[i, 0], za0, za1 = _section(ext[i, 0], za0, za1, b0, b1, b2, a1, a2)
                    ext[i, 1], zb0, zb1 = _section(ext[i, 1], zb0, zb1, b0, b1, b2, a1, a2)
                    ext[i, 2], zc0, zc1 = _section(ext[i, 2], zc0, zc1, b0, b1, b2, a1, a2)
                    ext[i, 3], zd0, zd1 = _section(ext[i, 3], zd0, zd1, b0, b1, b2, a1, a2)
        for j in range(w):
            for k in range(n):
                out[c0 + j, k] = ext[edge + k, j]
    return out


def _section(xn, z0, z1, b0, b1, b2, a1, a2):
    """One sample through one second-order section (``sosfilt``'s transposed direct form II): (y, z0, z1)."""
    yn = b0 * xn + z0
    return yn, b1 * xn - a1 * yn + z1, b2 * xn - a2 * yn


def _flushed(z0, z1):
    """A section's states, zero when their magnitudes sum under :data:`FLUSH_BELOW`."""
    if abs(z0) + abs(z1) < FLUSH_BELOW:
        return 0.0, 0.0
    return z0, z1


#: How often (samples) :func:`_filtfilt_rows` looks for states to set to zero, and below what sum of their
#: magnitudes it does.
FLUSH_EVERY = 32
FLUSH_BELOW = 1e-200


_hold = getattr(acquisition.hold, "py_func", acquisition.hold)     # the plain function, compiled here
if numba is not None:
    drop_stale_cache("sensing", "acquisition", acquisition)
    _hold = njit()(_hold)
    _section, _flushed = njit(inline="always")(_section), njit(inline="always")(_flushed)
    _locate, _interp_at, _guess, _cells, _smooth, _impulse_sums, _count_at_or_before, _grid_velocity, \
        _mean_rows, _chain_rows, _filtfilt_rows = (njit()(f) for f in (
            _locate, _interp_at, _guess, _cells, _smooth, _impulse_sums, _count_at_or_before, _grid_velocity,
            _mean_rows, _chain_rows, _filtfilt_rows))
