"""A folder written as one set (``identification._folders.FolderSet``, ``report`` and ``demo``): the new set
is built beside the old one and swapped in whole; a failed run leaves the old one; a second run on the folder
is refused; what a killed run left is cleared by the next one."""

import errno
import json
import hashlib
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

import identification._folders as folders
from identification._files import OutputFolders
from identification._folders import FolderSet, sibling
from identification.errors import InputError
from identification.rig import run_rig, write_run


def tree(folder: Path) -> dict:
    """Every file (hash) and folder under `folder`, hidden ones included."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "dir"
            for p in sorted(folder.rglob("*"))}


def plant(folder: Path, files: dict) -> dict:
    for name, data in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(data)
    return tree(folder)


def beside(out: Path) -> list[str]:
    """What is in the output folder's parent."""
    return sorted(p.name for p in out.parent.iterdir())


def dead_pid() -> int:
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


PREVIOUS = {"report.html": b"<html>old</html>", "summary.json": b'{\n "format": "cleatfmu-report-summary/1"}\n',
            "fmu/other_FL.fmu": b"PK old", "fmu/point_contact/other_FL.fmu": b"PK old", "params/other.json": b"{}",
            "tables/verdict.csv": b"old", "figures/other_decay.png": b"png"}


@pytest.fixture(params=["exchange", "two renames"])
def swap(request, monkeypatch):
    """Both ways of swapping: one renameat2(RENAME_EXCHANGE), and the two renames where it is missing."""
    if request.param == "two renames":
        monkeypatch.setattr(folders, "_exchange", lambda a, b: False)
    return request.param


def test_a_set_is_written_beside_the_old_one_and_replaces_it_whole(tmp_path, swap):
    out = tmp_path / "out"
    before = plant(out, PREVIOUS)
    with FolderSet(out) as new:
        assert new == tmp_path / f"out.cleatfmu-new-{os.getpid()}"
        (new / "fmu").mkdir()
        (new / "fmu" / "mine_FL.fmu").write_bytes(b"PK new")
        assert tree(out) == before                 # a reader sees the old set until the swap
        assert beside(out) == ["out", "out.cleatfmu-lock", new.name]
    assert sorted(tree(out)) == ["fmu", "fmu/mine_FL.fmu"]
    assert beside(out) == ["out"]


@pytest.mark.parametrize("failure", ["error", "ctrl-c", "full disk"])
def test_a_failed_run_leaves_the_previous_set_and_nothing_beside_it(tmp_path, failure):
    out = tmp_path / "out"
    before = plant(out, PREVIOUS)
    raised = {"error": RuntimeError("bug"), "ctrl-c": KeyboardInterrupt(),
              "full disk": OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), "x.png")}[failure]
    expected = InputError if failure == "full disk" else type(raised)
    with pytest.raises(expected) as caught:
        with FolderSet(out) as new:
            (new / "report.html").write_bytes(b"half")
            raise raised
    if failure == "full disk":
        assert caught.value.one_line() == f"{out}: cannot write: No space left on device (the previous contents " \
                                          "are kept)"
    assert tree(out) == before and beside(out) == ["out"]


@pytest.mark.parametrize("how", ["exchange", "two renames"])
def test_ctrl_c_during_the_swap_itself_leaves_the_previous_set(tmp_path, monkeypatch, how):
    """An interrupt that comes while the names are being swapped waits for the swap's end, then undoes it."""
    out = tmp_path / "out"
    before = plant(out, PREVIOUS)
    real_exchange, real_rename, sent = folders._exchange, os.rename, []

    def interrupt_once():
        if not sent:
            sent.append(1)
            os.kill(os.getpid(), signal.SIGINT)

    def exchange(a, b):
        interrupt_once()
        return real_exchange(a, b)

    def rename(a, b):
        if Path(b) == out:                         # the new set's rename into place
            interrupt_once()
        return real_rename(a, b)

    if how == "exchange":
        monkeypatch.setattr(folders, "_exchange", exchange)
    else:
        monkeypatch.setattr(folders, "_exchange", lambda a, b: False)
        monkeypatch.setattr(folders.os, "rename", rename)
    with pytest.raises(KeyboardInterrupt):
        with FolderSet(out) as new:
            (new / "report.html").write_bytes(b"new")
    assert sent and tree(out) == before and beside(out) == ["out"]


