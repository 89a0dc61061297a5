"""Physical evidence for each effect of the whole-tractor model: a gate, and a sentence a person can check.

``enveloping``          every fitted footprint ≥ 0.1 m, its interval above 0.05 m;
``lift_off``            the fitted model loses contact ≥ 15 ms on some tire, and the measured hub there
                        is near free fall (mean within 0.35 g of −1 g); a briefer loss (≥ 2 samples: a steep
                        bevel, a fast pass) counts when the hub falls freely and the unilateral tire removes
                        ≥ 50 % of its own channel's residual - or, on a coupled body (the other tires carry
                        the hub), the model explains ≥ 50 % of the residual over a loss of ≥ 15 ms;
``axle_coupling``       the other axle's impact shows in a channel (the extended model's residual there
                        ≥ 5× the noise), and the pitch index differs from 1 by ≥ 0.05, its interval excluding 1
                        (with ``roll_coupling``, the rigid body: the body explains ≥ 50 % of that cross-talk,
                        which at a pitch index of 1 travels through the shared roll alone);
``roll_coupling``       the other side's impact shows in a channel (≥ 5× the noise) and the roll index is
                        identified (interval within a factor 3); without ``axle_coupling`` (axle pairs) it
                        also differs by ≥ 0.05 from each axle's decoupling index 1 − ybar² (ybar the pair's
                        left/right load offset), its interval excluding it: at that index the pair is two
                        independent corners, and a gain there is a better fit of the current model;
``front_axle_pivot``    the front-axle roll index is identified (interval within a factor 10) and the front
                        channels' residual falls by ≥ 25 %;
``nonlinear_stiffness`` the exponent differs from 1 by ≥ 0.08, its interval excluding 1; on independent
                        corners not refuted by the channels' own free decays where any counts
                        (:func:`~identification.diagnose.decay_shape.exponent_evidence`: their second harmonic's
                        exponent, pooled, must lie on the same side of 1 by ≥ 0.08, its interval excluding 1);
``friction_damping``    a friction force ≥ 30 N, its interval excluding 0; on independent corners (no body
                        named) not refuted by the channels' own free decays: where two or more of them
                        ring long enough to tell (:func:`viscous_decays`) and every one of those decays
                        viscously, the damping does not grow as the amplitude falls, as friction's would;
``periodic_disturbance`` a spectral line at a fitted frequency in the residual ≥ 8× its floor, present at
                        half that amplitude or more before the impact (in the engine band, the sentence says
                        that a single engine line looks the same).

Where an effect acts on a narrow part of the data, :func:`local_gain` measures it there as well: for
``periodic_disturbance`` the share of the line's energy (in the channel where the line is strongest)
that the extended model removes; for ``nonlinear_stiffness`` the share of the free decays' in-phase second
harmonic (:func:`~identification.diagnose.decay_shape.harmonic_share`).  The selection accepts a candidate on
that share when the rest of the residual (a footprint of another shape, say) is too large for the overall
gain to show a steady line or a progressive law.
"""

from __future__ import annotations

import math

import numpy as np

from ..recording.condition import ENGINE_BAND_HZ
from ..recording import FRONT_TIRES, STANDARD_GRAVITY
from ..model.fitting import BODY_EFFECTS, axle_of
from .decay_shape import exponent_evidence, free_decays, harmonic_share, pooled_text
from .joint_fit import TractorFit

__all__ = ["check_tractor", "final_evidence", "contact_losses", "interval_text", "local_gain", "viscous_decays"]


def interval_text(value: float, lo: float, hi: float, decimals: int = 3, *, sep: str = "-") -> str:
    """``value (lo-hi)`` with at least `decimals` decimals and as many more (up to 9) as it takes for the
    ends of a non-empty interval to differ in print (never ``0.800 (0.800-0.800)``).

    Parameters
    ----------
    value, lo, hi : float
        The estimate and its interval.
    decimals : int
        Fewest decimals.
    sep : str
        Between the ends.
    """
    d = decimals
    if all(map(math.isfinite, (lo, hi))) and hi > lo:
        while d < 9 and f"{lo:.{d}f}" == f"{hi:.{d}f}":
            d += 1
    return f"{value:.{d}f} ({lo:.{d}f}{sep}{hi:.{d}f})"


