"""The model's compiled code: where numba caches it (:func:`njit`, one folder per version of the package's
source, shared by every install of that version) and how long a block spent compiling it
(:func:`compile_seconds`, numba's compile events), so that run times can be told apart from the
once-per-version compilation."""

from __future__ import annotations

from contextlib import contextmanager

__all__ = ["compile_seconds", "njit", "install_cache_locator", "cache_root", "user_cache_dir", "source_stamp"]


class _Clock:
    seconds = 0.0


@contextmanager
def compile_seconds():
    """Measure the compilation inside the block: ``with compile_seconds() as c: ...; c.seconds``.

    Only numba's outermost compile events count (a function compiled while compiling another is inside
    its time).  Loading compiled code from numba's on-disk cache is not compilation and counts 0; so does
    everything without numba.
    """
    clock = _Clock()
    try:
        from numba.core import event
    except ImportError:   # pragma: no cover - without numba nothing is compiled
        yield clock
        return
    with event.install_recorder("numba:compile") as recorder:
        try:
            yield clock
        finally:
            depth, start = 0, 0.0
            for stamp, ev in recorder.buffer:
                if ev.is_start:
                    if depth == 0:
                        start = stamp
                    depth += 1
                elif depth:
                    depth -= 1
                    if depth == 0:
                        clock.seconds += stamp - start


# --- where numba keeps this package's compilations ------------------------------------------------------
#
# numba's own cache sits beside each source file (``__pycache__``) or under NUMBA_CACHE_DIR in a folder named
# after the source folder's path: every install, and a checkout beside its installed copy, compiles again.
# This package's functions are cached instead in one folder per version of the package's source (a hash of
# its .py files), under NUMBA_CACHE_DIR if set, else the user's cache directory: a reinstall of the same code,
# or the same code in another folder, loads what an earlier one compiled, and any change of any module
# (a kernel compiled with code it calls from another file) compiles afresh.

#: Versions of the package's source kept in the cache folder besides the one in use, and the days after which
#: an older one unused is removed (not sooner: another checkout may be running it).
KEEP_VERSIONS, KEEP_DAYS = 5, 7

_STATE: dict = {}


#: Environment variable that overrides the package's cache folder (compiled FMU binaries, numba's code).
CACHE_ENV = "CLEATFMU_CACHE_DIR"


def cache_root():
    """The package's cache folder: ``$CLEATFMU_CACHE_DIR``, else ``$XDG_CACHE_HOME/cleatfmu``, else
    ``~/.cache/cleatfmu`` (the native FMU binaries, :func:`build_scripts.native.cache_dir`, and under
    ``numba/`` the compiled model code)."""
    import os
    from pathlib import Path

    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache", "cleatfmu")


def user_cache_dir():
    """The folder numba caches this package's functions in: ``NUMBA_CACHE_DIR`` if set, else
    :func:`cache_root` / ``numba``."""
    import os
    from pathlib import Path

    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    return cache_root() / "numba"


def source_stamp() -> str:
    """16 hex digits of the SHA-256 over the package's .py files (relative path and content, in path order)."""
    if "stamp" not in _STATE:
        import hashlib
        from pathlib import Path

        digest = hashlib.sha256()
        root = Path(__file__).resolve().parent
        for path in sorted(root.rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
        _STATE["stamp"] = digest.hexdigest()[:16]
    return _STATE["stamp"]


def _prune(version_dir) -> None:
    """Keep the folder of the version in use and the `KEEP_VERSIONS` most recently used others; remove the
    rest once unused for `KEEP_DAYS` days (a version's folder is touched by every process that uses it)."""
    import os
    import shutil
    import time

    os.utime(version_dir)
    others = sorted((p for p in version_dir.parent.glob("cleatfmu-*") if p.is_dir() and p != version_dir),
                    key=lambda p: p.stat().st_mtime, reverse=True)
    for old in others[KEEP_VERSIONS:]:
        if time.time() - old.stat().st_mtime > KEEP_DAYS * 86400:
            shutil.rmtree(old, ignore_errors=True)


def install_cache_locator() -> bool:
    """Let numba cache this package's functions in :func:`user_cache_dir` / ``cleatfmu-<source_stamp>``
    (idempotent; other packages' functions keep numba's own locators).  False where that folder cannot be
    written: numba then uses its own (``__pycache__`` beside the source)."""
    if "installed" in _STATE:
        return _STATE["installed"]
    import hashlib
    from pathlib import Path

    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")
    package = Path(__file__).resolve().parent
    try:
        version_dir = user_cache_dir() / f"cleatfmu-{source_stamp()}"
        version_dir.mkdir(parents=True, exist_ok=True)
        _prune(version_dir)
    except OSError:
        _STATE["installed"] = False
        return False

    class PackageVersionLocator(caching._CacheLocator):
        """A function of this package: cached in the folder of this version of the package's source."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._path = version_dir.joinpath(*Path(py_file).resolve().parent.relative_to(package).parts)

        def get_cache_path(self):
            return str(self._path)

        def get_source_stamp(self):   # the file's content, not its time: a copy elsewhere shares the cache
            with open(self._py_file, "rb") as f:
                return hashlib.sha256(f.read()).hexdigest()

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            try:
                Path(py_file).resolve().relative_to(package)
            except (OSError, ValueError):
                return None
            self = cls(py_func, py_file)
            try:
                self.ensure_cache_path()
            except OSError:
                return None
            return self

    impl._locator_classes = [PackageVersionLocator] + [c for c in impl._locator_classes
                                                       if c.__name__ != "PackageVersionLocator"]
    _STATE["installed"] = True
    return True


def njit(**options):
    """``numba.njit(cache=True, **options)`` with this package's cache folder (:func:`install_cache_locator`);
    raises ImportError without numba."""
    import numba

    install_cache_locator()
    return numba.njit(cache=True, **options)
