"""Property-based fuzzing of the commands and file types ``tests/test_fuzz.py`` does not reach.

Same property (:func:`test_fuzz.check_case`): exit 0 with a sound result and only the files asked for, or
exit 2 with one line ``cleatfmu: error: <file or option>: <problem>`` and nothing written; never a
traceback, never a leftover.  Commands and the files they read:

* ``static`` (compression-test CSV), ``comfort`` (acceleration record CSV), ``map`` (a report's
  ``summary.json``), ``ride`` (recording, ``--body`` diagnosis or summary, ``--compare`` with
  ``static=FILE``, ``params=FILE``, ``fmu=DIR``, ``map=FILE``), ``ssp`` and ``simulate --body`` (four tire
  FMUs, their zip archives mutated, and the body document), ``export`` of a ``diagnose --json`` document;
* JSON documents mutated at any path of their tree, and as text: keys named twice, nesting 100,000 deep,
  non-ASCII and control characters, numbers beyond every range, a byte-order mark, invalid UTF-8;
* every file type of every command as a FIFO, a symlink to /dev/zero, a folder, a dangling symlink or an
  unreadable file;
* in a subprocess: stdout to /dev/full and stdout closed (every command that prints), and a file-size limit
  (``RLIMIT_FSIZE``: a full disk) for every command that writes a file.

The valid inputs are made once per test process from a short, low-rate whole-tractor run of the virtual
rig (its diagnosis, four tire FMUs, parameters, a report summary of two speeds and their tire map) and
the embedded compression test, so a case costs well under a second; ``ride`` runs 10 s of one road.  The
faults found are pinned by ``tests/test_fuzz_found.py``.
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import math
import os
import resource
import shlex
import signal
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.fuzz   # its own CI step (pytest -m fuzz), left out of the default run

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from test_fuzz import (CI, Case, FuzzFailure, Special, _SUCCESS, _check_fmu, _check_written,  # noqa: E402
                       _json_or_text, _option, check_case, mutated_csv, dumps_raw, garbage, huge_literals,
                       json_values, numbers, scaled)

ROOT = Path(__file__).resolve().parents[1]
TIRES = ("FL", "FR", "RL", "RR")

# ----------------------------------------------------------------------------- valid starting points


def _main(argv) -> str:
    from identification.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        status = main([str(a) for a in argv])
    assert status == 0, argv
    return out.getvalue()


@functools.lru_cache(maxsize=1)
def command_files() -> dict[str, bytes]:
    """File name -> bytes of the valid inputs: ``run.csv``/``run.json`` (a four-hub rig run at 250 Hz),
    ``diag.json`` (its ``diagnose --json``), ``fmus/run_<TIRE>.fmu`` (its ``--fmu-dir``), ``params4.json``
    (its ``identify --json``), ``summary.json`` (a report summary of it and of a 10 km/h run, the diagnosis
    in its entry), ``tire_map.json`` (``map`` of that summary), ``comp.csv`` (the embedded compression
    test), ``road.csv`` and ``road.crg`` (a ride's ``--save-road``, 20 m of a class B road) and ``seat.json``
    (the default seat's parameters)."""
    files = {}
    with tempfile.TemporaryDirectory() as work:
        w = Path(work)
        for name, speed in (("run", "7"), ("run10", "10")):
            _main(["rig", "-o", w / name, "--speed", speed, "--param=sensor.rate_hz=250"])
        diag = json.loads(_main(["diagnose", w / "run.csv", "--json", "--workers=1", "--fmu-dir", w / "fmus"]))
        diag["recording"] = "run.csv"
        ident = {n: json.loads(_main(["identify", w / f"{n}.csv", "--json", "--method=waveform"]))
                 for n in ("run", "run10")}
        recordings = []
        for name, speed in (("run", 7.0), ("run10", 10.0)):
            meta = json.loads((w / f"{name}.json").read_text())
            tires = {t: {"recommended": {key: e[key] for key in ("k", "c", "k_ci", "c_ci")} | {"conditional": False}}
                     for t, e in (diag if name == "run" else ident[name])["tires"].items()}
            recordings.append({"name": name, "source": f"{name}.csv", "ok": True, "error": None,
                               "conditions": {"speed_m_s": speed / 3.6,
                                              "wheel_load_N": {t: 1e3 * v for t, v in meta["wheel_load_kN"].items()},
                                              "inflation_pressure_Pa": None},
                               "diagnosis": diag if name == "run" else None, "tires": tires})
        summary = {"format": "cleatfmu-report-summary/1", "recordings": recordings}
        (w / "summary.json").write_text(json.dumps(summary))
        _main(["map", w / "summary.json", "-o", w / "map", "--no-fmu"])
        (w / "diag.json").write_text(json.dumps(diag))
        _main(["ride", w / "run.csv", "--body", w / "diag.json", "--compare=final", "--workers=1", "--duration-s=10",
               "--realisations=1", "--save-road", w / "road.csv"])
        from identification.comfort.road_files import read_road, write_road
        from identification.comfort.seat import DEFAULT_SEAT

        write_road(read_road(w / "road.csv"), w / "road.crg")
        seat = {k: v for k, v in DEFAULT_SEAT.to_json().items() if k not in ("natural_frequency_hz", "damping_ratio")}
        files = {"run.csv": (w / "run.csv").read_bytes(), "run.json": (w / "run.json").read_bytes(),
                 "diag.json": json.dumps(diag, indent=1).encode(), "summary.json": json.dumps(summary).encode(),
                 "params4.json": json.dumps(ident["run"], indent=1).encode(),
                 "tire_map.json": (w / "map" / "tire_map.json").read_bytes(),
                 "comp.csv": (ROOT / "identification" / "data" / "testday_compression.csv").read_bytes(),
                 "road.csv": (w / "road.csv").read_bytes(), "road.crg": (w / "road.crg").read_bytes(),
                 "seat.json": json.dumps(dict(seat, comment="a passive seat"), indent=1).encode()}
        for tire in TIRES:
            files[f"fmus/run_{tire}.fmu"] = (w / "fmus" / f"run_{tire}.fmu").read_bytes()
    return files


def _files(*names, **changed) -> dict:
    """The valid files `names` (``fmus`` for the four FMUs), with `changed` (file name -> bytes) instead."""
    base = command_files()
    out = {}
    for name in names:
        out.update({k: v for k, v in base.items() if k.startswith("fmus/")} if name == "fmus" else {name: base[name]})
    out.update(changed)
    out["out/.keep"] = b""
    return out


# ----------------------------------------------------------------------------- strategies: any JSON document

#: Text that a JSON string may hold and a careless reader trips over.
odd_text = st.one_of(st.text(max_size=12), st.sampled_from(["\u00e9\u00df", "\u2212" "1", "\x00", "\x1b[2J", "\ufeff",
                                                            "\u202e", "a\nb", "\U0001f69c", "\ud7ff"]))
odd_values = st.one_of(json_values, huge_literals, odd_text, numbers)


def _paths(value, prefix=()) -> list[tuple]:
    """Every path (tuple of keys and indices) of a JSON tree."""
    paths = [prefix]
    if isinstance(value, dict):
        for key, item in value.items():
            paths += _paths(item, prefix + (key,))
    elif isinstance(value, list):
        for i, item in enumerate(value[:6]):
            paths += _paths(item, prefix + (i,))
    return paths


@st.composite
def json_tree_mutation(draw, doc):
    """`doc` with 1-3 changes at random paths: a value replaced, a key removed or added, a list emptied."""
    doc = json.loads(json.dumps(doc))
    for _ in range(draw(st.integers(1, 3))):
        path = draw(st.sampled_from(_paths(doc)))
        if not path:
            continue
        *head, last = path
        parent = doc
        for key in head:
            parent = parent[key]
        kind = draw(st.sampled_from(["set", "set", "set", "delete", "extra", "scale", "empty"]))
        if kind == "delete":
            del parent[last]
        elif kind == "extra" and isinstance(parent, dict):
            parent[draw(odd_text)] = draw(odd_values)
        elif kind == "scale" and isinstance(parent[last], (int, float)) and not isinstance(parent[last], bool):
            parent[last] = parent[last] * draw(st.sampled_from([-1, 0, 1e-300, 1e300, 1e308, 10 ** 30]))
        elif kind == "empty":
            parent[last] = draw(st.sampled_from([{}, [], "", None]))
        else:
            parent[last] = draw(odd_values)
    return doc


@st.composite
def json_file(draw, name: str) -> bytes:
    """The valid JSON file `name` mutated in its tree (mostly) or as text: a key named twice, deep nesting,
    a byte-order mark, invalid UTF-8, control characters, truncation; or garbage."""
    text = command_files()[name]
    kind = draw(st.sampled_from(["tree"] * 6 + ["duplicate", "deep", "bom", "bytes", "control", "truncate",
                                               "garbage", "raw"]))
    if kind == "tree":
        return dumps_raw(draw(json_tree_mutation(json.loads(text))))
    if kind == "duplicate":   # the first key again, in the outermost object
        key = next(iter(json.loads(text)))
        return text.replace(b"{", b"{" + json.dumps(key).encode() + b": null, ", 1)
    if kind == "deep":
        n = draw(st.sampled_from([100, 1000, 100_000]))
        return b"[" * n + b"]" * n if draw(st.booleans()) else b'{"a":' * n + b"1" + b"}" * n
    if kind == "bom":
        return b"\xef\xbb\xbf" + text
    if kind == "bytes":
        i = draw(st.integers(0, len(text) - 1))
        return text[:i] + draw(st.sampled_from([b"\xff", b"\xc3", b"\x00", b"\xed\xa0\x80"])) + text[i + 1:]
    if kind == "control":
        i = draw(st.integers(0, len(text) - 1))
        return text[:i] + draw(st.sampled_from([b"\x01", b"\x1b", b"\x7f", b"\r", b"\t", b"\x0c"])) + text[i:]
    if kind == "truncate":
        return text[:draw(st.integers(0, len(text) - 1))]
    if kind == "raw":        # a number of the document as a literal beyond every range
        doc = json.loads(text)
        paths = [p for p in _paths(doc) if p and isinstance(_get(doc, p), float)]
        if paths:
            path = draw(st.sampled_from(paths))
            _set(doc, path, draw(huge_literals))
        return dumps_raw(doc)
    return draw(garbage)


def _get(doc, path):
    for key in path:
        doc = doc[key]
    return doc


def _set(doc, path, value):
    _get(doc, path[:-1])[path[-1]] = value


# ----------------------------------------------------------------------------- strategies: CSV and zip

@st.composite
def csv_file(draw, name: str) -> bytes:
    """The valid CSV `name` with 1-3 line mutations (cells, header, rows, time, separators), or garbage."""
    return mutated_csv(draw, command_files()[name].decode().splitlines())


@st.composite
def zip_file(draw, data: bytes) -> bytes:
    """The zip archive `data` (an FMU) mutated: truncated, bytes flipped, a member dropped, its
    ``modelDescription.xml`` broken, a member outside the archive's folder, or garbage."""
    kind = draw(st.sampled_from(["truncate", "flip", "drop", "xml", "xml", "escape", "garbage"]))
    if kind == "truncate":
        return data[:draw(st.integers(0, len(data) - 1))]
    if kind == "flip":
        data = bytearray(data)
        for _ in range(draw(st.integers(1, 8))):
            data[draw(st.integers(0, len(data) - 1))] ^= draw(st.integers(1, 255))
        return bytes(data)
    if kind == "garbage":
        return draw(garbage)
    with zipfile.ZipFile(io.BytesIO(data)) as src:
        members = {info.filename: src.read(info) for info in src.infolist()}
    if kind == "drop":
        del members[draw(st.sampled_from(sorted(members)))]
    elif kind == "escape":
        members[draw(st.sampled_from(["../evil.txt", "/abs.txt", "binaries/../../x"]))] = b"x"
    else:
        xml = members["modelDescription.xml"].decode()
        change = draw(st.sampled_from(["truncate", "attribute", "value", "garbage"]))
        if change == "truncate":
            xml = xml[:draw(st.integers(0, len(xml) - 1))]
        elif change == "attribute":
            xml = xml.replace('fmiVersion="2.0"', 'fmiVersion="' + draw(st.sampled_from(["1.0", "3.0", "", "x"])) + '"')
        elif change == "value":   # a start value
            import re

            starts = list(re.finditer(r'start="([^"]*)"', xml))
            if starts:
                m = draw(st.sampled_from(starts))
                value = draw(st.sampled_from(["nan", "-1", "1e400", "", "abc", "0", "-inf", "1e308"]))
                xml = xml[:m.start(1)] + value + xml[m.end(1):]
        else:
            xml = draw(st.text(max_size=100))
        members["modelDescription.xml"] = xml.encode("utf-8", "surrogatepass")
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as dst:
        for name, member in members.items():
            dst.writestr(name, member)
    return out.getvalue()


@st.composite
def text_file(draw, name: str) -> bytes:
    """The valid text file `name` (an OpenCRG road) with 1-3 line mutations: a line deleted, repeated, cut,
    replaced, a fixed-width field or a character replaced; or garbage."""
    if draw(st.integers(0, 9)) == 0:
        return draw(garbage)
    lines = command_files()[name].decode("latin-1").splitlines()
    for _ in range(draw(st.integers(1, 3))):
        i = draw(st.integers(0, min(len(lines) - 1, 40)) if draw(st.booleans()) else st.integers(0, len(lines) - 1))
        kind = draw(st.sampled_from(["delete", "repeat", "cut", "replace", "field", "char", "truncate"]))
        if kind == "delete":
            del lines[i]
        elif kind == "repeat":
            lines.insert(i, lines[i])
        elif kind == "cut":
            lines[i] = lines[i][:draw(st.integers(0, max(0, len(lines[i]) - 1)))]
        elif kind == "replace":
            lines[i] = draw(st.one_of(st.sampled_from(["$", "$$$$", "#:KDBI", "#:XXXX", "D:long section 3,m",
                                                      "REFERENCE_LINE_INCREMENT = 0", "LONG_SECTION_V_LEFT = nan",
                                                      "REFERENCE_LINE_INCREMENT = -0.01", "*", "!", ""]),
                                      st.text(max_size=30).filter(lambda t: "\n" not in t and "\r" not in t)))
        elif kind == "field" and len(lines[i]) >= 20:
            j = draw(st.integers(0, len(lines[i]) // 20 - 1)) * 20
            cell = draw(st.sampled_from(["nan", "inf", "1e308", "-1e400", "*", "abc", "1" * 25, ""]))
            lines[i] = lines[i][:j] + cell.rjust(20)[:20] + lines[i][j + 20:]
        elif kind == "char" and lines[i]:
            j = draw(st.integers(0, len(lines[i]) - 1))
            char = draw(st.sampled_from(["x", "-", ".", "e", " ", "\x00", "\u00e9"]))
            lines[i] = lines[i][:j] + char + lines[i][j + 1:]
        elif kind == "truncate":
            lines = lines[:i]
        if not lines:
            break
    return ("\n".join(lines) + "\n").encode("latin-1", "replace")


def _fmu_changed(draw) -> dict:
    """One of the four FMUs mutated (file name -> bytes)."""
    tire = draw(st.sampled_from(TIRES))
    return {f"fmus/run_{tire}.fmu": draw(zip_file(command_files()[f"fmus/run_{tire}.fmu"]))}


def _maybe(draw, values, p: int = 2):
    """One of `values`, with chance 1/p; else None."""
    return draw(st.sampled_from(values)) if draw(st.integers(0, p - 1)) == 0 else None


def _floats_text(extra=()):
    return st.one_of(st.sampled_from(["nan", "inf", "-inf", "0", "-1", "1e308", "1e-320", "x", "", *extra]),
                     st.floats().map(repr))


good_pngs = st.sampled_from([None, None, "{dir}/out/p.png", "{dir}/new/sub/p.PNG"])
bad_pngs = st.sampled_from(["{dir}/out/p.jpg", "{dir}/out", "{dir}/out/.keep/p.png", "{dir}/out/" + "a" * 300 + ".png"])


def _png(draw, bad: bool) -> list[str]:
    plot = draw(bad_pngs) if bad and draw(st.integers(0, 3)) == 0 else draw(good_pngs)
    return [] if plot is None else ["--plot=" + plot]


# ----------------------------------------------------------------------------- static, comfort

@st.composite
def static_cases(draw) -> Case:
    """``static`` of a mutated compression test (or the valid one with mutated options)."""
    bad_file = draw(st.booleans())
    files = _files(**{"comp.csv": draw(csv_file("comp.csv")) if bad_file else command_files()["comp.csv"]})
    args = ["{dir}/comp.csv"]
    if draw(st.booleans()):
        args.append("--json")
    segments = _maybe(draw, ["1", "2", "5", "10", "0", "-1", "1000000", "x", "1.5"], 3)
    if segments is not None:
        args.append("--segments=" + segments)
    return Case("static", files, args + _png(draw, not bad_file))


def _static_ok(where, argv, folder, new, stdout) -> None:
    plot = _option(argv, "--plot")
    _check_written(where, folder, new, {Path(plot)} if plot else set())
    doc = _json_or_text(where, stdout, "--json" in argv)
    if doc is not None:
        k, (lo, hi) = doc["k_static_N_per_m"], doc["k_ci95_N_per_m"]
        if not all(math.isfinite(x) for x in (k, lo, hi, doc["r2"])) or not lo <= k <= hi:
            raise FuzzFailure(f"{where}: k = {k!r}, interval {lo!r} .. {hi!r}, r2 {doc['r2']!r}")


@st.composite
def comfort_cases(draw) -> Case:
    """``comfort`` of a mutated acceleration record (a rig run's CSV) or of the valid one with mutated options."""
    bad_file = draw(st.booleans())
    files = _files(**{"acc.csv": draw(csv_file("run.csv")) if bad_file else command_files()["run.csv"]})
    args = ["{dir}/acc.csv"]
    for flag in ("--json", "--bands"):
        if draw(st.booleans()):
            args.append(flag)
    weighting = _maybe(draw, ["Wk", "Wd", "Wf", "wk", "W", ""], 2)
    if weighting is not None:
        args.append("--weighting=" + weighting)
    if draw(st.integers(0, 3)) == 0:
        args.append("--axes=" + draw(st.sampled_from(["FL,FR,RL", "RR,RL,FL", "FL,FL,FR", "FL,FR", "FL,FR,XX",
                                                      "time,FL,FR", ",,", "FL,FR,RL,RR"])))
    column = _maybe(draw, ["FL", "RR", "fl", "time", "XX", ""], 3)
    if column is not None:
        args.append("--column=" + column)
    window = _maybe(draw, ["1", "0.5", "2", "0.01", "60", "0", "-1", "nan", "inf", "100", "4.9", "5", "x"], 3)
    if window is not None:
        args.append("--mtvv-window-s=" + window)
    exposure = _maybe(draw, ["8", "0.5", "24", "24.01", "0", "-1", "nan", "inf", "x", "1e-300"], 3)
    if exposure is not None:
        args.append("--exposure-h=" + exposure)
    return Case("comfort", files, args + _png(draw, not bad_file))


def _comfort_ok(where, argv, folder, new, stdout) -> None:
    plot = _option(argv, "--plot")
    _check_written(where, folder, new, {Path(plot)} if plot else set())
    doc = _json_or_text(where, stdout, "--json" in argv)
    if doc is None:
        return
    channels = doc["channels"].values() if "channels" in doc else [doc]      # every column, or --column's
    values = [doc["vector_sum_health"]] if "axes" in doc else \
        [ch[key] for ch in channels for key in ("a_w", "vdv", "mtvv")]
    if not values or not all(math.isfinite(v) and v >= 0 for v in values):
        raise FuzzFailure(f"{where}: ratings {values!r}")


# ----------------------------------------------------------------------------- ride

_GOOD_SETS = ["final", "static=5e5", "static={dir}/comp.csv", "params={dir}/params4.json", "fmu={dir}/fmus",
              "map={dir}/tire_map.json", "waveform"]
_BAD_SETS = ["static=0", "static=-1", "static=nan", "static=", "static=1e400", "static={dir}/missing.csv",
             "params={dir}/missing.json", "fmu={dir}/out", "map={dir}/diag.json", "bogus", "", ",", "final,final",
             "params={dir}/diag.json", "static={dir}/run.csv"]


@st.composite
def ride_cases(draw) -> Case:
    """``ride`` with ``--body`` (no diagnosis: the case stays cheap), one 10 s road, one or two parameter sets;
    about half the cases with one input file mutated (body, parameters, map, compression test, an FMU,
    the recording) or bad options."""
    bad = draw(st.booleans())
    changed = {}
    body = draw(st.sampled_from(["diag.json", "diag.json", "summary.json"]))
    sets = draw(st.lists(st.sampled_from(_GOOD_SETS), min_size=1, max_size=2, unique=True))
    if bad:
        target = draw(st.sampled_from(["body", "params", "map", "comp", "fmu", "rec", "road", "road", "seat",
                                       "options", "options"]))
        if target == "body":
            changed[body] = draw(json_file(body))
        elif target == "params":
            changed["params4.json"] = draw(json_file("params4.json"))
            sets = ["params={dir}/params4.json"]
        elif target == "map":
            changed["tire_map.json"] = draw(json_file("tire_map.json"))
            sets = ["map={dir}/tire_map.json"]
        elif target == "comp":
            changed["comp.csv"] = draw(csv_file("comp.csv"))
            sets = ["static={dir}/comp.csv"]
        elif target == "fmu":
            changed.update(_fmu_changed(draw))
            sets = ["fmu={dir}/fmus"]
        elif target == "rec":
            changed["run.csv"] = draw(csv_file("run.csv"))
        elif target == "road":
            road = draw(st.sampled_from(["road.csv", "road.crg"]))
            changed[road] = draw(csv_file(road) if road == "road.csv" else text_file(road))
        elif target == "seat":
            changed["seat.json"] = draw(json_file("seat.json"))
        else:
            sets = sets + [draw(st.sampled_from(_BAD_SETS))]
    files = _files("run.csv", "run.json", "diag.json", "summary.json", "params4.json", "tire_map.json",
                   "comp.csv", "fmus", "road.csv", "road.crg", "seat.json", **changed)
    args = ["{dir}/run.csv", "--body={dir}/" + body, "--compare=" + ",".join(sets), "--workers=1"]
    options = {"--duration-s": ["10", "12"], "--realisations": ["1", "1", "2"], "--road": ["A", "B", "e"],
               "--seed": ["0", "1", "7"], "--tires": ["auto", "linear", "lift-off"], "--exposure-h": ["8", "0.5", "24"],
               "--seat-y": ["0", "1.5", "-0.5"], "--seat-x-m": ["2", "0"], "--seat-height-m": ["0.9", "0", "5"],
               "--speed-kmh": ["7", "1", "12"]}
    broken = {"--duration-s": ["9.99", "3601", "0", "nan", "-10", "x"], "--realisations": ["0", "-1", "100000", "x"],
              "--road": ["F", "", "AB"], "--seed": ["-1", "x", "1.5"], "--tires": ["none"],
              "--exposure-h": ["0", "24.5", "nan"], "--seat-y": ["1.51", "nan", "inf"],
              "--seat-x-m": ["100", "-1.5", "nan", "inf"], "--seat-height-m": ["5.1", "-2", "nan"],
              "--speed-kmh": ["0.5", "61", "nan", "inf", "-7"], "--workers": ["0", "-1", "x"]}
    for option, values in options.items():
        if option == "--duration-s" or option == "--realisations" or draw(st.integers(0, 3)) == 0:
            args.append(f"{option}={draw(st.sampled_from(values))}")
    if bad and target == "options" and draw(st.booleans()):
        option = draw(st.sampled_from(sorted(broken)))
        args.append(f"{option}={draw(st.sampled_from(broken[option]))}")
    road = draw(st.sampled_from([None, None, "road.csv", "road.crg"]))
    if bad and target == "road":
        road = next(name for name in changed if name.startswith("road."))
    if road is not None:
        args.append("--road-file={dir}/" + road)
    if (bad and target == "seat") or draw(st.integers(0, 3)) == 0:
        args.append("--seat={dir}/seat.json")
    if draw(st.integers(0, 4)) == 0:
        args.append("--coherence=" + draw(st.sampled_from(["uniform", "class"] + (["none"] if bad else []))))
    if draw(st.integers(0, 4)) == 0:
        broken = ["{dir}/out/saved.txt", "{dir}/out", "{dir}/out/.keep/r.csv"] if bad else []
        args.append("--save-road=" + draw(st.sampled_from(["{dir}/out/saved.csv", "{dir}/new/saved.CRG"] + broken)))
    if draw(st.booleans()):
        args.append("--json")
    args += _png(draw, bad)
    if draw(st.integers(0, 5)) == 0:
        args.append("--ssp=" + draw(st.sampled_from(["{dir}/ssp", "{dir}/out/.keep"] if bad else ["{dir}/ssp"])))
    return Case("ride", files, args)


def _ride_ok(where, argv, folder, new, stdout) -> None:
    plot, ssp, road = _option(argv, "--plot"), _option(argv, "--ssp"), _option(argv, "--save-road")
    expected = {Path(p) for p in (plot, road) if p}
    if ssp:
        expected |= set(Path(ssp).glob("*.ssp"))
        if not any(Path(ssp).glob("*.ssp")):
            raise FuzzFailure(f"{where}: --ssp wrote no SSP")
    _check_written(where, folder, new, expected)
    doc = _json_or_text(where, stdout, "--json" in argv)
    if doc is None:
        return
    names = [n for n in _option(argv, "--compare").split(",") if n]
    if sorted(doc["sets"]) != sorted(n.replace(str(folder), "{dir}") for n in names) and \
            sorted(doc["sets"]) != sorted(names):
        raise FuzzFailure(f"{where}: sets {sorted(doc['sets'])} for --compare {names}")
    for name, entry in doc["sets"].items():
        values = [entry[key] for key in ("a_w", "vdv", "mtvv")] + list(entry["k"].values()) + list(entry["c"].values())
        if not all(math.isfinite(v) and v >= 0 for v in values):
            raise FuzzFailure(f"{where}: set {name}: {values!r}")


# ----------------------------------------------------------------------------- ssp, simulate --body, export DIAG

good_ssp = st.sampled_from(["{dir}/out/x.ssp", "{dir}/new/sub/x.SSP"])
bad_ssp = st.sampled_from(["{dir}/out/x.zip", "{dir}/out", "{dir}/out/.keep/x.ssp", "{dir}/out/" + "a" * 300 + ".ssp"])


def _body_inputs(draw, bad: bool) -> tuple[dict, list[str], str]:
    """The four FMUs, the recording and ``--body`` (diagnosis or summary); with `bad`, one of them mutated
    or missing: (files, [FMU args, REC.csv], body file name)."""
    body = draw(st.sampled_from(["diag.json", "diag.json", "summary.json"]))
    changed, fmus = {}, ["{dir}/fmus"]
    if bad:
        target = draw(st.sampled_from(["body", "body", "body", "fmu", "rec", "fmu_args"]))
        if target == "body":
            changed[body] = draw(json_file(body))
        elif target == "fmu":
            changed.update(_fmu_changed(draw))
        elif target == "rec":
            changed["run.csv"] = draw(csv_file("run.csv"))
        else:
            fmus = draw(st.sampled_from([["{dir}/out"], ["{dir}/fmus/run_FL.fmu"], ["{dir}/missing"],
                                         [f"{{dir}}/fmus/run_{t}.fmu" for t in ("FL", "FR", "RL", "FL")],
                                         ["{dir}/diag.json"]]))
    elif draw(st.booleans()):
        fmus = [f"{{dir}}/fmus/run_{t}.fmu" for t in TIRES]
    files = _files("run.csv", "run.json", "diag.json", "summary.json", "fmus", **changed)
    return files, fmus + ["{dir}/run.csv"], body


@st.composite
def ssp_cases(draw) -> Case:
    """``ssp`` of the four tire FMUs under the diagnosed body; about half with an input mutated or bad options."""
    bad = draw(st.booleans())
    files, args, body = _body_inputs(draw, bad)
    args += ["--body={dir}/" + body, "--output=" + draw(bad_ssp if bad and draw(st.booleans()) else good_ssp)]
    for option, good, broken in (("--seat-x-m", ["1", "2.5"], ["nan", "inf", "x"]),
                                 ("--seat-y", ["0", "0.5", "-1"], ["nan", "-inf", "x"]),
                                 ("--stop-s", ["1", "3"], ["0", "0.2", "-1", "nan", "1e308"])):
        if draw(st.integers(0, 3)) == 0:
            args.append(f"{option}={draw(st.sampled_from(broken if bad and draw(st.booleans()) else good))}")
    if draw(st.booleans()):
        args.append("--json")
    return Case("ssp", files, args)


def _ssp_ok(where, argv, folder, new, stdout) -> None:
    out = Path(_option(argv, "--output"))
    _check_written(where, folder, new, {out})
    with zipfile.ZipFile(out) as z:
        names = z.namelist()
    if "SystemStructure.ssd" not in names or sum(n.endswith(".fmu") for n in names) != 5:
        raise FuzzFailure(f"{where}: the SSP holds {names}")
    doc = _json_or_text(where, stdout, "--json" in argv)
    if doc is not None and not (all(math.isfinite(doc[k]) for k in ("start_s", "stop_s", "step_s"))
                                and doc["start_s"] < doc["stop_s"] and doc["step_s"] > 0):
        raise FuzzFailure(f"{where}: experiment {doc['start_s']!r} .. {doc['stop_s']!r} step {doc['step_s']!r}")


@st.composite
def simulate_body_cases(draw) -> Case:
    """``simulate FMUS REC.csv --body DOC``: the four tires under the body, the body document (or an FMU, or
    the recording) mutated in about half the cases."""
    bad = draw(st.booleans())
    files, args, body = _body_inputs(draw, bad)
    args.append("--body={dir}/" + body)
    if draw(st.booleans()):
        args.append("--json")
    return Case("simulate", files, args)


@st.composite
def export_diagnosis_cases(draw) -> Case:
    """``export DIAG.json --tire T``: a ``diagnose --json`` document as the parameter file, mutated."""
    files = _files(**{"diag.json": draw(json_file("diag.json")) if draw(st.integers(0, 4)) else
                      command_files()["diag.json"]})
    args = ["{dir}/diag.json", "--output={dir}/out/x.fmu", "--platforms=linux64"]
    tire = draw(st.sampled_from(["FL", "FL", "FL", "FL", "rr", "XX", "", None]))
    if tire is not None:
        args.append("--tire=" + tire)
    return Case("export", files, args)


# ----------------------------------------------------------------------------- map

@st.composite
def map_cases(draw) -> Case:
    """``map`` of a mutated report summary (or the valid one with mutated options); FMUs in a few cases."""
    bad_file = draw(st.booleans())
    files = _files(**{"summary.json": draw(json_file("summary.json")) if bad_file else
                      command_files()["summary.json"]})
    report = draw(st.sampled_from(["{dir}/summary.json"] * 4 + ["{dir}", "{dir}/out", "{dir}/missing.json"]))
    args = [report, "--output=" + draw(st.sampled_from(["{dir}/map", "{dir}/new/map", "{dir}/out"] +
                                                       (["{dir}/out/.keep"] if not bad_file else [])))]
    if draw(st.integers(0, 4)) or bad_file:
        args.append("--no-fmu")
    else:
        args.append("--platforms=" + draw(st.sampled_from(["linux64", "linux64", "bogus", ""])))
        if draw(st.booleans()):
            args.append("--fmi-version=" + draw(st.sampled_from(["2", "3", "1"])))
    for _ in range(draw(st.integers(0, 2))):
        args.append("--tire=" + draw(st.sampled_from(["FL", "rr", "XX", ""])))
    for option, values in (("--pressure-kpa", ["100", "0", "-1", "nan", "inf", "x"]),
                           ("--unloaded-radius-m", ["0.75", "0", "-1", "nan", "1e308", "x"])):
        value = _maybe(draw, values, 5)
        if value is not None:
            args.append(f"{option}={value}")
    if draw(st.booleans()):
        args.append("--json")
    return Case("map", files, args)


def _map_ok(where, argv, folder, new, stdout) -> None:
    out = Path(_option(argv, "--output"))
    doc = json.loads((out / "tire_map.json").read_text())
    fmus = set() if "--no-fmu" in argv else {out / f"tire_map_{t}.fmu" for t in doc["tires"]}
    _check_written(where, folder, new, {out / "tire_map.json"} | fmus)
    for fmu in fmus:
        _check_fmu(where, fmu)
    for tire, entry in doc["tires"].items():
        low, high = entry["tested_speed_m_s"]
        if not (math.isfinite(low) and math.isfinite(high) and 0 <= low <= high):
            raise FuzzFailure(f"{where}: tire {tire} tested at {low!r} .. {high!r} m/s")
    printed = _json_or_text(where, stdout, "--json" in argv)
    if printed is not None and printed["tires"].keys() != doc["tires"].keys():
        raise FuzzFailure(f"{where}: printed tires {list(printed['tires'])}, wrote {list(doc['tires'])}")


@st.composite
def seat_cases(draw) -> Case:
    """``seat [PARAMS.json]`` of a mutated seat (or the valid one, or none) with mutated options; floor records
    of 10 s (the shortest allowed) keep a case cheap."""
    kind = draw(st.sampled_from(["mutated", "mutated", "valid", "none"]))
    files = _files(**{"seat.json": draw(json_file("seat.json")) if kind == "mutated" else command_files()["seat.json"]})
    args = [] if kind == "none" else ["{dir}/seat.json"]
    bad = kind != "mutated" and draw(st.booleans())
    durations = ["9.99", "3601", "nan", "-10", "x"] if bad and draw(st.booleans()) else ["10", "10", "12"]
    args.append("--duration-s=" + draw(st.sampled_from(durations)))
    klass = draw(st.sampled_from([None, "I", "ii", "3"] + (["IV", "0", ""] if bad else [])))
    if klass is not None or kind != "none":     # (the three classes of 10 s each when no class is named)
        args.append("--class=" + (klass if klass is not None else "I"))
    if draw(st.integers(0, 3)) == 0:
        args.append("--seed=" + draw(st.sampled_from(["0", "7"] + (["-1", "x"] if bad else []))))
    if draw(st.booleans()):
        args.append("--json")
    return Case("seat", files, args)


def _seat_ok(where, argv, folder, new, stdout) -> None:
    _check_written(where, folder, new, set())
    doc = _json_or_text(where, stdout, "--json" in argv)
    if doc is None:
        return
    for row in doc["classes"]:
        values = [row[key] for key in ("floor_a_w", "seat_a_w", "seat_factor", "seat_factor_linear")]
        if not all(math.isfinite(v) and v >= 0 for v in values):
            raise FuzzFailure(f"{where}: class {row['class']}: {values!r}")


_SUCCESS.update({"static": _static_ok, "comfort": _comfort_ok, "ride": _ride_ok, "ssp": _ssp_ok, "map": _map_ok,
                 "seat": _seat_ok})

#: Every strategy of this module, by test name.
COMMAND_STRATEGIES = {"static": static_cases, "comfort": comfort_cases, "ride": ride_cases, "ssp": ssp_cases,
                      "simulate_body": simulate_body_cases, "export_diagnosis": export_diagnosis_cases,
                      "map": map_cases, "seat": seat_cases}


@settings(CI, max_examples=scaled(80))
@given(case=static_cases())
def test_static(case):
    check_case(case)


@settings(CI, max_examples=scaled(80))
@given(case=comfort_cases())
def test_comfort(case):
    check_case(case)


@settings(CI, max_examples=scaled(20))
@given(case=ride_cases())
def test_ride(case):
    check_case(case)


@settings(CI, max_examples=scaled(20))
@given(case=ssp_cases())
def test_ssp(case):
    check_case(case)


@settings(CI, max_examples=scaled(30))
@given(case=simulate_body_cases())
def test_simulate_body(case):
    check_case(case)


@settings(CI, max_examples=scaled(40))
@given(case=export_diagnosis_cases())
def test_export_diagnosis(case):
    check_case(case)


@settings(CI, max_examples=scaled(60))
@given(case=map_cases())
def test_map(case):
    check_case(case)


@settings(CI, max_examples=scaled(60))
@given(case=seat_cases())
def test_seat(case):
    check_case(case)


# ----------------------------------------------------------------------------- special files

#: (command, the file that is replaced, arguments): every file type each command reads.
_ROLES = [
    ("identify", "run.csv", ["{dir}/run.csv"]),
    ("identify", "run.json", ["{dir}/run.csv"]),
    ("diagnose", "run.csv", ["{dir}/run.csv", "--workers=1"]),
    ("diagnose", "run.json", ["{dir}/run.csv", "--workers=1"]),
    ("export", "params4.json", ["{dir}/params4.json", "--tire=FL", "--output={dir}/out/x.fmu"]),
    ("export", "diag.json", ["{dir}/diag.json", "--tire=FL", "--output={dir}/out/x.fmu"]),
    ("simulate", "fmus/run_FL.fmu", ["{dir}/fmus/run_FL.fmu", "{dir}/run.csv"]),
    ("simulate", "fmus/run_RR.fmu", ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json"]),
    ("simulate", "diag.json", ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json"]),
    ("simulate", "summary.json", ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/summary.json"]),
    ("ssp", "fmus/run_FR.fmu", ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json", "-o", "{dir}/out/x.ssp"]),
    ("ssp", "diag.json", ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json", "-o", "{dir}/out/x.ssp"]),
    ("ssp", "run.csv", ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json", "-o", "{dir}/out/x.ssp"]),
    ("ride", "diag.json", ["{dir}/run.csv", "--body={dir}/diag.json", "--duration-s=10", "--realisations=1"]),
    ("ride", "summary.json", ["{dir}/run.csv", "--body={dir}/summary.json", "--duration-s=10", "--realisations=1"]),
    ("ride", "comp.csv", ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=static={dir}/comp.csv",
                          "--duration-s=10", "--realisations=1"]),
    ("ride", "params4.json", ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=params={dir}/params4.json",
                              "--duration-s=10", "--realisations=1"]),
    ("ride", "tire_map.json", ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=map={dir}/tire_map.json",
                               "--duration-s=10", "--realisations=1"]),
    ("ride", "fmus/run_RL.fmu", ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=fmu={dir}/fmus",
                                 "--duration-s=10", "--realisations=1"]),
    ("ride", "road.csv", ["{dir}/run.csv", "--body={dir}/diag.json", "--road-file={dir}/road.csv",
                          "--duration-s=10", "--realisations=1"]),
    ("ride", "road.crg", ["{dir}/run.csv", "--body={dir}/diag.json", "--road-file={dir}/road.crg",
                          "--duration-s=10", "--realisations=1"]),
    ("ride", "seat.json", ["{dir}/run.csv", "--body={dir}/diag.json", "--seat={dir}/seat.json",
                           "--duration-s=10", "--realisations=1"]),
    ("seat", "seat.json", ["{dir}/seat.json", "--duration-s=10"]),
    ("static", "comp.csv", ["{dir}/comp.csv"]),
    ("comfort", "run.csv", ["{dir}/run.csv"]),
    ("map", "summary.json", ["{dir}/summary.json", "-o", "{dir}/map"]),
    ("report", "run.csv", ["{dir}/run.csv", "-o", "{dir}/rep", "--workers=1"]),
    ("report", "run.json", ["{dir}/run.csv", "-o", "{dir}/rep", "--workers=1"]),
    ("report", "comp.csv", ["{dir}/run.csv", "-o", "{dir}/rep", "--workers=1", "--static={dir}/comp.csv"]),
]


@pytest.mark.parametrize("kind", Special.KINDS)
@pytest.mark.parametrize("command,role,args", _ROLES, ids=[f"{c}-{r}" for c, r, _ in _ROLES])
def test_special_file_in_place_of_an_input(command, role, args, kind):
    """A FIFO, /dev/zero, a folder, a dangling symlink or an unreadable file where a command expects one of
    its inputs: one line, exit 2, within seconds (a FIFO opened for reading would wait for ever, /dev/zero
    read to its end fills memory)."""
    files = _files("run.csv", "run.json", "diag.json", "summary.json", "params4.json", "tire_map.json", "comp.csv",
                   "fmus", "road.csv", "road.crg", "seat.json", **{role: Special(kind)})

    def hung(signum, frame):
        raise FuzzFailure(f"{command} with {role} a {kind}: no answer within 60 s")

    previous = signal.signal(signal.SIGALRM, hung)
    signal.alarm(60)
    try:
        outcome = check_case(Case(command, files, args))
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    assert outcome == "error", f"{command} read a {kind} as {role} and succeeded"


# ----------------------------------------------------------------------------- stdout failures and a full disk

#: A valid command line of every command that prints (and, with ``writes``, the files it writes).
_COMMANDS = {
    "identify": (["identify", "{dir}/run.csv"], False),
    "export": (["export", "{dir}/params4.json", "--tire=FL", "-o", "{dir}/out/x.fmu", "--platforms=linux64"], True),
    "diagnose": (["diagnose", "{dir}/run.csv", "--workers=1", "--tire=FL", "--fmu-dir={dir}/out/fmus"], True),
    "simulate": (["simulate", "{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json"], False),
    "rig": (["rig", "-o", "{dir}/out/r", "--param=duration_s=1.5", "--param=sensor.rate_hz=200",
             "--param=sensor.channels=FL"], True),
    "static": (["static", "{dir}/comp.csv", "--plot={dir}/out/s.png"], True),
    "comfort": (["comfort", "{dir}/run.csv", "--bands", "--plot={dir}/out/c.png"], True),
    "ride": (["ride", "{dir}/run.csv", "--body={dir}/diag.json", "--duration-s=10", "--realisations=1",
              "--compare=final", "--workers=1", "--plot={dir}/out/r.png", "--save-road={dir}/out/road.csv"], True),
    "ssp": (["ssp", "{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json", "-o", "{dir}/out/x.ssp"], True),
    "map": (["map", "{dir}/summary.json", "-o", "{dir}/out/map", "--platforms=linux64"], True),
    "seat": (["seat", "{dir}/seat.json", "--duration-s=10", "--class=I"], False),
}
#: The costly commands' stdout and disk cases run in CI's fuzz step (CLEATFMU_FUZZ_SCALE >= 2), not by default.
_COSTLY = {"diagnose", "ride", "ssp", "simulate"}
_MODES = ["dev_full", "closed", "closed_pipe", "file_size"]


def _subprocess_case(command: str, mode: str, folder: Path):
    """Run `command`'s valid line in `folder` (its inputs written there) with stdout broken as `mode`."""
    argv, _ = _COMMANDS[command]
    inputs = _files("run.csv", "run.json", "diag.json", "summary.json", "params4.json", "comp.csv", "fmus",
                    "seat.json")
    del inputs["out/.keep"]
    for name, data in inputs.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(data)
    tmp = folder / "tmp"
    tmp.mkdir()
    line = [sys.executable, "-m", "identification.cli"] + [a.replace("{dir}", str(folder)) for a in argv]
    env = dict(os.environ, TMPDIR=str(tmp), PYTHONDONTWRITEBYTECODE="1")
    if mode == "dev_full":
        return subprocess.run(["bash", "-c", shlex.join(line) + " > /dev/full"], capture_output=True, text=True,
                              timeout=300, cwd=ROOT, env=env)
    if mode == "closed":
        return subprocess.run(["bash", "-c", shlex.join(line) + " >&-"], capture_output=True, text=True,
                              timeout=300, cwd=ROOT, env=env)
    if mode == "closed_pipe":
        read, write = os.pipe()
        os.close(read)
        try:
            return subprocess.run(line, stdout=write, stderr=subprocess.PIPE, text=True, timeout=300, cwd=ROOT,
                                  env=env)
        finally:
            os.close(write)

    def small_files():       # a full disk: no file may grow beyond 4 kB (EFBIG; Python ignores SIGXFSZ)
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

    return subprocess.run(line, capture_output=True, text=True, timeout=300, cwd=ROOT, env=env,
                          preexec_fn=small_files)


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full here")
@pytest.mark.parametrize("command,mode", [(c, m) for c in sorted(_COMMANDS) for m in _MODES
                                          if m != "file_size" or _COMMANDS[c][1]])   # a full disk: writers only
def test_stdout_that_fails_or_a_full_disk(command, mode, tmp_path):
    """stdout to /dev/full, stdout closed, a pipe closed by its reader, and a 4 kB file-size limit: exit 2 and
    one line (141 and nothing for the closed pipe, as documented), no file written, no temporary file left."""
    if command in _COSTLY and mode != "closed" and float(os.environ.get("CLEATFMU_FUZZ_SCALE", "1")) < 2:
        pytest.skip("run in CI's fuzz step (CLEATFMU_FUZZ_SCALE >= 2)")
    folder = tmp_path / "case"
    folder.mkdir()
    (folder / "out").mkdir()
    done = _subprocess_case(command, mode, folder)
    import test_fuzz

    test_fuzz.CASES[0] += 1
    where = f"{command} ({mode})"
    assert "Traceback" not in done.stderr, f"{where}: {done.stderr}"
    if mode == "closed_pipe":
        assert (done.returncode, done.stderr) == (141, ""), f"{where}: {done.returncode} {done.stderr!r}"
    else:
        lines = done.stderr.splitlines()
        expected = {"dev_full": "cleatfmu: error: stdout: cannot write: No space left on device",
                    "closed": "cleatfmu: error: stdout: closed (the result would be lost)",
                    "file_size": f"cleatfmu: error: {folder}/"}[mode]
        assert done.returncode == 2 and len(lines) == 1 and lines[0].startswith(expected), \
            f"{where}: exit {done.returncode}, stderr {done.stderr!r}"
        if mode == "file_size":
            assert "File too large" in lines[0], f"{where}: {lines[0]!r}"
    written = sorted(str(p.relative_to(folder)) for p in (folder / "out").rglob("*"))
    assert written == [] and list((folder / "tmp").iterdir()) == [], f"{where}: left {written}"
