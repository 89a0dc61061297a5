"""Time to generate one 4-channel, 5 s recording with the virtual rig (goal: <= 1 s).

Run: ``python benchmarks/bench_rig.py``.  Prints the median of 3 runs per case.
"""

import statistics
import time

from identification.rig import EFFECTS, run_rig

CASES = [("baseline", ())] + [(e, (e,)) for e in EFFECTS] + [
    ("test day (enveloping+axle_coupling+lift_off)", ("enveloping", "axle_coupling", "lift_off")),
    ("all six effects", EFFECTS)]


def main():
    run_rig(())  # warm-up
    print("virtual rig: one 4-channel, 5 s recording at 1 kHz (goal <= 1 s)")
    worst = 0.0
    for name, effects in CASES:
        times = []
        for seed in range(3):
            t = time.perf_counter()
            run = run_rig(effects, {"duration_s": 5.0}, seed=seed)
            times.append(time.perf_counter() - t)
        med = statistics.median(times)
        worst = max(worst, med)
        print(f"  {name:<46} {med:6.3f} s  ({run.truth['solver']['pieces']} pieces, "
              f"{run.truth['solver']['rhs_evaluations']} rhs evaluations)")
    print(f"  slowest case: {worst:.3f} s")


if __name__ == "__main__":
    main()
