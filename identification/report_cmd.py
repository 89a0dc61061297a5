"""``cleatfmu demo`` and ``cleatfmu report``: the whole chain into one HTML report."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from .errors import InputError

__all__ = ["add_parser"]


def _run(paths, out, *, title: str, workers: int | None, extra: dict | None = None,
         scheduler: str | None = None) -> int:
    from .batch import run_batch
    from .report_html import write_report

    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(out, "exists and is not a directory")
    if not out.parent.resolve().is_dir():
        raise InputError(out, "parent directory does not exist")
    t0 = time.perf_counter()
    if workers is not None and workers < 1:
        raise InputError("--workers", f"at least 1, got {workers}")
    result = run_batch(paths, out, workers=workers, scheduler=scheduler)
    t_report = time.perf_counter()
    report = write_report(result, title=title, extra=extra)
    n_tires = sum(len(r.tires) for r in result.recordings)
    print(f"{report}: {len(result.recordings)} recording(s), {n_tires} tire(s) in {time.perf_counter() - t0:.1f} s "
          f"(report {time.perf_counter() - t_report:.1f} s)")
    stages = result.timings
    total = sum(stages.values()) or 1.0
    print("stage shares (CPU time summed over jobs): " +
          ", ".join(f"{k} {v / total:.0%}" for k, v in sorted(stages.items(), key=lambda kv: -kv[1])))
    for line in result.failures:
        print(f"cleatfmu: error: {line}", file=sys.stderr)
    return 2 if result.failures else 0


def run_demo(args) -> int:
    from .examples import EXAMPLES, example_path
    paths = [example_path(name) for name in EXAMPLES]
    return _run(paths, args.out, title="cleatfmu demo: the embedded cleat-test day", workers=args.workers,
                extra={"data": "embedded test day: " + ", ".join(p.name for p in paths)})


def run_report(args) -> int:
    from .batch import collect_recordings
    return _run(collect_recordings(args.inputs), args.output, title=args.title, workers=args.workers,
                scheduler=args.scheduler)


def add_parser(subparsers) -> None:
    workers = min(os.cpu_count() or 1, 8)
    p = subparsers.add_parser(
        "demo", help="run the whole chain on the embedded test day and write a report",
        description="Identify every tire of the embedded cleat-test day (paper's and waveform method), export the "
                    "tire FMUs, co-simulate them, diagnose, export the extended FMUs, co-simulate again, and write "
                    "DIR/report.html (self-contained) with DIR/fmu/, DIR/params/ and DIR/summary.json.")
    p.add_argument("--out", default="cleatfmu-demo", metavar="DIR", help="output folder (default: %(default)s)")
    p.add_argument("--workers", type=int, default=workers, help="processes (default: the machine's cores)")
    p.set_defaults(func=run_demo)
    r = subparsers.add_parser(
        "report", help="the whole chain over your recordings, into one report",
        description="Process recordings (files, or folders of *.csv with their sidecars) as 'demo' does. A recording "
                    "that cannot be processed is named in the summary and on stderr, the others go on; the exit "
                    "status is 2 if anything failed.")
    r.add_argument("inputs", nargs="+", metavar="DIR_OR_FILE")
    r.add_argument("-o", "--output", required=True, metavar="OUT", help="output folder")
    r.add_argument("--title", default="cleatfmu report", help="report title")
    r.add_argument("--workers", type=int, default=workers, help="processes (default: the machine's cores)")
    r.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run the jobs on a Dask distributed cluster (e.g. tcp://host:8786; the recordings and OUT "
                        "on a file system its workers share) instead of local processes (default: local)")
    r.set_defaults(func=run_report)
