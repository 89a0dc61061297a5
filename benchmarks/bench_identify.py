"""Speed of ``identify`` on a 4-channel, 5 s, 1 kHz recording (goal: in-process <= 20 ms).

Prints the in-process time (reading the files + preprocessing + the paper's
identification, and the identification alone) and the whole-process time of
``cleatfmu identify REC.csv --json``.  Run: ``python benchmarks/bench_identify.py``.
"""

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from identification.identify.paper import identify
from identification.recording import read_recording
from identification.rig import run_rig, write_run


def _times(fn, repeat):
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return out


def main():
    with tempfile.TemporaryDirectory() as tmp:
        run = run_rig(("enveloping", "axle_coupling", "lift_off"), {"duration_s": 5.0, "sensor.rate_hz": 1000.0})
        csv_path, _ = write_run(run, Path(tmp) / "bench")
        rec = read_recording(csv_path)
        assert rec.tires == ("FL", "FR", "RL", "RR") and len(rec.time_s) == 5000
        identify(rec)  # warm-up (imports, caches)
        full = _times(lambda: identify(read_recording(csv_path)), 50)
        core = _times(lambda: identify(rec), 50)
        exe = [sys.executable, "-m", "identification.cli", "identify", str(csv_path), "--json"]
        proc = _times(lambda: subprocess.run(exe, check=True, capture_output=True), 5)
    print("identify, 4 channels x 5 s x 1 kHz")
    print(f"  in-process, read + identify : median {statistics.median(full) * 1e3:6.1f} ms  "
          f"(min {min(full) * 1e3:.1f} ms; goal <= 20 ms)")
    print(f"  in-process, identify only   : median {statistics.median(core) * 1e3:6.1f} ms  "
          f"(min {min(core) * 1e3:.1f} ms)")
    print(f"  whole process (cleatfmu identify --json): median {statistics.median(proc) * 1e3:6.0f} ms  "
          f"(min {min(proc) * 1e3:.0f} ms)")


if __name__ == "__main__":
    main()
