"""Starting values of the whole-tractor fit: each tire's k, c and its own cleat arrival.

A tire's channel also shows the other tires' impacts through the body, so its
first burst is not necessarily its own impact.  Each channel's own arrival is
found by scanning a single corner (the tire under its corner mass, k and c from
the waveform fit) over the span from 50 ms before the channel's first burst
to 250 ms after it and keeping the best fit around the impact; the
left/right stagger and the front/rear delay follow from the four arrivals.
"""

from __future__ import annotations

import math

import numpy as np

from .. import tire_law
from ..acquisition import sensed_acceleration
from ..errors import InputError
from ..identify import identify_paper
from ..model import Body, Cleat, TractorModel
from ..model.kernels import run_model
from ..preprocess import lowpass, preprocess
from ..recording import FRONT_TIRES
from ..waveform import identify_waveform
from .tractor import UNLOADED_RADIUS_M, TractorProblem

__all__ = ["tire_start", "arrival_scan", "starting_values"]

_SCAN_BEFORE_S = 0.03
_SCAN_AFTER_S = 0.2
_SCAN_STEP_S = 1e-3
_SCORE_SPAN_S = 0.3


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


def _corner(pb: TractorProblem, tire: str, k: float, c: float, arrival: float, footprint_m: float) -> np.ndarray:
    rec = pb.rec
    p = dict(tire_law.EXTENDED_DEFAULTS)
    p.update(stiffness=k, damping=c, unloaded_radius=UNLOADED_RADIUS_M, static_load=rec.wheel_load_N[tire])
    if footprint_m:
        p.update(footprint_length=footprint_m, cleat_height=rec.cleat_height_m, cleat_width=rec.cleat_width_m)
    record = TractorModel(Body((tire,), (rec.wheel_load_N[tire],), rec.wheelbase_m), (p,),
                          Cleat(rec.cleat_height_m, rec.cleat_width_m, rec.speed_m_s), (arrival,))
    start = pb.onsets[tire] - _SCAN_BEFORE_S - 0.1
    grid = record.grid(start, min(rec.time_s[-1], pb.onsets[tire] + _SCAN_AFTER_S + _SCORE_SPAN_S) + 0.01,
                       _SCAN_STEP_S)
    traj = run_model(record, *grid)
    fs = rec.sample_rate_hz
    return lowpass(sensed_acceleration(traj, 0, rec.time_s, fs, rec.acquisition), sample_rate_hz=fs,
                   cutoff_hz=pb.cutoff_hz)


def _impact_sse(pb: TractorProblem, tire: str, k: float, c: float, arrival_s: float, footprint_m: float) -> float:
    """The corner's squared misfit around its impact at `arrival_s`, less the measurement's energy there."""
    t = pb.rec.time_s
    meas = pb.measured[tire]
    lead = footprint_m / 2 / pb.rec.speed_m_s
    sel = (t >= arrival_s - lead - 0.02) & (t <= arrival_s + lead + pb.rec.cleat_width_m / pb.rec.speed_m_s + 0.06)
    pred = _corner(pb, tire, k, c, arrival_s, footprint_m)
    return float(np.sum((pred[sel] - meas[sel]) ** 2) - np.sum(meas[sel] ** 2))   # gain over zero model


def arrival_scan(pb: TractorProblem, tire: str, k: float, c: float, footprint_m: float = 0.0) -> float:
    """The channel's own cleat arrival (s): the corner's best fit near the channel's first burst.

    With `footprint_m` the corner envelops the cleat (its impact starts half a
    footprint before the arrival).
    """
    onset = pb.onsets[tire]
    best, best_sse = onset, math.inf
    for shift in np.arange(-_SCAN_BEFORE_S, _SCAN_AFTER_S + 1e-9, _SCAN_STEP_S):
        arr = onset + shift + footprint_m / 2 / pb.rec.speed_m_s
        sse = _impact_sse(pb, tire, k, c, arr, footprint_m)
        if sse < best_sse:
            best, best_sse = arr, sse
    return best


def starting_values(pb: TractorProblem) -> dict:
    """k, c per channel and the arrival, stagger and delay, from per-channel fits and scans.

    The timing is found twice: for point contact, and for a tire enveloping
    the cleat with a typical 0.3 m footprint (``enveloped`` holds the latter,
    the start of models with ``enveloping``).
    """
    start = {}
    for tire in pb.channels:
        k, c = tire_start(pb, tire)
        start[f"k_{tire}"], start[f"c_{tire}"] = k, max(c, 50.0)
    start.update(_timing(pb, start, 0.0))
    start["enveloped"] = _timing(pb, start, ENVELOPE_GUESS_M)
    return start


#: Footprint of the enveloping start, m.
ENVELOPE_GUESS_M = 0.3


def _timing(pb: TractorProblem, start: dict, footprint_m: float) -> dict:
    rec = pb.rec
    own = {t: arrival_scan(pb, t, start[f"k_{t}"], start[f"c_{t}"], footprint_m) for t in pb.channels}
    start = {}
    # arrival, stagger and delay from the own arrivals, least squares (exact with three channels or fewer)
    names = ["arrival"] + (["stagger"] if pb.both_sides else []) + (["delay"] if pb.both_axles else [])
    A = np.array([[1.0] + ([1.0 * (t in ("FR", "RR"))] if pb.both_sides else [])
                  + ([1.0 * (t not in FRONT_TIRES)] if pb.both_axles else []) for t in pb.channels])
    sol = np.linalg.lstsq(A, np.array([own[t] for t in pb.channels]), rcond=None)[0]
    start.update(dict(zip(names, map(float, sol))))
    nominal = rec.rear_axle_delay_s()
    if pb.both_axles and not 0.8 * nominal <= start["delay"] <= 1.2 * nominal:
        start["delay"] = nominal
    return start


_MULTIPLIERS = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.15, 1.3, 1.6)


def body_start(model, start: dict, *, step_s: float) -> dict:
    """Starting values for a model that adds a body coupling: a scan of per-axle stiffness multipliers.

    The corners' k absorb the body's motion (a front tire under a pitching body
    rings at another frequency than under its corner mass), so a body model
    started from them sits far from its optimum; k of each axle is scaled
    together (c keeps its damping ratio), and the front-axle roll index, when
    new, is scanned over a decade, before the least-squares fit.
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
    for mf in (_MULTIPLIERS if fronts else (1.0,)):
        for mr in (_MULTIPLIERS if rears else (1.0,)):
            trial = scaled(mf, mr)
            try:
                sse = sse_of(model, trial, step_s)
            except (ValueError, FloatingPointError, np.linalg.LinAlgError):
                continue
            if sse < best_sse:
                best, best_sse = trial, sse
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