def test_a_result_that_cannot_reach_stdout_puts_the_previous_set_back(tmp_path, swap):
    """The command's block fails after the swap (its result cannot be printed): the old set comes back."""
    out = tmp_path / "out"
    before = plant(out, PREVIOUS)
    with pytest.raises(OSError):
        with OutputFolders():
            with FolderSet(out) as new:
                (new / "report.html").write_bytes(b"new")
            assert tree(out) == {"report.html": hashlib.sha256(b"new").hexdigest()}
            raise OSError(errno.ENOSPC, "stdout")
    assert tree(out) == before and beside(out) == ["out"]
    # a new folder (and its new parents) goes whole
    deeper = tmp_path / "a" / "b" / "out"
    with pytest.raises(OSError):
        with OutputFolders():
            with FolderSet(deeper) as new:
                (new / "report.html").write_bytes(b"new")
            assert deeper.is_dir()
            raise OSError(errno.ENOSPC, "stdout")
    assert beside(out) == ["out"]


def test_a_second_run_on_the_folder_is_refused_naming_the_first(tmp_path):
    out = tmp_path / "out"
    before = plant(out, PREVIOUS)
    with FolderSet(out) as new:
        (new / "x").write_bytes(b"first")
        with pytest.raises(InputError) as caught:
            with FolderSet(out):
                pytest.fail("a second run went on")
        assert caught.value.one_line() == f"{out}: another cleatfmu run (pid {os.getpid()}) is writing this " \
                                          "folder; run again when it has ended"
        assert (new / "x").read_bytes() == b"first" and tree(out) == before
    assert tree(out) == {"x": hashlib.sha256(b"first").hexdigest()}
    with FolderSet(out):                          # the lock went with the first run
        pass
    assert beside(out) == ["out"]


def test_what_killed_runs_left_is_cleared_by_the_next_run(tmp_path):
    """SIGKILL runs no cleanup: a half-written set stays beside the folder, or (killed between the two
    renames of a swap) the previous set under its moved-away name; the next run removes the one and puts
    the other back."""
    out = tmp_path / "out"
    before = plant(out, PREVIOUS)
    pid = dead_pid()
    plant(sibling(out, "new", pid), {"fmu/half.fmu.part": b"half"})
    (tmp_path / "out.cleatfmu-lock").write_text(f"{pid}\n")
    with pytest.raises(KeyboardInterrupt):
        with FolderSet(out):
            assert beside(out) == ["out", "out.cleatfmu-lock", f"out.cleatfmu-new-{os.getpid()}"]
            raise KeyboardInterrupt
    assert tree(out) == before and beside(out) == ["out"]
    out.rename(sibling(out, "old", pid))
    plant(sibling(out, "new", pid), {"report.html": b"complete, but not swapped in"})
    with FolderSet(out) as new:
        assert tree(out) == before
        (new / "report.html").write_bytes(b"new")
    assert sorted(tree(out)) == ["report.html"] and beside(out) == ["out"]


def test_a_file_written_over_clears_only_the_temporaries_of_killed_runs(tmp_path):
    """A SIGKILLed single-file write (export, an atomic write, a backup) leaves ``.NAME.PID-XXXX.part``: the
    next write of NAME removes those whose process is gone, and keeps a live run's and other files'."""
    from identification._files import atomic_write_bytes

    dead, live = dead_pid(), os.getppid()
    left = {f".tire.fmu.{dead}-abcd1234.part": b"half", f".tire.fmu.{dead}-efgh5678.tmp": b"half",
            f".tire.fmu.{dead}-ijkl9012.previous": b"old"}
    kept = {f".tire.fmu.{live}-mnop3456.part": b"being written", f".other.fmu.{dead}-qrst7890.part": b"x",
            "tire.fmu.notes": b"user's"}
    plant(tmp_path, {**left, **kept, "tire.fmu": b"earlier"})
    atomic_write_bytes({tmp_path / "tire.fmu": b"new"})
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*kept, "tire.fmu"])
    assert (tmp_path / "tire.fmu").read_bytes() == b"new"


def test_the_runs_temporary_files_live_in_its_new_set(tmp_path, monkeypatch):
    """Temporary files of the run and its workers (a worker killed with its parent cannot remove them) go
    with the new set: swapped-in sets hold none, and nothing is left in $TMPDIR."""
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    monkeypatch.setenv("TMPDIR", str(tmpdir))
    monkeypatch.setattr(tempfile, "tempdir", None)
    out = tmp_path / "out"
    with FolderSet(out) as new:
        assert Path(tempfile.gettempdir()) == new / ".tmp" and os.environ["TMPDIR"] == str(new / ".tmp")
        tempfile.mkdtemp(prefix="cleatfmu_left_")
    assert tempfile.gettempdir() == str(tmpdir) and os.environ["TMPDIR"] == str(tmpdir)
    assert tree(out) == {} and list(tmpdir.iterdir()) == []


# ----------------------------------------------------------------------------- the commands


@pytest.fixture(scope="module")
def one(tmp_path_factory) -> Path:
    """One one-channel rig recording (a report of it takes a few seconds)."""
    folder = tmp_path_factory.mktemp("one")
    write_run(run_rig((), {"sensor.channels": "FL"}, seed=7), folder / "mine")
    return folder / "mine.csv"