def _ci(fit: TractorFit, name: str, fmt: str, unit: str = "") -> str:
    lo, hi = fit.ci[name]
    u = f" {unit}" if unit else ""
    if fmt.endswith("f") and fmt[1:-1].isdigit() and lo is not None and hi is not None:
        text = interval_text(fit.params[name], lo, hi, int(fmt[1:-1]))
        value, rest = text.split(" ", 1)
        return f"{value}{u} {rest}"
    return f"{format(fit.params[name], fmt)}{u} ({format(lo, fmt)}-{format(hi, fmt)})"


def contact_losses(fit: TractorFit) -> dict:
    """Per channel, where the fitted model's tire carries no load: [(start s, end s), ...]."""
    traj = fit.model.simulate(fit.params)
    out = {}
    for i, tire in enumerate(fit.model.problem.channels):
        free = traj.force_n[i] == 0.0
        edges = np.flatnonzero(np.diff(free.astype(int)))
        t, spans, start = traj.time_s, [], (traj.time_s[0] if free[0] else None)
        for e in edges:
            if free[e + 1]:
                start = t[e + 1]
            elif start is not None:
                spans.append((float(start), float(t[e])))
                start = None
        if start is not None:
            spans.append((float(start), float(t[-1])))
        out[tire] = spans
    return out


def _shows(fit: TractorFit, base: TractorFit, tire: str, at_s: float):
    """Peak and RMS-to-noise of `base`'s residual in `tire` around `at_s`, and the share `fit` explains."""
    pb = fit.model.problem
    t = pb.rec.time_s
    sel = (t >= at_s - 0.02) & (t <= at_s + 0.4) & pb.window
    if sel.sum() < 5:
        return 0.0, 0.0, 0.0
    rb = (pb.measured[tire] - base.prediction[tire])[sel]
    rf = (pb.measured[tire] - fit.prediction[tire])[sel]
    explained = 1.0 - float(rf @ rf) / max(float(rb @ rb), 1e-12)
    return float(np.max(np.abs(rb))), float(np.sqrt(np.mean(rb ** 2))) / pb.noise[tire], explained


def _best_cross(fit, base, pairs):
    """The (observer, source) pair whose residual shows the source's impact most clearly."""
    arrivals = fit.model.arrivals(fit.params)
    best = None
    for obs, src in pairs:
        if obs in arrivals and src in arrivals:
            peak, ratio, explained = _shows(fit, base, obs, arrivals[src])
            if best is None or ratio > best[2]:
                best = (obs, src, ratio, peak, explained, arrivals[src])
    return best


def _enveloping(fit, base):
    names = [n for n in fit.params if n.startswith("footprint_")]
    ok = all(fit.params[n] >= 0.1 and fit.ci[n][0] >= 0.05 for n in names)
    v = fit.model.problem.rec.speed_m_s
    parts = [f"{n.split('_')[1]} {_ci(fit, n, '.3f', 'm')}" for n in names]
    width = fit.model.problem.rec.cleat_width_m
    span = ", ".join(f"{(fit.params[n] + width) / v * 1e3:.0f} ms {n.split('_')[1]}" for n in names)
    return ok, (f"footprint (parabolic contact pressure) {'; '.join(parts)}: the cleat is felt for (footprint + width) / "
                f"speed = {span}, never as a step")


def _lift_off(fit, base):
    pb = fit.model.problem
    losses = contact_losses(fit)
    best = None
    for tire, spans in losses.items():
        for a, b in spans:
            if best is None or b - a > best[2] - best[1]:
                best = (tire, a, b)
    if best is None:
        return False, "the fitted unilateral tires never lose contact"
    tire, a, b = best
    t = pb.rec.time_s
    inner = (t >= a + 0.005) & (t <= b - 0.005)
    if inner.sum() < 3:
        inner = (t >= a) & (t <= b)
    mean_g = float(np.mean(pb.measured[tire][inner])) / STANDARD_GRAVITY if inner.any() else math.nan
    total = sum(b_ - a_ for spans in losses.values() for a_, b_ in spans)
    text = (f"{tire} hub at {mean_g:.2f} g for {(b - a) * 1e3:.0f} ms from t = {a:.3f} s "
            f"(contact lost {sum(map(len, losses.values()))}x, {total * 1e3:.0f} ms in all)")
    if not set(fit.model.effects) & {"axle_coupling", "roll_coupling"}:
        falls = abs(mean_g + 1.0) <= 0.35
        if (b - a) >= LIFT_OFF_S:
            return falls, text
        # a brief loss (a steep bevel, a fast pass): the hub falls freely for a few samples only, and the
        # unilateral tire must then account for most of what that wheel's channel left unexplained
        share = 1.0 - fit.sse[tire] / max(base.sse[tire], 1e-12)
        text += f"; the unilateral tire explains {max(share, 0.0):.0%} of {tire}'s residual"
        return (b - a) * pb.rec.sample_rate_hz >= 2 and falls and share >= BRIEF_LIFT_OFF_SHARE, text
    # on a coupled body the other tires carry the hub that lost contact: no free fall, but the unilateral
    # model must explain what the hub does while its tire is off the ground
    span = (t >= a) & (t <= b) & pb.window
    rb = (pb.measured[tire] - base.prediction[tire])[span]
    rf = (pb.measured[tire] - fit.prediction[tire])[span]
    explained = 1.0 - float(rf @ rf) / max(float(rb @ rb), 1e-12) if span.any() else 0.0
    text += (f"; the body carries the hub meanwhile (not free fall), and the unilateral tires explain "
             f"{max(explained, 0.0):.0%} of the residual there")
    return (b - a) >= LIFT_OFF_S and explained >= 0.5, text


