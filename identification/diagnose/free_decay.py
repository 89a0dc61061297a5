"""The diagnosis against the free decay alone: never worse than the simple fit it extends.

Where a hub rings as an independent corner (the diagnosis names no body coupling) with a linear tire
(no friction, no progressive stiffness - for that, below: the decay's shape is then the damped sinusoid, and the fit
explains its window to R² >= :data:`MIN_DECAY_R2`; a steady line, named or found in the quiet stretch, is
taken out of the channel first, :func:`_without_the_line`), the waveform fit of its free decay
(:func:`identification.identify.waveform.identify_waveform`) gives k and c from the part of the record that
needs the least of the model: the tire on flat ground.  The joint fit's k and c
must agree with it within their joint 95 % interval, √(h_joint² + h_decay²) (h the half-widths, each
interval's side facing the other estimate).
The free decay's intervals (:func:`~identification.identify.waveform.identify_waveform`'s) carry its noise (the
fit's covariance, inflated by the residual's colour and the move of a later window), the move between its
two halves (an amplitude-dependent tire) and :data:`~identification.identify.waveform.DECAY_FLOOR`, how far a
rolling tire's decay stands from the standing tire that defines k and c.
Where the joint fit's k or c lies outside the free decay's 95 % interval, the joint fit was pulled
by what its model gets wrong in the impact (a cleat shape, a footprint, an acquisition chain): the
tire's k and c are then the free decay's with its intervals (``"k_source": "free_decay"``; the extended
model keeps its own in ``parameters``, as its FMUs carry them), and a warning says so, by how much (and in
joint half-widths where the two intervals do not even overlap so far).  The joint fit's interval is not
joined to a corner's decay: a fit pulled by a model error measures that error, not the tire (joined, on the
acceptance seeds, it widened the median k interval from about 1 % to 8.6 %); to the body's decay it is
(:func:`reported`).  Where both lie inside but the joint model leaves the channel
above its noise floor, c alone is the free decay's (``"c_source": "free_decay"``): the decay rate is
what a mis-modelled impact pulls (its energy input trades against the damping), the frequency is held
by the whole record.  On the independent simulator's tuning seeds (100-139), of the 12 tires whose joint
values lay inside a valid decay's interval, the decay's c was the more accurate for 10 (median |c
error| 8.6 % against 15 %) and its k for 5 (0.61 % against 0.47 %).  The tire's values are never further
from the free decay than its interval allows.

Under a named progressive law (``nonlinear_stiffness``, no friction, no body) the decay is a damped sinusoid
to second order in its amplitude (:mod:`identification.identify.decay_exponent`: its second harmonic is a few
% of it), its decay rate the damper's, its frequency the equivalent linear stiffness at that amplitude, a
little below the tangent at the static load the joint fit gives: the joint k stands, and c is the decay's
(``"c_source": "free_decay"``) where the channel is left above its noise floor, as for a linear tire.  On the
independent simulator's progressive tuning corners (every channel 1.9-11x its noise) the joint c was 8-21 %
low, the decays' 0-4 % off; their k 2-3 % low on the fronts, the joint fit's within 0.4 %.  The decay of a
strongly progressive tire is not quite viscous: on the rig's progressive corners (n = 1.5, the model exact;
a bevel or a drift leaves channels above their noise) the decay's c is up to 4.7 % off where the joint fit's
was within 0.8 %.  The intervals do not tell the better c apart (on the independent simulator's short front
decays the joint fit's was the narrower, 14-21 % off); the decay's is taken, within the 10 % the rig's sweep
accepts.

A joint fit that leaves a tire's k or c outside the range it searches around its start (the final
model's bounds: k within 0.2-5x, c within 1e-3-5x + 2 kN s/m; seen: k -> 0 on rigid tractors with lugs or
friction the model does not know) has collapsed: that is no measurement.  The tire's k and c are then
the channel's own fit's (:func:`~identification.diagnose.joint_start.tire_start`: the waveform fit, the
paper's method or the ringing frequency), ``"k_source": "channel_fit"``, each interval the whole range
searched around it (the data do not narrow it), and a warning says so with the residual left.  Where that
tire's free decay is a valid check (one damped mode of a linear tire, no body, friction or progressive law
named, as above), its values and intervals are the tire's instead (``"decay_only"``,
``"k_source": "free_decay"``): the part of the record that needs the least of the model measures the tire
the collapsed fit does not.

A joint fit that leaves more than :data:`UNDETERMINED_SHARE` of a channel's signal energy unexplained
(beyond the noise) is no measurement of that tire either: its model does not describe what the hub did
(seen on recordings of another simulator: a slow pass over a cleat the footprint model does not envelope
alike, shares of 20-90 % with k off by 40-1400 % against intervals of ±10-40 %).  Each interval is then the
whole range searched (``"undetermined": true`` in the check, and a warning with the share): the interval
the data support.  Unless the free decay gives the tire's values, they are the channel's own fit's where no
body is named (``"k_source": "channel_fit"``: it needs the least of the model; on that simulator's slow
passes 0.5-16 % off where the joint fit was 8-70 % off), or the selection's start where that fit lies
outside the range searched around it (another mode), else the joint fit's (a channel's own fit would be the
body's mode).
Every check entry carries that range (``k_range``, ``c_range``).

Under a coupled body a channel's own decay is the body's mode, not its tire's.  For four channels without a
named friction or progressive tire, the named body's free decay (:mod:`~identification.diagnose.body_decay`: the
rigid tractor's modes after the last impact, fitted alone) takes the corner decay's part for every tire
where the diagnosis names that body and its decay counts (:func:`identification.diagnose.body_decay.why_not`):
``"body_decay": true``, the same comparison, and
where the joint fit collapsed or leaves the channel undetermined, the decay's values and intervals alone
(``"decay_only"``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import InputError
from ..recording.preprocess import preprocess
from ..recording import STANDARD_GRAVITY
from ..identify.waveform import ONE_MODE_R2, decay_to_noise, identify_waveform, noise_before, with_floor

__all__ = ["free_decay_check", "reported", "collapsed", "BODY_EFFECTS", "SHAPE_EFFECTS", "UNDETERMINED_SHARE"]

#: A channel the final model leaves this share of its signal energy unexplained (beyond the noise) is not
#: measured by it: its k and c intervals are the range searched.
UNDETERMINED_SHARE = 0.2

#: Named, these make the free decay a body's mode, not the tire's.
BODY_EFFECTS = ("axle_coupling", "roll_coupling", "front_axle_pivot")
#: The waveform fit must explain its window to this R² to count as the free decay of a linear corner (below
#: it: the tire still on the cleat, a progressive tire or a coupled body the diagnosis did not name).
MIN_DECAY_R2 = ONE_MODE_R2
#: A decay that one damped mode explains to within this multiple of the channel's noise RMS is a damped
#: sinusoid whatever its R²: a small decay's R² is capped by the noise (R² <= 1 - (noise / signal)², 0.96 at
#: 5x the noise), so that R² alone refused the rear decays of slow passes.  On the independent simulator's
#: tuning corners the 11 decays at R² 0.92-0.984 within 1.02x their noise gave k within 1.6 % and c within 6 %;
#: at 1.12-1.3x (friction the diagnosis had not named) c was 110-500 % off, and the missed bodies' decays
#: stood at 2-6x the noise before the first impact (the noise before their own impact holds the body's motion).
DECAY_AT_NOISE = 1.05
#: The noise rule and a collapsed tire's decay count only where no later channel moves more than this multiple
#: of its noise RMS between the recording's first impact and its own (:func:`moves_before_impact`): on the
#: independent simulator's corners 0.8-1.15, under the bodies the diagnosis missed 2.4-16.
MOVES_BEFORE_IMPACT = 2.0
#: ... where the decay stands this far above the noise (the fitted decay's RMS over its window / the noise
#: RMS): a decay buried in the noise is explained by any mode.
DECAY_MIN_SNR = 3.0
#: Named, these make the decay's shape other than a damped sinusoid.  (A steady line rides on it and is taken
#: out first: :func:`_without_the_line`.)
SHAPE_EFFECTS = ("friction_damping", "nonlinear_stiffness")


def free_decay_check(diag) -> dict:
    """Per channel: the free decay's k and c beside the joint fit's, and whether they agree.

    Returns ``{tire: {"valid": bool, "why_not": str | None, "k", "k_ci", "c", "c_ci", "k_apart",
    "c_apart", "agree": bool, "reason": str | None}}`` (``k_apart``: |Δk| over the joint half-width).
    """
    pb = diag.problem
    rec = pb.rec
    out = {}
    named = [e for e in diag.effects if e in BODY_EFFECTS + SHAPE_EFFECTS]
    # a progressive law alone leaves the decay a damped sinusoid to second order in its amplitude: its decay
    # rate is the damper's, its frequency the equivalent linear stiffness at that amplitude, not the tangent
    c_only = named == ["nonlinear_stiffness"]
    if c_only:
        named = []
    body, body_why = _body_free_decay(diag)
    if body is not None and body_why is None:
        for tire in pb.channels:
            out[tire] = _body_entry(diag, tire, body)
        return out
    no_check = (f"{', '.join(named)} named and {body_why}" if body_why else
                f"{', '.join(named)} named: the free decay is not a linear tire's under a corner mass" if named
                else None)
    # a channel's decay is its own tire's only where the corners are independent: a later hub that moves with
    # the first impact, before its own, rides on a body the diagnosis has not named
    moved = moves_before_impact(pb)
    corners = max(moved.values(), default=0.0) <= MOVES_BEFORE_IMPACT
    for tire in pb.channels:
        try:
            sig = preprocess(_without_the_line(rec, tire, diag), [tire], cutoff_hz=pb.cutoff_hz, min_peaks=1)[tire]
            wave = identify_waveform(sig, rec.wheel_load_N[tire] / STANDARD_GRAVITY, source=rec.source)
        except InputError as exc:
            out[tire] = (_channel_fit_instead(diag, tire) if collapsed(diag, tire) else
                         {"valid": False, "why_not": f"no waveform fit: {exc.problem}"})
            continue
        fin = diag.final
        entry = {"valid": True, "why_not": None, "k": float(wave.k), "c": float(wave.c),
                 "k_ci": [float(v) for v in wave.k_ci], "c_ci": [float(v) for v in wave.c_ci],
                 "amplitude_move": {q: float(v) for q, v in zip("kc", wave.amplitude_move)},
                 "r2": float(wave.r2)}
        residual, signal = decay_to_noise(sig, wave, pb.first_impact_s)
        entry.update(residual_to_noise=residual, signal_to_noise=signal, moves_before_impact=moved)
        why_not = no_check
        if why_not is None and wave.r2 < MIN_DECAY_R2 and not (corners and residual <= DECAY_AT_NOISE
                                                                and signal >= DECAY_MIN_SNR):
            # a forced response, a progressive or coupled hub; not a small decay whose R² the noise caps
            why_not = (f"the free decay is no damped sinusoid (R² {wave.r2:.3f} < {MIN_DECAY_R2}, its residual "
                       f"{residual:.2f}x the noise before the first impact)")
            if residual <= DECAY_AT_NOISE and signal >= DECAY_MIN_SNR:
                # the noise rule would count it: say that the body rule refuses it
                why_not = (f"the free decay's R² {wave.r2:.3f} < {MIN_DECAY_R2} would count at the noise level "
                           f"(residual {residual:.2f}x the noise), but a later hub moves "
                           f"{max(moved.values()):.1f}x its noise before its own impact (> {MOVES_BEFORE_IMPACT:g}): "
                           f"a body the diagnosis did not name carries this decay")
        if collapsed(diag, tire):
            # the free decay, where it is a linear tire's damped sinusoid, measures the tire the collapsed joint
            # fit does not; else the channel's own fit, with the range searched
            out[tire] = (_decay_instead(diag, tire, entry) if why_not is None and not c_only and corners else
                         _channel_fit_instead(diag, tire))
            continue
        sentences = _compare(fin, tire, entry, "the free decay's" if why_not is None else
                             "the channel's waveform fit's")
        if why_not is not None:
            # no check, but a disagreement beyond the joint interval is said, with why the fit is no check
            entry.update(valid=False, why_not=why_not, agree=not sentences, prefer=False, reason=None)
            if sentences:
                entry["reason"] = (f"{tire}: the joint fit's {' and '.join(sentences)}, which is no check here "
                                   f"({why_not}); the joint fit's values stand")
            out[tire] = entry
            continue
        _judge(diag, tire, entry, sentences, c_only=c_only)
        if sentences:
            left = diag.unexplained.get(tire)
            where = (f"it leaves {left['share']:.0%} of the signal unexplained in {left['window'][0]:.2f}-"
                     f"{left['window'][1]:.2f} s" if left else "its residual is at the noise floor, so the "
                                                                 "decay's own model may be the one that misses")
            entry["reason"] = (f"{tire}: the joint fit's {' and '.join(sentences)}: the impact pulls the joint "
                               f"fit ({where})")
        if entry["prefer"]:
            entry["reason"] = ((entry["reason"] + "; ") if entry["reason"] else f"{tire}: ") + \
                (f"k and c are the free decay's (k {entry['k'] / 1e3:.1f} kN/m, c {entry['c'] / 1e3:.3f} kN s/m), "
                 f"with its intervals: the joint fit's lie outside them (k "
                 f"{100 * (fin.params[f'k_{tire}'] / entry['k'] - 1):+.1f} %, c "
                 f"{100 * (fin.params[f'c_{tire}'] / entry['c'] - 1):+.1f} %)")
        elif c_only and (entry["prefer_c"] or sentences):
            said = (f"c is the free decay's ({entry['c'] / 1e3:.3f} kN s/m; the joint fit's "
                    f"{100 * (fin.params[f'c_{tire}'] / entry['c'] - 1):+.1f} %) and " if entry["prefer_c"] else "")
            entry["reason"] = ((entry["reason"] + "; ") if entry["reason"] else f"{tire}: ") + \
                (f"{said}k the joint fit's: under the progressive law named, the decay's frequency gives the "
                 f"equivalent linear stiffness at its amplitude, the joint fit the tangent at the static load")
        out[tire] = entry
    for tire, entry in out.items():
        entry.update(_searched(diag, tire))
        _undetermined(diag, tire, entry)
    return out


def moves_before_impact(pb) -> dict:
    """Per channel whose impact comes later than the first: the RMS of its raw signal over the first half of the
    time between the first impact and its own over its RMS before the first impact (independent corners: about
    1).  Only the first half: an enveloping tire feels the cleat from half a footprint ahead, on a slow pass
    0.3 s before its onset is detected."""
    t, out = pb.rec.time_s, {}
    for c in pb.channels:
        x = pb.rec.accel_m_s2[c]
        noise = noise_before(t, x, pb.first_impact_s)
        between = x[(t >= pb.first_impact_s) & (t < 0.5 * (pb.first_impact_s + pb.onsets[c]))]
        if between.size >= 20 and noise > 0:
            out[c] = float(np.std(between) / noise)
    return out


def _without_the_line(rec, tire: str, diag):
    """`rec` with the steady line taken out of the tire's channel: the sinusoid at the fitted lug frequency of
    its axle where ``periodic_disturbance`` is named, else at the steady line its quiet stretch holds (an engine
    line without visible orders, the lugs), refined on the record; least squares over the whole record (the
    line runs through it, the impact's transient projects little on it), so that the decay is the tire's
    alone."""
    from .body_decay import line_frequency

    t, x = rec.time_s, rec.accel_m_s2[tire]
    freq, fitted = line_frequency(diag.problem, tire, diag.final if "periodic_disturbance" in diag.effects else None)
    if not freq:
        return rec
    if not fitted:
        from ..recording.condition import refine_line
        from .joint_fit import LINE_SEARCH_HZ

        freq = refine_line(t, x[None, :] - x.mean(), float(freq), min(LINE_SEARCH_HZ, 0.5 * float(freq)))
    w = 2 * math.pi * float(freq)
    basis = np.column_stack([np.sin(w * t), np.cos(w * t), np.ones_like(t)])
    b = np.linalg.lstsq(basis, x, rcond=None)[0]
    return dataclasses.replace(rec, accel_m_s2={**rec.accel_m_s2, tire: x - basis[:, :2] @ b[:2]})


def _searched(diag, tire: str) -> dict:
    """The range the joint fit searched for the tire's k and c (the final model's bounds around its start)."""
    fin, start = diag.final, diag.extra.get("start") or {}
    return _range_around(fin, tire, start.get(f"k_{tire}", fin.params[f"k_{tire}"]),
                         start.get(f"c_{tire}", fin.params[f"c_{tire}"]))


def _range_around(fin, tire: str, k: float, c: float) -> dict:
    """``{"k_range", "c_range"}``: the final model's bounds of the tire's k and c around the values k, c."""
    lo, hi = fin.model.bounds({**fin.params, f"k_{tire}": k, f"c_{tire}": c})
    return {f"{q}_range": [float(lo[f"{q}_{tire}"]), float(hi[f"{q}_{tire}"])] for q in "kc"}


def _undetermined(diag, tire: str, entry: dict) -> None:
    """Mark the tire's values undetermined (intervals: the range searched) where the final model leaves more
    than :data:`UNDETERMINED_SHARE` of its channel unexplained, unless the free decay or the channel's own fit
    already gives them."""
    left = diag.unexplained.get(tire)
    if entry.get("prefer") or not left or left["share"] <= UNDETERMINED_SHARE:
        return
    entry["undetermined"] = True
    fin = diag.final
    sentence = (f"{tire}: the model leaves {left['share']:.0%} of this channel's signal unexplained "
                f"({left['residual_to_noise']:.1f}x the noise, in {left['window'][0]:.2f}-{left['window'][1]:.2f} s): "
                f"its k {fin.params[f'k_{tire}'] / 1e3:.1f} kN/m and c {fin.params[f'c_{tire}'] / 1e3:.3g} kN s/m "
                f"are not determined by the data, each interval is the whole range searched")
    if not any(e in BODY_EFFECTS for e in diag.effects):
        # an independent corner: its own fit (the free decay's, the part of the record that needs the least
        # of the model) is the better value in that range; under a body it would be the body's mode
        from .joint_start import tire_start

        k, c = tire_start(diag.problem, tire)
        start = diag.extra.get("start") or {}
        inside = entry["k_range"][0] <= k <= entry["k_range"][1] and entry["c_range"][0] <= c <= entry["c_range"][1]
        whose = "the channel's own fit's, which needs the least of the model"
        if not inside and f"k_{tire}" in start and f"c_{tire}" in start:
            # outside the range searched around the selection's start: the channel rings in another mode (a
            # missed pivot's roll read as a front tire's own, seen at 13x its k); the start, which the joint
            # timing search corrected, instead
            k, c = start[f"k_{tire}"], start[f"c_{tire}"]
            whose = "the selection's start (the channel's own fit rings in another mode, outside that range)"
        entry["channel_k"], entry["channel_c"] = float(k), float(c)
        sentence += f"; k and c are {whose} (k {k / 1e3:.1f} kN/m, c {c / 1e3:.3f} kN s/m)"
    entry["reason"] = f"{entry['reason']}; {sentence}" if entry.get("reason") else sentence


def _compare(fin, tire: str, entry: dict, other: str) -> list:
    """The joint fit's k and c against `entry`'s (another fit's, with intervals): fills ``<q>_apart`` (|Δ| in
    joint half-widths √(h_joint² + h_other²)) and ``<q>_outside_decay``; a sentence per quantity further apart
    than the joint interval."""
    sentences = []
    for q in ("k", "c"):
        est, (lo, hi) = fin.params[f"{q}_{tire}"], fin.ci[f"{q}_{tire}"]
        value, (o_lo, o_hi) = entry[q], entry[f"{q}_ci"]
        # each interval's side that faces the other estimate (a log-scale interval is not symmetric)
        h_joint = (hi - est if value > est else est - lo) if math.isfinite(hi) else math.inf
        h_decay = o_hi - value if est > value else value - o_lo
        joint = math.hypot(h_joint, h_decay)
        apart = abs(est - value) / joint if joint > 0 else math.inf
        entry[f"{q}_apart"] = float(apart)
        entry[f"{q}_outside_decay"] = bool(not (o_lo <= est <= o_hi))
        if apart > 1:
            unit = "kN/m" if q == "k" else "kN s/m"
            sentences.append(f"{q} {100 * (est / value - 1):+.1f} % from {other} {value / 1e3:.4g} {unit} "
                             f"({apart:.1f} joint half-widths)")
    return sentences


def _judge(diag, tire: str, entry: dict, sentences: list, *, c_only: bool = False) -> None:
    """A valid decay's verdict on the joint fit: ``agree``; ``prefer`` (the decay's k and c) where the joint k
    or c lies outside its interval; else ``prefer_c`` where the joint model leaves the channel above its noise
    floor: it misses something in the impact, and its c carries it (the decay's c needs the least of the
    model; the frequency, held by the whole record, keeps the joint k).  With `c_only` (a progressive law
    named: the decay's k is the equivalent linear one at its amplitude, the joint fit's the tangent at the
    static load) the joint k stands, and c is the decay's where the channel is left above its noise floor (where
    the model explains the channel its c stands: the decay of a strongly progressive tire is not quite
    viscous)."""
    entry["agree"] = not sentences
    entry["prefer"] = (entry["k_outside_decay"] or entry["c_outside_decay"]) and not c_only
    entry["prefer_c"] = not entry["prefer"] and diag.unexplained.get(tire) is not None
    entry["reason"] = None


def collapsed(diag, tire: str) -> bool:
    """Whether the joint fit left the tire's k or c outside the range it searched around its start (the final
    model's bounds)."""
    fin, start = diag.final, diag.extra.get("start") or {}
    names = (f"k_{tire}", f"c_{tire}")
    if not all(n in start and n in fin.params for n in names):
        return False
    lo, hi = fin.model.bounds({**fin.params, **{n: start[n] for n in names}})
    return any(not lo[n] <= fin.params[n] <= hi[n] for n in names)