def _cli(args, tmpdir: Path, **kw):
    env = dict(os.environ, TMPDIR=str(tmpdir))
    return subprocess.Popen([sys.executable, "-m", "identification.cli", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, **kw)


def test_a_rerun_over_other_recordings_keeps_none_of_their_files_and_counts_true(cli, one, tmp_path):
    """Before: one recording reported over a folder of others kept their FMUs and counted them."""
    out = tmp_path / "out"
    plant(out, PREVIOUS)
    res = cli("report", one, "-o", out, "--workers", "2")
    assert res.code == 0, res.err
    assert [p for p in tree(out) if "other" in p] == []
    assert f"{out / 'fmu'}{os.sep} (1 recommended tire FMUs <recording>_<TIRE>.fmu; 1 point-contact ones" in res.out
    assert (out / "fmu" / "mine_FL.fmu").is_file() and beside(out) == ["out"]


def test_a_folder_that_is_not_a_report_is_not_replaced(cli, one, tmp_path):
    out = tmp_path / "thesis"
    before = plant(out, {"thesis.tex": b"\\documentclass{book}", "fmu/x.fmu": b"PK"})
    res = cli("report", one, "-o", out)
    assert res.code == 2 and res.out == ""
    assert res.err == f"cleatfmu: error: {out}: is not a report folder (thesis.tex is not a file a report writes, " \
                      "and a report replaces the whole folder): give a new or empty folder\n"
    assert tree(out) == before and beside(out) == ["thesis"]


def test_two_runs_on_one_folder_the_second_refused_in_one_line(one, tmp_path):
    """Before: the second deleted the first's figure staging (a FileNotFoundError traceback)."""
    out = tmp_path / "out"
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    first = _cli(["report", one, "-o", out, "--workers", "1"], tmpdir)
    assert first.stdout.readline().startswith("cleatfmu report: 1 recording(s)")     # it has begun
    second = _cli(["report", one, "-o", out, "--workers", "1"], tmpdir)
    stdout, stderr = second.communicate(timeout=120)
    assert second.returncode == 2 and stdout == ""
    assert stderr == f"cleatfmu: error: {out}: another cleatfmu run (pid {first.pid}) is writing this folder; " \
                     "run again when it has ended\n"
    stdout, stderr = first.communicate(timeout=300)
    assert first.returncode == 0, stderr
    assert (out / "fmu" / "mine_FL.fmu").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "tmp"] and list(tmpdir.iterdir()) == []


def _mount_tmpfs(folder: Path, size: str) -> bool:
    folder.mkdir()
    if os.geteuid() != 0:
        return False
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                          capture_output=True).returncode == 0


@pytest.mark.parametrize("limit", ["small tmpfs", "RLIMIT_FSIZE"])
def test_a_full_disk_ends_in_one_line_and_keeps_the_previous_set(one, tmp_path, limit):
    """Before: an ENOSPC traceback from the figure streaming, exit 1, FMUs, parameters and staging files left.
    A small tmpfs where one can be mounted (root), else a file-size limit (EFBIG: Python ignores SIGXFSZ)."""
    import resource

    disk = tmp_path / "disk"
    mounted = limit == "small tmpfs" and _mount_tmpfs(disk, "512k")
    if limit == "small tmpfs" and not mounted:
        pytest.skip("cannot mount a tmpfs here (not root); the RLIMIT_FSIZE case covers a full disk")
    disk.mkdir(exist_ok=True)
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    out = disk / "out"
    try:
        before = plant(out, PREVIOUS)

        def small_files():
            if not mounted:
                resource.setrlimit(resource.RLIMIT_FSIZE, (40_000, 40_000))
        proc = _cli(["report", one, "-o", out, "--workers", "2"], tmpdir, preexec_fn=small_files)
        stdout, stderr = proc.communicate(timeout=300)
        assert proc.returncode == 2, stderr
        problem = "No space left on device" if mounted else "File too large"
        assert stderr == f"cleatfmu: error: {out}: cannot write: {problem} (the previous contents are kept)\n"
        assert tree(out) == before and beside(out) == ["out"] and list(tmpdir.iterdir()) == []
    finally:
        if mounted:
            subprocess.run(["umount", str(disk)], check=True)


