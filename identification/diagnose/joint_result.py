"""The whole-tractor diagnosis' result: each screened candidate, and the diagnosis with its JSON.

Built by :func:`~identification.diagnose.joint_select.diagnose_tractor`; read by the commands, the
report and the co-simulation master.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .joint_fit import TractorFit
from .wording import effects_sentence
from ..model.fitting import TractorProblem, axle_of, parameter_unit

__all__ = ["TractorCandidate", "TractorDiagnosis", "refit_confirmed", "ONSETS_CONFIRM"]


@dataclass(frozen=True, eq=False)
class TractorCandidate:
    effect: str               # the effect(s) added, joined by "+"
    fit: TractorFit
    delta_bic: float
    gain: float
    passed_gate: bool
    qualified: bool
    evidence: dict            # effect -> sentence
    local_gain: float | None = None   # share of the residual removed where the effect acts, if judged so


@dataclass(frozen=True, eq=False)
class TractorDiagnosis:
    """What the four-corner model misses in a recording, the extended model, and what is still unexplained."""

    problem: TractorProblem
    effects: list
    baseline: TractorFit
    final: TractorFit
    rounds: list
    evidence: dict
    unexplained: dict          # channel -> None or {"share", "window", "residual_to_noise"}
    seconds: float
    extra: dict = field(default_factory=dict)

    @property
    def channels(self) -> tuple:
        return self.problem.channels

    @property
    def conditional(self) -> bool:
        """The intervals hold only if the model is right: some channel keeps a residual above noise."""
        return any(v is not None for v in self.unexplained.values())

    def timings(self) -> dict:
        out = {self.baseline.label: self.baseline.seconds}
        for rnd in self.rounds:
            for cand in rnd:
                out[cand.fit.label] = cand.fit.seconds
        return out

    def noise_nrmse(self, tire: str) -> float:
        pb = self.problem
        meas = pb.measured[tire][pb.window]
        return float(pb.noise[tire] / np.sqrt(np.mean(meas ** 2)))

    def tire_parameters(self, tire: str) -> dict:
        """The parameters of the final model that belong to one tire (its axle's, the shared ones)."""
        fin = self.final
        axle = axle_of(tire)
        out = {}
        for name in fin.model.names:
            parts = name.rsplit("_", 1)
            if name in (f"k_{tire}", f"c_{tire}"):
                key = parts[0]
            elif len(parts) == 2 and parts[1] in ("FL", "FR", "RL", "RR", "front", "rear") and \
                    parts[0] not in ("k", "c"):
                if parts[1] not in (tire, axle):
                    continue
                key = parts[0]
            elif len(parts) == 2 and parts[1] in ("FL", "FR", "RL", "RR"):
                continue
            else:
                key = name
            out[key] = {"value": float(fin.params[name]), "ci": [float(v) for v in fin.ci[name]],
                        "unit": parameter_unit(name)[0]}
        out["arrival"] = {"value": float(fin.model.arrivals(fin.params)[tire]), "ci": None, "unit": "s"}
        return out

    def to_json(self, *, nrmse_before: dict | None = None, nrmse_after: dict | None = None) -> dict:
        """The ``diagnose --json`` document of the whole tractor (NRMSEs from the FMU runs when given)."""
        fin, rec = self.final, self.problem.rec
        before = nrmse_before or self.baseline.nrmse
        after = nrmse_after or fin.nrmse

        def value(name):
            if name not in fin.params:
                return None
            return {"value": float(fin.params[name]), "ci": [float(v) for v in fin.ci[name]]}

        from .free_decay import reported

        tires = {}
        checks = self.extra.get("free_decay") or {}
        for t in self.channels:
            check = checks.get(t, {})
            k, k_ci = reported(fin.params[f"k_{t}"], fin.ci[f"k_{t}"], check, "k")
            c, c_ci = reported(fin.params[f"c_{t}"], fin.ci[f"c_{t}"], check, "c")
            tires[t] = {"k": k, "c": c, "k_ci": k_ci, "c_ci": c_ci,
                        "k_source": "channel_fit" if check.get("collapsed") or "channel_k" in check else
                        "free_decay" if check.get("prefer") else "joint_fit",
                        "c_source": "channel_fit" if check.get("collapsed") or "channel_c" in check else
                        "free_decay" if check.get("prefer") or check.get("prefer_c") else "joint_fit",
                        "effects": list(self.effects), "parameters": self.tire_parameters(t),
                        "nrmse_before": float(before[t]), "nrmse_after": float(after[t]),
                        "noise_nrmse": self.noise_nrmse(t), "unexplained": self.unexplained[t],
                        "residual_test": self.residual_test(t),
                        **({"free_decay_check": check} if check else {})}
        return {"recording": rec.source, "effects": list(self.effects),
                "summary": effects_sentence({"effects": list(self.effects), "tires": tires}),
                "body": {"pitch_index": value("pitch_index"), "roll_index": value("roll_index"),
                         "front_axle": "pivot" if "front_axle_pivot" in self.effects else "rigid",
                         "pivot_index": value("pivot_index"),
                         "speed_m_s": self.speed_json()},
                "tires": tires, "evidence": dict(self.evidence),
                **({"sign_test": self.extra["sign_test"]} if self.extra.get("sign_test") else {}),
                **({"selection_starts": starts} if (starts := {k: self.extra[k] for k in ("rescue", "scaled_start")
                                                               if self.extra.get(k)}) else {}),
                "acquisition": rec.acquisition.to_json() if rec.acquisition is not None else None,
                "intervals": "conditional on the model: it leaves a residual above the noise floor"
                             if self.conditional else "the model explains the data to within noise"}

    def residual_test(self, tire: str) -> dict:
        """The final fit's residual in `tire`'s channel against its noise floor, over the window and over its
        worst stretch (:func:`~identification.model.fitting.residual_test`; the stretch in s)."""
        return self.problem.residual_test(self.final.prediction[tire], tire)

    def speed_json(self) -> dict:
        """The speeds, m/s: the sidecar's, the impact onsets' (conditioning), the one analysed with, and the
        fitted front/rear delay's (wheelbase / delay; the footprint modelled); with a refit at the delay's
        speed, whether the onsets confirm it (:func:`refit_confirmed`)."""
        rec, delay = self.problem.rec, self.final.params.get("delay")
        cond = (rec.conditioning or {}).get("speed", {})
        refit = self.extra.get("speed_refit") or {}
        sidecar = refit.get("sidecar_m_s", cond.get("sidecar_m_s", rec.speed_m_s))
        return {"sidecar": float(sidecar), "from_onsets": cond.get("from_delay_m_s"),
                "analysed_with": float(rec.speed_m_s),
                "from_delay": float(rec.wheelbase_m / delay) if delay else None,
                **({"refit_confirmed": refit_confirmed(refit)} if refit else {})}

    def tire_json(self, tire: str, *, nrmse_before: dict | None = None, nrmse_after: dict | None = None) -> dict:
        """One tire in the per-tire ``diagnose --tire`` shape, from the joint fit."""
        doc = self.to_json(nrmse_before=nrmse_before, nrmse_after=nrmse_after)
        t = doc["tires"][tire]
        return {"tire": tire, "effects": doc["effects"],
                "summary": effects_sentence({"effects": doc["effects"], "tires": {tire: t}}),
                "nrmse_before": t["nrmse_before"], "nrmse_after": t["nrmse_after"], "noise_nrmse": t["noise_nrmse"],
                "unexplained": t["unexplained"], "k": t["k"], "c": t["c"], "k_ci": t["k_ci"], "c_ci": t["c_ci"],
                "parameters": t["parameters"], "evidence": doc["evidence"]}


#: Relative difference between a refit's speed and the impact onsets' within which the onsets confirm it: the
#: footprints shift the onsets' delay by up to about 3 % (measured on the independent simulator's tuning seeds:
#: the onsets' speed 0-4 % above the true one on its corners; the rig's within 1 %).  Beyond it the refit's
#: speed is reported as unconfirmed (a model that misfits the impacts moves its delay: 12-15 % seen).
ONSETS_CONFIRM = 0.05


def refit_confirmed(refit: dict) -> bool:
    """Whether the impact onsets' speed confirms a refit at the fitted delay's speed (`refit`: the diagnosis'
    ``extra["speed_refit"]``): within :data:`ONSETS_CONFIRM` of it; False without onsets."""
    onsets = refit.get("from_onsets_m_s")
    return onsets is not None and abs(refit["from_delay_m_s"] / onsets - 1) <= ONSETS_CONFIRM
