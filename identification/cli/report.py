"""``cleatfmu demo`` and ``cleatfmu report``: the whole chain into one HTML report.

Both say at once what they are about to do (stdout), show a progress bar from
the first second (stderr, on a terminal), and end by listing what they wrote
and how to open the report.

The output folder is written as one set (:class:`identification._folders.FolderSet`): the run writes
``OUT.cleatfmu-new-<pid>`` beside ``OUT`` (its temporary files too) and swaps it in whole at the end, so
that ``OUT`` holds the previous report or the new one, never a mix, and nothing of an earlier run stays.
A run that fails or is interrupted (an error, Ctrl-C, SIGTERM, a full disk: one line on stderr) leaves
``OUT`` as it was and removes its new set and the missing parents it created; one killed by SIGKILL
leaves its new set, removed by the next run on ``OUT``.  A second run on a folder while one writes it is
refused in one line naming the running one's pid (the lock ``OUT.cleatfmu-lock``, beside it).  An
existing folder is replaced only if it holds a report, or nothing a report does not write.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from ..errors import InputError

__all__ = ["add_parser", "written_lines"]


def written_lines(out: Path) -> list[str]:
    """What a report run wrote into `out`, one line per file or folder, and how to open the report.

    Parameters
    ----------
    out : Path
        The report folder.

    Returns
    -------
    list of str
        ``wrote ...`` lines (report, summary, tables, FMUs, parameters, linked figures) and one
        ``open ...`` line with the report's ``file://`` address.
    """
    def count(sub: str, pattern: str) -> int:
        folder = out / sub
        return sum(1 for _ in folder.glob(pattern)) if folder.is_dir() else 0

    from ..report.files import NOT_RECOMMENDED, POINT_CONTACT, file_counts

    n = file_counts(out)
    items = [f"{out / 'report.html'} (the report, self-contained)", f"{out / 'summary.json'} (every number, SI units)"]
    if count("tables", "*.csv"):
        items.append(f"{out / 'tables'}{os.sep} ({count('tables', '*.csv')} CSV tables)")
    if n["fmu"] or n["point_contact"] or n["fmu_not_recommended"]:
        items.append(f"{out / 'fmu'}{os.sep} ({n['fmu']} recommended tire FMUs <recording>_<TIRE>.fmu; "
                     f"{n['point_contact']} point-contact ones of the same k, c in {POINT_CONTACT}{os.sep}; "
                     f"{n['fmu_not_recommended']} not recommended in {NOT_RECOMMENDED}{os.sep}"
                     + (f"; {n['campaign']} of repeated runs' pooled k, c in campaign{os.sep}" if n["campaign"] else "")
                     + ")")
    if n["params"] or n["params_not_recommended"]:
        items.append(f"{out / 'params'}{os.sep} ({n['params']} recommended parameter files <recording>.json; "
                     f"{n['params_not_recommended']} not recommended in {NOT_RECOMMENDED}{os.sep})")
    if count("figures", "*.png"):
        items.append(f"{out / 'figures'}{os.sep} ({count('figures', '*.png')} linked figures)")
    uri = (out / "report.html").resolve().as_uri()
    return [f"wrote {item}" for item in items] + [f"open the report in a web browser: {uri}"]


def _run(paths, out, *, title: str, command: str, workers: int | None, extra: dict | None = None,
         scheduler: str | None = None, static=None) -> int:
    """Run the batch over `paths` into `out` and write the report; the exit status (2 if anything failed).

    The arguments are checked first (nothing is written for a bad one); the start line is printed before
    the heavy imports, the list of what was written and the report's address at the end.
    """
    from .util import check_folder

    t0 = time.perf_counter()
    out = Path(out)
    if workers is not None and workers < 1:
        raise InputError("--workers", f"at least 1, got {workers}")
    if out.exists() and not out.is_dir():
        raise InputError(out, "exists and is not a directory")
    check_folder(out)                   # a part of the path is a file: refused before anything is done
    if static is not None:              # the compression test is read before anything is written
        from ..report.ride import static_source
        static = static_source(static)
    from .._folders import FolderSet, raise_write_error
    from ..report.files import replace_refusal

    # the new set is written beside `out` and swapped in whole at the end (a failed run leaves `out` as it was)
    with FolderSet(out, replaceable=replace_refusal) as new:
        where = f"the Dask cluster at {scheduler}" if scheduler else \
            f"up to {workers or os.cpu_count() or 1} local process(es)"
        print(f"cleatfmu {command}: {len(paths)} recording(s) into {out}{os.sep} on {where}", flush=True)
        from ..report.batch import run_batch
        from .util import announce_compilation
        from ..report.html import write_report

        announce_compilation()
        result = run_batch(paths, new, workers=workers, scheduler=scheduler, static=static)
        raise_write_error(result.failures)      # a job that could not write (a full disk): the run failed
        t_report = time.perf_counter()
        write_report(result, title=title, extra=extra)
    result.out_dir = out
    report = out / "report.html"
    n_tires = sum(len(r.tires) for r in result.recordings)
    print(f"{report}: {len(result.recordings)} recording(s), {n_tires} tire(s) in {time.perf_counter() - t0:.1f} s "
          f"(report {time.perf_counter() - t_report:.1f} s)")
    stages = result.timings
    total = sum(stages.values()) or 1.0
    print("stage shares (CPU time summed over jobs): " +
          ", ".join(f"{k} {v / total:.0%}" for k, v in sorted(stages.items(), key=lambda kv: -kv[1])))
    print("\n".join(written_lines(out)), flush=True)
    for line in result.failures:
        print(f"cleatfmu: error: {line}", file=sys.stderr)
    return 2 if result.failures else 0


def run_demo(args) -> int:
    """``cleatfmu demo``: the whole chain on the embedded test day."""
    from ..recording.examples import EXAMPLES, compression_path, example_path
    paths = [example_path(name) for name in EXAMPLES]
    return _run(paths, args.out, title="cleatfmu demo: the embedded cleat-test day", command="demo",
                workers=args.workers, static=compression_path(),
                extra={"data": "embedded test day: " + ", ".join(p.name for p in [*paths, compression_path()])})


def run_report(args) -> int:
    """``cleatfmu report``: the whole chain over the recordings named."""
    from ..report.batch import collect_recordings
    return _run(collect_recordings(args.inputs), args.output, title=args.title, command="report",
                workers=args.workers, scheduler=args.scheduler, static=args.static)


#: The output contract, as the commands' help says it.
_ONE_SET = ("OUT is written as one set: the run writes OUT.cleatfmu-new-<pid> beside it and swaps it in at the end "
            "(nothing of an earlier report stays); a failed or interrupted run leaves OUT as it was; a second run "
            "on OUT while one writes it is refused (the lock OUT.cleatfmu-lock); an existing folder holding files "
            "a report does not write is not replaced.")


def add_parser(subparsers) -> None:
    """Register ``cleatfmu demo`` and ``cleatfmu report``."""
    workers = min(os.cpu_count() or 1, 8)
    p = subparsers.add_parser(
        "demo", help="run the whole chain on the embedded test day and write a report",
        description="Identify every tire of the embedded cleat-test day (paper's and waveform method), export the "
                    "tire FMUs, co-simulate them, diagnose, export the extended FMUs, co-simulate again, ride the "
                    "tractor on ISO 8608 roads with the paper's, the diagnosed and the embedded compression test's "
                    "static stiffness, and write "
                    "DIR/report.html (self-contained) with DIR/fmu/, DIR/params/ and DIR/summary.json. DIR and "
                    "its missing parents are created. " + _ONE_SET.replace("OUT", "DIR"))
    p.add_argument("--out", default="cleatfmu-demo", metavar="DIR", help="output folder (default: %(default)s)")
    p.add_argument("--workers", type=int, default=workers, help="processes (default: the machine's cores)")
    p.set_defaults(func=run_demo)
    r = subparsers.add_parser(
        "report", help="the whole chain over your recordings, into one report",
        description="Process recordings (files, or folders of *.csv with their sidecars) as 'demo' does. A recording "
                    "that cannot be processed is named in the summary and on stderr, the others go on; the exit "
                    "status is 2 if anything failed (if no recording can be read, nothing is written). " + _ONE_SET)
    r.add_argument("inputs", nargs="+", metavar="DIR_OR_FILE")
    r.add_argument("-o", "--output", required=True, metavar="OUT",
                   help="output folder (created with its missing parents)")
    r.add_argument("--title", default="cleatfmu report", help="report title")
    r.add_argument("--static", metavar="COMPRESSION.csv", default=None,
                   help="a compression test (as 'cleatfmu static' reads it): its static stiffness rides beside "
                        "the cleat test's k in every recording's ride comparison, named by the file (default: no "
                        "static set)")
    r.add_argument("--workers", type=int, default=workers, help="processes (default: the machine's cores)")
    r.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run the jobs on a Dask distributed cluster (e.g. tcp://host:8786; the recordings and OUT "
                        "on a file system its workers share) instead of local processes (default: local)")
    r.set_defaults(func=run_report)
