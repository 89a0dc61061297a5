"""Whole-tractor diagnosis: forward selection of effects at the recording level, honest about what is left.

Round by round every available effect (:data:`~identification.model.fitting.EFFECTS`)
is added to the current model and the extended model is fitted to all
channels.  A candidate qualifies when its BIC (on n_eff = n · min(1, 2 f_c / f_s)
independent samples per channel) improves by ≥ 10, it removes ≥ 25 % of the
noise-weighted residual energy (or, for an effect that acts on a narrow part
of the data, ≥ 75 % of the residual there - a steady line, the free decays'
second harmonic:
:func:`~identification.diagnose.joint_evidence.local_gain`; an effect that adds no
parameter, unilateral contact, needs no share: its gate and the BIC name it), its parameters lie
within their physical bounds and it passes its physical gate
(:mod:`~identification.diagnose.joint_evidence`).  The best qualifier is named;
the selection stops when none qualifies.  Candidates are screened at a 2 ms
step; the named model is refitted at 1 ms.

Afterwards each channel's residual is compared with its noise floor: above
1.5× the noise RMS the channel is flagged ``unexplained`` (share of the signal,
window), and the intervals are marked as conditional on the model.
"""

from __future__ import annotations

import math
import time

from ..workers import one_blas_thread
from .joint_evidence import check_tractor, final_evidence, local_gain
from .joint_fit import TractorFit, fit_tractor, sse_of, unexplained
from .joint_result import TractorCandidate, TractorDiagnosis
from .joint_start import (ENVELOPE_GUESS_M, body_start, enveloped_timings, periodic_start, refine_timing,
                          rescue_start, starting_values)
from .joint_signs import settle_signs
from .joint_timing import BODY_DEFAULTS, joint_timing
from ..model.fitting import BODY_EFFECTS, EFFECTS, TractorFitModel, TractorProblem, axle_of

__all__ = ["TractorDiagnosis", "diagnose_tractor", "TractorCandidate"]

MIN_DELTA_BIC = 10.0
MIN_GAIN = 0.25
#: An effect acting on a narrow part of the data qualifies on removing this share of the residual there
#: (a steady line's energy), where the rest of the residual hides it from MIN_GAIN.
MIN_LOCAL_GAIN = 0.75
MAX_EFFECTS = 5
SCREEN_STEP_S = 2e-3
SCREEN_BUDGET = 150
FINAL_BUDGET = 400
_DEFAULTS = {**BODY_DEFAULTS, "exponent": 1.2, "friction": 100.0}


def _bic(sse_w: float, n: int, n_eff: float, p: int) -> float:
    return n_eff * math.log(sse_w / n) + p * math.log(n_eff)


def _candidate_start(model: TractorFitModel, current: TractorFit, start0: dict) -> dict:
    pb = model.problem
    s = dict(current.params)
    for name in [n for n in s if n[:2] in ("k_", "c_")]:
        # a misspecified current model may have collapsed a tire (k or c off by more than a factor of
        # three from its own waveform fit): start that tire from the waveform fit instead
        if not start0[name] / 3 <= s[name] <= 3 * start0[name]:
            s[name] = start0[name]
    timing = start0["enveloped"] if "enveloping" in model.effects else start0
    for name, v in {**_DEFAULTS, **timing["body"][1]}.items():   # the indices that placed the arrivals best
        s.setdefault(name, v)
    for axle in pb.axles():
        s.setdefault(f"footprint_{axle}", ENVELOPE_GUESS_M)
    if "enveloping" in model.effects and "enveloping" not in current.model.effects:
        options = [dict(s, **{n: t[n] for n in ("arrival", "stagger", "delay") if n in t})
                   for t in enveloped_timings(start0)]
        s = min(options, key=lambda o: sse_of(model, {n: o[n] for n in model.names}, SCREEN_STEP_S))
    if "periodic_disturbance" in model.effects and "periodic_disturbance" not in current.model.effects:
        arrivals = current.model.arrivals(current.params)
        for tire in pb.channels:
            est = periodic_start(pb.rec, tire, first_impact_s=pb.first_impact_s, cutoff_hz=pb.cutoff_hz,
                                 k=s[f"k_{tire}"], c=s[f"c_{tire}"], arrival=arrivals[tire],
                                 residual=pb.measured[tire] - current.prediction[tire], window=pb.window) or \
                {"lug_frequency": 10.0, "lug_amplitude": 1e-4, "lug_phase": 0.0}
            axle = axle_of(tire)
            s.setdefault(f"lug_frequency_{axle}", est["lug_frequency"])
            s[f"lug_amplitude_{tire}"], s[f"lug_phase_{tire}"] = est["lug_amplitude"], est["lug_phase"]
    return {name: s[name] for name in model.names}


