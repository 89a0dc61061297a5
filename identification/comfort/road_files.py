"""Road files: a two-track road profile as CSV or as ASAM OpenCRG (format details: docs/guide/ride.md).

**CSV** (:func:`write_road_csv`, :func:`read_road_csv`): UTF-8 text, ``#`` comment lines first (one may
read ``# track_width_m = 1.8``, m), the header ``x_m,left_m,right_m``, then per grid point the position
along the road (m, increasing, uniformly spaced) and the left and right tracks' heights (m), written in
Python's shortest round-trip form: a written road reads back bit for bit.

**OpenCRG** (:func:`write_road_crg`, :func:`read_road_crg`), ASAM OpenCRG 1.2: ISO 8859-1 text sections
opened by ``$KEYWORD`` and closed by a line starting with ``$`` (``*`` in column 1 a comment line, ``!`` an
inline comment): ``$CT`` a description, ``$ROAD_CRG`` the reference line's ``KEY = value`` parameters
(``REFERENCE_LINE_INCREMENT``, the step in u, m, mandatory; ``LONG_SECTION_V_*`` lateral positions v, m,
positive to the left), ``$KD_Definition`` the data format (``#:LRFI``/``#:LDFI`` text of 10/20-character
real/double fields, 80-character records, a row starting a record; ``#:KRBI``/``#:KDBI`` big-endian
float32/float64 in 80-byte records filled one after another, NaN-padded; KRBI when absent) and one ``D:``
channel per column (``reference line u,m``, ``long section at v = X,m``, ``long section N,m``; ``U:``
virtual channels ignored); then a ``$$$$`` line and the rows, one per cut across the road (a text field
starting with ``*`` is missing).  The writer writes LDFI (14 significant digits): u and the tracks at
v = -B/2 (right) and +B/2 (left).  The reader takes the four formats and a straight, level reference line
(heading channels ignored; slope and banking, which would change the heights, refused); the tracks are the
two long sections or, with more, interpolated at v = ±B/2.

Readers follow the package's input rules (:func:`identification._inputs.read_input_bytes`: special files
refused; one-line :class:`~identification.errors.InputError` naming the file; a non-finite value or a
non-uniform spacing refused with its row).  Positions count from the file's first point; the road's
class is :data:`~identification.comfort.road.FILE_CLASS`.  Writers write atomically.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .._files import atomic_write_texts
from .._inputs import parse_number, read_input_bytes, read_input_text
from ..errors import InputError
from .road import DEFAULT_TRACK_WIDTH_M, FILE_CLASS, RoadProfile

__all__ = ["CSV_HEADER", "SPACING_TOLERANCE", "write_road_csv", "read_road_csv", "write_road_crg", "read_road_crg",
           "write_road", "read_road"]

#: The header of a road CSV.
CSV_HEADER = "x_m,left_m,right_m"
#: Largest deviation of a position from the uniform grid through the first and last, as a share of a step.
SPACING_TOLERANCE = 0.01
_CRG_FORMATS = {"LRFI": (10, None), "LDFI": (20, None), "KRBI": (None, ">f4"), "KDBI": (None, ">f8")}


def _road_from(path, x, left, right, track_width_m: float, rows) -> RoadProfile:
    """A file road from its columns; `rows(i)` names grid point i in messages."""
    if x.size < 2:
        raise InputError(path, f"a road needs at least 2 points, found {x.size}")
    for name, col in (("x_m", x), ("left_m", left), ("right_m", right)):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            raise InputError(path, f"{rows(bad[0])}: {name} is not a finite number ({col[bad[0]]})")
    step = np.diff(x)
    if np.any(step <= 0):
        i = int(np.flatnonzero(step <= 0)[0]) + 1
        raise InputError(path, f"{rows(i)}: positions must increase ({x[i]:g} m after {x[i - 1]:g} m)")
    nominal = (x[-1] - x[0]) / (x.size - 1)
    dev = np.abs(x - (x[0] + nominal * np.arange(x.size)))
    worst = int(np.argmax(dev))
    if dev[worst] > SPACING_TOLERANCE * nominal:
        raise InputError(path, f"{rows(worst)}: position {x[worst]:.9g} m is {dev[worst] / nominal:.1%} of a step off "
                               f"the uniform grid of step {nominal:.6g} m (the spacing must be uniform within "
                               f"{SPACING_TOLERANCE:.0%})")
    x = x - x[0]
    return RoadProfile(x_m=x, left_m=left, right_m=right, road_class=FILE_CLASS, gd_n0_m3=math.nan,
                       band_cpm=(1.0 / float(x[-1]), 1.0 / (2.0 * nominal)), track_width_m=float(track_width_m),
                       coherence_decay=math.nan, seed=-1, period_m=0.0, coherence_model=FILE_CLASS)


def _width(path, value) -> float:
    try:
        b = parse_number(str(value))
    except ValueError:
        raise InputError(path, f"track width {value!r} is not a number") from None
    if not (math.isfinite(b) and b > 0):
        raise InputError(path, f"track width must be a finite number > 0 m, got {value}")
    return b


def _describe(road: RoadProfile) -> list[str]:
    if road.road_class == FILE_CLASS:
        return ["road profile read from a file"]
    return [f"ISO 8608 class {road.road_class} road, seed {road.seed}, {road.coherence_model} coherence",
            f"of the tracks; Gd(n0) = {road.gd_n0_m3:g} m^3 at n0 = 0.1 cycles/m"]


def write_road_csv(road: RoadProfile, path) -> Path:
    """Write both tracks of `road` as a road CSV (module docstring), atomically; returns the path."""
    path = Path(path)
    lines = [f"# {line}" for line in _describe(road)]
    lines += [f"# track_width_m = {float(road.track_width_m)!r}", CSV_HEADER]
    lines += [f"{x!r},{left!r},{right!r}" for x, left, right in
              zip(road.x_m.tolist(), road.left_m.tolist(), road.right_m.tolist())]
    atomic_write_texts({path: "\n".join(lines) + "\n"})
    return path


def read_road_csv(path, *, track_width_m: float | None = None) -> RoadProfile:
    """Read a road CSV (module docstring).

    Parameters
    ----------
    path : str or path-like
        The file.
    track_width_m : float, optional
        Distance between the tracks, m; default the file's ``# track_width_m = B`` comment, else
        :data:`~identification.comfort.road.DEFAULT_TRACK_WIDTH_M`.

    Returns
    -------
    RoadProfile
        Class :data:`~identification.comfort.road.FILE_CLASS`, positions from 0.

    Raises
    ------
    InputError
        Naming the file, in one line: unreadable or special file, no or another header, a row without
        three numbers, a non-finite value, positions not increasing or not uniformly spaced.
    """
    path = Path(path)
    lines = read_input_text(path, encoding="utf-8-sig").splitlines()
    width = None
    i = 0
    while i < len(lines) and (lines[i].lstrip().startswith("#") or not lines[i].strip()):
        key, sep, value = lines[i].lstrip()[1:].partition("=")
        if sep and key.strip() == "track_width_m":
            width = _width(path, value.strip())
        i += 1
    if i == len(lines):
        raise InputError(path, f"no header (expected '{CSV_HEADER}')")
    header = ",".join(h.strip() for h in lines[i].split(","))
    if header != CSV_HEADER:
        raise InputError(path, f"line {i + 1}: header {lines[i].strip()!r}, expected '{CSV_HEADER}'")
    numbered = [(k + 1, ln) for k, ln in enumerate(lines[i + 1:], start=i + 1) if ln.strip()]
    for lineno, line in numbered:
        if line.count(",") != 2:
            raise InputError(path, f"line {lineno}: expected 3 cells (x_m, left_m, right_m), found "
                                   f"{line.count(',') + 1}")
    try:
        bad = next((ln for _, ln in numbered if "_" in ln or not ln.isascii()), None)
        if bad is not None:
            raise ValueError(bad)
        data = np.loadtxt([ln for _, ln in numbered], delimiter=",", dtype=float, ndmin=2).reshape(-1, 3)
    except ValueError:
        for lineno, line in numbered:
            for column, cell in zip(CSV_HEADER.split(","), line.split(",")):
                try:
                    parse_number(cell)
                except ValueError:
                    raise InputError(path, f"line {lineno}, column {column}: {cell.strip()!r} is not a number") \
                        from None
        raise InputError(path, "unreadable numeric data") from None  # pragma: no cover
    b = track_width_m if track_width_m is not None else width if width is not None else DEFAULT_TRACK_WIDTH_M
    return _road_from(path, data[:, 0], data[:, 1], data[:, 2], _width(path, b),
                      lambda r: f"line {numbered[r][0]}")


def _field(value: float) -> str:
    text = f"{value:20.13e}"
    return text if len(text) == 20 else f"{value:20.12e}"         # a three-digit exponent


def write_road_crg(road: RoadProfile, path) -> Path:
    """Write both tracks of `road` as an OpenCRG file, LDFI (module docstring), atomically; returns the path."""
    path = Path(path)
    half = float(road.track_width_m) / 2.0
    x = road.x_m - road.x_m[0]
    ct = _describe(road) + [f"two tracks {road.track_width_m:g} m apart: right v = {-half:g} m, left v = {half:g} m;",
                            "heights in m; written by cleatfmu"]
    lines = ["$CT", *ct, "$", "$ROAD_CRG",
             "REFERENCE_LINE_START_U   = 0.0",
             f"REFERENCE_LINE_END_U     = {float(x[-1])!r}",
             f"REFERENCE_LINE_INCREMENT = {float(x[-1]) / (x.size - 1)!r}",
             f"LONG_SECTION_V_RIGHT     = {-half!r}",
             f"LONG_SECTION_V_LEFT      = {half!r}",
             "$", "$KD_Definition", "#:LDFI",
             "D:reference line u,m",
             f"D:long section at v = {-half!r},m",
             f"D:long section at v = {half!r},m",
             "$", "$" * 80]
    lines += [_field(u) + _field(r) + _field(left) for u, left, r in
              zip(x.tolist(), road.left_m.tolist(), road.right_m.tolist())]
    atomic_write_texts({path: "\n".join(lines) + "\n"})
    return path


def _crg_header(path, text: str) -> tuple[dict, str, list]:
    """The road parameters, the data format and the channel definitions of a CRG header."""
    params, fmt, channels, section = {}, "KRBI", [], None
    for lineno, raw in enumerate(text.splitlines(), start=1):
        if raw.startswith("*"):
            continue
        line = raw.split("!", 1)[0].strip()
        if raw.startswith("$"):
            section = line[1:].strip().upper() or None
            continue
        if not line:
            continue
        if section == "ROAD_CRG":
            key, sep, value = line.partition("=")
            if not sep:
                raise InputError(path, f"line {lineno}: {line!r} is not a 'KEY = value' road parameter")
            try:
                params[key.strip().upper()] = parse_number(value.strip())
            except ValueError:
                raise InputError(path, f"line {lineno}: {key.strip()} = {value.strip()!r} is not a number") from None
        elif section == "KD_DEFINITION":
            if line.startswith("#:"):
                fmt = line[2:6].upper()
                if fmt not in _CRG_FORMATS:
                    raise InputError(path, f"line {lineno}: unknown data format {line!r} (LRFI, LDFI, KRBI, KDBI)")
            elif line.upper().startswith("D:"):
                channels.append((lineno, line[2:].strip()))
    return params, fmt, channels


def _channel(path, lineno: int, text: str) -> float | str | tuple:
    """A channel definition: 'u', an ignored planar channel, the v position of a long section (m), or
    ("index", N) for the N-th long section."""
    name, _, unit = (t.strip() for t in text.rpartition(","))
    low = " ".join(name.lower().split())
    if low.startswith("reference line"):
        what = low[len("reference line"):].strip()
        if what in ("u", "x", "y", "phi"):
            return what
        raise InputError(path, f"line {lineno}: channel 'reference line {what}' is not supported (a sloped or "
                               f"banked reference line would change the tracks' heights)")
    if not low.startswith("long section") or unit.lower() != "m":
        raise InputError(path, f"line {lineno}: unknown channel 'D:{text}' (expected reference line u, long "
                               f"section at v = X,m or long section N,m)")
    rest = low[len("long section"):].strip()
    try:
        if rest.startswith("at v"):
            return parse_number(rest.partition("=")[2])
        return ("index", int(rest))
    except ValueError:
        raise InputError(path, f"line {lineno}: unreadable long section position in 'D:{text}'") from None


def _positions(path, kinds: list, params: dict) -> list:
    """`kinds` with the N-th long sections at their v, m: V_RIGHT + (N - 1) V_INCREMENT, the increment from
    V_RIGHT and V_LEFT where not given, the sections centred on the reference line where neither border is."""
    numbers = [k[1] for k in kinds if isinstance(k, tuple)]
    if not numbers:
        return kinds
    if len(numbers) != len([k for k in kinds if not isinstance(k, str)]):
        raise InputError(path, "long sections defined both by position (at v = X) and by number")
    if sorted(numbers) != list(range(1, len(numbers) + 1)):
        raise InputError(path, f"long sections numbered {sorted(numbers)}, expected 1 .. {len(numbers)}")
    right, left = params.get("LONG_SECTION_V_RIGHT"), params.get("LONG_SECTION_V_LEFT")
    inc = params.get("LONG_SECTION_V_INCREMENT")
    if inc is None and right is not None and left is not None and len(numbers) > 1:
        inc = (left - right) / (len(numbers) - 1)
    if inc is None or not (math.isfinite(inc) and inc > 0):
        raise InputError(path, "numbered long sections need LONG_SECTION_V_INCREMENT > 0 (or both "
                               "LONG_SECTION_V_RIGHT and LONG_SECTION_V_LEFT) in $ROAD_CRG")
    if right is None:
        right = -0.5 * (len(numbers) - 1) * inc if left is None else left - (len(numbers) - 1) * inc
    return [right + (k[1] - 1) * inc if isinstance(k, tuple) else k for k in kinds]


def _crg_values(path, body: bytes, fmt: str, n_channels: int, first_line: int) -> tuple[np.ndarray, callable]:
    """The data rows (one per lateral cut) and a namer of row i for messages."""
    width, dtype = _CRG_FORMATS[fmt]
    if dtype is not None:
        values = np.frombuffer(body[:len(body) // int(dtype[-1]) * int(dtype[-1])], dtype=dtype).astype(float)
        rows = values[:values.size // n_channels * n_channels].reshape(-1, n_channels)
        while rows.shape[0] and np.all(np.isnan(rows[-1])):       # the last record's NaN padding
            rows = rows[:-1]
        return rows, lambda i: f"data row {i + 1}"
    lines = body.decode("latin-1").splitlines()
    per_record = 80 // width
    records = -(-n_channels // per_record)
    if len(lines) % records:
        raise InputError(path, f"{len(lines)} data records do not make whole rows of {n_channels} channels "
                               f"({records} records a row)")
    rows = np.empty((len(lines) // records, n_channels))
    for r in range(rows.shape[0]):
        fields = []
        for line in lines[r * records:(r + 1) * records]:
            fields += [line[k:k + width] for k in range(0, min(len(line.rstrip()), 80), width)]
        if len(fields) != n_channels:
            raise InputError(path, f"line {first_line + r * records}: {len(fields)} values, expected {n_channels}")
        for c, cell in enumerate(fields):
            try:
                rows[r, c] = math.nan if cell.strip().startswith("*") else parse_number(cell)
            except ValueError:
                raise InputError(path, f"line {first_line + r * records}: {cell.strip()!r} is not a number") from None
    return rows, lambda i: f"line {first_line + i * records}"


def read_road_crg(path, *, track_width_m: float | None = None) -> RoadProfile:
    """Read an OpenCRG file (module docstring) as a two-track road.

    Parameters
    ----------
    path : str or path-like
        The file.
    track_width_m : float, optional
        Distance between the tracks, m, where the file has more than two long sections: the tracks are
        then interpolated at v = ±B/2 (default :data:`~identification.comfort.road.DEFAULT_TRACK_WIDTH_M`).
        With two long sections they are the tracks, B their distance.

    Returns
    -------
    RoadProfile
        Class :data:`~identification.comfort.road.FILE_CLASS`, positions from 0 (the u channel's, or
        REFERENCE_LINE_START_U + i REFERENCE_LINE_INCREMENT).

    Raises
    ------
    InputError
        Naming the file, in one line: unreadable or special file, no ``$$$$`` data separator, no
        REFERENCE_LINE_INCREMENT, fewer than two long sections, an unsupported channel, malformed or
        non-finite values (with the row), a non-uniform u.
    """
    path = Path(path)
    data = read_input_bytes(path)
    start = data.find(b"\n$$$$")
    if start < 0:
        raise InputError(path, "no '$$$$' line before the road data: not an OpenCRG file")
    body_at = data.find(b"\n", start + 1)
    body = b"" if body_at < 0 else data[body_at + 1:]
    head = data[:start].decode("latin-1")
    params, fmt, channels = _crg_header(path, head)
    inc = params.get("REFERENCE_LINE_INCREMENT")
    if inc is None or not (math.isfinite(inc) and inc > 0):
        raise InputError(path, "$ROAD_CRG needs REFERENCE_LINE_INCREMENT = the step along the road (> 0 m)")
    for key in ("REFERENCE_LINE_START_S", "REFERENCE_LINE_END_S", "REFERENCE_LINE_START_B", "REFERENCE_LINE_END_B"):
        if params.get(key, 0.0) != 0.0:
            raise InputError(path, f"{key} = {params[key]:g}: a sloped or banked reference line is not supported")
    kinds = [_channel(path, lineno, text) for lineno, text in channels]
    kinds = _positions(path, kinds, params)
    sections = sorted((v, i) for i, v in enumerate(kinds) if not isinstance(v, str))
    if len(sections) < 2:
        raise InputError(path, f"{len(sections)} long section(s) defined: two tracks need at least two")
    rows, name = _crg_values(path, body, fmt, len(kinds), head.count("\n") + 3)
    if rows.shape[0] < 2:
        raise InputError(path, f"{rows.shape[0]} data row(s): a road needs at least 2")
    v = np.array([s[0] for s in sections])
    z = rows[:, [s[1] for s in sections]]
    if "u" in kinds:
        x = rows[:, kinds.index("u")]
    else:
        x = params.get("REFERENCE_LINE_START_U", 0.0) + inc * np.arange(rows.shape[0])
    if abs((x[-1] - x[0]) / (x.size - 1) - inc) > SPACING_TOLERANCE * inc:
        raise InputError(path, f"the u channel's step {(x[-1] - x[0]) / (x.size - 1):.6g} m is not "
                               f"REFERENCE_LINE_INCREMENT = {inc:.6g} m")
    if v.size == 2:
        width, right, left = float(v[1] - v[0]), z[:, 0], z[:, 1]
    else:
        width = _width(path, DEFAULT_TRACK_WIDTH_M if track_width_m is None else track_width_m)
        if -width / 2 < v[0] or width / 2 > v[-1]:
            raise InputError(path, f"the tracks at v = ±{width / 2:g} m lie outside the long sections "
                                   f"({v[0]:g} .. {v[-1]:g} m)")
        right, left = _at(v, z, -width / 2), _at(v, z, width / 2)
    return _road_from(path, np.asarray(x, dtype=float), np.asarray(left, dtype=float), np.asarray(right, dtype=float),
                      width, name)


def _at(v: np.ndarray, z: np.ndarray, target: float) -> np.ndarray:
    """Heights at lateral position `target`: the long section there, or linear in v between the two around
    it (only those two: a missing value elsewhere does not matter, one there gives NaN, refused later)."""
    j = int(np.searchsorted(v, target))
    if j < v.size and v[j] == target:
        return z[:, j].copy()
    w = (target - v[j - 1]) / (v[j] - v[j - 1])
    return (1.0 - w) * z[:, j - 1] + w * z[:, j]


def write_road(road: RoadProfile, path) -> Path:
    """Write `road` as CSV or OpenCRG by the file's suffix (``.csv``, ``.crg``)."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".csv", ".crg"):
        raise InputError(path, "a road file must end in .csv or .crg")
    try:
        return write_road_csv(road, path) if suffix == ".csv" else write_road_crg(road, path)
    except OSError as exc:               # (a full disk: the file's error, not stdout's)
        raise InputError(path, f"cannot write: {exc.strerror or exc}") from None


def read_road(path, *, track_width_m: float | None = None) -> RoadProfile:
    """Read a road CSV or OpenCRG file by its suffix (``.csv``, ``.crg``)."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".csv", ".crg"):
        raise InputError(path, "a road file must end in .csv or .crg")
    reader = read_road_csv if suffix == ".csv" else read_road_crg
    return reader(path, track_width_m=track_width_m)
