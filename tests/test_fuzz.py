"""Property-based fuzzing of the command-line input handling (Hypothesis).

Every generated input must end in one of two ways:

* a valid result: exit status 0, nothing on stderr, and for ``identify
  --json`` a parseable document whose k and c are finite numbers (k > 0,
  c >= 0); for ``export`` the FMU file (and the missing folders of its path)
  and nothing else; for ``diagnose`` finite k and c and exactly the files
  asked for (``--plot``, ``--fmu``, ``--fmu-dir``); for ``simulate`` a finite
  NRMSE and the plot asked for; for ``rig`` the three files it prints, the
  recording readable;
* a user error: exit status 2, stderr exactly one line
  ``cleatfmu: error: <file or option>: <problem>``, and no file written.

Never a traceback and never a leftover file (temporary ``.tmp``/``.part``
staging files included).  The strategies start from a small valid recording
of the virtual rig (and its point-contact FMU) and mutate it (CSV cells,
header, time column, sidecar keys, identified parameters, FMU bytes,
command-line options of ``identify``, ``export``, ``diagnose``, ``simulate``
and ``rig``).  ``diagnose`` runs with one worker and ``rig`` from a short,
low-rate run, so that a case costs a fraction of a second.

The default run is bounded (a few hundred cases, seconds); ``CLEATFMU_FUZZ_SCALE=N``
multiplies every strategy's number of cases (CI's fuzz step), and a larger run
with the same strategies is ``benchmarks/fuzz_large.py``.  The other commands
and file types are fuzzed by ``tests/test_fuzz_commands.py`` with this
module's property (:func:`check_case`).
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import math
import os
import sys
import tempfile
import traceback
import warnings
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import pytest

pytestmark = pytest.mark.fuzz   # its own CI step (pytest -m fuzz), left out of the default run

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

__all__ = ["FuzzFailure", "Case", "Special", "scaled", "CASES",
           "recording_cases", "sidecar_cases", "identify_option_cases",
           "params_cases", "export_option_cases", "diagnose_cases", "simulate_cases", "rig_cases", "ALL_STRATEGIES",
           "check_case"]

#: Cases run by :func:`check_case` in this process (``tests/conftest.py`` adds them up per test).
CASES = [0]


def scaled(examples: int) -> int:
    """`examples` times ``CLEATFMU_FUZZ_SCALE`` (a positive number, default 1): CI's fuzz step runs more cases."""
    text = os.environ.get("CLEATFMU_FUZZ_SCALE", "1")
    try:
        factor = float(text)
    except ValueError:
        raise ValueError(f"CLEATFMU_FUZZ_SCALE must be a number, got {text!r}") from None
    if not (math.isfinite(factor) and factor > 0):
        raise ValueError(f"CLEATFMU_FUZZ_SCALE must be > 0, got {text!r}")
    return max(1, round(examples * factor))


# ----------------------------------------------------------------------------- valid starting points


@functools.lru_cache(maxsize=1)
def base_files() -> dict[str, bytes]:
    """The valid inputs every case mutates: ``csv``, ``json`` (sidecar), ``params`` (identify --json) and ``fmu``
    (its native point-contact FMU, linux64)."""
    from identification.cli import main
    from identification.rig import run_rig
    from identification.rig.generate import write_run

    run = run_rig((), {"sensor.channels": "FL", "sensor.rate_hz": 500.0}, seed=1)
    with tempfile.TemporaryDirectory() as work:
        csv, _ = write_run(run, Path(work, "base"))
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            status = main(["identify", str(csv), "--json", "--method", "waveform"])
        assert status == 0
        params = json.loads(out.getvalue())
        params["recording"] = "base.csv"
        params_path, fmu = Path(work, "params.json"), Path(work, "FL.fmu")
        params_path.write_text(json.dumps(params), encoding="utf-8")
        with contextlib.redirect_stdout(io.StringIO()):  # the point-contact FMU that simulate cases run
            status = main(["export", str(params_path), "-o", str(fmu), "--platforms", "linux64"])
        assert status == 0
        return {"csv": csv.read_bytes(), "json": Path(work, "base.json").read_bytes(),
                "params": json.dumps(params, indent=2).encode(), "fmu": fmu.read_bytes()}


# ----------------------------------------------------------------------------- a case


@dataclass
class Case:
    """One generated command line and the files it reads.

    Attributes
    ----------
    command : str
        ``identify`` or ``export``.
    files : dict of str to bytes
        File name (relative to the case folder) -> content.
    args : list of str
        Arguments after the command; ``{dir}`` is replaced by the case folder.
    """

    command: str
    files: dict[str, bytes]
    args: list[str] = field(default_factory=list)

    def __repr__(self) -> str:  # the base files are long: show only what differs from them
        base = {"rec.csv": "csv", "rec.json": "json", "params.json": "params"}
        shown = {}
        for name, data in self.files.items():
            original = base_files().get(base.get(name, ""))
            if data == original:
                shown[name] = "<valid>"
                continue
            start = 0
            if original is not None:
                while start < min(len(data), len(original)) and data[start] == original[start]:
                    start += 1
                start = max(0, start - 40)
            shown[name] = f"<{len(data)} bytes, from byte {start}: {data[start:start + 160]!r}>"
        return f"Case({self.command!r}, files={shown}, args={self.args!r})"

    def _repr_pretty_(self, printer, cycle) -> None:  # Hypothesis prints failing cases with this
        printer.text(repr(self))

    def argv(self, folder: Path) -> list[str]:
        """The full argument list, in `folder`."""
        return [self.command] + [a.replace("{dir}", str(folder)) for a in self.args]


