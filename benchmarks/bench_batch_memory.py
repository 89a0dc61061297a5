"""The report parent's memory against the batch size: figures stream to disk, large batches link them.

Each run is a fresh process: N copies of one small recording, every job replaced
by a stand-in that returns at once what a real job returns (numbers and its
figures: two per tire, two per recording, 40 kB of incompressible PNG-sized
bytes each), so that only the parent's bookkeeping is measured: its peak
resident memory over `run_batch` and `write_report`.

    python benchmarks/bench_batch_memory.py [--sizes 100 300 1000]
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import json, os, resource, sys, time
from pathlib import Path
import identification.report.batch as batch
from identification.report.html import write_report

FIG = 40_000

def fake_job(args):
    kind, *rest = args
    if kind == "recording":
        rep = batch.DiagnosisReport(recording=rest[1])
        rep.diagnosis = None
        rep.figures = {"diagnosis": os.urandom(FIG), "ride": os.urandom(FIG)}
    else:
        rep = batch.TireReport(recording=rest[1], tire=rest[2])
        rep.paper = {"T": 0.2, "zeta": 0.1, "delta": 0.6, "omega_n": 30.0, "k": 5e5, "c": 4e3, "r2": 0.99,
                     "n_peaks": 5, "decay_rate": 3.0}
        rep.figures = {"decay": os.urandom(FIG), "comparison": os.urandom(FIG)}
    rep.timings = {"stand-in": 0.0}
    return rep

batch._job = fake_job
paths, out = json.loads(sys.argv[1]), sys.argv[2]
if sys.argv[3] == "in-memory":                # the figures kept in the parent and embedded, as before streaming
    import identification.report.html as report_html
    batch._stream_figures = lambda rep, folder: None
    report_html.EMBED_MAX_RECORDINGS = 10 ** 9
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.perf_counter()
result = batch.run_batch(paths, out, workers=1, progress=False)
write_report(result, title="memory")
print(json.dumps({"peak_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, "start_kb": base,
                  "seconds": time.perf_counter() - t0,
                  "report_kb": os.path.getsize(Path(out) / "report.html") / 1024,
                  "linked": (Path(out) / "figures").is_dir()}))
"""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 300, 1000])
    args = ap.parse_args(argv)
    from identification.rig import run_rig, write_run

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        src, _ = write_run(run_rig((), {"sensor.channels": "FL", "sensor.rate_hz": 500.0}, seed=1), tmp / "one")
        data = tmp / "data"
        data.mkdir()
        paths = []
        for i in range(max(args.sizes)):
            dst = data / f"run_{i:04d}.csv"
            shutil.copyfile(src, dst)
            shutil.copyfile(src.with_suffix(".json"), dst.with_suffix(".json"))
            paths.append(str(dst))
        print(f"{'mode':>10}{'recordings':>11}{'parent peak MB':>16}{'per recording kB':>18}{'report MB':>11}"
              f"{'figures':>9}{'s':>7}")
        for mode in ("streamed", "in-memory"):
            first = None
            for n in args.sizes:
                out = tmp / f"out{n}"
                proc = subprocess.run([sys.executable, "-c", CHILD, json.dumps(paths[:n]), str(out), mode],
                                      capture_output=True, text=True, check=True)
                r = json.loads(proc.stdout.strip().splitlines()[-1])
                first = first or (n, r["peak_kb"])
                per = (r["peak_kb"] - first[1]) / (n - first[0]) if n > first[0] else float("nan")
                print(f"{mode:>10}{n:>11}{r['peak_kb'] / 1024:>16.1f}{per:>18.1f}{r['report_kb'] / 1024:>11.2f}"
                      f"{'linked' if r['linked'] else 'embedded':>9}{r['seconds']:>7.1f}")
                shutil.rmtree(out)
        print("figures per recording: 4 x 40 kB = 160 kB; 'in-memory' keeps them in the parent and embeds them "
              "(the behaviour before streaming)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
