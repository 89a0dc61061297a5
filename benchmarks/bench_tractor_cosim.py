"""Whole-tractor co-simulation (``simulate_tractor``) with four native FMUs and with four pythonfmu FMUs.

A rig recording of a tractor (enveloping tires, 10 km/h) is diagnosed once;
the fitted tire laws are built as four extended tire FMUs with each backend
(the same start values), and :func:`identification.tractor_cosim.simulate_tractor`
runs each set under the diagnosed body, interleaved over ``--rounds``.  Prints

* the wall time per run (median, range) of each backend and the ratio
  pythonfmu / native (goal: >= 2), and the same for the stepping loop alone
  (``run_body``, timed inside the run);
* that both give the same prediction (largest difference, m/s²);
* the cost of one tire-step through fmpy (setReal of 6 inputs, getReal of the
  force, doStep) of each backend, in a bare loop;
* where the time goes (one cProfile run each): the master in Python, fmpy's
  wrappers around the FMI calls, the FMI calls themselves (for a pythonfmu FMU
  this includes the Python slave it runs) and opening/closing the FMUs.

Prints the figures; it is not a test.  Usage::

    python benchmarks/bench_tractor_cosim.py [--rounds 3] [--workers 2]
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from build_scripts import build_fmu
from identification import tractor_cosim
from identification.cosim import TireFmu
from identification.diagnose.command import run_tractor_diagnosis
from identification.recording import read_recording
from identification.rig import run_rig, write_run
from identification.tractor_cosim import simulate_tractor

BACKENDS = ("native", "pythonfmu")
#: Wall time (s) of each call of the master's stepping loop (``run_body``) inside ``simulate_tractor``.
STEPPING: list = []


def _timed_run_body(run_body):
    """`run_body` that appends its wall time to :data:`STEPPING` (the stepping part of a run, FMUs open)."""
    def timed(*args, **kwargs):
        start = time.perf_counter()
        try:
            return run_body(*args, **kwargs)
        finally:
            STEPPING.append(time.perf_counter() - start)
    return timed


def build_set(fit, folder: Path, backend: str) -> dict:
    """One extended tire FMU per wheel of `fit` with `backend`: {tire: path} (the laws of build_tractor_fmus)."""
    folder.mkdir()
    paths = {}
    for tire in fit.model.problem.channels:
        paths[tire] = build_fmu("extended_tire", folder / f"rec_{tire}.fmu", backend=backend,
                                start_values=fit.model.law(fit.params, tire))
    return paths


def tire_step_seconds(path: Path, n: int = 20000) -> float:
    """Wall time of one tire-step through fmpy (the master's force callback, then doStep), bare loop."""
    with TireFmu(path, instance_name="bench") as tire:
        tire.initialize(0.0)
        force, do_step = tire.force_fn(), tire.slave.doStep
        z = tire.parameters()["unloaded_radius"] - 0.03
        start = time.perf_counter()
        for i in range(n):
            force(z + 1e-6 * (i & 63), 0.0, 0.0, 0.0, 0.0, 0.0)
            do_step(i * 1e-3, 1e-3)
        return (time.perf_counter() - start) / n


def profile_split(paths, rec, doc) -> dict:
    """Seconds of one profiled ``simulate_tractor`` run: the FMI calls, fmpy's wrappers around them, opening and
    closing the FMUs, and the rest (the master in Python: problem set-up, low-pass, equilibrium, stepping)."""
    profiler = cProfile.Profile()
    profiler.enable()
    simulate_tractor(paths, rec, doc)
    profiler.disable()
    stats = pstats.Stats(profiler).stats  # (file, line, name) -> (cc, nc, tottime, cumtime, callers)

    def cumulative(name, file_part):
        return sum(v[3] for k, v in stats.items() if k[2] == name and file_part in k[0])

    total = cumulative("simulate_tractor", "tractor_cosim")
    fmi = cumulative("_call", "fmpy")  # the ctypes call into the FMU (and, for pythonfmu, its Python slave)
    wrappers = sum(cumulative(n, "fmpy") for n in ("setReal", "getReal", "doStep"))
    # TireFmu: read the model description, extract, instantiate; close: free, remove the folder
    opening = cumulative("__init__", "identification/cosim.py") + cumulative("close", "identification/cosim.py")
    return {"total": total, "fmi": fmi, "fmpy": wrappers - fmi, "open": opening,
            "master": total - wrappers - opening,
            "calls": {n: sum(v[1] for k, v in stats.items() if k[2] == n and "fmpy" in k[0])
                      for n in ("setReal", "getReal", "doStep")}}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3,
                        help="timed runs per backend, interleaved (default %(default)s)")
    parser.add_argument("--workers", type=int, default=2, help="processes of the diagnosis (default %(default)s)")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="bench_tractor_cosim_") as tmp:
        folder = Path(tmp)
        csv_path, _ = write_run(run_rig(("enveloping",), {"speed_kmh": 10.0}, seed=8), folder / "rec")
        rec = read_recording(csv_path)
        t = time.perf_counter()
        diag, gain = run_tractor_diagnosis(rec, workers=args.workers)
        doc = json.loads(json.dumps(diag.to_json(nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after)))
        print(f"diagnosis of {Path(csv_path).name} ({rec.time_s.size} samples, 4 channels): "
              f"{time.perf_counter() - t:.1f} s; effects {', '.join(diag.effects) or 'none'}")
        sets = {b: build_set(diag.final, folder / b, b) for b in BACKENDS}
        results = {b: simulate_tractor(sets[b], rec, doc) for b in BACKENDS}  # warm-up (imports, extraction)
        times, stepping = {b: [] for b in BACKENDS}, {b: [] for b in BACKENDS}
        tractor_cosim.run_body = _timed_run_body(tractor_cosim.run_body)
        for _ in range(args.rounds):
            for b in BACKENDS:
                t = time.perf_counter()
                results[b] = simulate_tractor(sets[b], rec, doc)
                times[b].append(time.perf_counter() - t)
                stepping[b].append(STEPPING[-1])
        steps = int(round((rec.time_s[-1] - rec.time_s[0]) / results["native"].step_s))
        print(f"simulate_tractor, 4 extended tire FMUs, step {results['native'].step_s * 1e3:g} ms "
              f"(~{steps} steps over the recording), {args.rounds} rounds:")
        for b in BACKENDS:
            print(f"  {b:<10} median {statistics.median(times[b]):6.2f} s  (min {min(times[b]):.2f}, "
                  f"max {max(times[b]):.2f})")
        ratio = statistics.median(times["pythonfmu"]) / statistics.median(times["native"])
        print(f"  ratio pythonfmu / native: {ratio:.2f}x (goal >= 2)")
        print("  of which the stepping loop alone (run_body: master, fmpy and FMI calls, FMUs open): "
              + ", ".join(f"{b} {statistics.median(stepping[b]):.3f} s" for b in BACKENDS)
              + f", ratio {statistics.median(stepping['pythonfmu']) / statistics.median(stepping['native']):.2f}x")
        diff = max(float(np.max(np.abs(results["native"].predicted[c] - results["pythonfmu"].predicted[c])))
                   for c in results["native"].channels)
        print(f"  same prediction: largest difference {diff:.2e} m/s²; NRMSE native "
              + ", ".join(f"{c} {results['native'].nrmse[c]:.4f}" for c in results["native"].channels))
        per_step = {b: tire_step_seconds(sets[b]["FL"]) for b in BACKENDS}
        print("one tire-step through fmpy (set 6 inputs, get the force, doStep), bare loop: "
              + ", ".join(f"{b} {per_step[b] * 1e6:.1f} us" for b in BACKENDS)
              + f"; x {4 * steps} tire-steps per run: "
              + ", ".join(f"{b} {per_step[b] * 4 * steps:.3f} s" for b in BACKENDS))
        print("where the time goes (one cProfile run each; profiling slows the Python parts):")
        columns = ("total", "master", "fmpy", "fmi", "open")
        print(f"  {'':<10} " + " ".join(f"{c:>7}" for c in ("total", "master", "fmpy", "FMI", "open")) + "  calls")
        for b in BACKENDS:
            split = profile_split(sets[b], rec, doc)
            print(f"  {b:<10} " + " ".join(f"{split[c]:6.2f}s" for c in columns) + "  "
                  + ", ".join(f"{n} {c}" for n, c in split["calls"].items()))
        print("  master: the co-simulation master in Python (problem set-up, low-pass, equilibrium, stepping); "
              "fmpy: its setReal/getReal/doStep wrappers; FMI: the calls into the FMUs; open: extracting, "
              "instantiating and freeing the FMUs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