class Special(str):
    """A file of a case that is no regular file: ``fifo``, ``dev_zero`` (a symlink to /dev/zero), ``dir`` (an
    empty folder), ``dangling`` (a symlink to nothing), ``unreadable`` (mode 000; readable anyway by root)."""

    KINDS = ("fifo", "dev_zero", "dir", "dangling", "unreadable")

    def make(self, path: Path) -> None:
        if self == "fifo":
            os.mkfifo(path)
        elif self == "dev_zero":
            path.symlink_to("/dev/zero")
        elif self == "dir":
            path.mkdir()
        elif self == "dangling":
            path.symlink_to(path.parent / "nothing-here")
        elif self == "unreadable":
            path.write_bytes(b"time,FL\n")
            path.chmod(0)
        else:
            raise ValueError(f"unknown special file {self!r}")


class FuzzFailure(AssertionError):
    """A generated case broke the contract (traceback, wrong exit status, bad message, leftover file)."""


class _Raw(str):
    """A JSON number written verbatim (e.g. an integer of 5000 digits, beyond ``json.dumps``)."""


def dumps_raw(value) -> bytes:
    """`value` as JSON text; :class:`_Raw` strings become bare number literals."""
    raws: list[str] = []

    def swap(v):
        if isinstance(v, _Raw):
            raws.append(str(v))
            return f"\x00RAW{len(raws) - 1}\x00"
        if isinstance(v, dict):
            return {k: swap(x) for k, x in v.items()}
        if isinstance(v, list):
            return [swap(x) for x in v]
        return v

    text = json.dumps(swap(value), indent=1)  # NaN and Infinity are written as Python's json writes them
    for i, raw in enumerate(raws):
        text = text.replace(json.dumps(f"\x00RAW{i}\x00"), raw)
    return text.encode("utf-8")


# ----------------------------------------------------------------------------- strategies: values

#: Cells that are no plain decimal number, or are extreme ones.
BAD_CELLS = ["", " ", "abc", "nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1e309", "-1e309", "1e307",
             "-1e307", "1e-320", "0x10", "1_000", "1,5", "1;5", "+", "-", ".", "1e", "--1", "\t", "\"1\"",
             "\u00e9", "\u2212" "1", "0", "-0", "1" * 400, "9" * 5000]

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 0.0, -0.0, 1e-320, 5e-324, 1e-300, 1e307, 1e308, -1e308, 10 ** 30, 2 ** 63, -2 ** 63]),
    st.integers(min_value=-10 ** 20, max_value=10 ** 20),
)
#: JSON integers longer than Python's default int/str conversion limit (4300 digits) and other huge literals.
huge_literals = st.one_of(
    st.integers(min_value=4290, max_value=6000).map(lambda n: _Raw("9" * n)),
    st.integers(min_value=4290, max_value=6000).map(lambda n: _Raw("-" + "1" * n)),
    st.sampled_from([_Raw("1e400"), _Raw("-1e400"), _Raw("1" * 400), _Raw("1" * 400 + ".5"), _Raw("1e-400")]),
)
json_scalars = st.one_of(st.none(), st.booleans(), st.text(max_size=8), numbers, huge_literals)
json_values = st.recursive(json_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=5), inner, max_size=3)), max_leaves=6)
garbage = st.one_of(st.binary(max_size=200), st.text(max_size=200).map(lambda s: s.encode("utf-8")),
                    st.sampled_from([b"", b"\n", b"\xff\xfe\x00", b"\x00" * 50, b"\xef\xbb\xbf", b"{", b"[]",
                                     b"null", b"1", b'"x"']))


# ----------------------------------------------------------------------------- strategies: CSV


def _csv_lines() -> list[str]:
    return base_files()["csv"].decode().splitlines()


