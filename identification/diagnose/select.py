"""Forward selection of effects: information criterion plus physical evidence.

Round by round, every effect not yet in the model is added to it and the
extended model is fitted (:func:`identification.diagnose.fit.fit_model`).  A
candidate qualifies when

* its BIC improves on the current model's by at least 10 ("very strong"), with
  BIC = n_eff ln(SSE / n) + p ln(n_eff) and n_eff = n · min(1, 2 f_c / f_s),
  the number of independent samples the low-pass leaves;
* it removes at least 25 % of the current residual energy (a material gain);
* it passes its physical gate (:mod:`identification.diagnose.evidence`).

The qualifying candidate with the largest BIC gain is named and becomes the
current model; the selection stops when none qualifies, so a recording the
baseline explains yields no effect at all.

Candidates are screened with the model at a 2 ms step and a small budget of
evaluations, and compared with the current model evaluated at that same step;
the named model is then refitted at the fine step (1 ms), which is the one the
FMU co-simulation reproduces.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..identify import identify_paper
from ..waveform import identify_waveform
from ..workers import one_blas_thread, process_pool, stop_pool
from .evidence import check
from .fit import Fit, fit_model, scan_arrival, sse_at
from .models import EFFECTS, PARAMETERS, Model, Problem

__all__ = ["Candidate", "Diagnosis", "diagnose", "MIN_DELTA_BIC", "MIN_GAIN"]

MIN_DELTA_BIC = 10.0
MIN_GAIN = 0.25
MAX_EFFECTS = 3
#: Step and evaluation budget of the screening fits; evaluation budget of the final fits.
SCREEN_STEP_S = 2e-3
SCREEN_BUDGET = 60
FINAL_BUDGET = 200
#: Rough relative cost of a candidate, to dispatch the long ones first.
_COST = {"axle_coupling": 4, "enveloping": 2, "periodic_disturbance": 2}
_DEFAULTS = {"footprint": 0.3, "exponent": 1.2, "friction": 100.0, "dynamic_index": 0.9}


@dataclass(frozen=True, eq=False)
class Candidate:
    """One effect tried in one round."""

    effect: str
    fit: Fit
    delta_bic: float
    gain: float           # share of the current residual energy removed
    passed_gate: bool
    qualified: bool
    evidence: str


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """What the point-contact model misses in one tire's recording, and the extended model."""

    problem: Problem
    effects: list
    baseline: Fit
    final: Fit
    rounds: list                       # list of list of Candidate
    evidence: dict
    seconds: float
    extra: dict = field(default_factory=dict)

    @property
    def tire(self) -> str:
        return self.problem.tire

    def timings(self) -> dict:
        """Seconds spent fitting each model tried (label -> s)."""
        out = {self.baseline.label: self.baseline.seconds}
        for rnd in self.rounds:
            for cand in rnd:
                out[cand.fit.label] = cand.fit.seconds
        return out

    def to_json(self, *, nrmse_before: float | None = None, nrmse_after: float | None = None) -> dict:
        """The ``diagnose --json`` document (NRMSEs from the FMU co-simulation when given)."""
        fin = self.final
        params = {name: {"value": float(fin.params[name]), "ci": [float(v) for v in fin.ci[name]],
                         "unit": PARAMETERS[name][0]} for name in fin.model.names}
        return {"tire": self.tire, "effects": list(self.effects),
                "nrmse_before": float(self.baseline.nrmse if nrmse_before is None else nrmse_before),
                "nrmse_after": float(fin.nrmse if nrmse_after is None else nrmse_after),
                "k": float(fin.params["k"]), "c": float(fin.params["c"]),
                "k_ci": [float(v) for v in fin.ci["k"]], "c_ci": [float(v) for v in fin.ci["c"]],
                "parameters": params, "evidence": dict(self.evidence)}


def _bic(sse: float, n: int, n_eff: float, p: int) -> float:
    return n_eff * math.log(sse / n) + p * math.log(n_eff)