def _waveform_start(model: TractorFitModel, start: dict, start0: dict, timing: dict) -> dict:
    """`start` with every tire's k and c from its waveform fit (`start0`) and the arrivals of `timing`."""
    return dict(start, **{n: start0[n] for n in model.names if n[:2] in ("k_", "c_")},
                **{n: timing[n] for n in ("arrival", "stagger", "delay") if n in model.names})


def _flying_timing(model: TractorFitModel, start: dict, start0: dict) -> dict:
    """The arrivals (:func:`~identification.diagnose.joint_timing.joint_timing`) under the candidate's body with
    unilateral tires at their waveform fits: a wheel thrown off the cleat lands later than a bilateral
    tire's response says, and the search then places a side's cleat tens of ms off (seen: a stagger 18 ms
    short, no fit from there recovering it)."""
    body = tuple(e for e in model.effects if e in BODY_EFFECTS) + ("lift_off",)
    indices = {n: start[n] for n in BODY_DEFAULTS if n in start}
    footprints = [v for n, v in start.items() if n.startswith("footprint_")]
    footprint = sum(footprints) / len(footprints) if "enveloping" in model.effects and footprints else 0.0
    tires = {n: start0[n] for n in model.names if n[:2] in ("k_", "c_")}
    return joint_timing(model.problem, tires, footprint, hypotheses=[(body, indices)])


def _try(job):
    effects, current, new, start0 = job
    model = TractorFitModel(effects, current.model.problem)
    start = _candidate_start(model, current, start0)
    if set(new) & set(BODY_EFFECTS):
        # the current model's k (and timing) absorb the motion it lacks: scan around them and around the
        # waveform fits with the timing found under a coupled body
        timings = enveloped_timings(start0) if "enveloping" in model.effects else [start0]
        options = [body_start(model, s, step_s=SCREEN_STEP_S)
                   for s in [start] + [_waveform_start(model, start, start0, timing) for timing in timings]]
        # a scan cannot tell a wrong timing from a right one while the tires are still off (seen: the right
        # timing's scan 2x the wrong one's, its fit 400x lower): fit every option
    elif "lift_off" in new:
        # a wheel that flies lands later: the current model's timing and tires (fitted with a tire that pulls the
        # hub down) may hold the unilateral fit in a worse minimum; fit from the waveform fits as well, with
        # the timing found by bilateral responses and with the one the unilateral responses place best
        options = [start, _waveform_start(model, start, start0, start0),
                   _waveform_start(model, start, start0, _flying_timing(model, start, start0))]
    else:
        options = [start]
    # options that coincide (a current model whose tires are the waveform fits' and whose timing is the
    # search's) are fitted once: a fit is a deterministic function of its start
    options = list({tuple(sorted(o.items())): o for o in options}.values())
    fits = [fit_tractor(model, s, step_s=SCREEN_STEP_S, budget=SCREEN_BUDGET) for s in options]
    fit = min(fits, key=lambda f: (not f.in_bounds, f.weighted_sse()))
    checks = [check_tractor(effect, fit, current) for effect in new]
    local = local_gain(new[0], fit, current) if len(new) == 1 else None
    return TractorCandidate("+".join(new), fit, math.nan, math.nan, all(ok for ok, _ in checks), False,
                            {effect: text for effect, (_, text) in zip(new, checks)}, local)