@st.composite
def csv_mutation(draw, lines: list[str]) -> list[str]:
    """One mutation of the CSV (as a list of lines)."""
    n = len(lines)
    kind = draw(st.sampled_from(["cell", "cell", "header", "swap", "duplicate", "delete", "truncate",
                                 "scale_time", "scale_accel", "shift_time", "append", "extra_column",
                                 "short_row", "blank_lines", "separator"]))
    lines = list(lines)
    if kind == "cell":
        row = draw(st.integers(1, n - 1))
        col = draw(st.integers(0, lines[row].count(",")))
        cells = lines[row].split(",")
        cells[col] = draw(st.one_of(st.sampled_from(BAD_CELLS), st.floats().map(repr),
                                    st.text(max_size=6).filter(lambda s: "\n" not in s and "\r" not in s)))
        lines[row] = ",".join(cells)
    elif kind == "header":
        lines[0] = draw(st.one_of(
            st.sampled_from(["", "time", "Time,FL", "time,fl", "time,FL,FL", "time,XX", "time;FL", "FL,time",
                             "time,FL,FR", "time,", ",FL", " time , FL ", "time,FL,RR", "\ufefftime,FL",
                             "time,FL,FR,RL,RR,FL"]),
            st.text(max_size=20).filter(lambda s: "\n" not in s and "\r" not in s)))
    elif kind == "swap":
        i = draw(st.integers(1, n - 2))
        lines[i], lines[i + 1] = lines[i + 1], lines[i]
    elif kind == "duplicate":
        i = draw(st.integers(1, n - 1))
        lines.insert(i, lines[i])
    elif kind == "delete":
        i = draw(st.integers(1, n - 1))
        del lines[i]
    elif kind == "truncate":
        lines = lines[:draw(st.integers(0, n))]
    elif kind in ("scale_time", "scale_accel", "shift_time"):
        factor = draw(st.one_of(st.sampled_from([0.0, -1.0, 1e-300, 1e-12, 1e-3, 1e3, 1e12, 1e300, 1e307, 1e308]),
                                st.floats(min_value=-1e308, max_value=1e308)))
        col = 0 if kind != "scale_accel" else 1
        out = [lines[0]]
        for ln in lines[1:]:
            cells = ln.split(",")
            try:
                v = float(cells[col])
                v = v + factor if kind == "shift_time" else v * factor
                cells[col] = repr(v)
            except (ValueError, IndexError):
                pass
            out.append(",".join(cells))
        lines = out
    elif kind == "append":
        lines.append(draw(st.text(max_size=30).filter(lambda s: "\n" not in s and "\r" not in s)))
    elif kind == "extra_column":
        lines = [ln + ",0" for ln in lines]
    elif kind == "short_row":
        i = draw(st.integers(1, n - 1))
        lines[i] = lines[i].split(",")[0]
    elif kind == "blank_lines":
        i = draw(st.integers(1, n - 1))
        lines.insert(i, draw(st.sampled_from(["", " ", "\t", ","])))
    elif kind == "separator":
        lines = [ln.replace(",", draw(st.sampled_from([";", "\t", ", ", " ,"]))) for ln in lines]
    return lines


def mutated_csv(draw, lines: list[str]) -> bytes:
    """`lines` (a valid CSV) with 1-3 line mutations (cells, header, rows, time, separators) and a drawn line
    end, or garbage (for a ``@st.composite`` strategy's `draw`)."""
    if draw(st.integers(0, 9)) == 0:
        return draw(garbage)
    for _ in range(draw(st.integers(1, 3))):
        if len(lines) < 3:
            break
        lines = draw(csv_mutation(lines))
    end = draw(st.sampled_from(["\n", "\r\n", ""]))
    return (end or "\n").join(lines).encode("utf-8") + end.encode()


@st.composite
def csv_contents(draw) -> bytes:
    """The base CSV with 1-3 mutations, or garbage."""
    return mutated_csv(draw, _csv_lines())


# ----------------------------------------------------------------------------- strategies: sidecar

_SIDECAR_KEYS = ["format", "speed_kmh", "cleat_height_mm", "cleat_width_mm", "wheelbase_m", "wheel_load_kN",
                 "description", "acquisition"]
_ACQ_KEYS = ["anti_alias_order", "anti_alias_cutoff_hz", "highpass_hz"]


@st.composite
def sidecar_contents(draw) -> bytes:
    """The base sidecar with 1-3 key mutations (missing, extra, wrong type, extreme value), or garbage."""
    if draw(st.integers(0, 9)) == 0:
        return draw(garbage)
    meta = json.loads(base_files()["json"])
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["delete", "set", "set", "extra", "load", "load", "acquisition",
                                     "acquisition", "scale"]))
        if kind == "delete" and meta:
            del meta[draw(st.sampled_from(sorted(meta)))]
        elif kind == "set":
            meta[draw(st.sampled_from(_SIDECAR_KEYS))] = draw(json_values)
        elif kind == "extra":
            meta[draw(st.text(max_size=10))] = draw(json_values)
        elif kind == "load":
            loads = meta.get("wheel_load_kN")
            loads = dict(loads) if isinstance(loads, dict) else {}
            loads[draw(st.sampled_from(["FL", "FR", "XX", "", "fl"]))] = draw(json_values)
            if draw(st.booleans()) and "FL" in loads:
                del loads["FL"]
            meta["wheel_load_kN"] = loads
        elif kind == "acquisition":
            acq = meta.get("acquisition")
            acq = dict(acq) if isinstance(acq, dict) else {}
            acq[draw(st.sampled_from(_ACQ_KEYS + ["bogus"]))] = draw(st.one_of(
                json_values, st.integers(-3, 20), st.sampled_from([0.0, 124.9, 125.0, 249.99, 250.0, 1e308]),
                st.floats(min_value=0, max_value=1e4)))
            meta["acquisition"] = acq
        else:  # scale: absurd but positive physical values
            key = draw(st.sampled_from(_SIDECAR_KEYS[1:5]))
            meta[key] = draw(st.one_of(st.sampled_from([1e-300, 5e-324, 1e-9, 1e6, 1e300, 1e308, 1, 10 ** 30]),
                                       st.floats(min_value=1e-300, max_value=1e308)))
    return dumps_raw(meta)


# ----------------------------------------------------------------------------- strategies: options

