"""Extended tire FMUs from a diagnosis, and the gain measured by co-simulating them with fmpy.

The final model's tire-side effects become parameters of the extended tire
FMU (``fmu_src/extended_tire``): footprint (with its contact-pressure shape,
the Boolean ``parabolic_pressure``) and built-in cleat, unilateral contact,
stiffness exponent with its static load, friction, lugs - every entry of the
law's parameter dict, Booleans included, is a start value of the FMU.  With
``axle_coupling`` the other axle's tire gets its own FMU and both run as two
instances under the half-tractor master.  The co-simulation uses the fitting
model's grid, so that the fitting model and the FMU run compute the same
trajectory (the law is the same code; the agreement is checked to 1e-6).
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..cosim import run_half_tractor_fmus, run_quarter_tractor
from ..errors import InputError
from ..preprocess import lowpass
from .models import _PRE_S, Model
from .select import Diagnosis

__all__ = ["FMU_KIND", "GainCheck", "build_extended_fmus", "measure_gain", "fmu_start_values"]

FMU_KIND = "extended_tire"


def fmu_start_values(model: Model, params: dict, which: str = "tire") -> dict:
    """The extended FMU's parameter values for the model's tire (or the other axle's)."""
    return dict(model.tire_parameters(params, which))


def _description(diag_model: Model, params: dict, which: str) -> str:
    pb = diag_model.problem
    name = pb.tire if which == "tire" else pb.other
    effects = ", ".join(e for e in diag_model.label.split("+") if e != "baseline") or "none"
    return (f"Extended tire {name} identified from cleat recording '{pb.rec.source}' at "
            f"{pb.rec.speed_kmh:.4g} km/h; effects: {effects}. Parameters: "
            + "; ".join(f"{k} = {v:.6g}" if not isinstance(v, bool) else f"{k} = {v}"
                        for k, v in fmu_start_values(diag_model, params, which).items()) + " (SI units).")


def build_extended_fmus(model: Model, params: dict, out_path) -> list[Path]:
    """Build the FMU of the model's tire at `out_path` (and of the other axle's tire beside it).

    With ``axle_coupling`` the other axle's tire goes to ``<stem>_<TIRE>.fmu``
    next to `out_path`.  Returns the paths, the tire's first.
    """
    from build_scripts import build_fmu

    out_path = Path(out_path)
    if out_path.suffix != ".fmu":
        raise InputError(out_path, "the FMU file name must end with .fmu")
    if not out_path.parent.is_dir():
        raise InputError(out_path, f"directory {str(out_path.parent)!r} does not exist")
    paths = [out_path]
    if "axle_coupling" in model.effects:
        paths.append(out_path.with_name(f"{out_path.stem}_{model.problem.other}.fmu"))
    for path, which in zip(paths, ("tire", "other")):
        build_fmu(FMU_KIND, path, start_values=fmu_start_values(model, params, which),
                  provenance={"command": "cleatfmu diagnose", "tire": model.problem.tire if which == "tire"
                              else model.problem.other, "effects": sorted(model.effects),
                              "recording": model.problem.rec.source},
                  description=_description(model, params, which), backend="native")
    return paths


def cosimulate(model: Model, params: dict, fmu_paths) -> tuple[np.ndarray, float]:
    """Low-passed hub acceleration of the model's tire from the FMU co-simulation, and its wall time."""
    pb, rec = model.problem, model.problem.rec
    t0 = pb.first_impact_s - _PRE_S
    t_end = rec.time_s[-1] + 0.01
    wall = time.perf_counter()
    if "axle_coupling" in model.effects:
        delay = rec.rear_axle_delay_s()
        front_arrival = params["arrival"] - (0.0 if pb.front else delay)
        paths = list(fmu_paths) if pb.front else list(fmu_paths)[::-1]
        names = (pb.tire, pb.other) if pb.front else (pb.other, pb.tire)
        res = run_half_tractor_fmus(paths, loads_n=[rec.wheel_load_N[n] for n in names], wheelbase_m=rec.wheelbase_m,
                                    dynamic_index=params["dynamic_index"], speed_m_s=rec.speed_m_s,
                                    cleat_height_m=rec.cleat_height_m, cleat_width_m=rec.cleat_width_m,
                                    arrival_s=front_arrival, t0_s=t0, duration_s=t_end - t0, max_step_s=pb.step_s,
                                    cleat_profile=rec.cleat_profile)
        index = 0 if pb.front else 1
    else:
        res = run_quarter_tractor(fmu_paths[0], mass_kg=rec.mass_kg(pb.tire), speed_m_s=rec.speed_m_s,
                                  cleat_height_m=rec.cleat_height_m, cleat_width_m=rec.cleat_width_m,
                                  arrival_s=params["arrival"], t0_s=t0, duration_s=t_end - t0,
                                  max_step_s=pb.step_s, cleat_profile=rec.cleat_profile)
        index = 0
    wall = time.perf_counter() - wall
    fs = rec.sample_rate_hz
    raw = res.trajectory.mean_acceleration(index, rec.time_s, 1.0 / fs)
    return lowpass(raw, sample_rate_hz=fs, cutoff_hz=pb.cutoff_hz), wall


@dataclass(frozen=True, eq=False)
class GainCheck:
    """NRMSE of the baseline and final models as FMUs co-simulated with fmpy, and the agreement."""

    nrmse_before: float
    nrmse_after: float
    agreement: float          # max |FMU − fitting model| / max |fitting model|, final model
    fmu_paths: list
    seconds: float


def _nrmse(pred, pb) -> float:
    w = pb.window
    return float(np.sqrt(np.mean((pred - pb.measured)[w] ** 2)) / np.sqrt(np.mean(pb.measured[w] ** 2)))


def measure_gain(diag: Diagnosis, fmu_path=None) -> GainCheck:
    """Build the FMUs of the baseline and of the final model and co-simulate both.

    Parameters
    ----------
    diag : Diagnosis
    fmu_path : path-like, optional
        Where to keep the final model's FMU (and the other axle's); by default
        they are built in a temporary directory and removed.
    """
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="cleatfmu_diag_") as tmp:
        base_paths = build_extended_fmus(diag.baseline.model, diag.baseline.params, Path(tmp) / "baseline.fmu")
        before, _ = cosimulate(diag.baseline.model, diag.baseline.params, base_paths)
        target = Path(fmu_path) if fmu_path is not None else Path(tmp) / "final.fmu"
        final_paths = build_extended_fmus(diag.final.model, diag.final.params, target)
        after, _ = cosimulate(diag.final.model, diag.final.params, final_paths)
    fitting, _ = diag.final.model.predict(diag.final.params)
    agreement = float(np.max(np.abs(after - fitting)) / max(float(np.max(np.abs(fitting))), 1e-12))
    return GainCheck(nrmse_before=_nrmse(before, diag.problem), nrmse_after=_nrmse(after, diag.problem),
                     agreement=agreement, fmu_paths=final_paths if fmu_path is not None else [],
                     seconds=time.perf_counter() - t0)
