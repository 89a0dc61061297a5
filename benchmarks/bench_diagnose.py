"""Diagnosis speed: one tire of a 5 s, 1 kHz recording (goal <= 5 s, aim 1 s).

One tire's diagnosis is the joint diagnosis on that tire's channel and the same side's other axle
(:func:`identification.diagnose.run.run_diagnosis`).  For several hidden effects, prints the wall time
of the diagnosis (forward selection, 2 worker processes), the time per candidate model fitted, and the
time of the FMU gain check (building the FMUs and co-simulating them with fmpy).
Run: ``python benchmarks/bench_diagnose.py``.
"""

import statistics
import time

from identification.diagnose.run import run_diagnosis
from identification.rig import run_rig

CASES = [((), "FL"), (("enveloping",), "FL"), (("lift_off",), "FL"), (("axle_coupling",), "RL"),
         (("nonlinear_stiffness",), "RR"), (("friction_damping",), "FR"), (("periodic_disturbance",), "FL"),
         (("enveloping", "lift_off"), "FL")]
SYMMETRIC = {"tire.FR.k_N_m": 550e3, "tire.FR.c_Ns_m": 4200.0, "tire.RR.k_N_m": 420e3, "tire.RR.c_Ns_m": 2400.0}


def main():
    print("diagnose one tire of a 5 s, 1 kHz, 4-channel recording (2 workers; goal <= 5 s)")
    totals = []
    for effects, tire in CASES:
        overrides = dict(SYMMETRIC) if "axle_coupling" in effects else {}
        run = run_rig(effects, dict(overrides, duration_s=5.0), seed=11)
        t = time.perf_counter()
        diag, gain = run_diagnosis(run.recording, tire, workers=2)
        total = time.perf_counter() - t
        totals.append(total)
        fits = diag.timings()
        print(f"  {'+'.join(effects) or 'baseline':<28} {tire}: {total:5.2f} s in all = diagnosis {diag.seconds:.2f} s "
              f"+ FMU gain check {gain.seconds:.2f} s; found {diag.effects}")
        print(f"      {len(fits)} models fitted, per model: median {statistics.median(fits.values()):.2f} s, "
              f"max {max(fits.values()):.2f} s ({max(fits, key=fits.get)})")
    print(f"  median over cases {statistics.median(totals):.2f} s, slowest {max(totals):.2f} s")


if __name__ == "__main__":
    main()