cutoffs = st.one_of(
    st.sampled_from(["0", "-1", "-0.0", "nan", "-nan", "inf", "-inf", "1e308", "1e-320", "5e-324", "249.99",
                     "250", "1000", "1e400", "100", "60", "20", "0.5"]),
    st.floats().map(repr))
tire_options = st.sampled_from([None, "FL", "FR", "RR", "XX", "fl", "FL,FR", "FL FL", "FL,XX"])


def _identify_args(draw, csv_name: str = "rec.csv") -> list[str]:
    args = ["{dir}/" + csv_name]
    args += ["--method=" + draw(st.sampled_from(["paper", "waveform"]))]
    if draw(st.booleans()):
        args.append("--json")
    return args


def _option_args(draw) -> list[str]:
    args = []
    if draw(st.booleans()):
        args.append("--cutoff-hz=" + draw(cutoffs))
    tire = draw(tire_options)
    if tire is not None:
        args.append("--tire=" + tire)
    return args


@st.composite
def recording_cases(draw) -> Case:
    """``identify`` of a recording with a mutated CSV."""
    return Case("identify", {"rec.csv": draw(csv_contents()), "rec.json": base_files()["json"]},
                _identify_args(draw) + (["--json"] if draw(st.booleans()) else []))


@st.composite
def sidecar_cases(draw) -> Case:
    """``identify`` of a recording with a mutated sidecar."""
    files = {"rec.csv": base_files()["csv"], "rec.json": draw(sidecar_contents())}
    if draw(st.integers(0, 19)) == 0:
        del files["rec.json"]
    return Case("identify", files, _identify_args(draw))


@st.composite
def identify_option_cases(draw) -> Case:
    """``identify`` of the valid recording with mutated options (cut-off, tire, method)."""
    files = {"rec.csv": base_files()["csv"], "rec.json": base_files()["json"]}
    name = draw(st.sampled_from(["rec.csv", "rec.csv", "missing.csv", "rec.json", "rec.CSV", "."]))
    return Case("identify", files, _identify_args(draw, name) + _option_args(draw))


# ----------------------------------------------------------------------------- strategies: export

_ENTRY_KEYS = ["k", "c", "T", "delta", "zeta", "omega_n", "r2", "n_peaks", "mass", "k_ci", "c_ci"]
physical = st.one_of(
    numbers, huge_literals, st.sampled_from(["1e5", "NaN", "nan", "inf", "", "abc", None, True, [], {}, [1, 2]]))


@st.composite
def params_contents(draw) -> bytes:
    """The base ``identify --json`` document with 1-3 mutations of k, c, mass, ... or of its structure."""
    if draw(st.integers(0, 14)) == 0:
        return draw(garbage)
    doc = json.loads(base_files()["params"])
    entry = doc["tires"]["FL"]
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["k", "c", "k", "c", "mass", "entry", "ci", "delete", "doc", "tires"]))
        if kind in ("k", "c", "mass"):
            entry[kind] = draw(physical)
        elif kind == "entry":
            entry[draw(st.sampled_from(_ENTRY_KEYS))] = draw(physical)
        elif kind == "ci":
            entry[draw(st.sampled_from(["k_ci", "c_ci"]))] = draw(st.one_of(
                st.lists(physical, max_size=3), json_values))
        elif kind == "delete" and entry:
            del entry[draw(st.sampled_from(sorted(entry)))]
        elif kind == "doc":
            doc[draw(st.sampled_from(["recording", "speed_kmh", "tires", "extra"]))] = draw(json_values)
        else:
            doc["tires"] = draw(st.one_of(
                st.just({}), st.just({"FL": entry, "FR": dict(entry)}), st.just({"XX": entry}),
                st.just({"FL": entry})))
    return dumps_raw(doc)


outputs = st.sampled_from([None, "{dir}/out/FL.fmu", "{dir}/out/FL.fmu", "{dir}/missing/FL.fmu", "{dir}/out",
                           "{dir}/out/FL.zip", "{dir}/out/.fmu", "{dir}/out/FL.FMU", "{dir}/out/sub.fmu"])
radii = st.one_of(st.none(), st.sampled_from(["0", "-1", "nan", "inf", "-inf", "1e308", "5e-324", "0.75", "1e-300",
                                              "1e400"]), st.floats().map(repr))


def _export_args(draw, params_name: str = "params.json") -> list[str]:
    args = ["{dir}/" + params_name]
    out = draw(outputs)
    # without -o the FMU would land in the working folder; the case always names one
    args.append("--output=" + (out or "{dir}/out/FL.fmu"))
    tire = draw(st.sampled_from([None, None, "FL", "FR", "XX", ""]))
    if tire is not None:
        args.append("--tire=" + tire)
    radius = draw(radii)
    if radius is not None:
        args.append("--unloaded-radius-m=" + radius)
    return args


@st.composite
def params_cases(draw) -> Case:
    """``export`` of a mutated parameter file."""
    args = _export_args(draw)
    return Case("export", {"params.json": draw(params_contents()), "out/.keep": b""}, args)


