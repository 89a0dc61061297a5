"""The identified vertical tire as the property files ride and multibody tools read.

* **MF-Tyre / MF-Swift property file** (``.tir``): sections in brackets, ``KEY = value $comment`` lines,
  ``!`` and ``$`` comment lines.  :func:`tir_text` writes a vertical-only file (``USE_MODE = 0``: vertical
  force only, no Magic Formula evaluation): ``[DIMENSION] UNLOADED_RADIUS`` and ``[VERTICAL]
  VERTICAL_STIFFNESS``, ``VERTICAL_DAMPING``, ``FNOMIN`` (the test's wheel load).  :func:`patch_tir` sets
  ``VERTICAL_STIFFNESS`` and ``VERTICAL_DAMPING`` of ``[VERTICAL]`` in a supplier's file and keeps every
  other byte (line endings, alignment, comments, every other section), so the supplier's flat-road and
  drum data stand beside the cleat test's dynamic vertical values.
* **Chrono tire JSON**: :func:`patch_chrono_json` sets the ``"Vertical Stiffness"`` and
  ``"Vertical Damping"`` of a Chrono tire file (e.g. a Fiala tire's ``"Fiala Parameters"``), every other byte
  kept.  The cleat test gives the vertical properties only, so a Chrono file is always patched, never
  made up.

SI units throughout (N/m, N s/m, N, m).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from .._files import OutputFolders, atomic_write_bytes, check_folder, make_folders
from .._inputs import parse_json, read_input_bytes
from ..errors import InputError
from .export import (_STANDARD_GRAVITY, DEFAULT_UNLOADED_RADIUS_M, _method, _number as _is_number,
                     _recording_name, read_identified)

__all__ = ["tir_text", "patch_tir", "patch_chrono_json", "tir_values", "export_tire_file",
           "VERTICAL_KEYS", "FORMATS"]

#: The keys of ``[VERTICAL]`` the cleat test sets.
VERTICAL_KEYS = ("VERTICAL_STIFFNESS", "VERTICAL_DAMPING")
_SECTION = re.compile(r"^\s*\[([A-Za-z0-9_]+)\]")
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def _number(value: float) -> str:
    return f"{float(value):.6e}"


def tir_text(*, tire: str, k: float, c: float, load_n: float, unloaded_radius_m: float, source: str,
             speed_kmh: float | None = None) -> str:
    """A vertical-only MF-Tyre property file of one identified tire (``USE_MODE = 0``)."""
    for name, value in (("k", k), ("c", c), ("load", load_n), ("unloaded radius", unloaded_radius_m)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    speed = "" if speed_kmh is None else f" at {float(speed_kmh):.4g} km/h"
    rows = [
        "!: FILE_TYPE: TIR",
        f"!: COMMENT: vertical properties of tire {tire} from a cleat test{speed} ({source})",
        "!: COMMENT: vertical force only (USE_MODE 0): no Magic Formula coefficients are identified by a cleat test",
        "$-----------------------------------------------------------------mdi_header",
        "[MDI_HEADER]",
        "FILE_TYPE                = 'tir'",
        "FILE_VERSION             = 3.0",
        "FILE_FORMAT              = 'ASCII'",
        "$-----------------------------------------------------------------units",
        "[UNITS]",
        "LENGTH                   = 'meter'",
        "FORCE                    = 'newton'",
        "ANGLE                    = 'radians'",
        "MASS                     = 'kg'",
        "TIME                     = 'second'",
        "$-----------------------------------------------------------------model",
        "[MODEL]",
        "USE_MODE                 = 0                 $Vertical force only",
        "$-----------------------------------------------------------------dimension",
        "[DIMENSION]",
        f"UNLOADED_RADIUS          = {_number(unloaded_radius_m)}      $Free tyre radius",
        "$-----------------------------------------------------------------vertical",
        "[VERTICAL]",
        f"FNOMIN                   = {_number(load_n)}      $Nominal wheel load: the test's static load",
        f"VERTICAL_STIFFNESS       = {_number(k)}      $Tyre vertical stiffness (cleat test, dynamic)",
        f"VERTICAL_DAMPING         = {_number(c)}      $Tyre vertical damping (cleat test)",
    ]
    return "\n".join(rows) + "\n"


def _vertical_lines(lines: list[str], source) -> dict[str, int]:
    """``{key: line index}`` of :data:`VERTICAL_KEYS` in the ``[VERTICAL]`` section."""
    section, found, seen = None, {}, False
    for i, line in enumerate(lines):
        m = _SECTION.match(line)
        if m:
            section = m.group(1).upper()
            seen = seen or section == "VERTICAL"
            continue
        if section != "VERTICAL":
            continue
        for key in VERTICAL_KEYS:
            if re.match(rf"^\s*{key}\s*=", line, re.IGNORECASE):
                if key in found:
                    raise InputError(source, f"{key} is given twice in [VERTICAL] (lines {found[key] + 1} and "
                                             f"{i + 1})")
                found[key] = i
    if not seen:
        raise InputError(source, "has no [VERTICAL] section: not a tyre property file")
    missing = [k for k in VERTICAL_KEYS if k not in found]
    if missing:
        raise InputError(source, f"[VERTICAL] has no {' or '.join(missing)} to set")
    return found


def patch_tir(base: bytes, *, k: float, c: float, source) -> bytes:
    """`base` (a ``.tir``) with ``VERTICAL_STIFFNESS`` = k and ``VERTICAL_DAMPING`` = c in ``[VERTICAL]``;
    every other byte as it was (the value token is replaced in place, its line's layout kept)."""
    text = base.decode("latin-1")             # every byte maps to one character and back
    lines = text.splitlines(keepends=True)
    for key, index in _vertical_lines(lines, source).items():
        value = k if key == "VERTICAL_STIFFNESS" else c
        line = lines[index]
        m = re.match(rf"^(\s*{key}\s*=\s*)({_NUMBER}|'[^']*')", line, re.IGNORECASE)
        if m is None:
            raise InputError(source, f"line {index + 1}: {key} has no number to set")
        lines[index] = m.group(1) + _number(value) + line[m.end(2):]
    return "".join(lines).encode("latin-1")


def tir_values(text: str) -> dict[str, dict[str, str]]:
    """``{SECTION: {KEY: value text}}`` of a ``.tir`` (comments and tables left out)."""
    out, section = {}, None
    for line in text.splitlines():
        m = _SECTION.match(line)
        if m:
            section = out.setdefault(m.group(1).upper(), {})
            continue
        m = re.match(r"^\s*([A-Za-z0-9_]+)\s*=\s*('[^']*'|[^\s$!]+)", line)
        if m and section is not None:
            section[m.group(1).upper()] = m.group(2)
    return out


def patch_chrono_json(base: str, *, k: float, c: float, source) -> str:
    """A Chrono tire JSON with its ``"Vertical Stiffness"`` = k and ``"Vertical Damping"`` = c (each once in
    the file); every other character as it was."""
    parse_json(base, source)
    out = base
    for key, value in (("Vertical Stiffness", k), ("Vertical Damping", c)):
        pattern = re.compile(rf'("{key}"\s*:\s*)({_NUMBER})')
        hits = pattern.findall(out)
        if len(hits) != 1:
            raise InputError(source, f'has {len(hits)} numeric "{key}" entries (one is needed: a Chrono tire '
                                     f'file with a vertical stiffness and damping)')
        out = pattern.sub(lambda m, v=value: m.group(1) + repr(float(v)), out)
    return out


#: ``--format`` -> output suffix.
FORMATS = {"fmu": ".fmu", "tir": ".tir", "chrono-json": ".json"}


def export_tire_file(params_path, output_path, *, fmt: str, tire: str | None = None, base=None,
                     unloaded_radius_m: float | None = None, accept_out_of_range: bool = False) -> tuple[Path, list]:
    """Write one identified tire's vertical k and c as a tyre property file (``fmt="tir"``; with `base`, the
    supplier's file with its ``[VERTICAL]`` stiffness and damping set, every other byte kept) or into a
    Chrono tire JSON (``fmt="chrono-json"``, `base` required: the cleat test gives the vertical properties
    only).  Returns (path, notes: what the user should know, one sentence each)."""
    doc, tire, entry = read_identified(params_path, tire, accept_out_of_range=accept_out_of_range)
    output_path = Path(output_path)
    if output_path.suffix != FORMATS[fmt]:
        raise InputError(output_path, f"the output file name must end with {FORMATS[fmt]} for --format {fmt}")
    if output_path.is_dir():
        raise InputError(output_path, "is a directory")
    check_folder(output_path.parent)
    load = entry["mass"] * _STANDARD_GRAVITY if _is_number(entry.get("mass")) and entry["mass"] > 0 else None
    notes = []
    if base is not None:
        base = Path(base)
        data = read_input_bytes(base, limit=16 << 20)
        if fmt == "tir":
            out = patch_tir(data, k=entry["k"], c=entry["c"], source=base)
            fnomin = tir_values(data.decode("latin-1")).get("VERTICAL", {}).get("FNOMIN")
            try:
                nominal = float(fnomin) if fnomin is not None else None
            except ValueError:
                nominal = None
            if load and nominal and abs(nominal / load - 1) > 0.1:
                notes.append(f"{base.name}: FNOMIN {nominal:.6g} N is not the test's wheel load {load:.6g} N: k and "
                             f"c hold at the test's load")
        else:
            try:
                text = data.decode("utf-8")
            except UnicodeDecodeError:
                raise InputError(base, "is not UTF-8 text") from None
            out = patch_chrono_json(text, k=entry["k"], c=entry["c"], source=base).encode("utf-8")
    elif fmt == "tir":
        if load is None:
            raise InputError(params_path, f"tire {tire}: no wheel load (mass) to write as FNOMIN")
        radius = float(unloaded_radius_m) if unloaded_radius_m is not None else DEFAULT_UNLOADED_RADIUS_M
        if unloaded_radius_m is None:
            notes.append(f"UNLOADED_RADIUS is the default {DEFAULT_UNLOADED_RADIUS_M} m, an assumption "
                         f"(--unloaded-radius-m)")
        out = tir_text(tire=tire, k=entry["k"], c=entry["c"], load_n=load, unloaded_radius_m=radius,
                       source=f"{_recording_name(doc) or Path(params_path).name}, {_method(entry)} method",
                       speed_kmh=doc.get("speed_kmh")).encode("ascii", "replace")
    else:
        raise InputError("--base", "--format chrono-json patches a Chrono tire file: give it with --base "
                                   "(the cleat test identifies the vertical properties only)")
    try:
        with OutputFolders():
            make_folders(output_path.parent)
            atomic_write_bytes({output_path: out})
    except OSError as exc:
        raise InputError(output_path, f"cannot write: {exc.strerror or exc}") from None
    return output_path, notes
