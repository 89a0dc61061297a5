"""Whole-tractor co-simulation (``simulate_tractor``) with four native FMUs and with four pythonfmu FMUs.

A rig recording of a tractor (enveloping tires, 10 km/h) is diagnosed once;
the fitted tire laws are built as four extended tire FMUs with each backend
(the same start values), and :func:`identification.fmu.tractor_cosim.simulate_tractor`
runs each set under the diagnosed body, interleaved over ``--rounds``.  Prints

* the wall time per run (median, range) of each backend and the ratio
  pythonfmu / native (goal: >= 2), and the same for the stepping loop alone
  (``step_body_fmus``, timed inside the run);
* that both give the same prediction (largest difference, m/s²);
* the cost of one tire-step (fmi2SetReal of 6 inputs, fmi2GetReal of the
  force, fmi2DoStep) of each backend in a bare loop: through fmpy's wrappers,
  through the master's callbacks, and the FMI calls alone (as the stepping loop
  makes them, inline; for a pythonfmu FMU this includes the Python slave it
  runs), the last times the run's tire-steps splitting the stepping loop into
  FMI calls and the master in Python;
* where the time goes (one cProfile run each): the stepping loop, opening and
  closing the FMUs, fmpy's wrappers (set-up only) and the rest (problem
  set-up, reading the laws, equilibrium, low-pass, prediction).

Prints the figures; it is not a test.  Usage::

    python benchmarks/bench_tractor_cosim.py [--rounds 3] [--workers 2]
"""

from __future__ import annotations

import argparse
import cProfile
import ctypes
import json
import pstats
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from build_scripts import build_fmu
from identification.fmu import tractor_cosim
from identification.fmu.cosim import TireFmu, step_fn
from identification.diagnose.run import run_tractor_diagnosis
from identification.recording import read_recording
from identification.rig import run_rig, write_run
from identification.fmu.tractor_cosim import simulate_tractor

BACKENDS = ("native", "pythonfmu")
#: Wall time (s) of each call of the master's stepping loop (``step_body_fmus``) inside ``simulate_tractor``.
STEPPING: list = []


def _timed_stepping(step_body_fmus):
    """`step_body_fmus` that appends its wall time to :data:`STEPPING` (the stepping part of a run, FMUs open)."""
    def timed(*args, **kwargs):
        start = time.perf_counter()
        try:
            return step_body_fmus(*args, **kwargs)
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


def tire_step_seconds(path: Path, n: int = 20000) -> dict:
    """Wall time of one tire-step (set the 6 inputs, get the force, doStep), bare loop: {"fmpy": through fmpy's
    setReal/getReal/doStep, "callbacks": through TireFmu.force_fn and step_fn, "fmi": the calls alone, inline}."""
    out = {}
    with TireFmu(path, instance_name="bench") as tire:
        tire.initialize(0.0)
        z = tire.parameters()["unloaded_radius"] - 0.03
        s, in_vrs, f_vrs = tire.slave, tire.input_vrs, tire.force_vr
        start = time.perf_counter()
        for i in range(n):
            s.setReal(in_vrs, [z + 1e-6 * (i & 63), 0.0, 0.0, 0.0, 0.0, 0.0])
            s.getReal(f_vrs)
            s.doStep(i * 1e-3, 1e-3)
        out["fmpy"] = (time.perf_counter() - start) / n
        force, do_steps = tire.force_fn(), step_fn([tire])
        start = time.perf_counter()
        for i in range(n, 2 * n):
            force(z + 1e-6 * (i & 63), 0.0, 0.0, 0.0, 0.0, 0.0)
            do_steps(i * 1e-3, 1e-3)
        out["callbacks"] = (time.perf_counter() - start) / n
        set_real, get_real, c, vrs, n_in, values, f_vr, one, value = tire.exchange_args()
        do_step = tire._raw.do_step  # as step_fn calls it
        t_now, size, true = ctypes.c_double(), ctypes.c_double(1e-3), ctypes.c_int(1)
        start = time.perf_counter()
        for i in range(2 * n, 3 * n):
            values[:] = (z + 1e-6 * (i & 63), 0.0, 0.0, 0.0, 0.0, 0.0)
            set_real(c, vrs, n_in, values)
            get_real(c, f_vr, one, value)
            t_now.value = i * 1e-3
            do_step(c, t_now, size, true)
        out["fmi"] = (time.perf_counter() - start) / n
    return out