def test_a_set_that_keeps_the_folders_other_files_swaps_in_whole_or_not_at_all(tmp_path):
    """``FolderSet(keep_existing=True)`` (diagnose --fmu-dir, ride --ssp): the new set starts as the folder's
    files (hard links), the run replaces some; a failed run leaves the folder byte for byte, a finished one
    has the new files and every other one, and the earlier set's data never changes under a reader."""
    from identification._folders import FolderSet
    from identification._files import atomic_write_bytes

    out = tmp_path / "fmus"
    before = plant(out, {"other_FL.fmu": b"other recording", "rec_FL.fmu": b"earlier", "sub/keep.txt": b"x"})
    with pytest.raises(RuntimeError):
        with FolderSet(out, keep_existing=True) as new:
            atomic_write_bytes({new / "rec_FL.fmu": b"later", new / "rec_FR.fmu": b"later FR"})
            assert (out / "rec_FL.fmu").read_bytes() == b"earlier"     # the earlier set is untouched meanwhile
            raise RuntimeError("the run fails")
    assert tree(out) == before and beside(out) == ["fmus"]
    with FolderSet(out, keep_existing=True) as new:
        atomic_write_bytes({new / "rec_FL.fmu": b"later", new / "rec_FR.fmu": b"later FR"})
    assert {k: v for k, v in tree(out).items()} == {**before, "rec_FL.fmu": tree_digest(b"later"),
                                                    "rec_FR.fmu": tree_digest(b"later FR")}
    assert beside(out) == ["fmus"] and not list(out.glob(".*"))


def tree_digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def test_a_killed_runs_temporary_folders_go_with_the_next_run(tmp_path):
    """SIGKILL leaves a run's $TMPDIR folders (cleatfmu_<kind>_<pid>-*) behind; the next run's first temporary
    folder clears those of processes that are gone, and only those."""
    import signal

    from identification._files import clear_dead_temp_folders

    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"recording": "r.csv", "speed_kmh": 7.0,
                                  "tires": {"FL": {"k": 550e3, "c": 2500.0, "mass": 1716.2}}}))
    env = dict(os.environ, TMPDIR=str(tmpdir))
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead = int(gone.stdout)
    for name in (f"cleatfmu_fmus_{dead}-x1", f"cleatfmu_tractor_{dead}-x2"):
        (tmpdir / name).mkdir()
        (tmpdir / name / "FL.fmu").write_bytes(b"left by a killed run")
    alive = tmpdir / f"cleatfmu_fmus_{os.getpid()}-x3"            # a live run's (this process's)
    alive.mkdir()
    other = tmpdir / "cleatfmu_something_else"
    other.mkdir()
    res = subprocess.run([sys.executable, "-m", "identification.cli", "export", str(params), "--tire", "FL", "-o",
                          str(tmp_path / "t.fmu"), "--backend", "native", "--platforms", "linux64"],
                         capture_output=True, text=True, env=env, timeout=300)
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in tmpdir.iterdir()) == sorted([alive.name, other.name])
    assert clear_dead_temp_folders(tmpdir) == []
    proc = subprocess.Popen([sys.executable, "-m", "identification.cli", "diagnose", "--example", "7kmh"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    deadline = time.monotonic() + 120
    while not any(p.name.startswith(f"cleatfmu_") and f"_{proc.pid}-" in p.name for p in tmpdir.iterdir()):
        assert proc.poll() is None and time.monotonic() < deadline, "diagnose made no temporary folder"
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert any(f"_{proc.pid}-" in p.name for p in tmpdir.iterdir())       # nothing could remove it
    assert [p.name for p in clear_dead_temp_folders(tmpdir)] and not any(f"_{proc.pid}-" in p.name
                                                                         for p in tmpdir.iterdir())


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGALRM])
def test_a_signal_while_the_lock_is_taken_leaves_no_lock_behind(tmp_path, monkeypatch, sig):
    """A signal that comes between the lock file's creation and the lock being held waits for the lock step's
    end, then unwinds the run: nothing is left beside the folder (a lock left there was seen after SIGTERM).
    SIGALRM is the retry of a SIGTERM that came in fragile code (``identification.cli.signals``), which
    raises :class:`Terminated` when it fires (seen in CI: a lock left after a SIGTERM at 0.75 s)."""
    import fcntl

    from identification.cli.signals import Terminated

    out = tmp_path / "out"
    before = plant(out, PREVIOUS)
    real_flock, sent = fcntl.flock, []

    def flock(fd, op):
        if not sent:
            sent.append(1)
            os.kill(os.getpid(), sig)
        return real_flock(fd, op)

    def terminated(signum, frame):
        raise Terminated()

    monkeypatch.setattr(fcntl, "flock", flock)
    saved = {s: signal.signal(s, terminated) for s in (signal.SIGTERM, signal.SIGALRM)}
    try:
        with pytest.raises(KeyboardInterrupt if sig == signal.SIGINT else Terminated):
            with FolderSet(out):
                pass
    finally:
        for s, handler in saved.items():
            signal.signal(s, handler)
    assert sent and tree(out) == before and beside(out) == ["out"]