def _collapse_sentence(diag, tire: str, rng: dict) -> str:
    fin = diag.final
    left = diag.unexplained.get(tire)
    residual = (f"it leaves {left['residual_to_noise']:.1f}x the noise" if left else
                "its residual is at the noise floor")
    return (f"{tire}: the joint fit collapsed (k {fin.params[f'k_{tire}'] / 1e3:.3g} kN/m, c "
            f"{fin.params[f'c_{tire}'] / 1e3:.3g} kN s/m, outside the {rng['k_range'][0] / 1e3:.0f}-"
            f"{rng['k_range'][1] / 1e3:.0f} kN/m and {rng['c_range'][0] / 1e3:.3g}-{rng['c_range'][1] / 1e3:.3g} "
            f"kN s/m it searches): the model does not explain this channel ({residual})")


def _channel_fit_instead(diag, tire: str) -> dict:
    """The check's entry of a collapsed tire: the channel's own fit, each interval the range searched."""
    from .joint_start import tire_start

    k, c = tire_start(diag.problem, tire)
    rng = _range_around(diag.final, tire, k, c)
    entry = {"valid": False, "why_not": "the joint fit collapsed", "collapsed": True, "prefer": True,
             "agree": False, "k": float(k), "c": float(c), "k_ci": rng["k_range"], "c_ci": rng["c_range"]}
    entry["reason"] = (f"{_collapse_sentence(diag, tire, rng)}; k and c are the channel's own fit's (k "
                       f"{k / 1e3:.1f} kN/m, c {c / 1e3:.3f} kN s/m), not determined by the data: each interval is "
                       f"the whole range searched")
    return entry