#: Contact lost at least this long (s) is evidence of lift-off with the hub in free fall alone.
LIFT_OFF_S = 0.015
#: A briefer loss (two samples or more) counts when the unilateral tire removes at least this share of
#: its own channel's residual.
BRIEF_LIFT_OFF_SHARE = 0.5


def _axle(fit, base):
    best = _best_cross(fit, base, (("FL", "RL"), ("FR", "RR"), ("RL", "FL"), ("RR", "FR")))
    lo, hi = fit.ci["pitch_index"]
    if best is None:
        return False, "no channel on the other axle of the same side"
    obs, src, ratio, peak, explained, at = best
    if "roll_coupling" in fit.model.effects:
        # the rigid tractor: an impact reaches the other axle through pitch and through the shared roll (at a
        # pitch index of 1 through roll alone), so the evidence is the cross-talk the body explains
        return ratio >= 5.0 and explained >= 0.5, (
            f"{src}'s impact at t = {at:.3f} s shows in {obs}: {peak:.2f} m/s^2 peak ({ratio:.0f}x the noise "
            f"RMS), {max(explained, 0):.0%} of it explained through the rigid body's pitch and roll, pitch "
            f"dynamic index {_ci(fit, 'pitch_index', '.2f')}")
    coupled = abs(fit.params["pitch_index"] - 1.0) >= 0.05 and not (lo <= 1.0 <= hi)
    return ratio >= 5.0 and coupled, (
        f"{src}'s impact at t = {at:.3f} s shows in {obs}: {peak:.2f} m/s^2 peak ({ratio:.0f}x the noise RMS), "
        f"{max(explained, 0):.0%} of it explained through pitch, dynamic index {_ci(fit, 'pitch_index', '.2f')}")


def _roll(fit, base):
    best = _best_cross(fit, base, (("FL", "FR"), ("FR", "FL"), ("RL", "RR"), ("RR", "RL")))
    lo, hi = fit.ci["roll_index"]
    if best is None:
        return False, "no channel on the other side of the same axle"
    obs, src, ratio, peak, explained, at = best
    stagger = fit.params.get("stagger", 0.0)
    ok = ratio >= 5.0 and hi / max(lo, 1e-12) <= 3.0
    decoupled = ""
    if "axle_coupling" not in fit.model.effects:
        # axle pairs: the roll index 1 - ybar^2 of an axle (ybar its left/right load offset) decouples its
        # wheels, and a fit there is the independent corners again, however much it gains
        free = fit.model.body(fit.params).decoupled_roll_indices()
        ri = fit.params["roll_index"]
        ok = ok and all(abs(ri - r0) >= 0.05 and not lo <= r0 <= hi for r0 in free)
        decoupled = f" (left and right decoupled at {', '.join(f'{r0:.3f}' for r0 in free)})"
    return ok, (
        f"the right wheels meet the cleat {stagger * 1e3:+.0f} ms after the left ones; {src}'s impact at "
        f"t = {at:.3f} s shows in {obs}: {peak:.2f} m/s^2 peak ({ratio:.0f}x the noise RMS), "
        f"{max(explained, 0):.0%} of it explained through roll, roll index {_ci(fit, 'roll_index', '.3f')}{decoupled}")


