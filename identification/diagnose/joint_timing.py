"""Cleat arrivals of a whole-tractor recording: one search over every channel, cross-talk included.

Every hub feels the other tires' impacts through the body (with a pivoting
front axle, a front impact throws the other front hub the opposite way), so a
channel's first or largest burst is not necessarily its own impact.  The
arrivals are therefore found with a linear model of the whole tractor:

* for a body hypothesis (four corners, the rigid tractor, the tractor with a
  pivoting front axle) and starting k, c per tire, the response of every
  channel to one wheel's cleat is simulated once (``H[w][c]``);
* for arrivals ``a_w`` the model is the superposition ``Σ_w H[w][c](t − a_w)``
  (exact for the linear model), and its squared misfit expands into
  correlations of the measurement with the responses (one per wheel and
  arrival) and of the responses with each other (one per pair and lag);
* with ``fit_scale``, the responses carry one common scale, fitted in closed
  form for every timing: the misfit less the measurement's energy is then
  ``-L²/Q`` (``L`` the correlation of the measurement with the summed
  responses, ``Q`` their energy; 0 where ``L <= 0``).  Without it, a model
  whose impact is too large (a point contact on a wide, bevelled cleat) scores
  every timing above the zero prediction and prefers the one whose responses
  cancel each other (seen on another simulator's slow passes: a stagger of
  -0.26 s for a true -0.01 s, both hubs' onsets at the same sample); with it,
  start values far off let a wrong timing's shape tie the right one's (seen on
  the rig: a stagger of -0.28 s for a true +0.05 s).  Neither search is
  always right: the diagnosis runs from the fitted-scale timings too where its
  first selection leaves the record unexplained, the lower BIC kept
  (:func:`~identification.diagnose.joint_select.diagnose_tractor`);
* the arrival, left/right stagger and front/rear delay are searched
  exhaustively, first on a ~2 ms grid, then at the sampling grid around the
  best; the hypothesis that fits best gives the timing.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.signal import fftconvolve

from ..model.kernels import run_model
from ..model.sensing import sensed_lowpassed
from ..recording import FRONT_TIRES
from ..model.fitting import TractorFitModel, TractorProblem

__all__ = ["joint_timing", "scaled_timing", "BODY_DEFAULTS", "MAX_STAGGER_S", "DELAY_RANGE"]

#: Dynamic indices of the body hypotheses (a typical tractor).
BODY_DEFAULTS = {"pitch_index": 0.9, "roll_index": 0.6, "pivot_index": 0.1}
#: Pitch and roll indices of the body hypotheses.
PITCH_GRID = (0.7, 1.1)
ROLL_GRID = (0.35, 0.7)
#: Largest left/right stagger considered, s.
MAX_STAGGER_S = 0.3
#: Front/rear delay considered, as a fraction of the sidecar's: a GPS speed is a few percent off, and a wider
#: range lets a misfitting response (a hub that lifts off, unmodelled here) pull the rear arrival onto the
#: body's own pitch motion (seen: 0.8x on a lift-off recording at 11 km/h, the range's edge).
DELAY_RANGE = (0.9, 1.1)
#: Length of each wheel's response kept, s.
RESPONSE_S = 0.8
#: Step of the coarse search, s.
COARSE_S = 4e-3
#: Window of the first (left or only side's front) arrival around the first detected burst, s.
FIRST_WINDOW_S = (-0.35, 0.6)
_STEP_S = 1e-3
#: Half-width of a search near an earlier timing, s.
NEAR_S = 0.03
#: Per-axle stiffness multipliers of :func:`scaled_timing`.
STIFFNESS_MULTIPLIERS = (0.55, 0.8, 1.0, 1.25)
#: Front-to-rear ratio of the hubs' ringing frequencies (waveform fits) above which the front hubs are taken
#: to possibly ring in a pivoting axle's roll mode.
RING_RATIO = 2.0


def body_hypotheses(pb: TractorProblem) -> list[tuple[tuple, dict]]:
    """(body effects, dynamic indices) to try: the corners, and the coupled bodies the channels allow,
    each over a small grid of pitch and roll indices (the cross-talk, hence the timing, depends on them)."""
    out = [((), {})]
    if len(pb.channels) == 4:
        for body in (("axle_coupling", "roll_coupling"), ("axle_coupling", "roll_coupling", "front_axle_pivot")):
            out += [(body, dict(BODY_DEFAULTS, pitch_index=p, roll_index=r))
                    for p in PITCH_GRID for r in ROLL_GRID]
    elif pb.both_axles:
        out += [(("axle_coupling",), dict(BODY_DEFAULTS, pitch_index=p)) for p in PITCH_GRID]
    elif pb.both_sides:
        out += [(("roll_coupling",), dict(BODY_DEFAULTS, roll_index=r)) for r in ROLL_GRID]
    return out


def _tire_variants(pb: TractorProblem, start: dict, body: tuple, indices: dict) -> list[dict]:
    """k, c overrides to try under a body hypothesis: none; and under a pivoting front axle, the front tires'
    waveform k and c scaled by the pivot index.

    The front hubs of a pivoting axle ring mostly in the axle's roll mode, p m θ'' + c θ' + k θ = 0 (p the
    pivot index, m the corner mass): a fit of m z'' + c z' + k z = 0 to that ringing returns p⁻¹ k and
    p⁻¹ c (seen: 9-11x the front tires' k).  Tried for the front hubs that ring over RING_RATIO times
    faster than the rear ones (a tractor's front and rear tires ring at similar frequencies under their
    corners; a pivot index of 0.03-0.1 puts the roll mode at 3-6x): a softer front tire's slower response
    otherwise fits a footprint's gradual rise, or noise, about as well.
    """
    out = [{}]
    rears = [t for t in pb.channels if t not in FRONT_TIRES]
    if "front_axle_pivot" in body and rears:
        fastest_rear = max(start[f"k_{t}"] / pb.rec.mass_kg(t) for t in rears)
        ringing = [t for t in pb.channels if t in FRONT_TIRES and
                   start[f"k_{t}"] / pb.rec.mass_kg(t) > RING_RATIO ** 2 * fastest_rear]
        if ringing:
            p = indices["pivot_index"]
            out.append({f"{q}_{t}": start[f"{q}_{t}"] * p for t in ringing for q in "kc"})
    return out


def _responses(model: TractorFitModel, theta: dict, index: int, before: int, length: int) -> np.ndarray:
    """``H[w, c, j]``: channel c's low-passed response, at sample ``index - before + j``, to wheel w's cleat
    arriving at sample `index` (the other wheels off the cleat)."""
    pb, rec = model.problem, model.problem.rec
    t, fs = rec.time_s, rec.sample_rate_hz
    base = model.record(theta)
    m = len(pb.channels)
    stop = min(t.size, index - before + length)
    out = np.zeros((m, m, length))
    far = float(t[-1]) + 100.0
    for w in range(m):
        arrivals = tuple(float(t[index]) if j == w else far for j in range(m))
        record = dataclasses.replace(base, arrivals_s=arrivals)
        traj = run_model(record, *record.grid(float(t[index]) - (before / fs) - 0.1, float(t[stop - 1]) + 0.01,
                                              _STEP_S, 1.0 / fs))
        y = sensed_lowpassed(traj, t[:stop], fs, rec.acquisition, cutoff_hz=pb.cutoff_hz, tires=m)
        seg = y[:, index - before:stop]
        out[w, :, :seg.shape[1]] = seg
    return out


def _scaled(lin, energy):
    """The misfit less the measurement's energy with the responses' common scale fitted (>= 0): ``-L²/Q``
    for the correlation ``L`` and the responses' energy ``Q``; 0 where ``L <= 0`` (the scale 0); inf where
    ``L`` is not finite (an arrival outside the record)."""
    lin, energy = np.asarray(lin, dtype=float), np.asarray(energy, dtype=float)
    ok = (lin > 0) & (energy > 0)
    out = np.where(ok, -np.square(np.where(ok, lin, 0.0)) / np.where(ok, energy, 1.0), 0.0)
    return np.where(np.isfinite(lin), out, np.inf)


def _score(lin, energy, fit_scale):
    """The misfit less the measurement's energy: ``Q - 2 L``, or with `fit_scale` :func:`_scaled`'s."""
    return _scaled(lin, energy) if fit_scale else np.asarray(energy - 2 * np.asarray(lin, dtype=float))


def _coarse_min(energy, crossed, front, back, fit_scale):
    """The first minimum, in (stagger, delay, arrival) order, of the coarse scores for
    ``L = front[s, i] + back[s, d + i]`` and ``Q = energy + crossed[s, d]``: ``Q - 2 L`` (the responses as
    they are), or with `fit_scale` :func:`_scaled`'s ``-L²/Q``: (score, s, d, i) indices, score inf if none
    is finite.  Compiled with numba (one pass, no temporaries; the same operations as the array form)."""
    best, bs, bd, bi = math.inf, 0, 0, 0
    for s in range(front.shape[0]):
        for d in range(crossed.shape[1]):
            q = energy + crossed[s, d]
            for i in range(front.shape[1]):
                lin = front[s, i] + back[s, d + i]
                if not fit_scale:
                    v = q - 2 * lin
                elif not math.isfinite(lin):
                    continue
                else:
                    v = -(lin * lin) / q if lin > 0 and q > 0 else 0.0
                if v < best:
                    best, bs, bd, bi = v, s, d, i
    return best, bs, bd, bi


def _coarse_min_arrays(energy, crossed, front, back, fit_scale):
    """:func:`_coarse_min` with numpy arrays (without numba)."""
    pos = np.arange(crossed.shape[1])[:, None] + np.arange(front.shape[1])[None, :]
    sc = _score(front[:, None, :] + back[:, pos], energy + crossed[:, :, None], fit_scale)
    j = int(np.argmin(np.where(np.isnan(sc), np.inf, sc)))
    return (float(sc.flat[j]),) + tuple(int(k) for k in np.unravel_index(j, sc.shape))


try:
    from .._compile import njit
    _coarse_min = njit()(_coarse_min)
except ImportError:   # pragma: no cover - numba is a dependency
    _coarse_min = _coarse_min_arrays


def _search(pb: TractorProblem, H: np.ndarray, before: int, near=None,
            fit_scale: bool = False) -> tuple[float, int, int, int]:
    """Best (score, first arrival index, stagger, delay in samples) for responses `H`; with `near`
    ((arrival, stagger, delay) in samples, (arrival, stagger, delay) half-widths in samples) only there."""
    rec = pb.rec
    fs, n = rec.sample_rate_hz, rec.time_s.size
    m, _, length = H.shape
    right = np.array([pb.both_sides and c in ("FR", "RR") for c in pb.channels], dtype=int)
    rear = np.array([pb.both_axles and c not in FRONT_TIRES for c in pb.channels], dtype=int)
    y = np.stack([pb.measured[c] for c in pb.channels])
    ypad = np.concatenate([y, np.zeros((m, length))], axis=1)
    # linear terms: lin[w, a] = Σ_c <y_c, H[w, c](· − a)>, arrival a = sample index (the response starts `before` earlier)
    lin = np.full((m, n), -np.inf)
    for w in range(m):
        corr = fftconvolve(ypad, H[w, :, ::-1], mode="valid", axes=1).sum(axis=0)   # index: a − before
        a = np.arange(n)
        ok = (a - before >= 0) & (a - before < corr.size)
        lin[w, ok] = corr[a[ok] - before]
    # cross terms: cross[w, v][lag + length − 1] = Σ_c Σ_j H[w, c, j] H[v, c, j − lag], lag = a_v − a_w
    cross = {(w, v): fftconvolve(H[w], H[v, :, ::-1], mode="full", axes=1).sum(axis=0)
             for w in range(m) for v in range(w + 1, m)}
    energy = float(sum(np.sum(H[w] ** 2) for w in range(m)))

    def q(w, v, lag):   # Q_wv at integer lags (array), zero beyond the responses' length
        lag = np.asarray(lag)
        out = np.zeros(lag.shape)
        ok = np.abs(lag) < length
        out[ok] = cross[(w, v)][lag[ok] + length - 1]
        return out

    nominal = rec.rear_axle_delay_s()
    # the first arrival searched is the left (or only side's) front wheel's, or with no front channel the
    # rear one's: around the earliest onset, a rear onset moved back by the delay only if `d` adds it
    first = int(round((min(pb.onsets[c] - (nominal if rear[w] else 0.0) for w, c in enumerate(pb.channels))
                       - rec.time_s[0]) * fs))

    # lin padded by n on either side (-inf: outside the record), so that shifted indices need no clipping
    linpad = np.concatenate([np.full((m, n), -np.inf), lin, np.full((m, n), -np.inf)], axis=1)

    def at(w, idx):   # lin[w, idx], -inf outside the record (|idx| within n of it)
        return linpad[w, np.asarray(idx) + n]

    def cross_at(s, d):   # zero with a single channel (no pair)
        return sum((2 * q(w, v, (right[v] - right[w]) * s + (rear[v] - rear[w]) * d) for (w, v) in cross),
                   np.zeros(np.broadcast(s, d).shape))

    def score(i, s, d):   # arrays broadcast: i first arrival, s stagger, d delay (samples)
        if fit_scale:
            return _scaled(sum((at(w, i + right[w] * s + rear[w] * d) for w in range(m)), 0.0),
                           energy + cross_at(s, d))
        total = energy + cross_at(s, d)
        for w in range(m):
            total = total - 2 * at(w, i + right[w] * s + rear[w] * d)
        return total

    step = max(1, int(round(COARSE_S * fs)))
    lo_hi = [(first + int(FIRST_WINDOW_S[0] * fs), first + int(FIRST_WINDOW_S[1] * fs)),
             (-int(MAX_STAGGER_S * fs), int(MAX_STAGGER_S * fs)),
             (int(DELAY_RANGE[0] * nominal * fs), int(DELAY_RANGE[1] * nominal * fs))]
    if near is not None:
        lo_hi = [(max(lo, c - w), min(hi, c + w)) for (lo, hi), c, w in zip(lo_hi, *near)]
    i_range = np.arange(max(0, lo_hi[0][0]), min(n, lo_hi[0][1] + 1), step)
    s_range = np.arange(lo_hi[1][0], lo_hi[1][1] + 1, step) if pb.both_sides else np.zeros(1, int)
    d_range = np.arange(lo_hi[2][0], lo_hi[2][1] + 1, step) if pb.both_axles else np.zeros(1, int)
    # every stagger at once, scores[s, d, i] (the per-stagger loop's operations in its order, so the first
    # minimum in (stagger, delay, arrival) order is the same).  Arrival and delay share the coarse step, so
    # the rear arrivals i + d lie on one lattice, lattice[ii + di]: the rear terms are gathered there only.
    shifted = s_range[:, None]
    front = sum((at(w, i_range[None, :] + right[w] * shifted) for w in range(m) if not rear[w]),
                np.zeros((s_range.size, i_range.size)))
    lattice = i_range[0] + d_range[0] + step * np.arange(i_range.size + d_range.size - 1)
    back = sum((at(w, np.minimum(lattice, n)[None, :] + right[w] * shifted) for w in range(m) if rear[w]),
               np.zeros((s_range.size, lattice.size)))
    back[:, lattice >= n] = -np.inf                                      # beyond the record
    crossed = cross_at(s_range[:, None], d_range[None, :])               # (stagger, delay)
    value, si, di, ii = _coarse_min(float(energy), crossed, front, back, bool(fit_scale))
    best = (math.inf, 0, 0, 0)
    if math.isfinite(value):
        best = (float(value), int(i_range[ii]), int(s_range[si]), int(d_range[di]))
    # refine at the sampling grid
    _, i0, s0, d0 = best
    around = np.arange(-step, step + 1)
    ii, ss, dd = np.meshgrid(i0 + around, s0 + (around if pb.both_sides else 0),
                             d0 + (around if pb.both_axles else 0), indexing="ij")
    sc = score(ii, ss, dd)
    j = int(np.argmin(sc))
    return float(sc.flat[j]), int(ii.flat[j]), int(ss.flat[j]), int(dd.flat[j])


def joint_timing(pb: TractorProblem, start: dict, footprint_m: float = 0.0, hypotheses=None,
                 near: dict | None = None, fit_scale: bool = False) -> dict:
    """Arrival, stagger and delay of every channel at once, with the body's cross-talk.

    Parameters
    ----------
    pb : TractorProblem
    start : dict
        ``k_<TIRE>``, ``c_<TIRE>`` per channel.
    footprint_m : float
        Footprint of the tires enveloping the cleat (0: point contact).
    hypotheses : list of (tuple, dict), optional
        Body hypotheses (effects, indices) to try (default: :func:`body_hypotheses`).
    near : dict, optional
        A timing found before (``arrival``, ``stagger``, ``delay``, s): search only near it, the arrival
        within the footprint's passage time (at least NEAR_S), stagger and delay within NEAR_S.  A
        footprint moves every wheel's arrival alike; a search of its own would let start values that fit
        the point-contact response poorly pull the footprint's smoother response elsewhere.
    fit_scale : bool
        Fit the responses' common scale for every timing (see the module's notes).

    Returns
    -------
    dict
        ``arrival`` (the left or only side's front arrival, s), ``stagger``
        (right minus left, s) with both sides, ``delay`` (rear minus front, s)
        with both axles, and ``body``: the hypothesis that fitted best, as
        ``(effects, indices)``; ``front_tires`` (k, c of the front tires) when that hypothesis fitted best
        with the front tires' values scaled to a pivoting axle's roll mode (:func:`_tire_variants`);
        ``score``: the squared misfit less the measurement's energy (comparable between calls on one
        problem with the same `fit_scale`).
    """
    rec = pb.rec
    fs, t = rec.sample_rate_hz, rec.time_s
    lead = footprint_m / 2 / rec.speed_m_s
    before = int(math.ceil((lead + 0.02) * fs))
    length = before + int(round(RESPONSE_S * fs))
    index = min(t.size - 1, before + int(math.ceil(0.1 * fs)))
    window = None
    if near is not None:
        centre = (int(round((near["arrival"] - t[0]) * fs)), int(round(near.get("stagger", 0.0) * fs)),
                  int(round(near.get("delay", 0.0) * fs)))
        half = (int(round(max(NEAR_S, footprint_m / rec.speed_m_s) * fs)), int(round(NEAR_S * fs)),
                int(round(NEAR_S * fs)))
        window = (centre, half)
    best = None
    for body, indices in (hypotheses or body_hypotheses(pb)):
        effects = body + (("enveloping",) if footprint_m else ())
        model = TractorFitModel(effects, pb)
        for scaled in _tire_variants(pb, start, body, indices):
            theta = {name: {**start, **scaled}.get(name, indices.get(name, 0.0)) for name in model.names}
            for name in model.names:
                if name.startswith("footprint_"):
                    theta[name] = footprint_m
            H = _responses(model, theta, index, before, length)
            found = _search(pb, H, before, window, fit_scale)
            if best is None or found[0] < best[0][0]:
                best = (found, (body, indices), scaled)
    (score, i, s, d), body, scaled = best
    out = {"arrival": float(t[i]), "score": score}
    if scaled:
        out["front_tires"] = scaled
    if pb.both_sides:
        out["stagger"] = float(s / fs)
    if pb.both_axles:
        out["delay"] = float(d / fs)
    out["body"] = body
    return out


def scaled_timing(pb: TractorProblem, start: dict, footprint_m: float, hypotheses=None,
                  multipliers=STIFFNESS_MULTIPLIERS) -> dict:
    """The timing (:func:`joint_timing`) with each axle's k scaled over `multipliers` (c keeping its damping
    ratio): the best-scoring, with the scaled k, c as ``tires``.  About 16x the cost of one search.

    A tire's waveform fit can be far off under a coupled body (seen: a rear k twice the rig's), and a
    response ringing at the wrong frequency then matches a wrong arrival better than the right one; scaled
    to the right frequency, the impacts fall into place.
    """
    best = None
    fronts = any(t in FRONT_TIRES for t in pb.channels)
    rears = any(t not in FRONT_TIRES for t in pb.channels)
    for mf in (multipliers if fronts else (1.0,)):
        for mr in (multipliers if rears else (1.0,)):
            tires = {}
            for t in pb.channels:
                m = mf if t in FRONT_TIRES else mr
                tires[f"k_{t}"], tires[f"c_{t}"] = start[f"k_{t}"] * m, start[f"c_{t}"] * math.sqrt(m)
            found = joint_timing(pb, {**start, **tires}, footprint_m, hypotheses=hypotheses)
            tires.update(found.pop("front_tires", None) or {})
            if best is None or found["score"] < best["score"]:
                best = dict(found, tires=tires)
    return best
