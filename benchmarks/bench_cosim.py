"""Co-simulation speed: a 5 s quarter-tractor run vs the bare fmpy loop (goal: ratio <= 1.2).

Side by side in one process, the same tire FMU and the same number of steps:

* bare loop: instantiate, initialize, then per step ``setReal`` (4 inputs), ``doStep``,
  ``getReal`` (force), then terminate and free;
* co-simulation: :func:`identification.fmu.cosim.run_quarter_tractor` over a 5 s recording
  span at the default step (equilibrium search, cleat, master integration included).

Prints the median of 5 alternating rounds, for the stepping loops alone and for the whole
calls.  Run: ``python benchmarks/bench_cosim.py``.
"""

import shutil
import statistics
import tempfile
import time
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from build_scripts import build_fmu
from identification.fmu.cosim import run_quarter_tractor
from identification.fmu.validation import DEFAULT_MAX_STEP_S


def bare_loop(fmu, n_steps, h):
    t_all = time.perf_counter()
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzip = extract(str(fmu))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="bare")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    ins = [vr["hub_z"], vr["hub_vz"], vr["road_z"], vr["road_vz"]]
    out = [vr["force_z"]]
    t = 0.0
    t_loop = time.perf_counter()
    for i in range(n_steps):
        slave.setReal(ins, [0.66, 0.0, 0.0, 0.0])
        slave.doStep(t, h)
        slave.getReal(out)
        t += h
    t_loop = time.perf_counter() - t_loop
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(unzip, ignore_errors=True)
    return t_loop, time.perf_counter() - t_all


def cosim(fmu):
    t_all = time.perf_counter()
    res = run_quarter_tractor(fmu, mass_kg=1168.6, speed_m_s=7 / 3.6, cleat_height_m=0.04, cleat_width_m=0.1,
                              arrival_s=0.5, t0_s=0.0, duration_s=5.0, max_step_s=DEFAULT_MAX_STEP_S)
    return res.wall_s, time.perf_counter() - t_all, res.time_s.size - 1, res.step_s


def main():
    with tempfile.TemporaryDirectory() as tmp:
        fmu = build_fmu("point_contact", Path(tmp) / "tire.fmu", start_values={"stiffness": 550e3, "damping": 4200.0})
        _, _, n_steps, h = cosim(fmu)  # warm-up and step count
        bare_loop(fmu, 1000, h)
        rows = {"bare": [], "cosim": []}
        for _ in range(5):
            rows["bare"].append(bare_loop(fmu, n_steps, h))
            rows["cosim"].append(cosim(fmu)[:2])
    med = {k: (statistics.median(r[0] for r in v), statistics.median(r[1] for r in v)) for k, v in rows.items()}
    print(f"5 s quarter-tractor run, {n_steps} steps of {h * 1e3:.4f} ms (median of 5 alternating rounds)")
    print(f"  bare fmpy loop (setReal, doStep, getReal): loop {med['bare'][0]:.3f} s "
          f"({n_steps / med['bare'][0]:,.0f} steps/s), whole call {med['bare'][1]:.3f} s")
    print(f"  co-simulation (run_quarter_tractor)      : loop {med['cosim'][0]:.3f} s "
          f"({n_steps / med['cosim'][0]:,.0f} steps/s), whole call {med['cosim'][1]:.3f} s")
    print(f"  ratio co-simulation / bare: loop {med['cosim'][0] / med['bare'][0]:.3f}, "
          f"whole call {med['cosim'][1] / med['bare'][1]:.3f}  (goal <= 1.2)")


if __name__ == "__main__":
    main()
