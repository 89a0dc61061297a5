"""Physical evidence for each effect: a gate the fitted model must pass, and a sentence to check.

An information criterion alone would name an effect whenever its extra
parameters absorb some systematic misfit (the acquisition's anti-alias filter
at the impact, say).  Each effect is therefore also required to show itself
the way physics says it must:

``enveloping``
    a footprint (parabolic contact pressure) of at least 0.1 m (a tractor tire's is
    0.25-0.5 m), its 95 % interval above 0.05 m;
``lift_off``
    the fitted unilateral model loses contact for at least 15 ms, and there
    the measured hub is in free fall: its mean acceleration within 20 % of -g;
``axle_coupling``
    the other axle's impact shows in this channel (the residual of the model
    being extended stands above 5 times the noise around it), the
    half-tractor explains at least 30 % of that (the rest may be roll, which
    a half-tractor does not have), and its pitch dynamic index
    differs from 1 (at 1 the axles decouple) by at least 0.05, its interval
    excluding 1;
``nonlinear_stiffness``
    the exponent differs from 1 by at least 0.08, its interval excluding 1;
``friction_damping``
    a friction force of at least 30 N, its interval excluding 0;
``periodic_disturbance``
    a spectral line at the fitted frequency in the residual of the
    point-contact fit, at least 8 times the spectral floor around it, and
    present at half that amplitude or more before the impact (steady state).
"""

from __future__ import annotations

import numpy as np

from ..recording import STANDARD_GRAVITY
from .fit import Fit
from .models import Problem

__all__ = ["check", "contact_loss_intervals", "spectral_line"]


def contact_loss_intervals(fit: Fit) -> list[tuple[float, float]]:
    """Where the fitted model's tire carries no load, as (start s, end s)."""
    traj = fit.model.simulate(fit.params)
    f = traj.force_n[fit.model.tire_index()]
    free = f == 0.0
    edges = np.flatnonzero(np.diff(free.astype(int)))
    out, t = [], traj.time_s
    start = t[0] if free[0] else None
    for e in edges:
        if free[e + 1]:
            start = t[e + 1]
        elif start is not None:
            out.append((float(start), float(t[e])))
            start = None
    if start is not None:
        out.append((float(start), float(t[-1])))
    return out


def spectral_line(signal, sample_rate_hz: float, frequency_hz: float) -> tuple[float, float]:
    """Amplitude (signal units) of the line at `frequency_hz` and its ratio to the surrounding floor."""
    x = np.asarray(signal, dtype=float)
    if x.size < 32:
        return 0.0, 0.0
    x = (x - x.mean()) * np.hanning(x.size)
    n = max(1 << 16, 1 << int(np.ceil(np.log2(4 * x.size))))
    spec = np.abs(np.fft.rfft(x, n)) * 2 / np.sum(np.hanning(x.size))
    f = np.fft.rfftfreq(n, 1 / sample_rate_hz)
    resolution = 2 * sample_rate_hz / x.size
    near = np.abs(f - frequency_hz) <= resolution
    ring = (np.abs(f - frequency_hz) > 2 * resolution) & (np.abs(f - frequency_hz) < 8 * resolution + 2.0)
    if not near.any() or not ring.any():
        return 0.0, 0.0
    line = float(spec[near].max())
    return line, line / max(float(np.median(spec[ring])), 1e-12)


def _fmt_ci(fit: Fit, name: str, fmt: str, unit: str, scale: float = 1.0) -> str:
    lo, hi = fit.ci[name]
    value = format(fit.params[name] * scale, fmt) + (f" {unit}" if unit else "")
    return f"{value} ({format(lo * scale, fmt)}-{format(hi * scale, fmt)})"


def check(effect: str, fit: Fit, base: Fit, pb: Problem) -> tuple[bool, str]:
    """Whether `fit` (a model with `effect`) shows the effect physically, and the evidence sentence.

    `base` is the model `fit` extends (the baseline in the first round).
    """
    return _CHECKS[effect](fit, base, pb)


def _enveloping(fit, base, pb):
    lo, _ = fit.ci["footprint"]
    ell = fit.params["footprint"]
    rec, t = pb.rec, pb.rec.time_s
    duration = (ell + rec.cleat_width_m) / rec.speed_m_s
    start = fit.params["arrival"] - ell / 2 / rec.speed_m_s
    impact = (t >= start) & (t <= start + duration + 0.05)
    meas_peak = float(np.max(np.abs(pb.measured[impact]))) if impact.any() else float("nan")
    point_peak = float(np.max(np.abs(base.prediction[impact]))) if impact.any() else float("nan")
    text = (f"footprint (parabolic contact pressure) {_fmt_ci(fit, 'footprint', '.3f', 'm')}: the cleat is felt for "
            f"(footprint + width) / speed = {duration * 1e3:.0f} ms from t = {start:.3f} s, the impact peaks at "
            f"{meas_peak:.1f} m/s^2 where point contact predicts {point_peak:.1f} m/s^2")
    return ell >= 0.1 and lo >= 0.05, text