def _decay_instead(diag, tire: str, entry: dict) -> dict:
    """The check's entry of a collapsed tire whose free decay is a valid check (`entry`): the decay's values
    with its intervals (``decay_only``)."""
    rng = _range_around(diag.final, tire, entry["k"], entry["c"])
    entry.update(valid=True, prefer=True, decay_only=True, joint_collapsed=True, agree=False,
                 reason=f"{_collapse_sentence(diag, tire, rng)}; k and c are the free decay's (k "
                        f"{entry['k'] / 1e3:.1f} kN/m, c {entry['c'] / 1e3:.3f} kN s/m), with its intervals: one "
                        f"damped mode explains it (R² {entry['r2']:.3f}, its residual "
                        f"{entry['residual_to_noise']:.2f}x the noise)")
    return entry


def reported(value: float, ci, check: dict, q: str) -> tuple[float, list]:
    """The tire's value and interval of quantity `q` ('k' or 'c'): the joint fit's, or, where the joint fit's k
    or c lies outside the free decay's interval (and, for c, where the joint model leaves the channel above its
    noise floor), the free decay's with its interval (which carries :data:`~identification.identify.waveform.DECAY_FLOOR`),
    for the body's free decay stretched to hold the joint fit's interval too only where its window shift could
    not be measured (its slowest mode's period longer than the tail allows: on the tuning seeds' ``pivot_149``, a
    mode near 0 Hz, its own intervals missed c by 7-55 %; where the shift is measured, they held k for 44 of 44
    tires and c for 43 of 44 on the tuning seeds' rigid tractors); where the
    joint fit collapsed (:func:`collapsed`), the channel's own fit's with the range searched; where the model leaves too much of the channel unexplained (``undetermined``), the
    channel's own fit's (no body named: :func:`_undetermined`) or the joint fit's, with the range searched."""
    if check.get("collapsed") or check.get("decay_only"):
        return float(check[q]), [float(v) for v in check[f"{q}_ci"]]
    if check.get("undetermined"):
        lo, hi = check[f"{q}_range"]
        value = check.get(f"channel_{q}", value)
        return float(value), [float(min(value, lo)), float(max(value, hi))]
    if not check.get("valid") or not (check.get("prefer") or (q == "c" and check.get("prefer_c"))):
        return float(value), [float(v) for v in ci]
    lo, hi = check[f"{q}_ci"]
    if check.get("body_decay") and not check.get("shift_measured"):
        # the body's decay rests on the whole body's model (its inertia, its modes' split between the tires);
        # where its window shift, which carries what the decay does not model into its interval, could not be
        # measured, the tire's value may lie by either, so its interval holds the joint fit's too
        return float(check[q]), [float(min(ci[0], value, lo)), float(max(ci[1], value, hi))]
    return float(check[q]), [float(lo), float(hi)]