def _judge(cand, current_sse, current_p, n, n_eff):
    fit = cand.fit
    sse = fit.weighted_sse()
    gain = 1.0 - sse / current_sse
    dbic = _bic(current_sse, n, n_eff, current_p) - _bic(sse, n, n_eff, len(fit.model.names))
    # the 25 % rule guards against parameters that fit noise; an effect that adds none (unilateral contact)
    # is named on its physical gate and the BIC alone
    enough = (gain >= MIN_GAIN or (cand.local_gain is not None and cand.local_gain >= MIN_LOCAL_GAIN)
              or len(fit.model.names) <= current_p)
    qualified = bool(cand.passed_gate and fit.in_bounds and dbic >= MIN_DELTA_BIC and enough)
    return TractorCandidate(cand.effect, fit, float(dbic), float(gain), cand.passed_gate, qualified, cand.evidence,
                            cand.local_gain)


@one_blas_thread
def diagnose_tractor(rec, *, cutoff_hz: float = 100.0, effects=EFFECTS, progress=None, workers: int = 1,
                     channels=None) -> TractorDiagnosis:
    """Diagnose every channel of a recording jointly under one body.

    The selection starts from the per-channel waveform fits and the joint
    timing search (:func:`~identification.diagnose.joint_start.starting_values`).
    When its final model still leaves some channel's residual over RESCUE_RATIO
    times the noise (a wrong arrival: the right model from the right timing
    leaves a few times the noise at most), the selection runs again from a
    timing searched with each axle's k scaled
    (:func:`~identification.diagnose.joint_start.rescue_start`), and the run
    with the lower BIC is kept (``extra["rescue"]`` says which).  If the kept run still leaves that much,
    the selection runs once more from the timings searched with the responses' common scale fitted
    (``starting_values(..., fit_scale=True)``) where they make a new start, the lower BIC kept
    (``extra["scaled_start"]``).

    Sensor signs the conditioning left open (a front channel read upside down or a pivoting axle; no
    quiet stretch before an impact) are settled by diagnosing each hypothesis and keeping the one of
    the lowest BIC (:func:`~identification.diagnose.joint_signs.settle_signs`, ``extra["sign_test"]``).

    When the fitted front/rear delay implies a speed more than :data:`SPEED_REFIT` off the sidecar's
    (a GPS speed a few percent off), the diagnosis is fitted again at the delay's speed
    (``extra["speed_refit"]`` says so; :meth:`TractorDiagnosis.speed_json` reports both speeds).

    Parameters
    ----------
    rec : Recording
        Focused and conditioned here unless it was already (:func:`identification.recording.window.focus`).
    cutoff_hz : float
        Low-pass cut-off of the comparison, Hz.
    effects : iterable of str
        Candidate effects (default: all eight).
    progress : callable, optional
        ``progress(label)`` before each model fit.
    workers : int
        Processes fitting a round's candidates in parallel.
    channels : iterable of str, optional
        Channels to use (default: all recorded).
    """
    from dataclasses import replace

    from ..recording.window import focus

    t0 = time.perf_counter()
    rec = focus(rec, cutoff_hz=cutoff_hz, announce=False)   # itself when the caller focused it
    diag = settle_signs(rec, lambda r: _diagnose_once(r, cutoff_hz, effects, progress, workers, channels),
                        progress)
    rec = diag.problem.rec                                   # with the signs the joint fit chose
    delay = diag.final.params.get("delay")
    if delay and abs(rec.wheelbase_m / delay / rec.speed_m_s - 1) > SPEED_REFIT:
        # the fitted front/rear delay says the sidecar's speed is off: the cleat's crossing time and the
        # footprint's passage scale with the speed, so fit again at the delay's speed
        (progress or (lambda label: None))("refit at the speed of the fitted front/rear delay")
        first = diag
        diag = _diagnose_once(replace(rec, speed_m_s=rec.wheelbase_m / delay), cutoff_hz, effects, progress,
                              workers, channels)
        diag.extra["sign_test"] = first.extra.get("sign_test")
        onsets = (rec.conditioning or {}).get("speed") or {}
        diag.extra["speed_refit"] = {"sidecar_m_s": float(rec.speed_m_s),
                                     "from_delay_m_s": float(rec.wheelbase_m / delay),
                                     "from_onsets_m_s": onsets.get("from_delay_m_s"),
                                     "first_effects": list(first.effects)}
    from .free_decay import free_decay_check
    diag.extra["free_decay"] = free_decay_check(diag)
    return replace(diag, seconds=time.perf_counter() - t0)


