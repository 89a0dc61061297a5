"""A folder written as one set: the new set is built beside the old one and swapped in at the end.

A command that writes a whole folder ``OUT`` (``cleatfmu report``, ``cleatfmu demo``) does it inside a
:class:`FolderSet`:

1. it takes the folder's lock, ``OUT.cleatfmu-lock`` beside it (``flock``): a second run on the same folder
   is refused in one line naming the folder and the running one's pid;
2. it removes what killed runs left (``OUT.cleatfmu-new-<pid>`` folders; an ``OUT.cleatfmu-old-<pid>``
   left between the two renames of a swap goes back to ``OUT``);
3. the run writes into ``OUT.cleatfmu-new-<pid>``, its temporary files (``$TMPDIR``, also of its workers)
   in that folder's ``.tmp/``;
4. at the end the new set and ``OUT`` are exchanged in one step (``renameat2(RENAME_EXCHANGE)`` on Linux,
   else two renames) and the old set is deleted once the command's result has reached stdout.

A reader of ``OUT`` sees the old set or the new one, never a mix, and a re-run keeps nothing of the old
set.  A run that fails or is interrupted (an exception, Ctrl-C, SIGTERM, a full disk) removes its new set
and leaves ``OUT`` as it was; one killed by SIGKILL leaves its new set beside ``OUT``, which the next run
on ``OUT`` removes.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import shutil
import signal
import sys
import tempfile
import threading
from pathlib import Path

from ._files import STAGING_FOLDERS, at_forced_exit, make_folders, on_outcome
from ._files import process_alive as _alive
from .errors import InputError

__all__ = ["FolderSet", "sibling", "WRITE_ERRNOS", "raise_write_error"]

#: The errors of an output that cannot be written (a full disk, a quota, a file-size limit, a read-only or
#: failing disk): one line naming the folder, and the previous set is kept.
WRITE_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EIO)



def raise_write_error(problems) -> None:
    """Raise OSError when one of `problems` (one-line messages of a run's jobs, which record their errors and
    go on) says that an output could not be written (the text of one of :data:`WRITE_ERRNOS`): the whole run
    failed then, not one job of it.  Inside a :class:`FolderSet` the previous set is kept."""
    for line in problems:
        for code in WRITE_ERRNOS:
            if os.strerror(code) in line:
                raise OSError(code, os.strerror(code))


_TAG = ".cleatfmu-"
_TMP = ".tmp"
_LONGEST_KEY = 200          # bytes of the folder's name kept in its siblings' names (NAME_MAX is 255)


def _key(name: str) -> str:
    """`name`, or for a long one its first bytes and a hash, so that every sibling's name stays valid."""
    raw = os.fsencode(name)
    if len(raw) <= _LONGEST_KEY:
        return name
    import hashlib

    return os.fsdecode(raw[:_LONGEST_KEY - 20]) + "-" + hashlib.sha1(raw).hexdigest()[:12]


def sibling(target, kind: str, pid: int | None = None) -> Path:
    """``TARGET.cleatfmu-<kind>[-<pid>]`` beside `target`: ``new`` (a set being written), ``old`` (the
    previous set during a swap), ``lock``."""
    target = Path(target)
    return target.parent / f"{_key(target.name)}{_TAG}{kind}{'' if pid is None else f'-{pid}'}"


_renameat2 = None


def _exchange(a: Path, b: Path) -> bool:
    """Exchange the paths `a` and `b` in one step (Linux ``renameat2(RENAME_EXCHANGE)``); False where the
    system or its file system cannot."""
    global _renameat2
    if not sys.platform.startswith("linux"):
        return False
    if _renameat2 is None:
        import ctypes

        try:
            fn = ctypes.CDLL(None, use_errno=True).renameat2
        except (OSError, AttributeError):
            _renameat2 = False
            return False
        fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
        fn.restype = ctypes.c_int
        _renameat2 = fn
    if _renameat2 is False:
        return False
    import ctypes

    at_fdcwd, rename_exchange = -100, 2
    if _renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


