"""Cleat-test recordings: the ``cleat-recording/1`` format (read, validate, write).

A recording is two files with the same stem:

``NAME.csv``
    Header ``time,<channels>``.  ``time`` in s, strictly increasing and
    uniformly sampled: every time may be off the uniform grid of step
    ``h = (t[-1] - t[0]) / (n - 1)`` by at most 1 % of h (:data:`JITTER_TOLERANCE`),
    or by one unit of the last decimal written if that is more (1/2048 s written to 5 decimals).
    Channels are any non-empty subset of ``FL, FR, RL, RR`` (front/rear,
    left/right): hub vertical acceleration in m/s², upward positive, gravity
    excluded (AC-coupled accelerometers).  At least :data:`MIN_SAMPLES`
    samples spanning :data:`MIN_DURATION_S`.

``NAME.json``
    ``{"format": "cleat-recording/1", "speed_kmh": float > 0,
    "cleat_height_mm": float > 0, "cleat_width_mm": float > 0,
    "wheelbase_m": float > 0, "wheel_load_kN": {"FL": float > 0, ...},
    "description": str (optional), "acquisition": {...} (optional),
    "cleat_profile": "rectangular" | {"bevel_mm": b} | [[x_mm, z_mm], ...] (optional),
    "inflation_pressure_kPa": float > 0 | {"FL": float > 0, ...} (optional)}``.
    ``inflation_pressure_kPa`` is the tires' inflation pressure (gauge, kPa): one number for every tire, or
    one per channel (then every channel needs one).
    ``cleat_profile`` is the cleat's cross-section (:mod:`identification.recording.cleat`; absent: rectangular).
    ``wheel_load_kN`` holds the static wheel load of every channel (kN).
    ``acquisition`` describes the channels' analog chain:
    ``{"anti_alias_order": int 0..12, "anti_alias_cutoff_hz": float (below
    half the sampling rate), "highpass_hz": float >= 0}`` (see
    :mod:`identification.model.acquisition`; absent: unknown, the models then assume
    mean accelerations over each sample interval).  Unknown extra keys are kept
    and written back unchanged.

Plausibility: speed, cleat, wheelbase, wheel loads, the acquisition's
high-pass and the sampling rate must lie in the ranges of
:mod:`identification.recording.plausibility` (a 70 km/h cleat run, loads in N written as
kN, a 20 Hz sampling rate are refused).  A genuine value outside its range is
accepted when the sidecar lists the quantity in ``"out_of_range_ok"``, e.g.
``["speed_kmh", "sampling_rate_hz"]`` (kept and written back like any extra key).

Reading: the CSV is parsed in chunks (:mod:`identification.recording.csv_reader`), in
memory bounded by the float data; a long recording is analysed on the window
of its cleat impacts (:mod:`identification.recording.window`).

Inside the package every quantity is SI (m, s, N, kg); the file units above
are converted at this boundary only.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_write_texts, json_text
from .._inputs import read_json_file
from .acquisition import Acquisition, acquisition_from_sidecar
from ..errors import InputError
from .plausibility import OVERRIDE_KEY, check_value, out_of_range
from .csv_reader import JITTER_TOLERANCE, MIN_DURATION_S, MIN_SAMPLES, check_time, read_csv

__all__ = [
    "Acquisition", "FORMAT", "TIRES", "FRONT_TIRES", "REAR_TIRES", "STANDARD_GRAVITY",
    "JITTER_TOLERANCE", "MIN_SAMPLES", "MIN_DURATION_S",
    "Recording", "read_recording", "write_recording", "format_recording", "sidecar_path",
]

FORMAT = "cleat-recording/1"
TIRES = ("FL", "FR", "RL", "RR")
FRONT_TIRES = ("FL", "FR")
REAR_TIRES = ("RL", "RR")
#: Standard gravity, m/s² (the paper's m = W/g).
STANDARD_GRAVITY = 9.80665

_POSITIVE_KEYS = ("speed_kmh", "cleat_height_mm", "cleat_width_mm", "wheelbase_m")
_PRESSURE_KEY = "inflation_pressure_kPa"
_KNOWN_KEYS = {"format", "description", "wheel_load_kN", "acquisition", "cleat_profile", _PRESSURE_KEY,
               *_POSITIVE_KEYS}


@dataclass(frozen=True, eq=False)
class Recording:
    """One cleat-test run, in SI units.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Sample times, s.
    accel_m_s2 : dict of str to ndarray
        Hub vertical acceleration per tire channel, m/s² (gravity excluded).
    speed_m_s : float
        Driving speed, m/s.
    cleat_height_m, cleat_width_m : float
        Cleat cross-section, m.
    wheelbase_m : float
        Distance front axle to rear axle, m.
    wheel_load_N : dict of str to float
        Static wheel load per channel, N.
    description : str or None
        Free text from the sidecar.
    extra : dict
        Unknown sidecar keys, kept verbatim.
    source : str
        Where the recording came from (path of the CSV, or a label).
    acquisition : Acquisition or None
        The channels' analog chain, when the sidecar describes it.
    record_span_s : tuple of float or None
        When this is a window of a longer recording (:func:`identification.recording.window.focus`): the first
        and last sample time of the whole file, s; None: the whole file.
    decimated_from_hz : float or None
        When the samples were decimated for the analysis (:func:`identification.recording.window.decimate`): the
        file's sampling rate, Hz; None: the file's samples.
    cleat_profile : CleatProfile or None
        The cleat's cross-section when the sidecar gives one (:mod:`identification.recording.cleat`); None: the
        rectangular cleat of ``cleat_height_m`` x ``cleat_width_m``.
    conditioning : dict or None
        What :func:`identification.recording.condition.condition` found and removed (offsets, engine lines, flipped
        signs, the speed from the front/rear delay); None: not conditioned.
    inflation_pressure_Pa : dict of str to float or None
        Inflation pressure (gauge) per channel, Pa, when the sidecar gives it (``inflation_pressure_kPa``).
    """

    time_s: np.ndarray
    accel_m_s2: dict[str, np.ndarray]
    speed_m_s: float
    cleat_height_m: float
    cleat_width_m: float
    wheelbase_m: float
    wheel_load_N: dict[str, float]
    description: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    source: str = "<memory>"
    acquisition: Acquisition | None = None
    record_span_s: tuple[float, float] | None = None
    decimated_from_hz: float | None = None
    cleat_profile: Any = None
    conditioning: dict | None = None
    inflation_pressure_Pa: dict[str, float] | None = None

    def __post_init__(self):
        check_time(self.source, np.asarray(self.time_s, dtype=float))
        aa = self.acquisition
        if aa is not None and aa.anti_alias_order and aa.anti_alias_cutoff_hz >= self.sample_rate_hz / 2:
            raise InputError(self.source, f"acquisition: anti_alias_cutoff_hz {aa.anti_alias_cutoff_hz:g} Hz is "
                                          f"not below half the sampling rate ({self.sample_rate_hz / 2:g} Hz)")
        for name in self.accel_m_s2:
            if name not in TIRES:
                raise InputError(self.source, f"unknown channel {name!r} (allowed: {', '.join(TIRES)})")
            if name not in self.wheel_load_N:
                raise InputError(self.source, f"no wheel load for channel {name}")
            if len(self.accel_m_s2[name]) != len(self.time_s):
                raise InputError(self.source, f"channel {name} length differs from time")
            if not np.all(np.isfinite(self.accel_m_s2[name])):
                raise InputError(self.source, f"channel {name} holds non-finite values")
        if not self.accel_m_s2:
            raise InputError(self.source, "no acceleration channel")

    @property
    def tires(self) -> tuple[str, ...]:
        """Channel names in file order."""
        return tuple(self.accel_m_s2)

    @property
    def sample_rate_hz(self) -> float:
        """Nominal sampling rate, Hz."""
        t = self.time_s
        return (len(t) - 1) / (t[-1] - t[0])

    @property
    def speed_kmh(self) -> float:
        return self.speed_m_s * 3.6

    def mass_kg(self, tire: str) -> float:
        """Corner mass m = W/g of the paper, kg."""
        return self.wheel_load_N[tire] / STANDARD_GRAVITY

    def rear_axle_delay_s(self) -> float:
        """Time between front and rear axle reaching the cleat, s (L / v)."""
        return self.wheelbase_m / self.speed_m_s

    def sidecar(self) -> dict[str, Any]:
        """The ``NAME.json`` content (file units)."""
        meta: dict[str, Any] = {
            "format": FORMAT,
            "speed_kmh": self.speed_m_s * 3.6,
            "cleat_height_mm": self.cleat_height_m * 1e3,
            "cleat_width_mm": self.cleat_width_m * 1e3,
            "wheelbase_m": self.wheelbase_m,
            "wheel_load_kN": {t: self.wheel_load_N[t] / 1e3 for t in self.tires},
        }
        if self.description is not None:
            meta["description"] = self.description
        if self.acquisition is not None:
            meta["acquisition"] = self.acquisition.to_json()
        if self.cleat_profile is not None:
            meta["cleat_profile"] = self.cleat_profile.to_json()
        if self.inflation_pressure_Pa is not None:
            meta[_PRESSURE_KEY] = {t: self.inflation_pressure_Pa[t] / 1e3 for t in self.tires}
        meta.update(self.extra)
        return meta


def sidecar_path(csv_path: str | Path) -> Path:
    """The metadata file that belongs to a recording CSV."""
    return Path(csv_path).with_suffix(".json")


# ----------------------------------------------------------------------------- reading

def _not_a_file(path: Path) -> str:
    """Why `path` cannot be read as a file: missing, a folder, or a pipe or device."""
    return "no such file" if not path.exists() else "is a directory, not a file" if path.is_dir() else \
        "is not a regular file (a pipe or a device)"


def read_recording(csv_path: str | Path) -> Recording:
    """Read and validate a ``cleat-recording/1`` recording.

    Parameters
    ----------
    csv_path : path-like
        The ``NAME.csv`` file; its sidecar ``NAME.json`` is found by stem.

    Returns
    -------
    Recording

    Raises
    ------
    InputError
        For any violation of the format, naming the file and the problem.
    """
    csv_path = Path(csv_path)
    if csv_path.suffix.lower() != ".csv":
        raise InputError(csv_path, "expected a recording .csv file")
    if not csv_path.is_file():
        raise InputError(csv_path, _not_a_file(csv_path))
    meta_path = sidecar_path(csv_path)
    if not meta_path.is_file():
        raise InputError(csv_path, f"sidecar {meta_path.name} not found (a recording is NAME.csv + NAME.json)")
    meta = _read_sidecar(meta_path)
    names, data = read_csv(csv_path, TIRES)
    rate = (data.shape[1] - 1) / (data[0, -1] - data[0, 0])
    if "sampling_rate_hz" not in _waived(meta_path, meta.get(OVERRIDE_KEY, [])):
        problem = out_of_range("sampling_rate_hz", rate, label="sampling rate",
                               hint=_hint("sampling_rate_hz", meta_path))
        if problem:
            raise InputError(csv_path, problem)
    for i, name in enumerate(names):
        problem = out_of_range("peak_accel_m_s2", float(np.max(np.abs(data[i + 1]))),
                               label=f"channel {name}: largest acceleration")
        if problem:
            raise InputError(csv_path, problem)
    loads = meta["wheel_load_kN"]
    for name in names:
        if name not in loads:
            raise InputError(meta_path, f"wheel_load_kN has no entry for channel {name}")
    pressure = meta.get(_PRESSURE_KEY)
    if isinstance(pressure, dict):
        for name in names:
            if name not in pressure:
                raise InputError(meta_path, f"{_PRESSURE_KEY} has no entry for channel {name} (one number for "
                                            f"every tire, or one per channel)")
    return Recording(
        time_s=data[0],
        accel_m_s2={n: data[i + 1] for i, n in enumerate(names)},
        speed_m_s=meta["speed_kmh"] / 3.6,
        cleat_height_m=meta["cleat_height_mm"] / 1e3,
        cleat_width_m=meta["cleat_width_mm"] / 1e3,
        wheelbase_m=float(meta["wheelbase_m"]),
        wheel_load_N={n: loads[n] * 1e3 for n in loads},
        description=meta.get("description"),
        extra={k: v for k, v in meta.items() if k not in _KNOWN_KEYS},
        source=str(csv_path),
        acquisition=acquisition_from_sidecar(meta_path, meta["acquisition"]) if "acquisition" in meta else None,
        cleat_profile=_profile(meta, meta_path),
        inflation_pressure_Pa=None if pressure is None else
        {n: 1e3 * (pressure[n] if isinstance(pressure, dict) else pressure) for n in names},
    )


def _profile(meta: dict, meta_path):
    """The sidecar's ``cleat_profile``, or None for the default rectangular cleat."""
    if meta.get("cleat_profile", "rectangular") == "rectangular":
        return None
    from .cleat import parse_profile

    return parse_profile(meta["cleat_profile"], meta["cleat_height_mm"] / 1e3, meta["cleat_width_mm"] / 1e3,
                         meta_path)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _positive(path: Path, key: str, value: Any) -> float:
    if not _is_number(value):
        raise InputError(path, f"{key} must be a number, got {json.dumps(value)}")
    if isinstance(value, int) and abs(value) > 1e308:  # beyond float: math.isfinite would overflow
        raise InputError(path, f"{key} must be a finite number > 0, got an integer of {len(str(abs(value)))} digits")
    if not math.isfinite(value) or value <= 0:
        raise InputError(path, f"{key} must be a finite number > 0, got {value}")
    return float(value)


