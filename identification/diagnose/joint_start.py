"""Starting values of the whole-tractor fit: each tire's k, c and its own cleat arrival.

k and c per channel come from the channel's own waveform fit; the arrivals
from one search over every channel with the body's cross-talk
(:mod:`~identification.diagnose.joint_timing`).  Models that add a body
coupling start from a scan of per-axle stiffness multipliers
(:func:`body_start`); the timing is refined at the final grid before each fit
(:func:`refine_timing`).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..identify.paper import identify_paper
from ..recording.preprocess import preprocess
from ..recording import FRONT_TIRES
from ..identify.waveform import identify_waveform
from .joint_timing import joint_timing, scaled_timing
from ..model.fitting import TractorProblem

__all__ = ["tire_start", "starting_values", "rescue_start", "enveloped_timings", "body_start", "refine_timing", "ENVELOPE_GUESS_M",
           "periodic_start"]

def tire_start(pb: TractorProblem, tire: str) -> tuple[float, float]:
    """k (N/m) and c (N s/m) of one channel from the waveform fit, the paper's method, or its frequency."""
    rec = pb.rec
    mass = rec.mass_kg(tire)
    try:
        sig = preprocess(rec, [tire], cutoff_hz=pb.cutoff_hz, min_peaks=0)[tire]
    except InputError:
        sig = None
    if sig is not None:
        for method in (identify_waveform, identify_paper):
            try:
                r = method(sig, mass, source=rec.source)
                if 0.3 < r.k / (mass * (2 * math.pi * pb.dominant_hz[tire]) ** 2) < 3 and r.c > 0:
                    return r.k, r.c
            except (InputError, ValueError):
                pass
    wn = 2 * math.pi * pb.dominant_hz[tire]
    return mass * wn * wn, 2 * 0.1 * mass * wn


def starting_values(pb: TractorProblem, *, fit_scale: bool = False) -> dict:
    """k, c per channel and the arrival, stagger and delay, from per-channel fits and a joint timing search.

    The timing (:func:`~identification.diagnose.joint_timing.joint_timing`) is
    found for point contact, and for tires enveloping the cleat with a typical
    footprint twice: freely (``enveloped``) and near the point-contact timing
    (``enveloped_near``; with start values far off, the footprint's smooth
    response can fit a wrong timing better).  Models with ``enveloping``
    start from whichever fits them better.  ``body`` and ``enveloped["body"]`` name the body
    hypothesis and dynamic indices that placed the arrivals best.  With `fit_scale`, every search fits the
    responses' common scale (:func:`~identification.diagnose.joint_timing.joint_timing`).
    """
    start = {}
    for tire in pb.channels:
        k, c = tire_start(pb, tire)
        start[f"k_{tire}"], start[f"c_{tire}"] = k, max(c, 50.0)
    # a pivoting front axle's roll mode misread as the front tires' own: a timing's scaled values, if any
    start.update(joint_timing(pb, start, 0.0, fit_scale=fit_scale))
    start.update(start.pop("front_tires", None) or {})
    near = joint_timing(pb, start, ENVELOPE_GUESS_M, near=start, fit_scale=fit_scale)
    start["enveloped"] = joint_timing(pb, start, ENVELOPE_GUESS_M, fit_scale=fit_scale)
    start["enveloped_near"] = near
    for timing in (near, start["enveloped"]):
        start.update(timing.pop("front_tires", None) or {})
    return start


def rescue_start(pb: TractorProblem, start: dict) -> dict:
    """Starting values again, the timings searched with each axle's k scaled
    (:func:`~identification.diagnose.joint_timing.scaled_timing`), for point contact and for enveloping
    tires; k, c from the better-scoring of the two.  About 30 times the cost of :func:`starting_values`'s
    searches (a few seconds)."""
    point = scaled_timing(pb, start, 0.0)
    enveloped = scaled_timing(pb, start, ENVELOPE_GUESS_M)
    out = {**start, **min(point, enveloped, key=lambda t: t["score"])["tires"]}
    out.update({k: v for k, v in point.items() if k != "tires"})
    out["enveloped"] = {k: v for k, v in enveloped.items() if k != "tires"}
    out.pop("enveloped_near", None)
    return out


def enveloped_timings(start: dict) -> list[dict]:
    """The timings found for tires enveloping the cleat: searched freely, and near the point-contact one."""
    return [start["enveloped"]] + ([start["enveloped_near"]] if "enveloped_near" in start else [])


#: Footprint of an enveloping start where none is scanned, m.
ENVELOPE_GUESS_M = 0.3
_MULTIPLIERS = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.15, 1.3, 1.6)