#: Relative difference between the sidecar's speed and the fitted front/rear delay's above which the
#: diagnosis is fitted again at the delay's speed.
SPEED_REFIT = 0.02


def _diagnose_once(rec, cutoff_hz, effects, progress, workers, channels) -> TractorDiagnosis:
    from ..workers import process_pool, stop_pool

    t0 = time.perf_counter()
    tick = progress or (lambda label: None)
    pb = TractorProblem.from_recording(rec, cutoff_hz=cutoff_hz, channels=channels)
    tick("starting values")
    start0 = starting_values(pb)
    n = int(pb.window.sum()) * len(pb.channels)
    n_eff = n * min(1.0, 2 * cutoff_hz / rec.sample_rate_hz)
    pool = process_pool(workers)
    try:
        run = _select(pb, start0, effects, pool, tick, n, n_eff)

        def again(label, start1):
            """The selection once more from `start1` where it is a new start (`_new_start`), the lower BIC kept."""
            nonlocal run, start0
            record = {"residual_to_noise_before": max(_residual_to_noise(run)), "kept": False}
            if not _new_start(start1, start0, run["final"].params):
                record["skipped"] = "its start is where the selection already ended"
                return record
            tick(label)
            other = _select(pb, start1, effects, pool, tick, n, n_eff)
            record.update(kept=bool(_final_bic(other, n, n_eff) < _final_bic(run, n, n_eff)),
                          residual_to_noise_after=max(_residual_to_noise(other)))
            if record["kept"]:
                run, start0 = other, start1
            return record

        rescue = scaled = None
        if max(_residual_to_noise(run)) > RESCUE_RATIO and len(pb.channels) > 1:
            rescue = again("rescue: starting values with scaled stiffness", rescue_start(pb, start0))
        if max(_residual_to_noise(run)) > RESCUE_RATIO:
            # a model whose impact is too large for the data (a point contact on a wide, bevelled cleat)
            # can place the arrivals where its responses cancel; the searches with the responses' scale
            # fitted do not, but fail elsewhere (joint_timing's notes): from their timings too
            scaled = again("starting values with the responses' scale fitted", starting_values(pb, fit_scale=True))
    except BaseException:
        stop_pool(pool)
        raise
    if pool:
        pool.shutdown()
    return TractorDiagnosis(problem=pb, effects=run["selected"], baseline=run["baseline"], final=run["final"],
                            rounds=run["rounds"], evidence=run["evidence"], unexplained=run["unexplained"],
                            seconds=time.perf_counter() - t0,
                            extra={"n_eff": n_eff, "start": start0, "rescue": rescue, "scaled_start": scaled})


#: A channel residual over this many times its noise RMS after the selection triggers the rescue.
RESCUE_RATIO = 10.0


#: Timings (arrival, stagger, delay) further apart than this in some quantity are different starts, s.
OTHER_TIMING_S = 0.005
#: Starting tires (k, c) further apart than this relative difference are different starts.
OTHER_TIRES = 0.01


def _timing_differs(a: dict, b: dict) -> bool:
    return any(abs(a[k] - b[k]) > OTHER_TIMING_S for k in ("arrival", "stagger", "delay") if k in a and k in b)