def _read_sidecar(path: Path) -> dict[str, Any]:
    meta = read_json_file(path, limit=16 << 20)
    if not isinstance(meta, dict):
        raise InputError(path, "the sidecar must be a JSON object")
    fmt = meta.get("format")
    if fmt is None:
        raise InputError(path, f"missing key 'format' (expected \"{FORMAT}\")")
    if fmt != FORMAT:
        raise InputError(path, f"unsupported format {json.dumps(fmt)} (expected \"{FORMAT}\")")
    waived = _waived(path, meta.get(OVERRIDE_KEY, []))
    for key in _POSITIVE_KEYS:
        if key not in meta:
            raise InputError(path, f"missing key '{key}'")
        meta[key] = _positive(path, key, meta[key])
        if meta[key] / 3.6 == 0 or meta[key] / 1e3 == 0:  # would underflow to 0 in SI units (m/s, m)
            raise InputError(path, f"{key} must be a finite number > 0, got {meta[key]!r} (too small)")
        problem = None if key in waived else out_of_range(key, meta[key], hint=_hint(key))
        if problem:
            raise InputError(path, problem)
    loads = meta.get("wheel_load_kN")
    if loads is None:
        raise InputError(path, "missing key 'wheel_load_kN'")
    if not isinstance(loads, dict) or not loads:
        raise InputError(path, "wheel_load_kN must be an object such as {\"FL\": 11.46}")
    for name, value in loads.items():
        if name not in TIRES:
            raise InputError(path, f"wheel_load_kN: unknown tire {name!r} (allowed: {', '.join(TIRES)})")
        loads[name] = _positive(path, f"wheel_load_kN.{name}", value)
        problem = None if "wheel_load_kN" in waived else \
            out_of_range("wheel_load_kN", loads[name], label=f"wheel_load_kN.{name}", hint=_hint("wheel_load_kN"))
        if problem:
            raise InputError(path, problem)
    if _PRESSURE_KEY in meta:
        meta[_PRESSURE_KEY] = _pressure(path, meta[_PRESSURE_KEY], _PRESSURE_KEY in waived)
    if "description" in meta and not isinstance(meta["description"], str):
        raise InputError(path, "description must be a string")
    acq = meta.get("acquisition")
    if isinstance(acq, dict):
        for key in ("anti_alias_cutoff_hz", "highpass_hz"):
            value = acq.get(key)
            if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 1e308:
                raise InputError(path, f"acquisition: {key} must be a finite number >= 0, got an integer of "
                                       f"{len(str(abs(value)))} digits")
        if "highpass_hz" not in waived:
            problem = check_value("highpass_hz", acq.get("highpass_hz"), label="acquisition.highpass_hz",
                                  hint=_hint("highpass_hz"))
            if problem:
                raise InputError(path, problem)
    return meta