def _starting_values(pb: Problem) -> dict:
    """k and c from the waveform fit (the paper's method if that fails), arrival at the onset."""
    def kc(sig, name):
        mass = pb.rec.mass_kg(name)
        for method in (identify_waveform, identify_paper):
            try:
                r = method(sig, mass, source=pb.rec.source)
                return r.k, r.c
            except InputError:
                pass
        # too few peaks for either method: the dominant frequency and a typical damping ratio of 0.08
        wn = 2 * math.pi * sig.dominant_hz
        return mass * wn * wn, 2 * 0.08 * mass * wn

    k, c = kc(pb.sig, pb.tire)
    start = {"k": k, "c": max(c, 50.0), "arrival": pb.sig.impact_s, "onset": pb.sig.impact_s}
    if pb.other_sig is not None:
        ko, co = kc(pb.other_sig, pb.other)
        start.update(k_other=ko, c_other=max(co, 50.0))
    return start


def periodic_start(rec, tire: str, *, first_impact_s: float, cutoff_hz: float, k: float, c: float,
                   arrival: float) -> dict | None:
    """Frequency, road amplitude and phase of a steady periodic component before the impact in one channel."""
    t = rec.time_s
    pre = t < first_impact_s - 0.05
    if pre.sum() < 0.2 * rec.sample_rate_hz:
        return None
    x = rec.accel_m_s2[tire][pre] - np.mean(rec.accel_m_s2[tire][pre])
    n = max(1 << 16, 1 << int(np.ceil(np.log2(4 * x.size))))
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n))
    f = np.fft.rfftfreq(n, 1 / rec.sample_rate_hz)
    band = (f >= 1.0) & (f <= 0.45 * cutoff_hz)
    freq = float(f[band][np.argmax(spec[band])])
    w = 2 * np.pi * freq
    basis = np.column_stack([np.sin(w * t[pre]), np.cos(w * t[pre])])
    b1, b2 = np.linalg.lstsq(basis, x, rcond=None)[0]
    accel = b1 + 1j * b2                       # a(t) = Im(accel e^{jωt})
    m = rec.mass_kg(tire)
    H = (k + 1j * w * c) / (k - m * w * w + 1j * w * c)
    road = -accel / (w * w * H)
    return {"lug_amplitude": float(abs(road)), "lug_frequency": freq,
            "lug_phase": float(np.angle(road) + w * arrival)}


def _candidate_start(model: Model, current: Fit, pb: Problem, start0: dict) -> dict:
    """Starting values for `model`: the current fit's, the waveform's k and c in the first round,
    and defaults (or estimates from the data) for the new parameters."""
    s = dict(current.params)
    if not current.model.effects:
        s.update(k=start0["k"], c=start0["c"], arrival=start0["onset"])
    for name in ("k_other", "c_other"):
        if name in start0:
            s.setdefault(name, start0[name])
    for name, value in _DEFAULTS.items():
        s.setdefault(name, value)
    s.setdefault("footprint_other", s["footprint"])
    if "periodic_disturbance" in model.effects and "lug_frequency" not in s:
        s.update(periodic_start(pb.rec, pb.tire, first_impact_s=pb.first_impact_s, cutoff_hz=pb.cutoff_hz,
                                k=s["k"], c=s["c"], arrival=s["arrival"]) or
                 {"lug_amplitude": 1e-4, "lug_frequency": 10.0, "lug_phase": 0.0})
    if "enveloping" in model.effects and "enveloping" not in current.model.effects:
        s["arrival"] += s["footprint"] / 2 / pb.rec.speed_m_s
    return {name: s[name] for name in model.names}


def _try(pb: Problem, job) -> Candidate:
    """Screen one candidate model (runs in a worker process when there are several)."""
    effects, current, start0, effect = job
    model = Model(effects, pb)
    s = _candidate_start(model, current, pb, start0)
    if len(effects) == 1 or effect == "enveloping":
        s["arrival"] = scan_arrival(model, s, step_s=SCREEN_STEP_S)
    fit = fit_model(model, s, step_s=SCREEN_STEP_S, budget=SCREEN_BUDGET)
    ok, text = check(effect, fit, current, pb)
    return Candidate(effect, fit, math.nan, math.nan, bool(ok), False, text)