def _pivot(fit, base):
    pb = fit.model.problem
    fronts = [t for t in pb.channels if t in FRONT_TIRES]
    before = sum(base.sse[t] for t in fronts)
    after = sum(fit.sse[t] for t in fronts)
    gain = 1.0 - after / max(before, 1e-12)
    lo, hi = fit.ci["pivot_index"]
    J_mass = fit.params["pivot_index"] * sum(pb.rec.wheel_load_N[t] for t in fronts) / STANDARD_GRAVITY
    k_sum = sum(fit.params[f"k_{t}"] for t in fronts)
    f_roll = math.sqrt(k_sum / J_mass) / (2 * math.pi)
    return gain >= 0.25 and hi / max(lo, 1e-12) <= 10.0, (
        f"the front axle rolls on its pivot: front-axle roll index {_ci(fit, 'pivot_index', '.3f')}, its roll "
        f"mode at about {f_roll:.1f} Hz; the front channels' residual falls by {gain:.0%} against a rigid axle")


def _nonlinear(fit, base):
    lo, hi = fit.ci["exponent"]
    n = fit.params["exponent"]
    text = (f"stiffness exponent {_ci(fit, 'exponent', '.2f')}: the elastic force grows as deflection^{n:.2f}, so "
            f"the period changes with amplitude")
    ok = abs(n - 1.0) >= 0.08 and not (lo <= 1.0 <= hi)
    verdict, pooled, est = exponent_evidence(fit.model.problem, fit.model.effects)
    if verdict == "no decay":
        return ok, text
    said = pooled_text(pooled, est)
    if verdict != ("progressive" if n > 1.0 else "degressive"):
        return False, (f"{text}; refuted by the free decays: their second harmonic (in phase with the square of "
                       f"the fundamental, which an elastic law that is not linear adds) gives {said}")
    return ok, f"{text}; the free decays' second harmonic agrees: {said}"


def _friction(fit, base):
    lo, _ = fit.ci["friction"]
    fc = fit.params["friction"]
    text = (f"friction force {_ci(fit, 'friction', '.0f', 'N')} beside the dampers: a linear rather than "
            f"exponential envelope of the decay")
    if any(e in BODY_EFFECTS for e in fit.model.effects):   # a channel's own decay is then the body's mode
        return fc >= 30.0 and lo > 0.0, text
    long, viscous = viscous_decays(fit.model.problem)
    if len(long) >= 2 and len(viscous) == len(long):
        ratios = ", ".join(f"{t} {r:.2f}" for t, r in viscous.items())
        return False, (f"{text}; refuted by the free decays: {', '.join(long)} ring {MIN_DECAY_CYCLES:g} cycles "
                       f"or more and each decays viscously (decay rate over the second half of the decay / over "
                       f"the first half: {ratios}), where friction damps the smaller oscillations harder")
    return fc >= 30.0 and lo > 0.0, text


#: A channel's free decay tells viscous damping from friction when it spans this many cycles and its
#: amplitude falls by :data:`MIN_DECAY_FALL` over them.
MIN_DECAY_CYCLES = 4.0
MIN_DECAY_FALL = 4.0
#: ... and it is viscous when one damped mode explains it to this R² with a decay rate over its second
#: half within this range of its first half's.  On the independent simulator's tuning corners (seeds 101-136,
#: 141-156) the viscous decays gave 0.94-1.08; every such decay with friction had R² <= 0.988 (ratios 0.04-2.5).
VISCOUS_R2 = 0.99
VISCOUS_RATIO = (0.8, 1.25)


def viscous_decays(pb) -> tuple[list, dict]:
    """(channels whose own free decay spans :data:`MIN_DECAY_CYCLES` cycles and falls :data:`MIN_DECAY_FALL`x,
    {those of them that decay viscously: their ``WaveformResult.envelope_ratio``})."""
    long, viscous = [], {}
    for tire, (_, res) in free_decays(pb).items():
        span = res.window_s[1] - res.window_s[0]
        if span / res.T < MIN_DECAY_CYCLES or -res.decay_rate * span < math.log(MIN_DECAY_FALL):
            continue
        long.append(tire)
        ratio = res.envelope_ratio
        if res.r2 >= VISCOUS_R2 and VISCOUS_RATIO[0] <= ratio <= VISCOUS_RATIO[1]:
            viscous[tire] = ratio
    return long, viscous


