"""A report batch on a 2-worker Dask LocalCluster against the local process pool, side by side.

N rig recordings (default 64: one hub, 5 s at 500 Hz, seeds 0..N-1, every other one
with enveloping) go through ``cleatfmu report`` in both ways, each run a fresh process
(``--rounds`` of each, alternating which goes first):

* ``local``: ``--workers 2`` (the local pool);
* ``cluster``: ``--scheduler ADDRESS`` of a ``distributed.LocalCluster(n_workers=2,
  threads_per_worker=1)`` started beforehand (its start-up is shown apart: a report
  attaches to a running cluster).

It prints each run's wall time (the whole command), the ratio of the summed times cluster / local, the
time its jobs were busy (summed over jobs: a slower worker shows here, an idle one
only in the wall time), the report process's peak resident memory, and whether the two ``summary.json`` agree
(every number, run times aside) and the FMUs are byte-identical.  A one-recording
report runs first, so that neither run pays a cold FMU-binary cache.

    python benchmarks/bench_cluster.py [--recordings 64] [--workers 2] [--rounds 2]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: Run-time entries of ``summary.json``: they differ between any two runs.
TIMING_KEYS = {"seconds", "stage_seconds", "timings", "fmu_seconds"}

CHILD = r"""
import resource, sys
from identification.cli import main
code = main(sys.argv[1:])
print(f"PEAK_KB {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}", file=sys.stderr)
sys.exit(code)
"""


def _report(args: list[str]) -> tuple[float, float]:
    """Run ``cleatfmu report ARGS`` in a fresh process; its wall time (s) and peak resident memory (MB)."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", CHILD, "report", *args], capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"report {' '.join(args)} failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    peak = next(int(line.split()[1]) for line in proc.stderr.splitlines() if line.startswith("PEAK_KB"))
    return seconds, peak / 1024


def _strip(node):
    """`node` without its run-time entries."""
    if isinstance(node, dict):
        return {k: _strip(v) for k, v in node.items() if k not in TIMING_KEYS}
    if isinstance(node, list):
        return [_strip(v) for v in node]
    return node


def _differences(a, b, where: str = "") -> tuple[list[str], float]:
    """Structural differences of two JSON trees, and the largest relative difference of their numbers."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return [f"{where}: keys {sorted(a.keys() ^ b.keys())}"], 0.0
        out, worst = [], 0.0
        for k in a:
            o, w = _differences(a[k], b[k], f"{where}/{k}")
            out, worst = out + o, max(worst, w)
        return out, worst
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{where}: {len(a)} vs {len(b)} items"], 0.0
        out, worst = [], 0.0
        for i, (x, y) in enumerate(zip(a, b)):
            o, w = _differences(x, y, f"{where}[{i}]")
            out, worst = out + o, max(worst, w)
        return out, worst
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        if a == b or (math.isnan(a) and math.isnan(b)):
            return [], 0.0
        return [], abs(a - b) / max(abs(a), abs(b))
    return ([] if a == b else [f"{where}: {a!r} vs {b!r}"]), 0.0


def _fmu_digests(out: Path) -> dict:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted((out / "fmu").glob("*.fmu"))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--recordings", type=int, default=64, help="batch size (default: %(default)s)")
    ap.add_argument("--workers", type=int, default=2, help="local processes and cluster workers (default: 2)")
    ap.add_argument("--rounds", type=int, default=2,
                    help="runs of each (alternating which goes first, so that a drift of the machine's load "
                         "cancels; default: %(default)s)")
    args = ap.parse_args(argv)
    from distributed import LocalCluster

    from identification.rig import run_rig, write_run

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        day = tmp / "day"
        day.mkdir()
        for i in range(args.recordings):
            effects = ("enveloping",) if i % 2 else ()
            write_run(run_rig(effects, {"sensor.channels": "FL", "sensor.rate_hz": 500.0}, seed=i),
                      day / f"run_{i:03d}")
        warm = tmp / "warm"
        warm.mkdir()
        write_run(run_rig((), {"sensor.channels": "FL", "sensor.rate_hz": 500.0}, seed=999), warm / "warm")
        _report([str(warm), "-o", str(tmp / "warm_out"), "--workers", "1"])

        times = {"local": [], "cluster": []}
        peaks = {"local": [], "cluster": []}
        busy = {"local": [], "cluster": []}
        starts = []
        for i in range(args.rounds):                    # ABBA: local first in odd rounds, the cluster in even
            for mode in (("local", "cluster") if i % 2 == 0 else ("cluster", "local")):
                out = tmp / (mode if i == 0 else f"{mode}{i}")
                if mode == "local":
                    seconds, mb = _report([str(day), "-o", str(out), "--workers", str(args.workers)])
                else:
                    t0 = time.perf_counter()
                    with LocalCluster(n_workers=args.workers, threads_per_worker=1,
                                      dashboard_address=None) as cluster:
                        starts.append(time.perf_counter() - t0)
                        seconds, mb = _report([str(day), "-o", str(out), "--scheduler", cluster.scheduler_address])
                times[mode].append(seconds)
                peaks[mode].append(mb)
                busy[mode].append(sum(json.loads((out / "summary.json").read_text())["stage_seconds"].values()))
        local, remote = (json.loads((tmp / name / "summary.json").read_text()) for name in ("local", "cluster"))
        local, remote = _strip(local), _strip(remote)
        problems, worst = _differences(local, remote)
        fmus = [_fmu_digests(tmp / name) for name in ("local", "cluster")]
        same_fmus = fmus[0] == fmus[1]
        jobs = sum(1 + len(r["tires"]) for r in local["recordings"])

    print(f"{args.recordings} recordings ({jobs} jobs), {args.workers} workers, {args.rounds} round(s)")
    print(f"{'run':>8}{'wall s':>16}{'mean s':>8}{'per recording s':>17}{'jobs busy s':>13}{'report peak MB':>16}")
    for mode in ("local", "cluster"):
        mean = sum(times[mode]) / len(times[mode])
        print(f"{mode:>8}{' '.join(f'{t:.1f}' for t in times[mode]):>16}{mean:>8.1f}{mean / args.recordings:>17.2f}"
              f"{sum(busy[mode]) / len(busy[mode]):>13.1f}{max(peaks[mode]):>16.0f}")
    ratio = sum(times["cluster"]) / sum(times["local"])
    print(f"ratio cluster / local: {ratio:.3f} (goal <= 1.2); LocalCluster start-up "
          f"{max(starts):.1f} s, not included (a report attaches to a running cluster)")
    agree = "agree" if not problems and worst == 0.0 else \
        f"differ ({len(problems)} structural, largest relative difference of a number {worst:.1e})"
    print(f"summary.json (run times aside): {agree}; FMUs byte-identical: {same_fmus}")
    if not same_fmus:
        print("  FMUs that differ: " + ", ".join(sorted(k for k in set(fmus[0]) | set(fmus[1])
                                                        if fmus[0].get(k) != fmus[1].get(k)))[:300])
    for line in problems[:10]:
        print("  " + line)
    return 0 if not problems and same_fmus else 1


if __name__ == "__main__":
    sys.exit(main())
