"""Writing output files all-or-nothing."""

from __future__ import annotations

import json
import math
import os
import tempfile
import threading
from pathlib import Path
from typing import Mapping

from .errors import InputError

__all__ = ["atomic_write_texts", "atomic_write_bytes", "publish_files", "json_text", "finite_or_none",
           "OutputFolders", "check_folder", "make_folders", "missing_folders", "publish_path", "on_outcome"]

_XML_FORBIDDEN = None


def xml_text(text: str) -> str:
    """`text` with every character XML 1.0 forbids (control characters, lone surrogates, U+FFFE, U+FFFF)
    written as a ``\\xNN`` or ``\\uNNNN`` escape: any string can then go into an XML attribute or element
    (a recording's file name, a tire key) and the document still parses."""
    global _XML_FORBIDDEN
    if _XML_FORBIDDEN is None:
        import re

        _XML_FORBIDDEN = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
    return _XML_FORBIDDEN.sub(lambda m: f"\\x{ord(m.group()):02x}" if ord(m.group()) < 0x100
                              else f"\\u{ord(m.group()):04x}", str(text))


def finite_or_none(doc):
    """`doc` with every non-finite number (an interval's unbounded end, a quantity the data cannot give)
    replaced by None, numpy scalars and arrays as Python numbers and lists, tuples as lists."""
    if isinstance(doc, dict):
        return {str(k) if not isinstance(k, str) else k: finite_or_none(v) for k, v in doc.items()}
    if isinstance(doc, (list, tuple)):
        return [finite_or_none(v) for v in doc]
    if isinstance(doc, (bool, str, int)) or doc is None:
        return doc
    if hasattr(doc, "tolist"):                     # numpy scalar or array
        return finite_or_none(doc.tolist())
    if isinstance(doc, float):
        return doc if math.isfinite(doc) else None
    return doc


def json_text(doc, *, indent: int | None = 2, default=None) -> str:
    """`doc` as strict JSON (RFC 8259): non-finite numbers written as null, never as ``Infinity``/``NaN``,
    which strict parsers (JavaScript's, Go's, jq's) refuse."""
    return json.dumps(finite_or_none(doc), indent=indent, allow_nan=False,
                      default=None if default is None else (lambda o: finite_or_none(default(o))))


