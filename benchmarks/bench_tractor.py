"""Whole-tractor diagnosis speed: CPU per recording (goal: median <= 2 s, worst <= 6 s), the first run after
an install against a warm one (goal: <= 10 s more), and the stepping kernels.

Recordings: the rig's four cases (a rigid tractor, 4 channels, 5 s, 1 kHz; written to ``--cache``) and the
independent simulator's (``tests/independent``, one per setting: ``--seeds``, generated once into
``--cache``).  Each is diagnosed as the command does it, ``cleatfmu diagnose REC --json --workers 1``
(``--tire FL`` prints one tire of this same joint diagnosis: its time is the same), in a child process
per checkout (imports and the compilation excluded, after one warm-up run); the CPU counted is the
process's and its children's.  With ``--before CHECKOUT`` (another commit's worktree) the same recordings
are diagnosed by that code in the same run: both CPU times, their ratio and the largest relative change
of any tire's k or c between the two are printed side by side (tires whose joint fit collapsed, reported
as their channel's own fit by one of the two, are named instead).

Then: the wall time of one ``cleatfmu diagnose`` with an empty numba cache (a fresh install) against a
warm one, one model run stepped by the compiled kernel and by the plain-Python reference, and one
prediction's post-processing beside the channel-by-channel reference.

Run: ``python benchmarks/bench_tractor.py [--before /tmp/before] [--seeds 1-10]`` (about 1 min per
recording and checkout).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

RIG_CASES = [((), {}), (("axle_coupling",), {"cleat.stagger_m": 0.2}),
             (("axle_coupling", "enveloping"), {"cleat.stagger_m": 0.03}),
             (("axle_coupling", "enveloping", "lift_off"), {"cleat.stagger_m": 0.03})]


# --- the child: one checkout's commands, timed in-process ------------------------------------------------

def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _command(main, argv) -> tuple[float, float, dict | None]:
    out = io.StringIO()
    c0, w0 = _cpu(), time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        status = main(argv)
    cpu, wall = _cpu() - c0, time.perf_counter() - w0
    try:
        return cpu, wall, json.loads(out.getvalue()) if status == 0 else None
    except json.JSONDecodeError:
        return cpu, wall, None


def child(code: str, recordings: list[str]) -> None:
    """Print one JSON line per recording: CPU and wall of the whole-tractor diagnosis, every tire's k and c."""
    sys.path.insert(0, code)
    from identification.cli import main
    _command(main, ["diagnose", recordings[0], "--json", "--workers", "1"])     # compile or load the kernels
    for rec in recordings:
        cpu, wall, out = _command(main, ["diagnose", rec, "--json", "--workers", "1"])
        tires = (out or {}).get("tires") or {}
        print(json.dumps({"recording": rec, "cpu": cpu, "wall": wall,
                          "kc": {t: [v.get("k"), v.get("c")] for t, v in tires.items() if isinstance(v, dict)},
                          "channel_fit": [t for t, v in tires.items() if v.get("k_source") == "channel_fit"]}),
              flush=True)


# --- the parent ------------------------------------------------------------------------------------------

def rig_recordings(cache: Path) -> list[str]:
    sys.path.insert(0, str(ROOT))
    from identification.recording import write_recording
    from identification.rig import run_rig
    out = []
    for effects, overrides in RIG_CASES:
        path = cache / f"rig_{'+'.join(effects) or 'baseline'}.csv"
        if not path.exists():
            write_recording(run_rig(effects, dict(overrides, duration_s=5.0), seed=11).recording, path)
        out.append(str(path))
    return out


def independent_recordings(cache: Path, seeds: list[int]) -> list[str]:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    sys.path.insert(0, str(ROOT))
    from sweep_independent import generate, plan
    return [generate((setting, seed, str(cache))) + ".csv" for setting, seed in plan(seeds)]


def run_child(code: Path, recordings: list[str]) -> dict:
    proc = subprocess.run([sys.executable, __file__, "--child", str(code), *recordings], capture_output=True,
                          text=True, cwd=code)
    if proc.returncode:
        sys.exit(f"bench_tractor: the diagnosis in {code} failed:\n{proc.stderr[-2000:]}")
    return {r["recording"]: r for r in map(json.loads, proc.stdout.splitlines())}


def _largest_change(a: dict, b: dict, skip=()) -> float | None:
    changes = [abs(x / y - 1) for t in a if t in b and t not in skip for x, y in zip(a[t], b[t]) if x and y]
    return max(changes) if changes else None


