"""Steps per second of the native (C) point-contact tire FMU: in a C host, and beside the pythonfmu FMU in fmpy.

* ``C host``: ``tests/native_host.c`` compiled with gcc dlopens the FMU's
  linux64 binary and runs setReal (4 inputs), doStep, getReal (force) per
  step, timed in C (target: >= 10 M steps/s);
* ``bare fmpy loop``: the loop of ``benchmarks/bench_fmu.py`` (setReal 4,
  doStep, getReal 3 outputs) for the native and the pythonfmu FMU of the same
  kind, interleaved in rounds, median per FMU (target: native >= 1.5x pythonfmu).

Prints the figures; it is not a test.  Usage::

    python benchmarks/bench_native_fmu.py [--host-steps 20000000] [--steps 20000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from bench_fmu import open_slave, steps_per_second  # noqa: E402


def host_steps_per_second(fmu: Path, folder: Path, steps: int) -> float:
    """Compile the C host with gcc and run its bench mode on the linux64 binary of `fmu`."""
    from fmpy import read_model_description

    from build_scripts.native import _fmpy_headers

    gcc = shutil.which("gcc")
    if gcc is None:
        raise SystemExit("gcc is needed for the C host")
    exe = folder / "native_host"
    source = Path(__file__).parent.parent / "tests" / "native_host.c"
    subprocess.run([gcc, "-std=c99", "-O2", "-I", str(_fmpy_headers()), "-o", str(exe), str(source), "-ldl"],
                   check=True)
    unzipped = folder / "unzipped"
    zipfile.ZipFile(fmu).extractall(unzipped)
    guid = read_model_description(str(fmu), validate=False).guid
    lib = unzipped / "binaries" / "linux64" / "CleatfmuPointContact.so"
    out = subprocess.run([str(exe), str(lib), (unzipped / "resources").as_uri(), guid, "bench", str(steps)],
                         check=True, capture_output=True, text=True).stdout
    return float(out.split()[0])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--host-steps", type=int, default=20_000_000, help="steps in the C host (default %(default)s)")
    parser.add_argument("--steps", type=int, default=20000, help="fmpy steps per round (default %(default)s)")
    parser.add_argument("--rounds", type=int, default=5, help="fmpy rounds, interleaved (default %(default)s)")
    args = parser.parse_args(argv)

    import fmpy

    from build_scripts import build_fmu

    with tempfile.TemporaryDirectory(prefix="cleatfmu_bench_native_") as tmp:
        tmp = Path(tmp)
        native = build_fmu("point_contact", tmp / "native.fmu", backend="native", platforms=["linux64"])
        python = build_fmu("point_contact", tmp / "pythonfmu.fmu", backend="pythonfmu")
        host = host_steps_per_second(native, tmp, args.host_steps)
        slaves = {"native (C)": open_slave(native, "native"), "pythonfmu": open_slave(python, "pythonfmu")}
        for slave, vr_in, vr_out in slaves.values():
            steps_per_second(slave, vr_in, vr_out, 1000)  # warm-up
        rates = {name: [] for name in slaves}
        for _ in range(args.rounds):
            for name, (slave, vr_in, vr_out) in slaves.items():
                rates[name].append(steps_per_second(slave, vr_in, vr_out, args.steps))
        for slave, _, _ in slaves.values():
            slave.terminate()
            slave.freeInstance()

    print(f"C host (gcc, dlopen, setReal 4 + doStep + getReal 1): {host / 1e6:.1f} M steps/s over "
          f"{args.host_steps:,} steps (target >= 10 M)")
    print(f"bare fmpy FMU2Slave loop (setReal 4, doStep, getReal 3); {args.rounds} rounds x {args.steps} steps; "
          f"fmpy {fmpy.__version__}, Python {sys.version.split()[0]}")
    median = {name: statistics.median(r) for name, r in rates.items()}
    for name, r in rates.items():
        print(f"  {name:<12} {median[name]:>10,.0f} steps/s  (rounds: {', '.join(f'{x:,.0f}' for x in r)})")
    print(f"  ratio native / pythonfmu: {median['native (C)'] / median['pythonfmu']:.2f} (target >= 1.5)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
