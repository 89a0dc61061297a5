"""Reading input files: regular files of a bounded size, JSON by one rule, table numbers by one rule.

Every reader of the package takes its inputs through these, so that a FIFO, a device, a file too large,
malformed or too deeply nested JSON, a repeated key or a number in a form the other readers refuse ends
in one line naming the file (:class:`~identification.errors.InputError`), never a hang or a traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["read_input_bytes", "read_input_text", "read_json_file", "parse_json", "parse_number",
           "INPUT_LIMIT_BYTES"]

#: Largest input document (JSON, CSV table, property file) read whole, bytes.
INPUT_LIMIT_BYTES = 256 << 20


def read_input_bytes(path, *, limit: int = INPUT_LIMIT_BYTES) -> bytes:
    """The bytes of an input file: a regular file (a FIFO, a device or a directory, also behind a symlink, is
    refused before it is opened, so nothing hangs or fills memory) of at most `limit` bytes.

    Raises :class:`~identification.errors.InputError` naming the file, in one line.
    """
    from .errors import InputError

    path = Path(path)
    try:
        if not path.exists():
            raise InputError(path, "no such file")
        if path.is_dir():
            raise InputError(path, "is a directory, not a file")
        if not path.is_file():
            raise InputError(path, "is not a regular file (a pipe, a device or a socket)")
        if path.stat().st_size > limit:
            raise InputError(path, f"is larger than {limit >> 20} MiB")
        with path.open("rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise InputError(path, f"cannot read: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise InputError(path, f"is larger than {limit >> 20} MiB")
    return data


def read_input_text(path, *, limit: int = INPUT_LIMIT_BYTES, encoding: str = "utf-8") -> str:
    """:func:`read_input_bytes` decoded (UTF-8 by default); InputError naming the file if it is not."""
    from .errors import InputError

    try:
        return read_input_bytes(path, limit=limit).decode(encoding)
    except UnicodeDecodeError:
        raise InputError(path, "not a UTF-8 text file") from None


def _unique_keys(pairs):
    out = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


class _DuplicateKey(ValueError):
    def __init__(self, key):
        super().__init__(key)
        self.key = key


def parse_json(text: str, source):
    """The JSON document `text` of the input `source`; InputError naming `source` in one line when it is
    malformed, nested too deeply to read, holds a number beyond Python's integer-string limit, or names a key
    twice in one object (every reader takes JSON by this one rule: a repeated key is refused, not the last
    one silently taken)."""
    from .errors import InputError

    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except json.JSONDecodeError as exc:
        raise InputError(source, f"malformed JSON: {exc.msg} (line {exc.lineno}, column {exc.colno})") from None
    except RecursionError:
        raise InputError(source, "malformed JSON: nested too deeply to read") from None
    except _DuplicateKey as exc:
        raise InputError(source, f"malformed JSON: the key {exc.key!r} appears twice in one object") from None
    except ValueError as exc:  # e.g. an integer beyond the int/str conversion limit (4300 digits)
        raise InputError(source, f"malformed JSON: {exc}") from None


def read_json_file(path, *, limit: int = INPUT_LIMIT_BYTES):
    """The JSON document of an input file (:func:`parse_json`); InputError naming the file in one line."""
    return parse_json(read_input_text(path, limit=limit), path)


def parse_number(cell: str) -> float:
    """A number cell of a text table, by the one rule of every table reader: ASCII decimal or exponent
    notation with optional blanks around it (``1.5``, ``-2e-3``, ``nan``, ``inf``), as numpy reads it;
    Python's extras (digit separators ``1_000``, digits of other scripts) raise ValueError."""
    if "_" in cell or not cell.isascii():
        raise ValueError(f"not a number: {cell!r}")
    return float(cell)