def _table(recordings, now: dict, before: dict | None) -> None:
    print("\nwhole-tractor diagnosis: CPU s per recording (goal: median <= 2 s, worst <= 6 s)")
    print(f"  {'recording':<44} {'now':>7}" + (f" {'before':>7} {'ratio':>6} {'max |dk|,|dc|':>14}" if before else ""))
    cpus, olds = [], []
    for rec in recordings:
        r = now[rec]
        cpus.append(r["cpu"])
        line = f"  {Path(rec).stem:<44} {r['cpu']:7.2f}"
        if before:
            b = before[rec]
            olds.append(b["cpu"])
            skip = set(r.get("channel_fit", [])) | set(b.get("channel_fit", []))
            change = _largest_change(r["kc"], b["kc"], skip)
            line += f" {b['cpu']:7.2f} {b['cpu'] / r['cpu']:5.2f}x {'-' if change is None else f'{change:.1e}':>14}"
            if skip:
                line += f"  ({'/'.join(sorted(skip))}: the joint fit collapsed, the channel's fit reported)"
        print(line)
    line = f"  {'median':<44} {statistics.median(cpus):7.2f}"
    if before:   # the ratio column's median: the median recording's speed-up, not the medians' ratio
        ratios = [o / c for o, c in zip(olds, cpus)]
        line += (f" {statistics.median(olds):7.2f} {statistics.median(ratios):5.2f}x  (ratios "
                 f"{min(ratios):.2f}-{max(ratios):.2f}x, the median of the recordings' ratios)")
    print(line)
    print(f"  {'worst':<44} {max(cpus):7.2f}" + (f" {max(olds):7.2f}" if before else ""))


def first_run(recording: str) -> tuple[float, float]:
    """Wall s of ``cleatfmu diagnose`` with an empty numba cache, then warm."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        walls = []
        for _ in range(2):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "identification.cli", "diagnose", recording, "--json"],
                           capture_output=True, cwd=ROOT, env=env, check=True)
            walls.append(time.perf_counter() - t0)
    return walls[0], walls[1]


def _best_s(fn, number=50, repeat=5):
    fn()
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number


def kernels() -> None:
    from identification.model.fitting import TractorFitModel, TractorProblem
    from identification.model.kernels import run_model
    from identification.model.stepping import run_model_python
    from identification.rig import run_rig

    run = run_rig(("axle_coupling",), {"duration_s": 5.0}, seed=11)
    pb = TractorProblem.from_recording(run.recording)

    def model_theta(effects):
        model = TractorFitModel(effects, pb)
        theta = {n: 1.0 for n in model.names}
        for t in pb.channels:
            theta[f"k_{t}"], theta[f"c_{t}"] = 5e5, 3e3
        theta.update(arrival=0.5, stagger=0.0, delay=1.4, pitch_index=0.8, roll_index=0.5,
                     footprint_front=0.3, footprint_rear=0.38)
        return model, theta

    model, theta = model_theta(("axle_coupling", "roll_coupling", "enveloping"))
    record = model.record(theta)
    grid = model.grid(record)
    compiled = _best_s(lambda: run_model(record, *grid), number=20, repeat=3)
    t = time.perf_counter()
    run_model_python(record, *grid)
    python = time.perf_counter() - t
    print(f"\none model run ({grid[2]} steps, rigid tractor, 4 tires): compiled {compiled * 1e3:.2f} ms, "
          f"plain Python {python * 1e3:.0f} ms, ratio {python / compiled:.0f}x")
    model, theta = model_theta(("axle_coupling", "roll_coupling"))     # point contact: impulses
    traj = model.simulate(theta)
    predict = _best_s(lambda: model.predict(theta))
    post = _best_s(lambda: model.predict(theta, trajectory=traj))
    reference = _best_s(lambda: model.predict_reference(theta, trajectory=traj))
    print(f"one prediction (rigid tractor, point contact, 4 channels): {predict * 1e3:.2f} ms, of which "
          f"sensing + low-pass {post * 1e3:.2f} ms (channel by channel: {reference * 1e3:.2f} ms)")


def _seeds(text: str) -> list[int]:
    out = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b or a) + 1))
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", help="a checkout of the code before the change, diagnosed in the same run")
    ap.add_argument("--seeds", default="1-10", help="independent recordings (default 1-10: one per setting)")
    ap.add_argument("--cache", default="runs/bench_tractor", help="folder of the recordings")
    ap.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(args.child[0], args.child[1:])
    cache = Path(args.cache).resolve()
    cache.mkdir(parents=True, exist_ok=True)
    recordings = rig_recordings(cache) + (independent_recordings(cache, _seeds(args.seeds)) if args.seeds else [])
    print(f"{len(recordings)} recordings in {cache}; diagnosed by {ROOT}"
          + (f" and, before, by {args.before}" if args.before else ""), flush=True)
    now = run_child(ROOT, recordings)
    before = run_child(Path(args.before).resolve(), recordings) if args.before else None
    _table(recordings, now, before)
    cold, warm = first_run(recordings[1])
    print(f"\nfirst run after an install (empty numba cache) {cold:.1f} s, warm {warm:.1f} s: "
          f"{cold - warm:+.1f} s (goal <= 10 s)")
    sys.path.insert(0, str(ROOT))
    kernels()


if __name__ == "__main__":
    main()