def _pressure(path: Path, value: Any, waived: bool):
    """The sidecar's ``inflation_pressure_kPa`` checked: one number > 0, or ``{TIRE: number > 0}``."""
    key = _PRESSURE_KEY
    if isinstance(value, dict) and value:
        for name in value:
            if name not in TIRES:
                raise InputError(path, f"{key}: unknown tire {name!r} (allowed: {', '.join(TIRES)})")
        return {name: _one_pressure(path, f"{key}.{name}", v, waived) for name, v in value.items()}
    if not _is_number(value):
        raise InputError(path, f"{key} must be a number (kPa) or an object such as {{\"FL\": 160}}, "
                               f"got {json.dumps(value)}")
    return _one_pressure(path, key, value, waived)


def _one_pressure(path: Path, label: str, value: Any, waived: bool) -> float:
    number = _positive(path, label, value)
    problem = None if waived else out_of_range(_PRESSURE_KEY, number, label=label, hint=_hint(_PRESSURE_KEY))
    if problem:
        raise InputError(path, problem)
    return number


#: Quantities of a recording that its sidecar may accept out of their plausible range (``"out_of_range_ok"``).
WAIVABLE = (*_POSITIVE_KEYS, "wheel_load_kN", _PRESSURE_KEY, "sampling_rate_hz", "highpass_hz")