def _strongest_line(fit, base):
    """(channel, fitted frequency Hz, amplitude m/s², ratio to the floor) of the strongest line that
    `base` leaves in its residual at the frequencies `fit` found."""
    pb = fit.model.problem
    best = None
    for tire in pb.channels:
        f = fit.params[f"lug_frequency_{axle_of(tire)}"]
        amp, ratio = spectral_line((pb.measured[tire] - base.prediction[tire])[pb.window], pb.rec.sample_rate_hz, f)
        if best is None or ratio > best[3]:
            best = (tire, f, amp, ratio)
    return best


def _line_removed(fit, base, line=None) -> float:
    """Share of the strongest residual line's energy (`line`: :func:`_strongest_line`'s, found here where
    None) that `fit` removes (0 where it adds to the line)."""
    pb = fit.model.problem
    tire, f, amp, _ = line or _strongest_line(fit, base)
    after, _ = spectral_line((pb.measured[tire] - fit.prediction[tire])[pb.window], pb.rec.sample_rate_hz, f)
    return max(0.0, 1.0 - (after / amp) ** 2) if amp > 0 else 0.0


def local_gain(effect: str, fit: TractorFit, base: TractorFit) -> float | None:
    """Share of what `base` leaves unexplained that `fit` removes where `effect` acts, or None for an
    effect judged on the whole residual alone (see the module's text)."""
    if effect == "periodic_disturbance":
        return _line_removed(fit, base)
    if effect == "nonlinear_stiffness":
        return harmonic_share(fit, base)
    return None


def _periodic(fit, base):
    pb = fit.model.problem
    t = pb.rec.time_s
    pre = t < pb.first_impact_s - 0.05
    line = tire, f, amp, ratio = _strongest_line(fit, base)
    pre_amp, _ = spectral_line(pb.rec.accel_m_s2[tire][pre], pb.rec.sample_rate_hz, f)
    removed = _line_removed(fit, base, line)
    text = (f"{f:.2f} Hz line of {amp:.2f} m/s^2 in {tire} all through the residual ({ratio:.1f}x the spectral "
            f"floor), {pre_amp:.2f} m/s^2 already before the impact: steady, at speed / {pb.rec.speed_m_s / f:.3f} m; "
            f"the extended model removes {removed:.0%} of the line's energy")
    if f >= ENGINE_BAND_HZ[0]:
        # the conditioning removes an engine by its orders; one line alone looks the same as the lugs or the road
        text += (f"; the line lies in the engine band (from {ENGINE_BAND_HZ[0]:.0f} Hz) and an engine line without "
                 f"orders looks the same in one recording: one whose frequency does not follow the speed between "
                 f"runs is the engine's")
    prominent = ratio >= LINE_RATIO or (ratio >= REPRODUCED_LINE_RATIO and removed >= REPRODUCED_SHARE)
    return prominent and pre_amp >= 0.5 * amp, text


#: A residual line this many times its spectral floor, steady before the impact, is a periodic disturbance.
LINE_RATIO = 8.0
#: ... or this many times, where the extended model removes at least REPRODUCED_SHARE of its energy (the share
#: the selection asks of a line candidate that qualifies on its line, joint_select.MIN_LOCAL_GAIN).
REPRODUCED_LINE_RATIO = 5.0
REPRODUCED_SHARE = 0.75


_CHECKS = {"enveloping": _enveloping, "lift_off": _lift_off, "axle_coupling": _axle, "roll_coupling": _roll,
           "front_axle_pivot": _pivot, "nonlinear_stiffness": _nonlinear, "friction_damping": _friction,
           "periodic_disturbance": _periodic}


def final_evidence(final, bases: dict, screened: dict) -> dict:
    """Each named effect's evidence sentence in the final fit's numbers (those the diagnosis reports, so
    that an index reads the same in the evidence as in the body), against the model it extended.

    Parameters
    ----------
    final : TractorFit
        The named model's final fit.
    bases : dict
        Effect -> the fit of the model it extended.
    screened : dict
        Effect -> the screening fit's sentence, kept where the check cannot run on the final fit.
    """
    out = {}
    for effect, text in screened.items():
        try:
            out[effect] = check_tractor(effect, final, bases[effect])[1]
        except (KeyError, ValueError, ArithmeticError):
            out[effect] = text
    return out


def check_tractor(effect: str, fit: TractorFit, base: TractorFit) -> tuple[bool, str]:
    """Whether `fit` (a model with `effect`, extending `base`) shows the effect physically, and the sentence."""
    return _CHECKS[effect](fit, base)


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
