"""Bounded cost on a huge recording: ``identify`` and ``diagnose`` of 2 M rows (goals: 15 s / 1 GB, 60 s).

The short recording is the embedded test day's run (7 km/h, the rig's
``enveloping``, ``axle_coupling`` and ``lift_off``, 30 mm cleat stagger, noise
0.05 m/s², seed 7) made 12 s long, so that its free decay has ended before
the record does.  The long recording holds that run in the middle of 2 M
rows at its 1 kHz (33 min): before and after it, the rig's own sensor noise
(white, 0.05 m/s² RMS, written to the same 4 decimals), as an acquisition
left running while the tractor waits and drives on.

Runs ``cleatfmu identify --json`` and ``cleatfmu diagnose --json`` on both as
subprocesses and prints per run the wall time, the peak RSS of the command's
process (``os.wait4``; this process stays small, as a child's peak counts
from its parent's size at the fork) and the peak RSS summed over its process
tree (the diagnosis' workers included, sampled every 20 ms from /proc; forked
workers share pages, which this counts twice) beside the goals, the notes
and progress lines the long runs wrote to stderr, and the k and c of every
tire on the long recording against the short one.

Run: ``python benchmarks/bench_huge.py`` (about 2 min), or
``python benchmarks/bench_huge.py --rows 500000 --keep DIR``; ``--rate 20000``
makes both recordings at 20 kHz (the 2 M rows are then 100 s; the diagnosis
analyses them decimated to 2 kHz).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

GOALS = {"identify": (15.0, 1024.0), "diagnose": (60.0, None)}
#: Agreement asked of the long recording's k and c with the short one's (relative).
TOLERANCE = {"identify": (0.01, 0.03), "diagnose": (0.005, 0.02)}
_DECIMALS = 4


def make_recordings(folder: Path, rows: int, *, seed: int = 7, rate_hz: float = 1000.0) -> tuple[Path, Path]:
    """Write ``short.csv`` (12 s rig run at `rate_hz`) and ``long.csv`` (`rows` rows, the run in the middle)."""
    import numpy as np

    from identification.recording import read_recording
    from identification.rig import run_rig, write_run
    from identification.rig.testday import TESTDAY

    effects, overrides, _ = TESTDAY["testday_7kmh"]
    run = run_rig(effects, dict(overrides, duration_s=12.0, **{"sensor.rate_hz": rate_hz}), seed=seed)
    short, _ = write_run(run, folder / "short", value_decimals=_DECIMALS)
    rec = read_recording(short)
    n_short = rec.time_s.size
    fs = rec.sample_rate_hz
    noise = float(overrides["sensor.noise_m_s2"])
    before = (rows - n_short) // 2
    rng = np.random.default_rng(seed + 1)
    long_csv = folder / "long.csv"
    sidecar = json.loads(short.with_suffix(".json").read_text())
    sidecar["description"] = (f"{sidecar.get('description', '')}: the 12 s run at {before / fs:g} s of a "
                              f"{rows / fs:g} s record, sensor noise around it")
    long_csv.with_suffix(".json").write_text(json.dumps(sidecar, indent=2) + "\n")
    tires = rec.tires
    fmt = ",".join(["%.6f"] + [f"%.{_DECIMALS}f"] * len(tires))
    chunk = 200_000
    with open(long_csv, "w", encoding="utf-8") as f:
        f.write("time," + ",".join(tires) + "\n")
        for a in range(0, rows, chunk):
            b = min(rows, a + chunk)
            block = np.empty((b - a, 1 + len(tires)))
            block[:, 0] = np.arange(a, b) / fs
            block[:, 1:] = np.round(noise * rng.standard_normal((b - a, len(tires))), _DECIMALS)
            lo, hi = max(a, before), min(b, before + n_short)
            if lo < hi:
                for j, tire in enumerate(tires):
                    block[lo - a:hi - a, 1 + j] = rec.accel_m_s2[tire][lo - before:hi - before]
            np.savetxt(f, block, fmt=fmt)
    return short, long_csv


def _tree_rss_mb(pid: int) -> float:
    """RSS of `pid` and its descendants, MB (from /proc)."""
    children: dict[int, list[int]] = {}
    rss: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(entry))
        rss[int(entry)] = int(fields[21])
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        total += rss.get(p, 0)
        todo += children.get(p, [])
    return total * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def run(argv: list[str]) -> dict:
    """Run ``cleatfmu ARGV``: wall time, peak RSS of the process and of its tree, stdout, stderr, status."""
    exe = [sys.executable, "-m", "identification.cli", *argv]
    start = time.perf_counter()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(exe, stdout=out, stderr=err)
        peak = [0.0]
        done = threading.Event()

        def sample():
            while not done.is_set():
                peak[0] = max(peak[0], _tree_rss_mb(proc.pid))
                done.wait(0.02)

        sampler = threading.Thread(target=sample, daemon=True)
        sampler.start()
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - start
        done.set()
        sampler.join()
        out.seek(0)
        err.seek(0)
        return {"wall_s": wall, "rss_mb": usage.ru_maxrss / 1024, "tree_mb": max(peak[0], usage.ru_maxrss / 1024),
                "stdout": out.read().decode(), "stderr": err.read().decode(), "status": proc.returncode}


def _kc(command: str, doc: dict) -> dict:
    return {t: (v["k"], v["c"]) for t, v in doc["tires"].items()}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=2_000_000, help="rows of the long recording (default %(default)s)")
    parser.add_argument("--keep", metavar="DIR", help="write the recordings into DIR and keep them")
    parser.add_argument("--rate", type=float, default=1000.0,
                        help="sampling rate of both recordings, Hz (default %(default)g, the test day's)")
    parser.add_argument("--skip-diagnose", action="store_true", help="identify only")
    parser.add_argument("--make-into", metavar="DIR", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.make_into:   # the child that writes the recordings
        make_recordings(Path(args.make_into), args.rows, rate_hz=args.rate)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.keep or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        # in a child process: a command's peak RSS (wait4) starts from its parent's RSS at the fork, so this
        # process stays small (no numpy, no recording in memory)
        subprocess.run([sys.executable, __file__, "--make-into", str(folder), "--rows", str(args.rows),
                        "--rate", str(args.rate)], check=True)
        short, long_csv = folder / "short.csv", folder / "long.csv"
        print(f"recordings at {args.rate:g} Hz: {short.name} (12 s), {long_csv.name} ({args.rows} rows, "
              f"{args.rows / args.rate:g} s, {long_csv.stat().st_size / 2 ** 20:.0f} MB), written in "
              f"{time.perf_counter() - t0:.0f} s")
        commands = [("identify", ["--json"]), ("identify", ["--json", "--method", "waveform"])]
        if not args.skip_diagnose:
            commands.append(("diagnose", ["--json"]))
        failed = False
        print(f"{'command':<28}{'recording':>10}{'wall/s':>9}{'goal':>7}{'RSS/MB':>9}{'tree/MB':>9}{'goal':>7}")
        for command, extra in commands:
            label = " ".join([command] + [e for e in extra if e != "--json"])
            results = {}
            for name, path in (("short", short), ("long", long_csv)):
                r = run([command, str(path), *extra])
                if r["status"] != 0:
                    print(f"{label}: {name}: exit {r['status']}\n{r['stderr']}")
                    return 1
                results[name] = r
                wall_goal, mem_goal = GOALS[command] if name == "long" else (None, None)
                ok = name == "short" or (r["wall_s"] <= wall_goal and (mem_goal is None or r["tree_mb"] <= mem_goal))
                failed |= not ok
                print(f"{label:<28}{name:>10}{r['wall_s']:>9.1f}{(f'{wall_goal:.0f}' if wall_goal else '-'):>7}"
                      f"{r['rss_mb']:>9.0f}{r['tree_mb']:>9.0f}{(f'{mem_goal:.0f}' if mem_goal else '-'):>7}"
                      f"{'' if ok else '   MISSED'}")
            doc_short, doc_long = json.loads(results["short"]["stdout"]), json.loads(results["long"]["stdout"])
            notes = [ln for ln in results["long"]["stderr"].splitlines() if ln.strip()]
            print(f"  stderr of the long run: {len(notes)} line(s)")
            for line in notes[:3] + (["  ..."] if len(notes) > 6 else []) + notes[max(3, len(notes) - 3):]:
                print(f"    {line}")
            window = doc_long.get("analysis_window") or next(
                ({k: v[k] for k in v if k in ("analysed_s", "record_s")} for v in doc_long["tires"].values()), None)
            print(f"  long run analysed: {window}")
            tol_k, tol_c = TOLERANCE[command]
            a, b = _kc(command, doc_short), _kc(command, doc_long)
            for tire in a:
                dk, dc = b[tire][0] / a[tire][0] - 1, b[tire][1] / a[tire][1] - 1
                ok = abs(dk) <= tol_k and abs(dc) <= tol_c
                failed |= not ok
                print(f"  {tire}: k {a[tire][0] / 1e3:9.2f} -> {b[tire][0] / 1e3:9.2f} kN/m ({dk:+.3%})   "
                      f"c {a[tire][1]:8.1f} -> {b[tire][1]:8.1f} N s/m ({dc:+.3%})   "
                      f"{'agree' if ok else 'DIFFER'} (tolerance {tol_k:.1%}, {tol_c:.1%})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