def _waived(path: Path, value: Any) -> frozenset:
    """The quantities a sidecar's ``"out_of_range_ok"`` list accepts out of range."""
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise InputError(path, f"{OVERRIDE_KEY} must be a list of quantity names such as [\"speed_kmh\"]")
    for name in value:
        if name not in WAIVABLE:
            raise InputError(path, f"{OVERRIDE_KEY}: unknown quantity {name!r} (known: {', '.join(WAIVABLE)})")
    return frozenset(value)


def _hint(key: str, sidecar: Path | None = None) -> str:
    where = f" of {sidecar.name}" if sidecar is not None else ""
    return f"; a genuine value: list \"{key}\" in \"{OVERRIDE_KEY}\"{where} to accept it"


# ----------------------------------------------------------------------------- writing

def format_recording(rec: Recording, stem: str | Path, *, time_decimals: int = 6,
                     value_decimals: int = 5) -> dict[Path, str]:
    """The two files of a recording as ``{path: text}`` (nothing written).

    Parameters
    ----------
    rec : Recording
    stem : path-like
        Output path without suffix (a ``.csv`` suffix is accepted and ignored).
    time_decimals, value_decimals : int
        Fixed-point decimals for time (s) and acceleration (m/s²).
    """
    stem = Path(stem)
    if stem.suffix.lower() in (".csv", ".json"):
        stem = stem.with_suffix("")
    csv_path, meta_path = stem.with_name(stem.name + ".csv"), stem.with_name(stem.name + ".json")
    if not stem.parent.is_dir():
        raise InputError(stem.parent, "output directory does not exist")
    written = np.round(rec.time_s, time_decimals)
    nominal = (rec.time_s[-1] - rec.time_s[0]) / (len(rec.time_s) - 1)
    if np.max(np.abs(np.diff(written) - nominal)) > JITTER_TOLERANCE * nominal / 2:
        raise InputError(csv_path, f"{time_decimals} time decimals cannot represent the sampling step")
    cols = [rec.time_s] + [rec.accel_m_s2[n] for n in rec.tires]
    fmt = ",".join([f"%.{time_decimals}f"] + [f"%.{value_decimals}f"] * len(rec.tires))
    body = "\n".join(fmt % row for row in zip(*cols))
    return {csv_path: "time," + ",".join(rec.tires) + "\n" + body + "\n",
            meta_path: json_text(rec.sidecar()) + "\n"}


def write_recording(rec: Recording, stem: str | Path, *, time_decimals: int = 6,
                    value_decimals: int = 5) -> Path:
    """Write ``STEM.csv`` and ``STEM.json``; return the CSV path.

    Both files are written to temporary names first and renamed only when both
    are complete, so a failure leaves nothing half-written.  See
    :func:`format_recording` for the arguments.
    """
    files = format_recording(rec, stem, time_decimals=time_decimals, value_decimals=value_decimals)
    atomic_write_texts(files)
    return next(iter(files))