@contextlib.contextmanager
def _signals_deferred():
    """Ctrl-C, SIGTERM and SIGALRM (the command's retry of a signal that came in fragile code, which raises
    too: :mod:`identification.cli.signals`) wait until the block is done (main thread; elsewhere the block
    runs as is)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []
    saved = {s: signal.signal(s, lambda signum, frame: got.append(signum))
             for s in (signal.SIGINT, signal.SIGTERM, signal.SIGALRM)}
    try:
        yield
    finally:
        for s, handler in saved.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
        if got:
            handler = saved[got[0]]
            if callable(handler):
                handler(got[0], None)
            elif handler != signal.SIG_IGN:
                os.kill(os.getpid(), got[0])


def _link_or_copy(src, dst) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            path.unlink()


class FolderSet:
    """Write the folder `target` as one set (the module's docstring): ``with FolderSet(OUT) as new: ...``
    writes into ``new`` and swaps it in when the block succeeds.

    Parameters
    ----------
    target : path-like
        The folder; its missing parents are created (inside an
        :class:`~identification._files.OutputFolders` block they go again if the run fails).
    replaceable : callable, optional
        ``replaceable(folder)``: None when the existing `target` may be replaced whole, else why not (one
        line, e.g. it holds a file the run does not write): refused, nothing changed.
    keep_existing : bool
        The new set starts as the existing folder's contents (hard links where the file system allows,
        else copies), so that the run adds and replaces files and keeps the others (``diagnose --fmu-dir``
        into a folder of other recordings' FMUs).  The run must replace a file (write a new one and rename
        it over, as :func:`identification._files.atomic_write_bytes` does), never write into it: a hard
        link shares the previous set's data.

    Notes
    -----
    Inside an :class:`~identification._files.OutputFolders` block the swap is undone if the block fails
    later (the command's result cannot reach stdout), and the old set deleted and the lock released when
    the block succeeds; outside one, both at the end of the ``with``.  The run's temporary files go to the
    new set's ``.tmp/`` (``TMPDIR`` and :data:`tempfile.tempdir`, for the process and the workers it starts
    meanwhile).

    Raises
    ------
    InputError
        `target` is a file or may not be replaced, another run holds its lock, or it cannot be written (a
        full disk: :data:`WRITE_ERRNOS`); the previous set stays as it was.
    """

    def __init__(self, target, *, replaceable=None, keep_existing: bool = False):
        self.shown = Path(target)
        self.keep_existing = keep_existing
        self.target = Path(os.path.realpath(target))
        self.replaceable = replaceable
        self.staging = sibling(self.target, "new", os.getpid())
        self._made = False                        # the new set's folder is this run's (not a refused run's)
        self._lock_fd: int | None = None
        self._locked = False
        self._saved_tmp = None
        self._previous: Path | None = None       # where the previous set is after the swap (None: there was none)
        self._swapped = False
        self._existed = False                     # the folder held a previous set when the run began
        self._settled = False                     # kept or undone (:meth:`_settle`)
        self._settle_lock = threading.Lock()

    # ------------------------------------------------------------------ the run
    def __enter__(self) -> Path:
        if self.target.exists() and not self.target.is_dir():
            raise InputError(self.shown, "exists and is not a directory")
        make_folders(self.target.parent)
        self._existed = self.target.is_dir()
        at_forced_exit(self, self._end_now)
        try:
            self._lock()
            self._recover()
            why = self.replaceable(self.target) if self.replaceable and self.target.is_dir() else None
            if why:
                raise InputError(self.shown, why)
            self._made = True                     # (a copy that fails half-way is removed with it)
            if self.keep_existing and self.target.is_dir():
                shutil.copytree(self.target, self.staging, symlinks=True, copy_function=_link_or_copy)
            else:
                os.mkdir(self.staging)
            self._redirect_tmp()
        except BaseException as exc:
            self._abandon()
            if isinstance(exc, OSError):
                raise InputError(self.shown, f"cannot write: {exc.strerror or exc}") from None
            raise
        return self.staging

    def __exit__(self, exc_type, exc, tb) -> bool:
        self._restore_tmp()
        if exc_type is None:
            try:
                self._swap()
            except BaseException as err:        # an interrupt deferred to the swap's end comes here too
                self._undo() if self._swapped else self._abandon()
                self._raise_write_error(err)
                raise
            on_outcome(self._undo, self._keep)
            return False
        self._abandon()
        self._raise_write_error(exc)
        return False

    def _raise_write_error(self, exc) -> None:
        if isinstance(exc, OSError) and exc.errno in WRITE_ERRNOS:
            kept = " (the previous contents are kept)" if self._existed else ""
            raise InputError(self.shown, f"cannot write: {exc.strerror}{kept}") from None

    # ------------------------------------------------------------------ the lock
    def _lock(self) -> None:
        """Take the folder's lock; Ctrl-C and SIGTERM wait until it is taken or refused, so that a run stopped
        there never leaves a lock file it made without knowing it."""
        with _signals_deferred():
            self._take_lock()

    def _take_lock(self) -> None:
        import fcntl

        path = sibling(self.target, "lock")
        while True:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
                os.close(fd)
                who = f"pid {holder}" if holder.isdigit() else "another process"
                raise InputError(self.shown, f"another cleatfmu run ({who}) is writing this folder; run again "
                                             "when it has ended") from None
            except OSError:             # a file system without locks: runs on it are not kept apart
                self._lock_fd, self._locked = fd, False
                break
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(path))
            except FileNotFoundError:
                same = False
            if same:
                self._lock_fd, self._locked = fd, True
                break
            os.close(fd)                # the run that held it removed it meanwhile: lock the new one
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)

    def _unlock(self) -> None:
        """Remove the lock file and release the lock; a signal meanwhile waits until both are done."""
        with _signals_deferred():
            self._release_lock()

    def _release_lock(self) -> None:
        at_forced_exit(self, None)
        fd, self._lock_fd = self._lock_fd, None
        if fd is None:
            return
        import fcntl

        with contextlib.suppress(OSError):
            os.unlink(sibling(self.target, "lock"))       # while still held: a waiting run locks a new file
        with contextlib.suppress(OSError):
            fcntl.flock(fd, fcntl.LOCK_UN)                 # also held by forked workers' copies of the fd
        os.close(fd)

    def _recover(self) -> None:
        """Remove the sets of killed runs; put back a previous set a run killed in its swap moved away."""
        prefix = f"{_key(self.target.name)}{_TAG}"
        for path in sorted(self.target.parent.glob(glob.escape(prefix) + "*")):
            kind, _, pid = path.name[len(prefix):].partition("-")
            if kind not in ("new", "old") or not pid.isdigit():
                continue
            if not self._locked and int(pid) != os.getpid() and _alive(int(pid)):
                continue
            if kind == "old" and path.is_dir() and not self.target.exists():
                os.rename(path, self.target)
            else:
                _remove(path)

    # ------------------------------------------------------------------ temporary files
    def _redirect_tmp(self) -> None:
        STAGING_FOLDERS.add(Path(os.path.abspath(self.staging)))
        tmp = self.staging / _TMP
        tmp.mkdir()
        self._saved_tmp = (tempfile.tempdir, os.environ.get("TMPDIR"))
        tempfile.tempdir = str(tmp)
        os.environ["TMPDIR"] = str(tmp)

    def _restore_tmp(self) -> None:
        STAGING_FOLDERS.discard(Path(os.path.abspath(self.staging)))
        if self._saved_tmp is None:
            return
        tempfile.tempdir, env = self._saved_tmp
        if env is None:
            os.environ.pop("TMPDIR", None)
        else:
            os.environ["TMPDIR"] = env
        self._saved_tmp = None

    # ------------------------------------------------------------------ the swap
    def _swap(self) -> None:
        _remove(self.staging / _TMP)
        with _signals_deferred():
            if not self.target.exists():
                os.rename(self.staging, self.target)
                self._previous = None
            elif _exchange(self.staging, self.target):
                self._previous = self.staging
            else:
                old = sibling(self.target, "old", os.getpid())
                os.rename(self.target, old)
                try:
                    os.rename(self.staging, self.target)
                except BaseException:
                    os.rename(old, self.target)
                    raise
                self._previous = old
            self._swapped = True

    def _settle(self) -> bool:
        """Whether this call is the one that ends a swapped set: its keep or undo runs once, even when a forced
        exit (another thread) and the command's own end come together."""
        with self._settle_lock:
            first, self._settled = not self._settled, True
        return first

    def _keep(self) -> None:
        """The new set stays: delete the previous one, release the lock."""
        if not self._settle():
            return
        try:
            with _signals_deferred():           # the command has succeeded: an interrupt now changes nothing
                if self._previous is not None:
                    _remove(self._previous)
        finally:
            self._unlock()

    def _undo(self) -> None:
        """Put the previous set back (or no folder, if there was none), delete the new one, release the lock."""
        if not self._settle():
            return
        try:
            with _signals_deferred(), contextlib.suppress(OSError):
                if self._previous is None:
                    os.rename(self.target, self.staging)
                elif self._previous == self.staging:
                    _exchange(self.staging, self.target)
                else:
                    os.rename(self.target, self.staging)
                    os.rename(self._previous, self.target)
            _remove(self.staging)
        finally:
            self._unlock()

    def _abandon(self) -> None:
        """The run failed before its swap: delete its new set, release the lock."""
        self._restore_tmp()
        try:
            if self._made:
                _remove(self.staging)
        finally:
            self._unlock()

    def _end_now(self) -> None:
        """The process is ended where it stands (:func:`identification._files.undo_at_forced_exit`, from
        another thread): the previous set back, the new one and the lock removed."""
        if self._swapped:
            self._undo()
        else:
            _remove(self.staging)
            with contextlib.suppress(OSError):
                os.unlink(sibling(self.target, "lock"))
