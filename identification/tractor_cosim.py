"""Whole-tractor co-simulation: one tire FMU instance per wheel under the body, stepped with fmpy.

The master takes the body, the cleat and the arrivals from the model record
(:class:`identification.model.TractorModel`) and steps it with the scheme of
:mod:`identification.model.stepping` - the one the fitting models run
compiled - reading each wheel's force from its FMU (one ``doStep`` per FMU
per step, one ``setReal``/``getReal`` per force).  Before the first step it
finds each tire's static height itself, from the FMU's force (as an importer
whose body includes gravity must).
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .cosim import TireFmu
from .errors import InputError
from .model import TractorModel
from .model.stepping import run_body
from .preprocess import lowpass
from .scheme import Trajectory, _equilibrium_corner

__all__ = ["run_tractor_fmus", "TractorGain", "measure_tractor_gain", "build_tractor_fmus"]


def run_tractor_fmus(fmu_paths, record: TractorModel, *, start_s: float, step_s: float, n: int) -> Trajectory:
    """Co-simulate the record's body on one tire FMU per wheel (paths in the record's tire order).

    The FMUs carry their own parameters (an extended tire FMU with a built-in
    cleat places the cleat itself from the hub's longitudinal position).
    """
    paths = [Path(p) for p in fmu_paths]
    if len(paths) != len(record.tires):
        raise ValueError(f"one FMU per tire is needed ({len(record.tires)}), got {len(paths)}")
    J, mass, _ = record.body.matrices()
    inputs = record.inputs(start_s, step_s, n)
    loads = np.array([p["static_load"] for p in record.laws], dtype=float)
    tires = []
    try:
        for path, name in zip(paths, record.tires):
            tires.append(TireFmu(path, instance_name=name))
        forces, static = [], []
        for i, tire in enumerate(tires):
            tire.initialize(start_s)
            params = tire.parameters()
            force = tire.force_fn()
            forces.append(force)
            x0 = float(inputs.hub_x[i, 0])
            static.append(_equilibrium_corner(lambda z, f=force, x=x0: f(z, 0.0, x, 0.0, 0.0, 0.0), loads[i],
                                              params["unloaded_radius"], loads[i] / params["stiffness"]))
        q0, dq0 = record.initial_state(start_s, inputs.hub_x[:, 0], inputs.hub_vx[:, 0])

        def do_steps(t_n, h):
            for tire in tires:
                tire.slave.doStep(t_n, h)

        traj = run_body(forces, J=J, mass=mass, static_z=np.array(static), loads_n=loads, inputs=inputs,
                        start_s=start_s, step_s=step_s, q0=q0, dq0=dq0, before_step=do_steps)
    finally:
        for tire in tires:
            tire.close()
    if not np.all(np.isfinite(traj.force_n)):
        raise InputError(paths[0], "the co-simulation diverged (non-finite tire force)")
    return traj


def build_tractor_fmus(fit, directory, stem: str, *, description_prefix: str = "") -> list[Path]:
    """Build one extended tire FMU per wheel of a fitted whole-tractor model: ``DIR/<stem>_<TIRE>.fmu``."""
    from build_scripts import build_fmu

    model, params = fit.model, fit.params
    rec = model.problem.rec
    directory = Path(directory)
    out = []
    effects = sorted(e for e in model.effects)
    for tire in model.problem.channels:
        law = model.law(params, tire)
        path = directory / f"{stem}_{tire}.fmu"
        text = (f"{description_prefix}Extended tire {tire} identified jointly with the whole tractor from cleat "
                f"recording '{Path(rec.source).name}' at {rec.speed_kmh:.4g} km/h; effects: "
                f"{', '.join(effects) or 'none'}. Parameters: "
                + "; ".join(f"{k} = {v}" if isinstance(v, bool) else f"{k} = {v:.6g}" for k, v in law.items())
                + " (SI units).")
        build_fmu("extended_tire", path, start_values=law, description=text,
                  provenance={"command": "cleatfmu diagnose", "tire": tire, "effects": effects,
                              "recording": Path(rec.source).name})
        out.append(path)
    return out


@dataclass(frozen=True, eq=False)
class TractorGain:
    """Per channel NRMSE of the baseline and final models as FMUs co-simulated with fmpy."""

    nrmse_before: dict
    nrmse_after: dict
    agreement: float          # max |FMU − fitting model| / max |fitting model|, final model, all channels
    fmu_paths: list
    seconds: float


def _cosim_predict(fit, paths) -> dict:
    model = fit.model
    record = model.record(fit.params)
    traj = run_tractor_fmus(paths, record, **dict(zip(("start_s", "step_s", "n"), model.grid(record))))
    return model.predict(fit.params, trajectory=traj)


def _nrmse(problem, pred: dict) -> dict:
    w = problem.window
    return {c: float(np.sqrt(np.mean((pred[c] - problem.measured[c])[w] ** 2))
                     / np.sqrt(np.mean(problem.measured[c][w] ** 2))) for c in problem.channels}


def measure_tractor_gain(diag, fmu_dir=None, *, stem: str | None = None) -> TractorGain:
    """Build the FMUs of the baseline and of the final model, co-simulate both under the body.

    With `fmu_dir` the final model's FMUs are kept there (``<stem>_<TIRE>.fmu``,
    one per tire, written together or not at all).
    """
    t0 = time.perf_counter()
    pb = diag.problem
    stem = stem or Path(pb.rec.source).stem or "tire"
    with tempfile.TemporaryDirectory(prefix="cleatfmu_tractor_") as tmp:
        base_paths = build_tractor_fmus(diag.baseline, tmp, "baseline")
        before = _cosim_predict(diag.baseline, base_paths)
        final_paths = build_tractor_fmus(diag.final, tmp, stem)
        after = _cosim_predict(diag.final, final_paths)
        kept = []
        if fmu_dir is not None:
            from ._files import publish_files
            kept = publish_files({Path(fmu_dir) / p.name: p for p in final_paths})
    fitting = diag.final.prediction
    scale = max(float(np.max(np.abs(fitting[c]))) for c in pb.channels)
    agreement = max(float(np.max(np.abs(after[c] - fitting[c]))) for c in pb.channels) / max(scale, 1e-12)
    return TractorGain(nrmse_before=_nrmse(pb, before), nrmse_after=_nrmse(pb, after), agreement=agreement,
                       fmu_paths=kept, seconds=time.perf_counter() - t0)
