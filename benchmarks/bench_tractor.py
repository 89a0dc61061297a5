"""Whole-tractor diagnosis speed (goal <= 8 s, aim 4 s on 2 cores) and compiled vs plain-Python stepping.

For rig recordings of a rigid tractor (4 channels, 5 s, 1 kHz) prints the wall
time of the joint diagnosis (2 worker processes), the time per candidate
model, the FMU gain check (one extended tire FMU per wheel under the body,
fmpy), and, side by side in one run, one model run stepped by the compiled
kernel and by the plain-Python reference with the ratio, and one prediction (the
run, then every channel through the acquisition chain and the low-pass in one
compiled pass) with its post-processing beside the channel-by-channel reference.
Run: ``python benchmarks/bench_tractor.py``.
"""

import statistics
import time
import timeit

from identification.diagnose.command import run_tractor_diagnosis
from identification.diagnose.tractor import TractorFitModel, TractorProblem
from identification.model.kernels import run_model
from identification.model.stepping import run_model_python
from identification.rig import run_rig

CASES = [((), {}), (("axle_coupling",), {"cleat.stagger_m": 0.2}),
         (("axle_coupling", "enveloping"), {"cleat.stagger_m": 0.03}),
         (("axle_coupling", "enveloping", "lift_off"), {"cleat.stagger_m": 0.03})]


def _model_and_theta(run, effects=("axle_coupling", "roll_coupling", "enveloping")):
    pb = TractorProblem.from_recording(run.recording)
    model = TractorFitModel(effects, pb)
    theta = {n: 1.0 for n in model.names}
    for t in pb.channels:
        theta[f"k_{t}"], theta[f"c_{t}"] = 5e5, 3e3
    theta.update(arrival=0.5, stagger=0.0, delay=1.4, pitch_index=0.8, roll_index=0.5, footprint_front=0.3,
                 footprint_rear=0.38)
    return model, theta


def _stepping_ratio(run):
    model, theta = _model_and_theta(run)
    record = model.record(theta)
    grid = model.grid(record)
    run_model(record, *grid)                     # compile (or load the cache)
    reps = 20
    t = time.perf_counter()
    for _ in range(reps):
        run_model(record, *grid)
    compiled = (time.perf_counter() - t) / reps
    t = time.perf_counter()
    run_model_python(record, *grid)
    python = time.perf_counter() - t
    return compiled, python, grid[2]


def _best_s(fn, number=50, repeat=5):
    fn()
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number


def _prediction_times(run):
    """(predict s, its post-processing s, the channel-by-channel reference's post-processing s)."""
    model, theta = _model_and_theta(run, ("axle_coupling", "roll_coupling"))     # point contact: impulses
    traj = model.simulate(theta)
    return (_best_s(lambda: model.predict(theta)), _best_s(lambda: model.predict(theta, trajectory=traj)),
            _best_s(lambda: model.predict_reference(theta, trajectory=traj)))


def main():
    print("whole-tractor diagnosis of a 4-channel, 5 s, 1 kHz recording (2 workers; goal <= 8 s, aim 4 s)")
    totals = []
    for effects, overrides in CASES:
        run = run_rig(effects, dict(overrides, duration_s=5.0), seed=11)
        t = time.perf_counter()
        diag, gain = run_tractor_diagnosis(run.recording, workers=2)
        total = time.perf_counter() - t
        totals.append(total)
        fits = diag.timings()
        print(f"  {'+'.join(effects) or 'baseline':<36} {total:5.2f} s in all = diagnosis {diag.seconds:.2f} s + "
              f"FMU gain check {gain.seconds:.2f} s; found {diag.effects}")
        print(f"      {len(fits)} models fitted, per model: median {statistics.median(fits.values()):.2f} s, "
              f"max {max(fits.values()):.2f} s ({max(fits, key=fits.get)})")
    print(f"  median over cases {statistics.median(totals):.2f} s, slowest {max(totals):.2f} s")
    rigid = run_rig(("axle_coupling",), {"duration_s": 5.0}, seed=11)
    compiled, python, n = _stepping_ratio(rigid)
    print(f"one model run ({n} steps, rigid tractor, 4 tires): compiled {compiled * 1e3:.2f} ms, "
          f"plain Python {python * 1e3:.0f} ms, ratio {python / compiled:.0f}x")
    predict, post, reference = _prediction_times(rigid)
    print(f"one prediction (rigid tractor, point contact, 4 channels): {predict * 1e3:.2f} ms, of which "
          f"sensing + low-pass {post * 1e3:.2f} ms (channel by channel: {reference * 1e3:.2f} ms)")


if __name__ == "__main__":
    main()