def profile_split(paths, rec, doc) -> dict:
    """Seconds of one profiled ``simulate_tractor`` run: the stepping loop (the master and the FMI calls it makes
    inline), opening and closing the FMUs, fmpy's setReal/getReal/doStep wrappers (set-up) and the rest (problem
    set-up, reading the laws, equilibrium, low-pass, prediction)."""
    profiler = cProfile.Profile()
    profiler.enable()
    simulate_tractor(paths, rec, doc)
    profiler.disable()
    stats = pstats.Stats(profiler).stats  # (file, line, name) -> (cc, nc, tottime, cumtime, callers)

    def cumulative(name, file_part):
        return sum(v[3] for k, v in stats.items() if k[2] == name and file_part in k[0])

    total = cumulative("simulate_tractor", "tractor_cosim")
    stepping = cumulative("step_body_fmus", "tractor_cosim")
    wrappers = sum(cumulative(n, "fmpy") for n in ("setReal", "getReal", "doStep"))
    # TireFmu: read the model description, extract, instantiate; close: free, remove the folder
    opening = cumulative("__init__", "identification/fmu/cosim.py") + cumulative("close", "identification/fmu/cosim.py")
    return {"total": total, "stepping": stepping, "open": opening, "fmpy": wrappers,
            "rest": total - stepping - opening - wrappers,
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
        tractor_cosim.step_body_fmus = _timed_stepping(tractor_cosim.step_body_fmus)
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
            print(f"  {b:<10} median {statistics.median(times[b]):6.3f} s  (min {min(times[b]):.3f}, "
                  f"max {max(times[b]):.3f})")
        ratio = statistics.median(times["pythonfmu"]) / statistics.median(times["native"])
        print(f"  ratio pythonfmu / native: {ratio:.2f}x (goal >= 2)")
        step_median = {b: statistics.median(stepping[b]) for b in BACKENDS}
        print("  of which the stepping loop alone (step_body_fmus: master and FMI calls, FMUs open): "
              + ", ".join(f"{b} {step_median[b]:.3f} s" for b in BACKENDS)
              + f", ratio {step_median['pythonfmu'] / step_median['native']:.2f}x")
        diff = max(float(np.max(np.abs(results["native"].predicted[c] - results["pythonfmu"].predicted[c])))
                   for c in results["native"].channels)
        print(f"  same prediction: largest difference {diff:.2e} m/s²; NRMSE native "
              + ", ".join(f"{c} {results['native'].nrmse[c]:.4f}" for c in results["native"].channels))
        per_step = {b: tire_step_seconds(sets[b]["FL"]) for b in BACKENDS}
        print("one tire-step (set 6 inputs, get the force, doStep), bare loop:")
        for way, label in (("fmpy", "through fmpy's wrappers"), ("callbacks", "through the master's callbacks"),
                           ("fmi", "the FMI calls alone, inline")):
            print(f"  {label:<31} " + ", ".join(f"{b} {per_step[b][way] * 1e6:5.2f} us" for b in BACKENDS))
        print(f"  stepping loop = its FMI calls ({4 * steps} tire-steps x the last) + the master in Python: "
              + ", ".join(f"{b} {per_step[b]['fmi'] * 4 * steps:.3f} s + "
                          f"{step_median[b] - per_step[b]['fmi'] * 4 * steps:.3f} s" for b in BACKENDS))
        print("where the time goes (one cProfile run each; profiling slows the Python parts):")
        columns = ("total", "stepping", "open", "fmpy", "rest")
        print(f"  {'':<10} " + " ".join(f"{c:>8}" for c in columns) + "  fmpy wrapper calls")
        for b in BACKENDS:
            split = profile_split(sets[b], rec, doc)
            print(f"  {b:<10} " + " ".join(f"{split[c]:7.3f}s" for c in columns) + "  "
                  + ", ".join(f"{n} {c}" for n, c in split["calls"].items()))
        print("  stepping: the stepping loop (the master and the FMI calls it makes inline); open: extracting, "
              "instantiating and freeing the FMUs; fmpy: its setReal/getReal/doStep wrappers (set-up); rest: "
              "problem set-up, reading the laws, equilibrium, low-pass, prediction")
    return 0


if __name__ == "__main__":
    sys.exit(main())
