"""Wall time of ``cleatfmu export`` in a fresh process, native binaries cached (target: <= 1 s).

* ``export``: the median (and range) over ``--runs`` cold processes of
  ``cleatfmu export PARAMS.json --tire FL -o FL.fmu`` (the console script when it
  is on PATH, and ``python -m identification.cli``), after one untimed export
  that fills the binary cache if needed;
* ``python -c pass``: the interpreter's own start-up, the floor of the above;
* ``imports``: ``python -X importtime`` of the same export: the summed import
  time, the slowest top-level imports and which heavy packages (scipy, numba,
  matplotlib, fmpy, numpy) were imported at all.

Prints the figures; it is not a test.  Usage::

    python benchmarks/bench_export.py [--runs 7]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HEAVY = ("scipy", "numba", "matplotlib", "fmpy", "control", "numpy")


def wall(cmd, cwd: Path, runs: int) -> list[float]:
    """Wall times (s) of `runs` runs of `cmd` (each must succeed)."""
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(cmd, cwd=cwd, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return times


def import_profile(cmd, cwd: Path) -> tuple[float, list[tuple[float, str]], set[str]]:
    """Summed top-level import time (s), the top-level imports by cumulative time, and the packages imported."""
    env = {**os.environ, "PYTHONPROFILEIMPORTTIME": "1"}
    err = subprocess.run(cmd, cwd=cwd, check=True, capture_output=True, text=True, env=env).stderr
    top, packages = [], set()
    for line in err.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cumulative, name = line.split("|")
        if not cumulative.strip().isdigit():
            continue  # the header
        packages.add(name.strip().split(".")[0])
        if not name[1:].startswith(" "):  # top level: one space after the bar
            top.append((int(cumulative) * 1e-6, name.strip()))
    return sum(t for t, _ in top), sorted(top, reverse=True), packages


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="cold processes per command (default %(default)s)")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        doc = subprocess.run([sys.executable, "-m", "identification.cli", "identify", "--example", "--json"],
                             check=True, capture_output=True, text=True).stdout
        (folder / "params.json").write_text(doc, encoding="utf-8")
        tail = ["export", "params.json", "--tire", "FL", "-o", "FL.fmu"]
        module = [sys.executable, "-m", "identification.cli", *tail]
        subprocess.run(module, cwd=folder, check=True, capture_output=True)  # fills the binary cache
        print(f"tire FL of the 7 km/h example: k {json.loads(doc)['tires']['FL']['k']:.6g} N/m; "
              f"FMU {(folder / 'FL.fmu').stat().st_size} bytes; {args.runs} cold runs each")
        commands = {"python -c pass": [sys.executable, "-c", "pass"], "python -m identification.cli export": module}
        script = shutil.which("cleatfmu", path=str(Path(sys.executable).parent)) or shutil.which("cleatfmu")
        if script:
            commands["cleatfmu export (console script)"] = [script, *tail]
        for label, cmd in commands.items():
            times = wall(cmd, folder, args.runs)
            print(f"{label:<36} median {statistics.median(times):6.3f} s  "
                  f"(min {min(times):.3f}, max {max(times):.3f})")
        total, top, packages = import_profile(module, folder)
        print(f"imports of the export (python -X importtime): {total:.3f} s in all; slowest top-level:")
        for seconds, name in top[:6]:
            print(f"  {seconds:6.3f} s  {name}")
        heavy = sorted(p for p in HEAVY if p in packages)
        print(f"heavy packages imported: {', '.join(heavy) if heavy else 'none'}")
        if "scipy" in packages:
            _, top_package, _ = import_profile([sys.executable, "-c", "import identification"], folder)
            print(f"  of which 'import identification' alone (the package's __init__): {top_package[0][0]:.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
