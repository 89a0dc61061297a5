"""Writing output files all-or-nothing."""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from typing import Mapping

__all__ = ["atomic_write_texts", "atomic_write_bytes", "publish_files", "json_text", "finite_or_none"]


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
