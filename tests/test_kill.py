"""Killed and interrupted runs: no worker outlives its parent, Ctrl-C stops a report at once, a re-run succeeds."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from identification.rig import run_rig, write_run

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    """Three one-channel rig recordings: a report of them keeps two workers busy for several seconds."""
    folder = tmp_path_factory.mktemp("day")
    for i, effects in enumerate(((), ("enveloping",), ("lift_off",))):
        write_run(run_rig(effects, {"sensor.channels": "FL"}, seed=10 + i), folder / f"run_{i}")
    return folder


def _children(pid: int) -> list[int]:
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _start_report(day, out):
    return subprocess.Popen([sys.executable, "-m", "identification.cli", "report", str(day), "-o", str(out),
                             "--workers", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for_workers(proc, n=2, timeout=60.0) -> list[int]:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        kids = _children(proc.pid)
        if len(kids) >= n:
            time.sleep(0.5)          # the workers started their first jobs
            return _children(proc.pid)
        if proc.poll() is not None:
            pytest.fail(f"the report ended before its workers started: {proc.communicate()}")
        time.sleep(0.05)
    pytest.fail("no workers started")


def test_sigkill_to_the_parent_leaves_no_worker_alive_and_a_rerun_succeeds(day, tmp_path):
    out = tmp_path / "out"
    proc = _start_report(day, out)
    workers = _wait_for_workers(proc)
    proc.kill()
    proc.wait(timeout=10)
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline and any(_alive(w) for w in workers):
        time.sleep(0.05)
    assert not [w for w in workers if _alive(w)], "workers outlived their killed parent"
    # a re-run into the same folder succeeds and leaves no staging file of either run (one planted as a
    # killed write would leave it)
    (out / "fmu").mkdir(parents=True, exist_ok=True)
    (out / "fmu" / ".run_0_FL.abc123.fmu.part").write_bytes(b"half")
    (out / ".report.html.xyz.tmp").write_text("half")
    rerun = subprocess.run([sys.executable, "-m", "identification.cli", "report", str(day), "-o", str(out),
                            "--workers", "2"], capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert (out / "report.html").is_file()
    staging = [p for p in out.rglob("*") if p.name.startswith(".") or p.suffix in (".tmp", ".part")]
    assert staging == []


def test_sigint_stops_a_report_within_2_s_with_exit_130_and_no_traceback(day, tmp_path):
    proc = _start_report(day, tmp_path / "out")
    workers = _wait_for_workers(proc)
    t0 = time.monotonic()
    os.killpg(os.getpgid(proc.pid), signal.SIGINT) if os.getpgid(proc.pid) != os.getpgrp() else \
        proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("SIGINT did not stop the report within 10 s")
    elapsed = time.monotonic() - t0
    assert proc.returncode == 130, (proc.returncode, err)
    assert elapsed <= 2.0, elapsed
    assert "Traceback" not in err and err.strip().count("\n") == 0, err
    time.sleep(0.2)
    assert not [w for w in workers if _alive(w)]
