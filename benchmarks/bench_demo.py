"""``cleatfmu demo`` end to end: wall time and each stage's share (goal <= 60 s).

Runs the demo into a temporary folder with the machine's cores and prints the
wall time, the CPU time of each stage summed over the parallel jobs and its
share.  Run: ``python benchmarks/bench_demo.py``.
"""

import os
import tempfile
import time
from pathlib import Path

from identification.report.batch import run_batch
from identification.recording.examples import EXAMPLES, example_path
from identification.report.html import write_report


def main():
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        result = run_batch([example_path(n) for n in EXAMPLES], Path(tmp) / "demo", progress=False)
        t1 = time.perf_counter()
        write_report(result, title="benchmark")
        t2 = time.perf_counter()
    stages = dict(result.timings, report=t2 - t1)
    total = sum(stages.values())
    print(f"demo on the embedded test day ({os.cpu_count()} cores): wall {t2 - t0:.1f} s "
          f"(pipeline {t1 - t0:.1f} s, report {t2 - t1:.2f} s); goal <= 60 s")
    print(f"  CPU time per stage, summed over jobs ({total:.1f} s in all):")
    for name, sec in sorted(stages.items(), key=lambda kv: -kv[1]):
        print(f"    {name:<12} {sec:6.1f} s  {sec / total:5.1%}")
    print(f"  failures: {len(result.failures)}")


if __name__ == "__main__":
    main()