def _judge(cand: Candidate, current_sse: float, current_p: int, n: int, n_eff: float) -> Candidate:
    fit = cand.fit
    gain = 1.0 - fit.sse / current_sse
    dbic = _bic(current_sse, n, n_eff, current_p) - _bic(fit.sse, n, n_eff, len(fit.model.names))
    qualified = bool(cand.passed_gate and fit.in_bounds and dbic >= MIN_DELTA_BIC and gain >= MIN_GAIN)
    return Candidate(cand.effect, fit, float(dbic), float(gain), cand.passed_gate, qualified, cand.evidence)


@one_blas_thread
def diagnose(rec, tire: str, *, cutoff_hz: float = 100.0, progress=None, effects=EFFECTS,
             workers: int = 1) -> Diagnosis:
    """Diagnose one tire of a recording.

    Parameters
    ----------
    rec : Recording
    tire : str
    cutoff_hz : float
        Low-pass cut-off of the comparison, Hz.
    progress : callable, optional
        ``progress(label)``, called before each model fit.
    effects : iterable of str
        Candidate effects (default: all six).
    workers : int
        Processes that fit a round's candidates in parallel (1: in this process).
    """
    t0 = time.perf_counter()
    from ..window import focus

    rec = focus(rec, cutoff_hz=cutoff_hz, announce=False)   # itself when the caller focused it
    pb = Problem.from_recording(rec, tire, cutoff_hz=cutoff_hz)
    tick = progress or (lambda label: None)
    start0 = _starting_values(pb)
    tick("baseline")
    base_model = Model((), pb)
    base_start = {name: start0[name] for name in base_model.names}
    base_start["arrival"] = scan_arrival(base_model, base_start)
    baseline = fit_model(base_model, base_start, budget=FINAL_BUDGET)
    n = baseline.n
    n_eff = n * min(1.0, 2 * cutoff_hz / rec.sample_rate_hz)
    current, selected, rounds, evidence = baseline, [], [], {}
    candidates_all = [e for e in effects if e != "axle_coupling" or pb.other is not None]
    pool = process_pool(workers)
    try:
        while len(selected) < MAX_EFFECTS:
            tries = sorted((e for e in candidates_all if e not in selected), key=lambda e: -_COST.get(e, 1))
            jobs = [(selected + [e], current, start0, e) for e in tries]
            current_sse = sse_at(current.model, current.params, SCREEN_STEP_S)
            rnd = []
            for cand in (pool.map(_try, [pb] * len(jobs), jobs) if pool else map(_try, [pb] * len(jobs), jobs)):
                tick(cand.fit.label)
                rnd.append(_judge(cand, current_sse, len(current.model.names), n, n_eff))
            rnd.sort(key=lambda c: EFFECTS.index(c.effect))
            rounds.append(rnd)
            best = max((c for c in rnd if c.qualified), key=lambda c: c.delta_bic, default=None)
            if best is None:
                break
            tick(f"refit {best.fit.label}")
            current = fit_model(best.fit.model, best.fit.params, budget=FINAL_BUDGET)
            selected.append(best.effect)
            evidence[best.effect] = best.evidence
    except BaseException:
        stop_pool(pool)
        raise
    if pool:
        pool.shutdown()
    # evidence restated with the final model where it still holds against the model without that effect
    for effect in selected:
        others = [e for e in selected if e != effect]
        reference = baseline if not others else next(
            (c.fit for rnd in rounds for c in rnd if set(c.fit.model.effects) == set(others)), None)
        if reference is not None:
            ok, text = check(effect, current, reference, pb)
            if ok:
                evidence[effect] = text
    return Diagnosis(problem=pb, effects=selected, baseline=baseline, final=current, rounds=rounds,
                     evidence=evidence, seconds=time.perf_counter() - t0, extra={"n_eff": n_eff})