def body_start(model, start: dict, *, step_s: float) -> dict:
    """Starting values for a model that adds a body coupling: a scan of per-axle stiffness multipliers.

    The corners' k absorb the body's motion (a front tire under a pitching body
    rings at another frequency than under its corner mass), so a body model
    started from them sits far from its optimum; k of each axle is scaled
    together (c keeps its damping ratio) by the multipliers of
    :data:`_MULTIPLIERS`, one axle at a time (front, rear, front again), and
    the front-axle roll index, when new, is scanned over a decade, before the
    least-squares fit.
    """
    from .joint_fit import sse_of

    pb = model.problem
    best, best_sse = dict(start), sse_of(model, start, step_s)

    def scaled(mf, mr):
        s = dict(start)
        for t in pb.channels:
            m = mf if t in FRONT_TIRES else mr
            s[f"k_{t}"] = start[f"k_{t}"] * m
            s[f"c_{t}"] = start[f"c_{t}"] * math.sqrt(m)
        return s

    fronts = any(t in FRONT_TIRES for t in pb.channels)
    rears = any(t not in FRONT_TIRES for t in pb.channels)
    scores = {}

    def score(mf, mr):
        if (mf, mr) not in scores:
            try:
                scores[mf, mr] = sse_of(model, scaled(mf, mr), step_s)
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                scores[mf, mr] = math.inf
        return scores[mf, mr]

    # one axle's multiplier at a time, the other held at its best so far (front, rear, front again): the
    # axles' multipliers barely interact, and the fit that follows finishes the job; a third of the grid's runs
    mf, mr = 1.0, 1.0
    for axle in ("front", "rear", "front"):
        if not (fronts if axle == "front" else rears):
            continue
        if axle == "front":
            mf = min(_MULTIPLIERS, key=lambda m: (score(m, mr), abs(m - 1.0)))
        else:
            mr = min(_MULTIPLIERS, key=lambda m: (score(mf, m), abs(m - 1.0)))
    if score(mf, mr) < best_sse:
        best, best_sse = scaled(mf, mr), score(mf, mr)
    if "pivot_index" in model.names:
        for value in (0.02, 0.05, 0.1, 0.2, 0.5, 1.0):
            trial = dict(best, pivot_index=value)
            sse = sse_of(model, trial, step_s)
            if sse < best_sse:
                best, best_sse = trial, sse
    return best


def refine_timing(model, theta: dict, *, step_s: float | None = None, half_width_s: float = 0.004,
                  points: int = 17, sweeps: int = 2) -> dict:
    """Arrival, stagger and delay scanned one at a time (±`half_width_s`), the rest held.

    An impact is a sharp feature: a least-squares fit started a few
    milliseconds off settles on a neighbouring minimum, and the screening fits
    run on a coarser grid than the final ones; this puts the timing at the
    final grid's best before the fit.
    """
    from .joint_fit import sse_of

    best = dict(theta)
    best_sse = sse_of(model, best, step_s)
    for _ in range(sweeps):
        for name in ("arrival", "stagger", "delay"):
            if name not in model.names:
                continue
            centre = best[name]
            for shift in np.linspace(-half_width_s, half_width_s, points):
                trial = dict(best, **{name: centre + shift})
                sse = sse_of(model, trial, step_s)
                if sse < best_sse:
                    best, best_sse = trial, sse
    return best


def periodic_start(rec, tire: str, *, first_impact_s: float, cutoff_hz: float, k: float, c: float,
                   arrival: float, residual=None, window=None) -> dict | None:
    """Frequency, road amplitude and phase of a steady periodic component before the impact in one channel.

    The frequency is the pre-impact spectrum's peak; with the current model's `residual` over the fit
    `window` (a bool mask), it is refined to that residual's peak within ±:data:`LINE_REFINE` of it: the
    line runs all through the window, seconds against the fraction of a second before the impact, and a
    frequency 2 % off (0.4 Hz at 20 Hz) turns the line's phase by 2.5 rad a second, more than a fit started
    there repairs.
    """
    t = rec.time_s
    pre = t < first_impact_s - 0.05
    if pre.sum() < 0.2 * rec.sample_rate_hz:
        return None
    x = rec.accel_m_s2[tire][pre] - np.mean(rec.accel_m_s2[tire][pre])
    freq = _peak(x, rec.sample_rate_hz, 1.0, 0.45 * cutoff_hz)
    if residual is not None and window is not None and window.sum() > 2 * x.size:
        freq = _peak(residual[window] - np.mean(residual[window]), rec.sample_rate_hz,
                     (1 - LINE_REFINE) * freq, (1 + LINE_REFINE) * freq)
    w = 2 * np.pi * freq
    basis = np.column_stack([np.sin(w * t[pre]), np.cos(w * t[pre])])
    b1, b2 = np.linalg.lstsq(basis, x, rcond=None)[0]
    accel = b1 + 1j * b2                       # a(t) = Im(accel e^{jωt})
    m = rec.mass_kg(tire)
    H = (k + 1j * w * c) / (k - m * w * w + 1j * w * c)
    road = -accel / (w * w * H)
    return {"lug_amplitude": float(abs(road)), "lug_frequency": freq,
            "lug_phase": float(np.angle(road) + w * arrival)}


#: Relative band around the pre-impact peak where :func:`periodic_start` refines a line's frequency.
LINE_REFINE = 0.05


def _peak(x: np.ndarray, sample_rate_hz: float, low_hz: float, high_hz: float) -> float:
    """Frequency (Hz) of the largest Hann-windowed spectral peak of `x` between `low_hz` and `high_hz`."""
    n = max(1 << 16, 1 << int(np.ceil(np.log2(4 * x.size))))
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n))
    f = np.fft.rfftfreq(n, 1 / sample_rate_hz)
    band = (f >= low_hz) & (f <= high_hz)
    return float(f[band][np.argmax(spec[band])])
