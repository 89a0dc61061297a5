"""Writing output files all-or-nothing."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Mapping

__all__ = ["atomic_write_texts", "atomic_write_bytes", "publish_files"]


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
            fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
            tmp[path] = name
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
            os.chmod(name, 0o666 & ~umask)
        for path, name in tmp.items():
            os.replace(name, path)
        tmp.clear()
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