@st.composite
def export_option_cases(draw) -> Case:
    """``export`` of the valid parameter file with mutated options (backend, FMI version, platforms)."""
    args = _export_args(draw, draw(st.sampled_from(["params.json", "params.json", "missing.json", "out"])))
    backend = draw(st.sampled_from([None, "native", "native", "bogus", ""]))
    if backend is not None:
        args.append("--backend=" + backend)
    version = draw(st.sampled_from([None, "2", "3", "1", "0", "-2", "4"]))
    if version is not None:
        args.append("--fmi-version=" + version)
    platforms = draw(st.sampled_from([None, "linux64", "win64,darwin64", "x86_64-linux", "bogus", "", ",",
                                      "linux64,linux64"]))
    if platforms is not None:
        args.append("--platforms=" + platforms)
    return Case("export", {"params.json": base_files()["params"], "out/.keep": b""}, args)



# ----------------------------------------------------------------------------- strategies: diagnose

def _recording_files(draw) -> dict[str, bytes]:
    """The base recording, mostly valid; else its CSV or its sidecar mutated (those end early, in reading)."""
    kind = draw(st.sampled_from(["valid", "valid", "valid", "csv", "sidecar"]))
    csv = draw(csv_contents()) if kind == "csv" else base_files()["csv"]
    meta = draw(sidecar_contents()) if kind == "sidecar" else base_files()["json"]
    return {"rec.csv": csv, "rec.json": meta}


workers = st.sampled_from(["0", "-1", "2", "65", "1000000", "x", "1.5", ""])
plots = st.sampled_from(["{dir}/out/d.jpg", "{dir}/out", "{dir}/out/.keep/d.png"])
fmus = st.sampled_from(["{dir}/out/x.zip", "{dir}/out", "{dir}/out/.keep/x.fmu"])
fmu_dirs = st.sampled_from(["{dir}/out/.keep", "{dir}/out"])
good_plots = st.sampled_from([None, None, None, "{dir}/out/d.png", "{dir}/new/sub/d.PNG"])
good_fmus = st.sampled_from([None, None, None, "{dir}/out/x.fmu"])
good_fmu_dirs = st.sampled_from([None, None, None, None, "{dir}/fmus", "{dir}/new/fmus"])


@st.composite
def diagnose_cases(draw) -> Case:
    """``diagnose`` of the base recording (or a mutated one) with cheap options: one worker (a pool per case would
    cost a second), the tire, the cut-off, the output paths; about half the cases valid, the others with one
    or more bad options."""
    files = dict(_recording_files(draw), **{"out/.keep": b""})
    bad = draw(st.booleans())
    args = [draw(st.sampled_from(["{dir}/missing.csv", "{dir}/rec.json"])) if bad and draw(st.integers(0, 4)) == 0
            else "{dir}/rec.csv"]
    args.append("--workers=" + (draw(workers) if bad and draw(st.integers(0, 3)) == 0 else "1"))
    for flag in ("--json", "-v"):
        if draw(st.booleans()):
            args.append(flag)
    if bad and draw(st.integers(0, 2)) == 0:
        args.append("--cutoff-hz=" + draw(cutoffs))
    tire = draw(st.sampled_from([None, "FL", "fl", "RR", "XX"] if bad else [None, "FL", "fl"]))
    if tire is not None:
        args.append("--tire=" + tire)
    for option, good, broken in (("--plot", good_plots, plots), ("--fmu", good_fmus, fmus),
                                 ("--fmu-dir", good_fmu_dirs, fmu_dirs)):
        value = draw(broken) if bad and draw(st.integers(0, 3)) == 0 else draw(good)
        if value is not None:
            args.append(f"{option}={value}")
    return Case("diagnose", files, args)


# ----------------------------------------------------------------------------- strategies: simulate

steps = st.one_of(st.none(), st.none(), st.sampled_from(["0", "-1e-3", "nan", "inf", "1e-12", "1e-6", "9e-6", "5e-4",
                                                        "0.005", "0.01", "0.02", "1", "1e308", "abc"]))
fmu_contents = st.one_of(st.sampled_from([b"", b"PK\x05\x06" + b"\x00" * 18, b"not a zip"]), st.binary(max_size=64))


@st.composite
def simulate_cases(draw) -> Case:
    """``simulate FMU REC.csv`` of the base FMU (or a broken one) over the base recording (or a mutated one); about
    half the cases with valid options, the others with one or more bad ones."""
    files = dict(_recording_files(draw), **{"out/.keep": b""})
    bad = draw(st.booleans())
    fmu_kind = draw(st.sampled_from(["bytes", "missing", "csv", "dir"])) if bad and draw(st.integers(0, 3)) == 0 \
        else "valid"
    fmu = {"valid": "{dir}/FL.fmu", "bytes": "{dir}/FL.fmu", "missing": "{dir}/nope.fmu", "csv": "{dir}/rec.csv",
           "dir": "{dir}/out"}[fmu_kind]
    files["FL.fmu"] = draw(fmu_contents) if fmu_kind == "bytes" else base_files()["fmu"]
    args = [fmu, "{dir}/rec.csv"]
    if draw(st.booleans()):
        args.append("--json")
    step = draw(steps) if bad else draw(st.sampled_from([None, None, "5e-4", "4e-3"]))
    if step is not None:
        args.append("--max-step-s=" + step)
    if bad and draw(st.integers(0, 2)) == 0:
        args.append("--cutoff-hz=" + draw(cutoffs))
    method = draw(st.sampled_from([None, "paper", "waveform"] + (["bogus"] if bad else [])))
    if method is not None:
        args.append("--method=" + method)
    tire = draw(st.sampled_from([None, "FL", "fl"] + (["RR", "XX"] if bad else [])))
    if tire is not None:
        args.append("--tire=" + tire)
    plot = draw(plots) if bad and draw(st.integers(0, 3)) == 0 else draw(good_plots)
    if plot is not None:
        args.append("--plot=" + plot)
    if bad and draw(st.integers(0, 9)) == 0:
        args.append("--body={dir}/rec.json")
    return Case("simulate", files, args)


