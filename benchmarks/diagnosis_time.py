"""Where a whole-tractor diagnosis spends its CPU: the diagnoses and selections it runs, the fits and model
predictions they make, and one prediction's cost split into stepping, sensing and the rest.

A diagnosis runs one forward selection per start (the first, and where a channel's residual stays over
``RESCUE_RATIO`` times its noise the rescue's and the scaled searches' starts), once per sensor-sign
hypothesis and again at the fitted delay's speed where that differs from the sidecar's.  This script
counts them from the diagnosis' own progress labels and times each stretch in CPU seconds; the fits and
predictions are counted by wrapping ``fit_tractor`` and ``TractorFitModel.predict`` for the run (the code
itself is unchanged).  The split of one prediction is timed on the final model.

Run: ``python benchmarks/diagnosis_time.py REC.csv [REC.csv ...]`` (about as long as ``cleatfmu diagnose``
per recording; the first run in a process also compiles or loads the kernels, done before the timing).
"""

from __future__ import annotations

import argparse
import sys
import time
import timeit
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Progress labels that open a stretch of the diagnosis (a label that starts with one of them).
STARTS = ("starting values", "rescue:", "signs:", "refit at the speed")


def _read(path: str):
    from identification.recording import read_recording
    from identification.recording.preprocess import default_cutoff_hz
    from identification.recording.window import decimate, focus

    rec = read_recording(path)
    cutoff = default_cutoff_hz(rec.sample_rate_hz)
    return decimate(focus(rec, cutoff_hz=cutoff, announce=False), cutoff_hz=cutoff), cutoff


def measure(path: str) -> dict:
    """One recording's diagnosis, counted and timed (CPU s)."""
    from identification.diagnose import joint_select
    from identification.model.fitting import TractorFitModel

    rec, cutoff = _read(path)
    counts = {"fits": 0, "fit_cpu": 0.0, "predictions": 0}
    labels = []
    fit, predict = joint_select.fit_tractor, TractorFitModel.predict

    def counted_fit(*args, **kwargs):
        c0 = time.process_time()
        try:
            return fit(*args, **kwargs)
        finally:
            counts["fits"] += 1
            counts["fit_cpu"] += time.process_time() - c0

    def counted_predict(self, *args, **kwargs):
        counts["predictions"] += 1
        return predict(self, *args, **kwargs)

    joint_select.fit_tractor, TractorFitModel.predict = counted_fit, counted_predict
    c0 = time.process_time()
    try:
        diag = joint_select.diagnose_tractor(rec, cutoff_hz=cutoff, workers=1,
                                             progress=lambda label: labels.append((time.process_time(), label)))
    finally:
        joint_select.fit_tractor, TractorFitModel.predict = fit, predict
    total = time.process_time() - c0
    stretches, selections = [], 0
    for (t, label), nxt in zip(labels, labels[1:] + [(c0 + total, None)]):
        selections += label == "baseline"
        if label.startswith(STARTS) or not stretches:
            stretches.append([label, 0.0])
        stretches[-1][1] += nxt[0] - t
    return {"recording": Path(path).stem, "cpu": total, "effects": list(diag.effects), "selections": selections,
            "stretches": stretches, **counts, "split": split(diag), "again": {
                k: _again(diag.extra.get(k)) for k in ("rescue", "scaled_start")},
            "signs": bool(diag.extra.get("sign_test")), "refit": bool(diag.extra.get("speed_refit"))}


def _again(record) -> str:
    """What became of a selection run again from another start (``diag.extra["rescue"]`` and the like)."""
    if not record:
        return "not needed"
    if record.get("skipped"):
        return "skipped (no new start)"
    return "run, kept" if record.get("kept") else "run, not kept"


def split(diag) -> dict:
    """One prediction of the final model: ms in all, in the compiled stepping, in sensing and low-pass."""
    from identification.model.kernels import run_model
    from identification.model.sensing import sensed_lowpassed

    model, theta = diag.final.model, diag.final.params
    record = model.record(theta)
    grid = model.grid(record)
    pb = model.problem
    traj = run_model(record, *grid)

    def best(fn, number=20):
        fn()
        return min(timeit.repeat(fn, number=number, repeat=3)) / number * 1e3

    sense = best(lambda: sensed_lowpassed(traj, pb.rec.time_s, pb.rec.sample_rate_hz, pb.rec.acquisition,
                                          cutoff_hz=pb.cutoff_hz, tires=len(pb.channels)))
    return {"prediction_ms": best(lambda: model.predict(theta)), "stepping_ms": best(lambda: run_model(record, *grid)),
            "sensing_ms": sense, "steps": grid[2], "parameters": len(model.names)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("recordings", nargs="+")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    warnings.simplefilter("ignore")
    measure(args.recordings[0])          # compile or load the kernels outside the timing
    for path in args.recordings:
        r = measure(path)
        s = r["split"]
        print(f"\n{r['recording']}: {r['cpu']:.1f} s CPU, effects {'+'.join(r['effects']) or 'none'}")
        print(f"  {r['selections']} forward selections (sign hypotheses tested: {r['signs']}, refit at the delay's "
              f"speed: {r['refit']}; in the diagnosis kept, the rescue's start: {r['again']['rescue']}, the scaled "
              f"searches' start: {r['again']['scaled_start']})")
        print(f"  {r['fits']} fits of the selections, {r['fit_cpu']:.1f} s ({r['fit_cpu'] / r['cpu']:.0%}); {r['predictions']} "
              f"predictions, {r['predictions'] / max(1, r['fits']):.0f} per fit")
        print(f"  one prediction of the final model ({s['parameters']} parameters, {s['steps']} steps): "
              f"{s['prediction_ms']:.2f} ms, of which stepping {s['stepping_ms']:.2f} ms, sensing and low-pass "
              f"{s['sensing_ms']:.2f} ms")
        for label, cpu in r["stretches"]:   # a start's search runs before its label: in the stretch before
            print(f"    {cpu:6.1f} s  from '{label}' to the next such label")
    return 0


if __name__ == "__main__":
    sys.exit(main())