def process_alive(pid: int) -> bool:
    """Whether process `pid` exists (another user's counts as alive)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:                 # another user's process
        return True
    return True


#: Suffixes of the temporaries written beside a file (:func:`temp_beside`).
TEMP_SUFFIXES = (".tmp", ".part", ".previous")


def temp_beside(path, suffix: str) -> tuple[int, str]:
    """Open a new temporary file ``.NAME.PID-XXXXXXXX<suffix>`` in the folder of `path` (NAME its name, PID
    this process's); return ``(fd, name)`` as :func:`tempfile.mkstemp` does.

    A SIGKILL leaves such a file behind (nothing can remove it then); the temporaries of `path` whose process
    is gone are removed first, so the next run that writes `path` clears what a killed one left.  The file is
    recorded before this returns (a command's Ctrl-C or SIGTERM waits until then), and a command that ends
    removes what its caller had no time to (:func:`remove_open_temporaries`).
    """
    path = Path(path)
    clear_dead_temporaries(path)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{os.getpid()}-", suffix=suffix)
    _OPEN_TEMPORARIES.add(name)
    return fd, name


#: The temporaries this process made (:func:`temp_beside`; most are renamed or removed since): what
#: :func:`undo_at_forced_exit` removes of them where they still are.
_OPEN_TEMPORARIES: set = set()
#: Output under way that a run ended where it stands must undo: the open :class:`OutputFolders` blocks of
#: every thread, and the clean-ups registered with :func:`at_forced_exit` (a folder set being written).
_OPEN_BLOCKS: list = []
_FORCED_EXIT_CLEANUPS: dict = {}


def at_forced_exit(key, cleanup=None) -> None:
    """Register ``cleanup()`` under `key` to run if the process is ended where it stands (a terminated run
    that did not unwind in time: :func:`undo_at_forced_exit`); ``cleanup=None`` unregisters `key`."""
    if cleanup is None:
        _FORCED_EXIT_CLEANUPS.pop(key, None)
    else:
        _FORCED_EXIT_CLEANUPS[key] = cleanup


def undo_at_forced_exit() -> None:
    """Undo the output under way, from any thread, before the process is ended without unwinding: the
    registered clean-ups (latest first), the open :class:`OutputFolders` blocks (innermost first: older
    files back, new files and folders removed) and the temporaries beside files.  Each step is tried on its
    own; nothing raises."""
    for key in reversed(list(_FORCED_EXIT_CLEANUPS)):
        cleanup = _FORCED_EXIT_CLEANUPS.pop(key, None)
        try:
            if cleanup is not None:
                cleanup()
        except BaseException:       # a forced exit follows: what can be undone is undone
            pass
    for block in reversed(list(_OPEN_BLOCKS)):
        try:
            block.remove()
        except BaseException:
            pass
    remove_open_temporaries()
    if _TEMP_FOLDERS_BEFORE is not None:
        try:
            folder, before = _TEMP_FOLDERS_BEFORE
            remove_temp_folders(own_temp_folders(folder) - before)
        except BaseException:
            pass


#: The temporary directory and this process's temporary folders in it as its command started
#: (:func:`note_temp_folders`): those made since are the command's, removed as it ends, even by a forced
#: exit (while an output set is written the temporary directory is inside it, and goes with it).
_TEMP_FOLDERS_BEFORE = None


def note_temp_folders() -> set:
    """Note (and return) this process's temporary folders as a command starts (:data:`_TEMP_FOLDERS_BEFORE`)."""
    global _TEMP_FOLDERS_BEFORE
    before = own_temp_folders()
    _TEMP_FOLDERS_BEFORE = (tempfile.gettempdir(), before)
    return before


def remove_open_temporaries() -> list[str]:
    """Remove the temporaries this process made (:func:`temp_beside`) that are still there, and forget them
    all; return the removed names.  Called as a command ends: a Ctrl-C or SIGTERM between the file's creation
    and the caller's own clean-up (its ``try``) would leave it otherwise.  A temporary renamed into place or
    removed since is no longer there; nothing raises."""
    removed = [name for name in list(_OPEN_TEMPORARIES) if os.path.lexists(name)]
    for name in removed:
        _unlink_quietly(name)
    _OPEN_TEMPORARIES.clear()
    return removed


def own_temp_folders(folder=None) -> set:
    """This process's temporary folders (:func:`temp_prefix`) in `folder` (default: the temporary directory
    now)."""
    import re

    folder = tempfile.gettempdir() if folder is None else folder
    pattern = re.compile(rf"cleatfmu_[a-z0-9]+_{os.getpid()}-.*")
    try:
        return {entry.path for entry in os.scandir(folder) if pattern.fullmatch(entry.name)
                and entry.is_dir(follow_symlinks=False)}
    except OSError:
        return set()


def remove_temp_folders(paths) -> None:
    """Remove the folders `paths` and what they hold; nothing raises.  A command ends by removing the
    temporary folders it made that are still there (:func:`own_temp_folders` then and at its start): a
    Ctrl-C or SIGTERM between a folder's creation and its owner's clean-up would leave it otherwise."""
    import shutil

    for path in paths:
        shutil.rmtree(path, ignore_errors=True)


_CLEARED_TEMP_FOLDERS = False


def temp_prefix(kind: str) -> str:
    """The name prefix of this process's temporary folders of `kind` (``cleatfmu_<kind>_<pid>-``), for
    ``tempfile.mkdtemp`` / ``TemporaryDirectory``.  A SIGKILLed run leaves its folders behind (nothing can
    remove them then); the first call in a process removes those whose process is gone
    (:func:`clear_dead_temp_folders`)."""
    clear_dead_temp_folders_once()
    return f"cleatfmu_{kind}_{os.getpid()}-"


def clear_dead_temp_folders_once() -> None:
    """:func:`clear_dead_temp_folders` of the temporary directory, once per process (every command starts
    with it)."""
    global _CLEARED_TEMP_FOLDERS
    if not _CLEARED_TEMP_FOLDERS:
        _CLEARED_TEMP_FOLDERS = True
        clear_dead_temp_folders()


def clear_dead_temp_folders(folder=None) -> list[Path]:
    """Remove the temporary folders (:func:`temp_prefix`) in `folder` (default: the temporary directory) of
    processes that no longer exist; return them."""
    import re
    import shutil

    folder = Path(folder or tempfile.gettempdir())
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        m = re.fullmatch(r"cleatfmu_[a-z0-9]+_(\d+)-.*", entry.name)
        if m and int(m.group(1)) != os.getpid() and not process_alive(int(m.group(1))) \
                and entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
            removed.append(Path(entry.path))
    return removed


def clear_dead_temporaries(path) -> list[Path]:
    """Remove the temporaries (:func:`temp_beside`) of `path` left by processes that no longer exist; return
    them."""
    path = Path(path)
    prefix = f".{path.name}."
    removed = []
    try:
        entries = list(os.scandir(path.parent))
    except OSError:
        return removed
    for entry in entries:
        name = entry.name
        if not (name.startswith(prefix) and name.endswith(TEMP_SUFFIXES)):
            continue
        pid, dash, _ = name[len(prefix):].partition("-")
        if dash and pid.isdigit() and int(pid) != os.getpid() and not process_alive(int(pid)) \
                and entry.is_file(follow_symlinks=False):
            try:
                os.unlink(entry.path)
                removed.append(Path(entry.path))
            except FileNotFoundError:
                pass
    return removed


def atomic_write_bytes(files: Mapping[Path, bytes]) -> None:
    """Write several files so that either all appear or none does.

    Each file is written to a temporary name in its target directory; the
    temporary files are renamed only once all of them are complete.
    """
    tmp: dict[Path, str] = {}
    umask = os.umask(0)
    os.umask(umask)
    try:
        for path, data in files.items():
            path = Path(path)
            fd, name = temp_beside(path, ".tmp")
            tmp[path] = name
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
            os.chmod(name, 0o666 & ~umask)
        for path, name in list(tmp.items()):
            publish_path(name, path)
            del tmp[path]
    finally:
        for name in tmp.values():
            if os.path.exists(name):
                os.unlink(name)


def atomic_write_texts(files: Mapping[Path, str]) -> None:
    """:func:`atomic_write_bytes` for UTF-8 texts (newline line ends)."""
    atomic_write_bytes({path: text.encode("utf-8") for path, text in files.items()})


def publish_files(sources: Mapping[Path, Path]) -> list[Path]:
    """Copy finished files (source -> target mapping given as target: source) all-or-nothing."""
    atomic_write_bytes({Path(dst): Path(src).read_bytes() for dst, src in sources.items()})
    return [Path(dst) for dst in sources]


# ----------------------------------------------------------------------------- output files and folders

_local = threading.local()


def _blocks() -> list:
    if not hasattr(_local, "blocks"):
        _local.blocks = []
    return _local.blocks


class OutputFolders:
    """A block whose output goes again if it fails: the folders it created, and the files it published.

    Folders made by :func:`make_folders` (or :func:`check_output`) and files put in place by
    :func:`publish_path` (every writer here: :func:`atomic_write_bytes`, the FMU builds) inside the block are
    recorded.  When the block raises, or :meth:`remove` is called, each file published over an older one
    gets the older one back, each new file is removed, and then the folders, deepest first, where empty.
    When it succeeds inside an enclosing block, that block takes them over; at the outermost block the
    older files' copies are dropped.  A command is such a block up to the moment its output has reached
    stdout: a result that cannot be printed (a full disk behind ``>``) leaves the files as they were.
    Any other change made inside the block registers its own undo and keep with :func:`on_outcome` (a whole
    folder swapped in, :class:`identification._folders.FolderSet`); those are undone first.
    """

    def __init__(self):
        self.created: list[Path] = []
        self.published: list[tuple[Path, Path | None]] = []      # (file, the older file's copy or None)
        self.outcomes: list[tuple] = []                          # (undo, keep) callables

    def __enter__(self) -> "OutputFolders":
        _blocks().append(self)
        _OPEN_BLOCKS.append(self)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        blocks = _blocks()
        blocks.remove(self)
        _OPEN_BLOCKS.remove(self)
        if exc_type is not None:
            self.remove()
        elif blocks:
            blocks[-1].created.extend(self.created)
            blocks[-1].published.extend(self.published)
            blocks[-1].outcomes.extend(self.outcomes)
            self.created, self.published, self.outcomes = [], [], []
        else:
            self.keep()

    def keep(self) -> None:
        """Keep the published files: drop the older files' copies (and run each registered keep)."""
        outcomes, self.outcomes = self.outcomes, []
        for _, keep in outcomes:
            keep()
        for _, backup in self.published:
            if backup is not None:
                _unlink_quietly(backup)
        self.published = []

    def remove(self) -> None:
        """Undo the block's output: older files back, new files removed, then the recorded folders that are
        empty (the deepest first); forget all of them.  The changes registered with :func:`on_outcome` are
        undone first, the latest first."""
        outcomes, self.outcomes = self.outcomes, []
        for undo, _ in reversed(outcomes):
            undo()
        for path, backup in reversed(self.published):
            try:
                if backup is not None:
                    os.replace(backup, path)
                else:
                    os.unlink(path)
            except OSError:
                pass
        self.published = []
        for folder in reversed(self.created):
            try:
                folder.rmdir()
            except OSError:
                pass
        self.created = []


def on_outcome(undo, keep) -> None:
    """Register a change that the enclosing :class:`OutputFolders` block undoes (``undo()``) if it fails,
    or confirms (``keep()``) when it succeeds; outside any block the change is kept at once.

    Parameters
    ----------
    undo, keep : callable
        Called without arguments, exactly one of them, once.
    """
    blocks = _blocks()
    if blocks:
        blocks[-1].outcomes.append((undo, keep))
    else:
        keep()


def _unlink_quietly(path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


#: The new sets being written (:class:`identification._folders.FolderSet` registers its staging folder): a
#: file published inside one needs no backup, the set is swapped in or dropped whole.
STAGING_FOLDERS: set = set()


def _in_staging(path: Path) -> bool:
    return any(folder == path or folder in path.parents for folder in STAGING_FOLDERS)


def publish_path(finished, path) -> None:
    """Put the finished file `finished` (a temporary name in `path`'s folder) in place as `path`
    (``os.replace``).  Inside an :class:`OutputFolders` block the file is recorded, and an older `path` is
    kept as a hidden hard link (or copy) beside it until the block ends, so that a failed block can put it
    back; not inside a new set being written (:data:`STAGING_FOLDERS`), which goes whole."""
    path = Path(path)
    if _in_staging(Path(os.path.abspath(path))):
        os.replace(finished, path)
        return
    blocks = _blocks()
    backup = None
    if blocks and path.is_file():
        fd, name = temp_beside(path, ".previous")
        os.close(fd)
        os.unlink(name)
        try:
            os.link(path, name)
        except OSError:
            import shutil

            shutil.copy2(path, name)
        backup = Path(name)
    try:
        os.replace(finished, path)
    except BaseException:
        if backup is not None:
            _unlink_quietly(backup)
        raise
    if blocks:
        blocks[-1].published.append((path, backup))


def missing_folders(folder) -> list[Path]:
    """The folders that must be created to have `folder`, outermost first.

    Raises
    ------
    InputError
        A part of the path exists and is not a folder.
    """
    folder = Path(folder)
    missing: list[Path] = []
    for path in (folder, *folder.parents):
        if path.is_dir():
            break
        if path.exists():
            raise InputError(path, "is not a directory")
        missing.append(path)
    return missing[::-1]


def check_folder(folder) -> None:
    """Refuse an output folder that cannot be created (a part of its path is a file); nothing is created."""
    missing_folders(folder)


def make_folders(folder) -> list[Path]:
    """Create `folder` and its missing parents; return those created, outermost first.

    Inside an :class:`OutputFolders` block they are recorded, to be removed again if the block fails.

    Raises
    ------
    InputError
        A part of the path is a file, or a folder cannot be created.
    """
    created: list[Path] = []
    for path in missing_folders(folder):
        try:
            path.mkdir()
        except FileExistsError:
            if not path.is_dir():
                raise InputError(path, "is not a directory") from None
            continue
        except OSError as exc:
            raise InputError(path, f"cannot create the directory: {exc.strerror or exc}") from None
        created.append(path)
        blocks = _blocks()
        if blocks:
            blocks[-1].created.append(path)
    return created