# ----------------------------------------------------------------------------- strategies: rig

#: Values for any ``--param``: outside every range, at its edges, no number at all.
_PARAM_VALUES = ["0", "-1", "1e-300", "1e308", "nan", "inf", "", "abc", "1e400", "0.5", "2", "FL", "FL,XX", "1,2"]
#: Plausible values that keep a rig run short (the run is the case's cost).
_CHEAP = {"duration_s": ["1.2", "1.5", "2"], "sensor.rate_hz": ["50", "100", "200", "250"], "t0_s": ["0.2", "0.3"]}


@st.composite
def rig_param(draw) -> str:
    """One ``--param KEY=VALUE``: a known key with an edge value, a plausible one, or a broken assignment."""
    from identification.rig.params import PARAMS

    keys = sorted(PARAMS)
    kind = draw(st.sampled_from(["edge", "edge", "scaled", "broken", "unknown"]))
    key = draw(st.sampled_from(keys))
    if kind == "broken":
        return draw(st.sampled_from(["", "=", "=1", "speed_kmh", "speed_kmh==7", "tire.fl.k_N_m=5e5",
                                     "sensor.channels=fl,rr", "tire..k_N_m=1"]))
    if kind == "unknown":
        return draw(st.text(max_size=12).filter(lambda s: "=" not in s)) + "=1"
    if key in _CHEAP:
        return f"{key}={draw(st.sampled_from(_CHEAP[key] + _PARAM_VALUES[:6]))}"
    if kind == "edge":
        return f"{key}={draw(st.sampled_from(_PARAM_VALUES))}"
    default = PARAMS[key].default
    if isinstance(default, str):
        return f"{key}={draw(st.sampled_from(['FL', 'RR', 'FL,FR,RL,RR', 'FR,FR', '']))}"
    return f"{key}={default * draw(st.sampled_from([0.0, 0.5, 0.9, 1.1, 2.0, 10.0, -1.0, 1e3])):g}"


@st.composite
def rig_cases(draw) -> Case:
    """``rig`` with mutated options; every case starts from a short, low-rate, one-channel run (cheap)."""
    args = ["--param=duration_s=1.5", "--param=sensor.rate_hz=200", "--param=sensor.channels=FL"]
    for _ in range(draw(st.integers(0, 3))):
        args.append("--param=" + draw(rig_param()))
    if draw(st.integers(0, 3)) == 0:
        args.append("--speed=" + draw(st.sampled_from(["7", "10", "0", "-7", "0.3", "70", "nan", "inf", "x"])))
    if draw(st.integers(0, 3)) == 0:
        args.append("--effect=" + draw(st.sampled_from(["enveloping", "lift_off,axle_coupling", "none", "wobble",
                                                       "", ",", "enveloping,enveloping", "friction_damping"])))
    if draw(st.integers(0, 4)) == 0:
        args.append("--seed=" + draw(st.sampled_from(["0", "-1", "2", str(2 ** 70), "x", "1.5"])))
    if draw(st.integers(0, 4)) == 0:
        args.append("--decimals=" + draw(st.sampled_from(["1", "2", "9", "10", "-1", "x"])))
    out = draw(st.sampled_from(["{dir}/out/r", "{dir}/out/r", "{dir}/new/sub/r", "{dir}/out", "{dir}/out/.keep/r",
                                "{dir}/out/r.csv"]))
    args.append("--output=" + out)
    return Case("rig", {"out/.keep": b""}, args)


#: Every strategy, by test name (the benchmark runs them all).
ALL_STRATEGIES = {"recording": recording_cases, "sidecar": sidecar_cases, "identify_options": identify_option_cases,
                  "params": params_cases, "export_options": export_option_cases, "diagnose": diagnose_cases,
                  "simulate": simulate_cases, "rig": rig_cases}


# ----------------------------------------------------------------------------- the property


def _listing(folder: Path) -> set[str]:
    return {str(Path(root, name).relative_to(folder)) for root, dirs, files in os.walk(folder)
            for name in files + dirs}


