"""What the channels' own free decays say about the tires' laws, for the whole-tractor evidence.

Each channel's free decay (the waveform fit's window, :func:`~identification.identify.waveform.identify_waveform`)
is fitted once per problem (:func:`free_decays`, kept for the problem's life).  Two questions are asked of it:

* does it decay viscously (``friction_damping``: :func:`~identification.diagnose.joint_evidence.viscous_decays`);
* what stiffness exponent its second harmonic gives (``nonlinear_stiffness``:
  :func:`~identification.identify.decay_exponent.decay_exponent`).  A progressive elastic law rings with a
  second harmonic in phase with the square of the fundamental, its size set by the exponent and the
  amplitude in g alone; a linear tire rings without one.  Only decays one damped mode explains
  (R² >= :data:`~identification.identify.waveform.ONE_MODE_R2`) count, and only on independent corners (no
  body named: under a coupled body a channel rings with the body's modes, and the relation is a corner's).

:func:`pooled_exponent` pools the channels' u = (n - 1) / n by inverse variance, each half-width widened by
the Birge ratio where the channels disagree beyond their intervals (the tires' exponents differ).
:func:`harmonic_share` is the share of the decays' in-phase second harmonic that a fit's prediction
explains beyond a base model's: the exponent's effect where it acts alone, measured there.
"""

from __future__ import annotations

import math
import weakref

import numpy as np

from ..errors import InputError
from ..identify.decay_exponent import decay_exponent, harmonic_exponent
from ..identify.waveform import ONE_MODE_R2, identify_waveform
from ..model.fitting import BODY_EFFECTS
from ..recording.preprocess import preprocess

__all__ = ["free_decays", "decay_exponents", "pooled_exponent", "harmonic_share", "exponent_evidence"]

#: The decays call a law other than linear where their pooled exponent differs from 1 by this much (the joint
#: fit's gate asks the same of its exponent), its interval excluding 1.  On the independent simulator's tuning
#: corners, the linear bristle-bed tires' decays gave 0.84-1.11 (pooled per recording: within 0.08 of 1), a few
#: of them with intervals just off 1.
MIN_EXPONENT_SHIFT = 0.08

_DECAYS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def free_decays(pb) -> dict:
    """{channel: (TireSignal, WaveformResult)} of every channel of problem `pb` whose free decay can be
    fitted (computed once per problem)."""
    found = _DECAYS.get(pb)
    if found is None:
        found = {}
        for tire in pb.channels:
            try:
                sig = preprocess(pb.rec, [tire], cutoff_hz=pb.cutoff_hz, min_peaks=1)[tire]
                found[tire] = sig, identify_waveform(sig, pb.rec.mass_kg(tire), source=pb.rec.source)
            except (InputError, ValueError, FloatingPointError, np.linalg.LinAlgError):
                continue
        _DECAYS[pb] = found
    return found


def decay_exponents(pb) -> dict:
    """{channel: DecayExponent} of the decays one damped mode explains."""
    out = {}
    for tire, (sig, wave) in free_decays(pb).items():
        if wave.r2 < ONE_MODE_R2:
            continue
        try:
            est = decay_exponent(sig, wave)
        except (ValueError, np.linalg.LinAlgError):
            continue
        if est is not None and math.isfinite(est.u) and est.u_half > 0:
            out[tire] = est
    return out


def pooled_exponent(estimates) -> tuple[float, float] | None:
    """(u, 95 % half-width of u) pooled over `estimates` (DecayExponent), u = (n - 1) / n, or None."""
    est = list(estimates)
    if not est:
        return None
    w = np.array([1.0 / e.u_half ** 2 for e in est])
    u = np.array([e.u for e in est])
    mean = float(np.sum(w * u) / np.sum(w))
    half = float(1.0 / math.sqrt(np.sum(w)))
    if len(est) > 1:   # Birge ratio: chi² per degree of freedom, with the half-widths as 1.96 sigma
        chi2 = float(np.sum(w * (u - mean) ** 2)) * 1.96 ** 2
        half *= math.sqrt(max(1.0, chi2 / (len(est) - 1)))
    return mean, half


def _n(u: float) -> float:
    return 1.0 / (1.0 - u) if u < 1.0 else math.inf


def exponent_evidence(pb, effects) -> tuple[str, tuple | None, dict]:
    """What the free decays say of a progressive (or degressive) elastic law under a model with `effects`.

    Returns
    -------
    (verdict, pooled, estimates)
        verdict ``"no decay"`` (a body named, or no decay one mode explains), ``"linear"`` (the pooled
        interval holds n = 1, or n lies within :data:`MIN_EXPONENT_SHIFT` of it) or ``"progressive"`` /
        ``"degressive"``; pooled (u, half-width) or None; the
        per-channel estimates.
    """
    if any(e in BODY_EFFECTS for e in effects):
        return "no decay", None, {}
    est = decay_exponents(pb)
    pooled = pooled_exponent(est.values())
    if pooled is None:
        return "no decay", None, est
    u, half = pooled
    n = _n(u)
    if u - half <= 0.0 <= u + half or abs(n - 1.0) < MIN_EXPONENT_SHIFT:
        return "linear", pooled, est
    return ("progressive" if u > 0 else "degressive"), pooled, est


def pooled_text(pooled, est: dict) -> str:
    """The decays' exponent in words: pooled n with its interval, and each channel's."""
    u, half = pooled
    lo, hi = _n(u - half), _n(u + half)
    each = ", ".join(f"{t} {e.n:.2f}" for t, e in est.items())
    return f"n = {_n(u):.2f} ({lo:.2f}-{hi:.2f}) from {len(est)} free decay(s) ({each})"


def harmonic_share(fit, base) -> float | None:
    """Share of the in-phase second harmonic of the decays (:func:`decay_exponents`) left by `base` that `fit`
    explains: 1 - Σ u_fit² / Σ u_base² (u of each residual, weighted by the decay's 1/half-width²), or None
    where no decay counts (a body named in `fit`'s model)."""
    pb = fit.model.problem
    if any(e in BODY_EFFECTS for e in fit.model.effects):
        return None
    est = decay_exponents(pb)
    if not est:
        return None
    t = pb.rec.time_s
    left = {"fit": 0.0, "base": 0.0}
    for tire, e in est.items():
        _, wave = free_decays(pb)[tire]
        sel = (t >= e.window_s[0]) & (t <= e.window_s[1])
        rate = dict(decay_rate_1_s=-wave.decay_rate, omega_d_rad_s=2 * math.pi / wave.T)
        for name, model in (("fit", fit), ("base", base)):
            # referred to the recorded decay's fundamental (the low-pass, zero-phase and far above the first two
            # harmonics, leaves both as they are)
            res = harmonic_exponent(t[sel], (pb.measured[tire] - model.prediction[tire])[sel],
                                    fundamental=e.fundamental, **rate)
            if res is None:
                return None
            left[name] += (res.u / e.u_half) ** 2
    return 1.0 - left["fit"] / left["base"] if left["base"] > 0 else None
