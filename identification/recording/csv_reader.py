"""Reading the CSV of a ``cleat-recording/1`` recording in bounded memory, and the checks of its time column.

The text is parsed in chunks of :data:`CHUNK_LINES` lines into float arrays,
never held whole: a 2 M-row file (70-80 MB) needs its floats (16 MB per
column) and one chunk.  See :mod:`identification.recording` for the format.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

from .._inputs import parse_number
from ..errors import InputError

__all__ = ["JITTER_TOLERANCE", "MIN_SAMPLES", "MIN_DURATION_S", "CHUNK_LINES", "read_csv", "check_time",
           "check_uniform_time", "time_resolution"]

#: Largest accepted deviation of a time from the uniform grid t[0] + i h, h = (t[-1] - t[0]) / (n - 1), as a
#: fraction of h (or one unit of the time column's last written decimal, if that is more: 1/2048 s to 5 decimals).
JITTER_TOLERANCE = 0.01
#: Largest deviation accepted as the rounding of times written with too few decimals for their step, as a
#: fraction of the step (fewer decimals than that are refused: the times no longer say when samples were taken).
ROUNDING_LIMIT = 0.05
#: Shortest accepted record.
MIN_SAMPLES = 100
MIN_DURATION_S = 1.0
#: Lines parsed per chunk: memory stays bounded by the chunk and the float result, not the file's text.
CHUNK_LINES = 65536


def read_csv(path: Path, channels) -> tuple[list[str], np.ndarray]:
    """The channel names of the header ``time,<channels>`` and the data, read chunk by chunk.

    Parameters
    ----------
    path : Path
        The CSV file (UTF-8, an optional byte-order mark).
    channels : sequence of str
        The channel names allowed in the header.

    Returns
    -------
    names : list of str
        The channels, in file order.
    data : ndarray, shape (1 + channels, n)
        Time (row 0, s) and each channel (m/s²), every row contiguous.

    Raises
    ------
    InputError
        A bad header, cell, row length, non-finite value or time column, naming the file's line.

    Notes
    -----
    Lines are parsed in chunks of :data:`CHUNK_LINES` into float arrays: a
    2 M-row, 80 MB file peaks at about twice its 80 MB of floats.  Blank lines
    are skipped; messages name the file's line numbers.
    """
    try:
        with open(path, encoding="utf-8-sig", newline=None) as f:
            header_line = f.readline()
            if not header_line.strip():
                raise InputError(path, "empty file (expected a header 'time,<channels>')")
            header = [h.strip() for h in header_line.split(",")]
            names = _check_header(path, header, channels)
            chunks, blanks, rows = [], [], 0
            first_line = 2
            while True:
                block = list(itertools.islice(f, CHUNK_LINES))
                if not block:
                    break
                lines = []
                for i, ln in enumerate(block):
                    if ln.strip():
                        lines.append(ln)
                    else:
                        blanks.append(first_line + i)
                if lines:
                    try:
                        data = np.loadtxt(lines, delimiter=",", dtype=float, ndmin=2, comments=None)
                        if data.shape[1] != len(header):
                            raise ValueError
                    except ValueError:
                        _locate_bad_cell(path, header, _numbered(block, first_line))
                        raise InputError(path, "unreadable numeric data") from None  # pragma: no cover
                    chunks.append(data)
                    rows += len(data)
                first_line += len(block)
    except UnicodeDecodeError:
        raise InputError(path, "not a UTF-8 text file") from None
    except OSError as exc:
        raise InputError(path, f"cannot read: {exc.strerror or exc}") from None
    if rows < MIN_SAMPLES:
        raise InputError(path, f"record too short: {rows} samples (at least {MIN_SAMPLES} needed)")
    data = np.empty((len(header), rows))  # one row per column: each channel contiguous
    at = 0
    while chunks:
        part = chunks.pop(0)
        data[:, at:at + len(part)] = part.T
        at += len(part)

    def line_of(row: int) -> int:  # the file line of data row `row` (blank lines skipped)
        line = row + 2
        for blank in blanks:
            if blank <= line:
                line += 1
        return line

    finite = np.isfinite(data)
    if not finite.all():
        row = int(np.flatnonzero(~finite.all(axis=0))[0])
        col = int(np.flatnonzero(~finite[:, row])[0])
        raise InputError(path, f"line {line_of(row)}, column {header[col]}: non-finite value {data[col, row]}")
    check_time(path, data[0], line_of=line_of)
    return names, data


def _check_header(path: Path, header: list[str], channels) -> list[str]:
    """The channel names of a CSV header ``time,<channels>`` (InputError for a bad header)."""
    if header[0] != "time":
        raise InputError(path, f"first column must be 'time', found {header[0]!r}")
    names = header[1:]
    if not names:
        raise InputError(path, "no acceleration channel (expected some of FL, FR, RL, RR)")
    for name in names:
        if name not in channels:
            raise InputError(path, f"unknown channel {name!r} (allowed: {', '.join(channels)})")
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise InputError(path, f"duplicate channel {dupes[0]}")
    return names


def _numbered(block: list[str], first_line: int) -> list[tuple[int, str]]:
    return [(first_line + i, ln) for i, ln in enumerate(block) if ln.strip()]


def _locate_bad_cell(path: Path, header: list[str], numbered: list[tuple[int, str]]) -> None:
    for lineno, line in numbered:
        cells = line.split(",")
        if len(cells) != len(header):
            raise InputError(path, f"line {lineno}: expected {len(header)} cells, found {len(cells)}")
        for name, cell in zip(header, cells):
            try:
                parse_number(cell)
            except ValueError:
                raise InputError(path, f"line {lineno}, column {name}: {cell.strip()!r} is not a number") from None


def time_resolution(t: np.ndarray) -> float:
    """The resolution the time column was written with: the largest 10^-d (d = 0..9) of which every time
    is a whole multiple (within round-off), or 0 when none is."""
    for d in range(10):
        scaled = t * 10.0 ** d
        if np.all(np.abs(scaled - np.round(scaled)) <= 1e-9 * np.maximum(1.0, np.abs(scaled))):
            return 10.0 ** -d
    return 0.0


def check_time(source, t: np.ndarray, line_of=None) -> None:
    """Refuse a time column that is too short, not finite, not strictly increasing or not uniform.

    Parameters
    ----------
    source : str or path-like
        Named in the message.
    t : ndarray
        Sample times, s.
    line_of : callable, optional
        Maps a sample index to the file's line number (messages then name lines, else samples).
    """
    if t.ndim != 1 or len(t) < MIN_SAMPLES:
        raise InputError(source, f"record too short: {len(t)} samples (at least {MIN_SAMPLES} needed)")
    if not np.all(np.isfinite(t)):
        raise InputError(source, "time holds non-finite values")
    if t[-1] - t[0] < MIN_DURATION_S:
        raise InputError(source, f"record too short: {t[-1] - t[0]:g} s (at least {MIN_DURATION_S:g} s needed)")
    check_uniform_time(source, t, line_of)


def check_uniform_time(source, t: np.ndarray, line_of=None) -> float:
    """Refuse a time column (finite, two samples or more) that is not strictly increasing or not uniform:
    every time within :data:`JITTER_TOLERANCE` of a step of the uniform grid t[0] + i h.  Where h itself cannot
    be written with the column's decimals (:func:`time_resolution`), within one unit of the last decimal if
    that is more, up to :data:`ROUNDING_LIMIT` of a step (times rounded to half a unit, the grid through the
    rounded end points is off the true one by up to half a unit more); returns h, s.
    The one rule of every reader of a time column."""
    def line(i: int) -> str:
        return f"line {line_of(i)}" if line_of else f"sample {i}"

    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        i = bad[0] + 1
        raise InputError(source, f"time is not strictly increasing at {line(i)} (t = {t[i]:g} s after {t[i - 1]:g} s)")
    duration = t[-1] - t[0]
    nominal = duration / (len(t) - 1)
    dev = np.abs(t - (t[0] + nominal * np.arange(len(t))))
    allowed = JITTER_TOLERANCE * nominal
    resolution = time_resolution(t)
    if resolution > 0 and abs(nominal / resolution - round(nominal / resolution)) > 1e-6:   # h not writable
        allowed = max(allowed, min(resolution * (1 + 1e-6), ROUNDING_LIMIT * nominal))
    worst = int(np.argmax(dev))
    if dev[worst] > allowed:
        raise InputError(source, f"time is not uniformly sampled: t = {t[worst]:.9g} s at {line(worst)} is "
                                 f"{dev[worst] / nominal:.1%} of a step off the uniform grid of step "
                                 f"{nominal:.6g} s (tolerance {JITTER_TOLERANCE:.0%}, or the time "
                                 f"column's last decimal)")
    return float(nominal)
