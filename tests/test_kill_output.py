"""SIGINT, SIGTERM and SIGKILL at random times during ``report`` and ``demo`` over an earlier run's folder.

After each: the folder holds the earlier set byte for byte (or, for a run that reached its end, printed its
result or was killed by SIGKILL after its swap, the complete new set), nothing partial is beside it (after
SIGKILL only the killed run's new set and lock, which the next run clears), no process of the run is left,
and nothing is left in ``$TMPDIR``.

``CLEATFMU_KILL_TIMES`` sets how many times per signal (default 3 for ``report``, 2 for ``demo``; the
issue's 20: ``CLEATFMU_KILL_TIMES=20``), ``CLEATFMU_KILL_SEED`` the random times (default 0).
"""

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from identification.rig import run_rig, write_run
from test_output_set import tree

# kill_suite: run in CI's own step at 20 times each (pytest -m kill_suite), not in the default run
pytestmark = [pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc"), pytest.mark.kill_suite]

SEED = int(os.environ.get("CLEATFMU_KILL_SEED", "0"))


def times(default: int) -> int:
    return int(os.environ.get("CLEATFMU_KILL_TIMES", default))


def _group(pgid: int) -> list[int]:
    """The live (not zombie) processes of the process group `pgid`."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[2]) == pgid and fields[0] != "Z":
                out.append(int(entry.name))
    return out


def _start(args, tmpdir: Path):
    env = dict(os.environ, TMPDIR=str(tmpdir))
    return subprocess.Popen([sys.executable, "-m", "identification.cli", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)


def _run(args, tmpdir: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "identification.cli", *map(str, args)], capture_output=True,
                          text=True, env=dict(os.environ, TMPDIR=str(tmpdir)), timeout=600)


def _complete_new_set(out: Path, stems: set) -> None:
    """`out` is a whole set of the later run: its summary names its recordings only, every file it lists is
    there, and no file names another recording."""
    summary = json.loads((out / "summary.json").read_text())
    assert {r["name"] for r in summary["recordings"]} == stems
    for r in summary["recordings"]:
        for path in [*r["recommended_fmus"].values(), *r["point_contact_fmus"].values(), r["params"]]:
            assert (out / path).is_file(), path
    assert all(any(s in p.name for s in stems) for p in out.rglob("*") if p.is_file() and p.parent.name != "tables"
               and p.name not in ("report.html", "summary.json"))


#: How a run answers SIGINT and SIGTERM: exit status and the last line on stderr.
ANSWERED = {signal.SIGINT: (130, "cleatfmu: interrupted"), signal.SIGTERM: (143, "cleatfmu: terminated")}


def stop_run(proc, sig, where: str) -> tuple[str, str]:
    """Send `sig` (SIGINT to the whole group, as Ctrl-C does), wait for the run and check that none of its
    processes outlives it; its stdout and stderr."""
    if sig == signal.SIGINT:
        os.killpg(proc.pid, sig)               # Ctrl-C reaches the whole foreground group
    else:
        proc.send_signal(sig)
    try:
        stdout, stderr = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail(f"{where}: the run did not stop within 60 s")
    deadline = time.monotonic() + 5.0
    while _group(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _group(proc.pid) == [], f"{where}: processes outlived the run"
    return stdout, stderr


def check_exit(where: str, sig, code: int, stderr: str) -> None:
    """130/143 with one line and no traceback, SIGKILL's own status, or the interpreter's (a signal in its
    start-up or shutdown, outside the program)."""
    if sig in ANSWERED and code == ANSWERED[sig][0]:
        assert stderr.strip().splitlines()[-1:] == [ANSWERED[sig][1]] and "Traceback" not in stderr, (where, stderr)
    elif sig == signal.SIGKILL:
        assert code in (0, -signal.SIGKILL), (where, code, stderr)
    elif code != 0:
        assert code == -sig and "identification" not in stderr, (where, code, stderr)


def check_beside(out: Path, sig, proc, killed: set, details) -> set:
    """Nothing beside `out` but what SIGKILLed runs left (their new set and the lock), which the next run that
    gets to its output clears (one stopped in its first fraction of a second leaves them to the one after);
    returns what is still left of them."""
    if sig == signal.SIGKILL:
        killed = killed | {f"{out.name}.cleatfmu-lock", f"{out.name}.cleatfmu-new-{proc.pid}"}
    left = {p.name for p in out.parent.iterdir()} - {out.name}
    assert left <= killed, (sorted(left), details)
    return killed & left


def kill_at_random_times(command: list, out: Path, earlier: Path, stems: set, window_s: float, n: int,
                         tmp_path: Path) -> dict:
    """Start `command` over a copy of `earlier` in `out` n times per signal, each stopped at a random time in
    ``(0.1, window_s)``; check each outcome (see the module); return the count per outcome.  A run that ended
    before its signal shortens the window to that time (a window measured while the machine was busier)."""
    rng = random.Random(f"{SEED} {command[0]}")
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    shutil.copytree(earlier, out, symlinks=True)
    before = tree(out)
    outcomes: dict = {}
    killed: set = set()
    for sig in [signal.SIGINT, signal.SIGTERM, signal.SIGKILL] * n:
        after_s = rng.uniform(0.1, window_s)
        where = f"{sig.name} at {after_s:.2f} s (CLEATFMU_KILL_SEED={SEED})"
        proc = _start(command, tmpdir)
        time.sleep(after_s)
        stdout, stderr = stop_run(proc, sig, where)
        code = proc.returncode
        # the earlier set, or the complete new one where the run got that far: it ended (0), its result reached
        # stdout before the signal (then answered, or the interpreter's own shutdown ended it), or SIGKILL
        # came after its swap (the old set's deletion left to the next run)
        finished = "open the report in a web browser:" in stdout
        if tree(out) == before:
            assert code != 0, (where, stdout)
        else:
            assert code == 0 or finished or sig == signal.SIGKILL, \
                f"{where}: the earlier set changed (exit {code}: {stderr[-500:]})"
            _complete_new_set(out, stems)
            shutil.rmtree(out)
            shutil.copytree(earlier, out, symlinks=True)
        check_exit(where, sig, code, stderr)
        killed = check_beside(out, sig, proc, killed, (where, code, stdout[-300:], stderr[-1500:]))
        assert list(tmpdir.iterdir()) == [], (where, sorted(p.name for p in tmpdir.iterdir()))
        outcomes[code] = outcomes.get(code, 0) + 1
        if code == 0:
            window_s = max(0.2, min(window_s, after_s))
    # what the last SIGKILL left goes with the next run on the folder (here one that finds nothing to read)
    (tmp_path / "bad.csv").write_text("t,FL\n0,1\n")
    res = _run(["report", tmp_path / "bad.csv", "-o", out], tmpdir)
    assert res.returncode == 2 and "bad.json" in res.stderr, res.stderr
    assert sorted(p.name for p in out.parent.iterdir()) == [out.name] and tree(out) == before
    assert list(tmpdir.iterdir()) == []
    return outcomes


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    """Two one-channel rig recordings: the earlier report's and the later run's."""
    root = tmp_path_factory.mktemp("recordings")
    for name, seed in (("earlier", 21), ("later", 30)):
        (root / name).mkdir()
        write_run(run_rig((), {"sensor.channels": "FL"}, seed=seed), root / name / f"{name}_run")
    return root


def test_report_killed_at_random_times_leaves_the_earlier_set_whole(recordings, tmp_path):
    """Before: killed runs left replaced FMUs under the earlier report.html, partial files and staging."""
    earlier = tmp_path / "earlier" / "out"
    scratch = tmp_path / "tmp0"
    scratch.mkdir()
    first = _run(["report", recordings / "earlier", "-o", earlier, "--workers", "2"], scratch)
    assert first.returncode == 0, first.stderr
    t0 = time.monotonic()                         # a warm run's time (the first one also compiles and builds)
    warm = _run(["report", recordings / "earlier", "-o", tmp_path / "warm" / "out", "--workers", "2"], scratch)
    whole_s = time.monotonic() - t0               # the later run is as long: one recording of the same kind
    assert warm.returncode == 0, warm.stderr
    out = tmp_path / "runs" / "out"
    out.parent.mkdir()
    outcomes = kill_at_random_times(["report", recordings / "later", "-o", out, "--workers", "2"], out, earlier,
                                    {"later_run"}, whole_s, times(3), tmp_path)
    print(outcomes)
    assert sum(n for code, n in outcomes.items() if code != 0) >= 3 * times(3) // 2, outcomes


def test_demo_killed_at_random_times_leaves_the_earlier_set_whole(demo, tmp_path):
    """Before: a demo killed at 15 s left empty fmu/, params/ and .figures-staging/ (here over an earlier
    demo's folder: its files replaced one by one).  Kill times within 12 s by default, within a warm run's
    whole duration in the robustness step (``CLEATFMU_KILL_TIMES`` set)."""
    code, earlier = demo
    assert code == 0
    out = tmp_path / "runs" / "out"
    out.parent.mkdir()
    window_s = 12.0
    if "CLEATFMU_KILL_TIMES" in os.environ:     # the robustness step: over a warm run's whole duration
        scratch = tmp_path / "tmp0"
        scratch.mkdir()
        t0 = time.monotonic()
        warm = _run(["demo", "--out", tmp_path / "warm" / "out", "--workers", "2"], scratch)
        window_s = time.monotonic() - t0
        assert warm.returncode == 0, warm.stderr
    outcomes = kill_at_random_times(["demo", "--out", out, "--workers", "2"], out, earlier,
                                    {"testday_7kmh", "testday_10kmh"}, window_s, times(2), tmp_path)
    print(outcomes)
    assert 0 not in outcomes or len(outcomes) > 1, outcomes