def _new_start(start1: dict, start0: dict, fitted: dict) -> bool:
    """Whether another selection's start (the rescue's, :func:`~identification.diagnose.joint_start.rescue_start`,
    or the scaled searches') is a new one: its tires off the first start's (by more than :data:`OTHER_TIRES`),
    its enveloped arrivals off the first start's, or its point-contact arrivals off both the first start's and
    the kept selection's fitted ones (`fitted`).  Otherwise the selection would run again from where it began
    or ended (measured on the independent simulator's point-contact corners: the same result again, at twice
    the cost; every result of its tuning and acceptance seeds unchanged)."""
    tires = any(abs(start1[n] / start0[n] - 1.0) > OTHER_TIRES for n in start0 if n[:2] in ("k_", "c_"))
    point = _timing_differs(start1, start0) and _timing_differs(start1, fitted)
    return tires or point or _timing_differs(start1["enveloped"], start0["enveloped"])


def _residual_to_noise(run: dict) -> list:
    return [v["residual_to_noise"] if v else 0.0 for v in run["unexplained"].values()]


def _final_bic(run: dict, n: int, n_eff: float) -> float:
    final = run["final"]
    return _bic(final.weighted_sse(), n, n_eff, len(final.model.names))


def _select(pb: TractorProblem, start0: dict, effects, pool, tick, n: int, n_eff: float) -> dict:
    """One forward selection from the starting values `start0`, the named model's final fit and what it
    leaves unexplained."""
    tick("baseline")
    base_model = TractorFitModel((), pb)
    baseline = fit_tractor(base_model, refine_timing(base_model, {n_: start0[n_] for n_ in base_model.names}),
                           budget=FINAL_BUDGET)
    current, selected, rounds, evidence, bases = baseline, [], [], {}, {}
    while len(selected) < MAX_EFFECTS:
        tries = [(e,) for e in effects if e not in selected and pb.available(e, selected)]
        if ("axle_coupling",) in tries and ("roll_coupling",) in tries and len(pb.channels) == 4:
            # the rigid tractor in one step; and with the footprint, which on a tractor that rolls and
            # pitches is often needed at the same time before either alone fits at all
            bodies = [("axle_coupling", "roll_coupling")]
            if "front_axle_pivot" in effects:
                bodies.append(("axle_coupling", "roll_coupling", "front_axle_pivot"))
            tries += bodies
            if ("enveloping",) in tries:
                tries += [("enveloping",) + body for body in bodies]
        if not tries:
            break
        jobs = [(selected + list(new), current, new, start0) for new in tries]
        current_sse = sse_of(current.model, current.params, SCREEN_STEP_S)
        rnd = []
        for cand in (pool.map(_try, jobs) if pool else map(_try, jobs)):
            tick(cand.fit.label)
            rnd.append(_judge(cand, current_sse, len(current.model.names), n, n_eff))
        rnd.sort(key=lambda c: (c.effect.count("+"), EFFECTS.index(c.effect.split("+")[0])))
        rounds.append(rnd)
        best = max((c for c in rnd if c.qualified), key=lambda c: c.delta_bic, default=None)
        if best is None:
            break
        tick(f"refit {best.fit.label}")
        bases.update({effect: current for effect in best.evidence})   # the model each effect extended
        current = fit_tractor(best.fit.model, refine_timing(best.fit.model, best.fit.params),
                              budget=FINAL_BUDGET)
        selected += best.effect.split("+")
        evidence.update(best.evidence)
    if current.model.has_sharp_edges:   # the final fit with the cleat edges resolved for the anti-alias filter
        tick(f"refit {current.label}, edges resolved")
        fine = TractorFitModel(current.model.effects, pb, resolve_edges=True)
        current = fit_tractor(fine, current.params, budget=FINAL_BUDGET, step_check=True)
    else:   # the named model once more from its optimum, with the grid step checked
        current = fit_tractor(current.model, current.params, budget=FINAL_BUDGET, step_check=True)
    left = {c: unexplained(pb, current.prediction, c) for c in pb.channels}
    evidence = final_evidence(current, bases, evidence)
    return {"baseline": baseline, "final": current, "selected": selected, "rounds": rounds,
            "evidence": evidence, "unexplained": left}