def _lift_off(fit, base, pb):
    intervals = contact_loss_intervals(fit)
    total = sum(b - a for a, b in intervals)
    if not intervals:
        return False, "the fitted unilateral tire never loses contact"
    a, b = max(intervals, key=lambda ab: ab[1] - ab[0])
    t = pb.rec.time_s
    inner = (t >= a + 0.01) & (t <= b - 0.01)
    if inner.sum() < 3:
        inner = (t >= a) & (t <= b)
    mean_g = float(np.mean(pb.measured[inner])) / STANDARD_GRAVITY if inner.any() else float("nan")
    text = (f"hub at {mean_g:.2f} g for {(b - a) * 1e3:.0f} ms from t = {a:.3f} s "
            f"(contact lost {len(intervals)}x, {total * 1e3:.0f} ms in all)")
    return total >= 0.015 and abs(mean_g + 1.0) <= 0.2, text


def _axle_coupling(fit, base, pb):
    rec, t = pb.rec, pb.rec.time_s
    delay = rec.rear_axle_delay_s()
    other_impact = pb.sig.impact_s + (delay if pb.front else -delay)
    sel = (t >= other_impact - 0.02) & (t <= other_impact + 0.6)
    if sel.sum() < 5:
        return False, "the other axle's impact is outside the record"
    meas = pb.measured[sel]
    resid_base = meas - base.prediction[sel]
    resid_fit = meas - fit.prediction[sel]
    shown = float(np.sqrt(np.mean(resid_base ** 2))) / pb.noise
    explained = 1.0 - float(np.sum(resid_fit ** 2)) / max(float(np.sum(resid_base ** 2)), 1e-12)
    lo, hi = fit.ci["dynamic_index"]
    coupled = abs(fit.params["dynamic_index"] - 1.0) >= 0.05 and not (lo <= 1.0 <= hi)
    which = "rear" if pb.front else "front"
    text = (f"the {which} axle's impact at t = {other_impact:.3f} s shows in {pb.tire}: "
            f"{float(np.max(np.abs(resid_base))):.2f} m/s^2 peak ({shown:.0f}x the noise RMS), "
            f"{max(explained, 0):.0%} of it explained by a half-tractor with pitch dynamic index "
            f"{_fmt_ci(fit, 'dynamic_index', '.2f', '')}")
    return shown >= 5.0 and explained >= 0.3 and coupled, text


def _nonlinear(fit, base, pb):
    lo, hi = fit.ci["exponent"]
    n = fit.params["exponent"]
    text = (f"stiffness exponent {_fmt_ci(fit, 'exponent', '.2f', '')}: the elastic force grows as "
            f"deflection^{n:.2f}, so the period changes with amplitude")
    return abs(n - 1.0) >= 0.08 and not (lo <= 1.0 <= hi), text


def _friction(fit, base, pb):
    lo, _ = fit.ci["friction"]
    fc = fit.params["friction"]
    k = fit.params["k"]
    text = (f"friction force {_fmt_ci(fit, 'friction', '.0f', 'N')} beside the damper: the peaks decay by "
            f"about 4 F_c / k = {4 * fc / k * 1e3:.1f} mm of hub travel per cycle, a linear rather than "
            f"exponential envelope")
    return fc >= 30.0 and lo > 0.0, text


def _periodic(fit, base, pb):
    f = fit.params["lug_frequency"]
    window = pb.window
    residual = (pb.measured - base.prediction)[window]
    amp, ratio = spectral_line(residual, pb.rec.sample_rate_hz, f)
    t = pb.rec.time_s
    pre = t < pb.first_impact_s - 0.05
    pre_amp, _ = spectral_line(pb.rec.accel_m_s2[pb.tire][pre], pb.rec.sample_rate_hz, f)
    pitch = pb.rec.speed_m_s / f
    text = (f"{f:.2f} Hz line of {amp:.2f} m/s^2 all through the point-contact fit's residual ({ratio:.0f}x the "
            f"spectral floor), {pre_amp:.2f} m/s^2 already before the impact: steady, at speed / {pitch:.3f} m "
            f"(lug passing)")
    return ratio >= 8.0 and pre_amp >= 0.5 * amp, text


_CHECKS = {"enveloping": _enveloping, "lift_off": _lift_off, "axle_coupling": _axle_coupling,
           "nonlinear_stiffness": _nonlinear, "friction_damping": _friction, "periodic_disturbance": _periodic}