@contextlib.contextmanager
def _native_output(sink):
    """Send what native code writes to file descriptors 1 and 2 (e.g. LAPACK's messages) to `sink`."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = {fd: os.dup(fd) for fd in (1, 2)}
    try:
        for fd in saved:
            os.dup2(sink.fileno(), fd)
        yield
    finally:
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)


def _run(argv: list[str]) -> tuple[int | None, str, str, str | None]:
    """Run the CLI in-process: (status, stdout, stderr, traceback text of an escaping exception).

    Warnings are shown as in a fresh process (once per location and run), and what native code
    writes to the process's stdout or stderr is appended to stderr.
    """
    from identification.cli import main

    out, err = io.StringIO(), io.StringIO()
    status, tb = None, None
    with tempfile.TemporaryFile() as sink:
        # record=True: under pytest, which records warnings itself, a shown warning would go to its list
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), _native_output(sink), \
                warnings.catch_warnings(record=True) as caught:
            warnings.resetwarnings()
            warnings.simplefilter("default")
            try:
                status = main(argv)
            except SystemExit as exc:  # argparse rejects the command line itself
                status = exc.code
            except Exception:
                tb = traceback.format_exc()
        sink.seek(0)
        native = sink.read().decode("utf-8", "replace")
    shown = "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line) for w in caught)
    return status, out.getvalue(), err.getvalue() + shown + native, tb


def _check_identify_output(stdout: str, as_json: bool) -> None:
    if not as_json:
        if not stdout.startswith("Recording "):
            raise FuzzFailure(f"no result table on stdout: {stdout[:200]!r}")
        return

    def refuse(token):
        raise FuzzFailure(f"identify --json wrote {token} (not JSON)")

    doc = json.loads(stdout, parse_constant=refuse)
    if not doc["tires"]:
        raise FuzzFailure("identify --json succeeded with no tire")
    for name, entry in doc["tires"].items():
        if "refused" in entry:   # the method refused the channel: the waveform fit of the decay there is, if any
            if entry["fallback"] is None:
                continue
            entry = entry["fallback"]
        k, c = entry["k"], entry["c"]
        if not (math.isfinite(k) and k > 0 and math.isfinite(c) and c >= 0):
            raise FuzzFailure(f"identify --json: tire {name}: k = {k!r}, c = {c!r}")


def _identify_ok(where, argv, folder, new, stdout) -> None:
    if new:
        raise FuzzFailure(f"{where}: identify wrote {sorted(new)}")
    _check_identify_output(stdout, "--json" in argv)


def _export_ok(where, argv, folder, new, stdout) -> None:
    fmu = [n for n in new if (folder / n).is_file()]
    folders = {str(p) for p in Path(fmu[0]).parents if str(p) != "."} if len(fmu) == 1 else set()
    if len(fmu) != 1 or not fmu[0].lower().endswith(".fmu") or set(new) - set(fmu) - folders:
        raise FuzzFailure(f"{where}: export wrote {sorted(new)} (expected one FMU, and its folders)")
    _check_fmu(where, folder / fmu[0])


def _check_fmu(where, path: Path) -> None:
    """The FMU holds a modelDescription.xml that parses (a name with a character XML forbids once broke it)."""
    import xml.etree.ElementTree as ET

    with zipfile.ZipFile(path) as z:
        if "modelDescription.xml" not in z.namelist():
            raise FuzzFailure(f"{where}: the FMU {path.name} has no modelDescription.xml")
        try:
            ET.fromstring(z.read("modelDescription.xml"))
        except ET.ParseError as exc:
            raise FuzzFailure(f"{where}: the FMU {path.name}'s modelDescription.xml does not parse: {exc}") from None


def _option(argv, name: str):
    """The value of ``--name=VALUE`` in `argv` (the last one), or None."""
    values = [a.split("=", 1)[1] for a in argv if a.startswith(name + "=")]
    return values[-1] if values else None


def _check_written(where, folder: Path, new: set, files: set) -> None:
    """`new` (paths relative to `folder`) holds exactly `files` and the folders made for them."""
    files = {str(Path(f).relative_to(folder)) for f in files}
    folders = {str(p) for f in files for p in Path(f).parents if str(p) != "."}
    missing = files - new
    if missing or new - files - folders:
        raise FuzzFailure(f"{where}: wrote {sorted(new)}, expected {sorted(files)} and their folders")


def _json_or_text(where, stdout: str, as_json: bool):
    if not as_json:
        if not stdout.strip():
            raise FuzzFailure(f"{where}: no output")
        return None

    def refuse(token):
        raise FuzzFailure(f"{where}: --json wrote {token} (not JSON)")

    return json.loads(stdout, parse_constant=refuse)


def _diagnose_ok(where, argv, folder, new, stdout) -> None:
    expected = {Path(p) for p in (_option(argv, "--plot"), _option(argv, "--fmu")) if p}
    fmu_dir = _option(argv, "--fmu-dir")
    if fmu_dir:
        made = sorted(Path(fmu_dir).glob("*.fmu"))
        if not made:
            raise FuzzFailure(f"{where}: --fmu-dir wrote no FMU")
        expected |= set(made)
    _check_written(where, folder, new, expected)
    for path in expected:
        if path.suffix == ".fmu":
            _check_fmu(where, path)
    doc = _json_or_text(where, stdout, "--json" in argv)
    if doc is not None:
        for name, entry in (doc["tires"].items() if "tires" in doc else [(doc["tire"], doc)]):
            k, c = entry["k"], entry["c"]
            if not (math.isfinite(k) and k > 0 and math.isfinite(c) and c >= 0):
                raise FuzzFailure(f"{where}: tire {name}: k = {k!r}, c = {c!r}")


def _simulate_ok(where, argv, folder, new, stdout) -> None:
    plot = _option(argv, "--plot")
    _check_written(where, folder, new, {Path(plot)} if plot else set())
    doc = _json_or_text(where, stdout, "--json" in argv)
    for name, entry in ({} if doc is None else doc["tires"] if "tires" in doc else {"": doc}).items():
        if not (math.isfinite(entry["nrmse"]) and entry["nrmse"] >= 0):    # one tire, or the four under a body
            raise FuzzFailure(f"{where}: {name} nrmse = {entry['nrmse']!r}")


def _rig_ok(where, argv, folder, new, stdout) -> None:
    from identification.errors import InputError
    from identification.recording import read_recording

    paths = [Path(line) for line in stdout.splitlines()]
    if len(paths) != 3 or [p.name.split(".", 1)[1] for p in paths] != ["csv", "json", "truth.json"]:
        raise FuzzFailure(f"{where}: printed {stdout!r}, expected the paths of NAME.csv, .json and .truth.json")
    _check_written(where, folder, new, set(paths))
    try:
        read_recording(paths[0])
    except InputError as exc:
        raise FuzzFailure(f"{where}: the rig wrote a recording that does not read back: {exc}") from None


_SUCCESS = {"identify": _identify_ok, "export": _export_ok, "diagnose": _diagnose_ok, "simulate": _simulate_ok,
            "rig": _rig_ok}


def check_case(case: Case, details: dict | None = None) -> str:
    """Run `case` in a fresh folder; return ``"valid"`` or ``"error"``, or raise :class:`FuzzFailure`.

    Parameters
    ----------
    case : Case
    details : dict, optional
        Filled with ``argv``, ``status`` and the error ``message`` (without the folder), when given.

    Returns
    -------
    str
        ``"valid"`` (exit 0, a sound result) or ``"error"`` (exit 2, one line naming a file or option).

    Raises
    ------
    FuzzFailure
        A traceback, another exit status, a malformed error message, or a file written on error.
    """
    with tempfile.TemporaryDirectory(prefix="cleatfmu_fuzz_") as work:
        folder = Path(work)
        for name, data in case.files.items():
            path = folder / name
            path.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(data, Special):
                data.make(path)
            else:
                path.write_bytes(data)
        stage = folder / "tmp"  # the process's temporary folder during the run: it must stay empty
        stage.mkdir()
        before = _listing(folder)
        argv = case.argv(folder)
        CASES[0] += 1
        saved = tempfile.tempdir
        tempfile.tempdir = str(stage)
        try:
            status, stdout, stderr, tb = _run(argv)
        finally:
            tempfile.tempdir = saved
        after = _listing(folder)
        new = after - before
        where = f"cleatfmu {' '.join(argv)}"
        if details is not None:
            details.update(argv=argv, status=status, message=stderr.strip().replace(str(folder), "{dir}"))
        if tb is not None:
            raise FuzzFailure(f"{where}: traceback\n{tb}")
        if status == 0:   # warnings (a corrected sensor sign, a removed engine line) are one line each
            if any(not line.startswith("cleatfmu: warning: ") for line in stderr.splitlines()):
                raise FuzzFailure(f"{where}: exit 0 with stderr {stderr!r}")
            _SUCCESS[case.command](where, argv, folder, new, stdout)
            return "valid"
        if status != 2:
            raise FuzzFailure(f"{where}: exit status {status!r}; stderr {stderr!r}")
        lines = stderr.splitlines()
        if len(lines) != 1 or not stderr.endswith("\n") or not lines[0].startswith("cleatfmu: error: "):
            raise FuzzFailure(f"{where}: exit 2 but stderr is not one 'cleatfmu: error: ' line: {stderr!r}")
        message = lines[0][len("cleatfmu: error: "):]
        if not (message.startswith("--") or message.startswith(str(folder))):
            raise FuzzFailure(f"{where}: the message names no file or option: {message!r}")
        if new:
            raise FuzzFailure(f"{where}: exit 2 but wrote {sorted(new)}")
        return "error"


# ----------------------------------------------------------------------------- the CI run

#: Reproducible and bounded: derandomized, no example database, no deadline (first cases build caches).
CI = settings(deadline=None, derandomize=True, database=None, print_blob=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                     HealthCheck.filter_too_much, HealthCheck.large_base_example])


@settings(CI, max_examples=scaled(300))
@given(case=recording_cases())
def test_identify_mutated_csv(case):
    check_case(case)


@settings(CI, max_examples=scaled(200))
@given(case=sidecar_cases())
def test_identify_mutated_sidecar(case):
    check_case(case)


@settings(CI, max_examples=scaled(120))
@given(case=identify_option_cases())
def test_identify_options(case):
    check_case(case)


@settings(CI, max_examples=scaled(150))
@given(case=params_cases())
def test_export_mutated_params(case):
    check_case(case)


@settings(CI, max_examples=scaled(80))
@given(case=export_option_cases())
def test_export_options(case):
    check_case(case)


@settings(CI, max_examples=scaled(40))
@given(case=diagnose_cases())
def test_diagnose_options(case):
    check_case(case)


@settings(CI, max_examples=scaled(60))
@given(case=simulate_cases())
def test_simulate_options(case):
    check_case(case)


@settings(CI, max_examples=scaled(100))
@given(case=rig_cases())
def test_rig_options(case):
    check_case(case)