def _body_free_decay(diag):
    """The rigid tractor's free decay (:mod:`~identification.diagnose.body_decay`) where the diagnosis names it
    (``axle_coupling`` and ``roll_coupling``, with ``front_axle_pivot`` the pivoting axle's) on four channels
    without a named friction or progressive tire: (BodyDecay or None, why it is no measurement or None)."""
    from .body_decay import body_decay, why_not

    pb = diag.problem
    if len(pb.channels) != 4 or any(e in SHAPE_EFFECTS for e in diag.effects) or \
            not {"axle_coupling", "roll_coupling"} <= set(diag.effects):
        return None, None
    kind = "pivot" if "front_axle_pivot" in diag.effects else "rigid"
    body = body_decay(pb, kind=kind, start=dict(diag.final.params), final=diag.final)
    if body is None:
        return None, None
    return body, why_not(body)


def _body_entry(diag, tire: str, body) -> dict:
    """A tire's check entry from the body's free decay: compared with the joint fit as a corner's free decay is;
    where the joint fit collapsed or leaves the channel undetermined, the decay's values and intervals alone."""
    fin = diag.final
    entry = {"valid": True, "why_not": None, "body_decay": True,
             "k": float(body.params[f"k_{tire}"]), "c": float(body.params[f"c_{tire}"]),
             "k_ci": with_floor(body.params[f"k_{tire}"], body.ci[f"k_{tire}"], "k"),
             "c_ci": with_floor(body.params[f"c_{tire}"], body.ci[f"c_{tire}"], "c"),
             "window": [float(v) for v in body.window], "residual_to_noise": body.residual_to_noise,
             "shift_measured": bool(body.extra.get("shift_measured"))}
    whose = (f"the {'pivoting ' if body.kind == 'pivot' else ''}rigid tractor's free decay "
             f"({body.window[0]:.2f}-{body.window[1]:.2f} s, modes {', '.join(f'{f:.2f}' for f in body.modes_hz)} Hz)")
    left = diag.unexplained.get(tire)
    entry.update(_searched(diag, tire))
    if collapsed(diag, tire) or (left and left["share"] > UNDETERMINED_SHARE):
        why = ("collapsed" if collapsed(diag, tire) else
               f"leaves {left['share']:.0%} of this channel unexplained")
        entry.update(decay_only=True, prefer=True, agree=False, joint_collapsed=collapsed(diag, tire))
        entry["reason"] = (f"{tire}: the joint fit {why}: k and c are {whose} (k {entry['k'] / 1e3:.1f} kN/m, "
                           f"c {entry['c'] / 1e3:.3f} kN s/m), with its intervals")
        return entry
    sentences = _compare(fin, tire, entry, whose)
    _judge(diag, tire, entry, sentences)
    if sentences or entry["prefer"]:
        entry["reason"] = (f"{tire}: " + (f"the joint fit's {' and '.join(sentences)}; " if sentences else "") +
                           f"k and c are {whose} (k {entry['k'] / 1e3:.1f} kN/m, c {entry['c'] / 1e3:.3f} kN s/m)"
                           + (", the interval stretched to hold the joint fit's (the decay's window shift could "
                              "not be measured)" if entry["prefer"] and not entry["shift_measured"] else
                              ", with its intervals" if entry["prefer"] else ""))
    return entry
