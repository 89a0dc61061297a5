"""Physical plausibility: the ranges of every quantity a cleat test of a tractor tire can have.

The input boundaries - a recording's sidecar and time column
(:mod:`identification.recording`), the parameter file of ``cleatfmu export``
and the virtual rig's options (:mod:`identification.rig.params`) - refuse a
value outside its range with one line naming the file or option, the value
and the range.  The ranges are wide on purpose: they bracket every
agricultural tractor, from a compact one to the largest articulated ones, and
refuse only what is no tractor tire cleat test (a speed in m/s written as
km/h, a load in N written as kN, a sampling rate of 5 Hz, ...).

Ranges (:data:`RANGES`; bounds inclusive):

* ``speed_kmh`` 0.5-60 km/h: a cleat test is driven at walking to road speed;
* ``cleat_height_mm`` 2-200 mm: a strip on the road to a beam;
* ``cleat_width_mm`` 5-1000 mm, in the driving direction;
* ``wheelbase_m`` 0.5-10 m: compact tractor to articulated 4WD;
* ``wheel_load_kN`` 0.1-100 kN per wheel (10 kg to 10 t);
* ``inflation_pressure_kPa`` 20-1000 kPa (optional): very low pressure tires to implement tires
  (a pressure in bar or Pa written as kPa is refused);
* ``sampling_rate_hz`` 50 Hz-100 kHz: the tire's mode (2-20 Hz) sampled
  well, up to an impact recorder;
* ``highpass_hz`` 0-10 Hz: the acquisition's AC coupling, below the tire's mode;
* ``peak_accel_m_s2`` 0.01-1e6 m/s²: a channel's largest value (a cleat
  impact is tens of m/s²; outside, the channel is no hub acceleration in
  m/s², and there is no override);
* ``stiffness_N_m`` 10 kN/m-10 MN/m and ``damping_Ns_m`` 0-100 kN s/m: the
  tire's vertical k and c;
* ``corner_mass_kg`` 10.2-10,197 kg: m = W / g of the wheel loads above;
* ``unloaded_radius_m`` 0.1-2 m: the tire's unloaded radius r0.

Command options whose value sets a run's cost (:data:`OPTION_RANGES`):
``--max-step-s`` 10 us-10 ms (``simulate``), ``--workers`` 1-64 (``diagnose``).

The virtual rig checks its options against ranges of its own
(:data:`identification.rig.params.RANGES`: track, tire diameters, noise,
duration ...), since it shares no code with the pipeline but the recording
format; those of the quantities above are the same (``tests/test_plausibility.py``
checks it), and every default passes.

**Override.**  A real test can lie outside (a scaled tire on a laboratory
rig, a high-speed run): a recording's sidecar may list the quantities it
accepts out of range, ``"out_of_range_ok": ["speed_kmh", "wheel_load_kN"]``
(the values must still be finite and > 0), and ``cleatfmu export
--accept-out-of-range`` accepts k, c, the corner mass and the unloaded radius
out of range (k > 0, c >= 0 and finite still).
The virtual rig has no override: its ranges are those of its model.

This module imports no numpy (``cleatfmu export`` starts without it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Range", "RANGES", "OPTION_RANGES", "OVERRIDE_KEY", "out_of_range", "check_value", "check_option",
           "range_text"]

#: The sidecar key listing the quantities accepted out of range.
OVERRIDE_KEY = "out_of_range_ok"


@dataclass(frozen=True)
class Range:
    """A closed interval [low, high] of a quantity, in the unit named.

    Attributes
    ----------
    low, high : float
        Bounds (inclusive).
    unit : str
        The unit the bounds (and the value checked) are in.
    what : str
        What the quantity is, for messages.
    """

    low: float
    high: float
    unit: str
    what: str

    def contains(self, value: float) -> bool:
        """Whether `value` lies in [low, high]."""
        return self.low <= value <= self.high


_G = 9.80665

#: The ranges of the recording, the identified tire and the exported FMU, by quantity name (file units).
RANGES: dict[str, Range] = {
    "speed_kmh": Range(0.5, 60.0, "km/h", "a tractor's speed over a cleat"),
    "cleat_height_mm": Range(2.0, 200.0, "mm", "a cleat's height"),
    "cleat_width_mm": Range(5.0, 1000.0, "mm", "a cleat's width in the driving direction"),
    "wheelbase_m": Range(0.5, 10.0, "m", "a tractor's wheelbase"),
    "wheel_load_kN": Range(0.1, 100.0, "kN", "a tractor wheel's static load"),
    "inflation_pressure_kPa": Range(20.0, 1000.0, "kPa", "a tractor tire's inflation pressure"),
    "sampling_rate_hz": Range(50.0, 100e3, "Hz", "a hub accelerometer's sampling rate"),
    "highpass_hz": Range(0.0, 10.0, "Hz", "an AC coupling's corner, below the tire's mode"),
    "peak_accel_m_s2": Range(0.01, 1e6, "m/s^2", "a hub's largest acceleration in a cleat run, in m/s^2"),
    "stiffness_N_m": Range(10e3, 10e6, "N/m", "a tractor tire's vertical stiffness"),
    "damping_Ns_m": Range(0.0, 100e3, "N*s/m", "a tractor tire's vertical damping"),
    "corner_mass_kg": Range(0.1e3 / _G, 100e3 / _G, "kg", "a tractor's corner mass W/g"),
    "unloaded_radius_m": Range(0.1, 2.0, "m", "a tractor tire's unloaded radius"),
}

#: Command options with a range: what keeps a run's cost bounded.
OPTION_RANGES: dict[str, Range] = {
    "--max-step-s": Range(1e-5, 1e-2, "s", "a co-simulation step: 10 us resolves any cleat edge, 10 ms still "
                                           "samples a tire's mode"),
    "--workers": Range(1, 64, "-", "worker processes"),
}

def _fmt(value: float) -> str:
    return f"{value:.6g}"


def _unit(rng: Range) -> str:
    return "" if rng.unit == "-" else f" {rng.unit}"


def range_text(rng: Range) -> str:
    """``0.5-60 km/h``."""
    return f"{_fmt(rng.low)}-{_fmt(rng.high)}{_unit(rng)}"


def out_of_range(name: str, value: float, rng: Range | None = None, *, label: str | None = None,
                 hint: str = "") -> str | None:
    """The one-line problem of a finite `value` outside the range of quantity `name`, or None.

    Parameters
    ----------
    name : str
        Quantity name in :data:`RANGES` (or any name, with `rng`).
    value : float
        The value, in the range's unit.
    rng : Range, optional
        The range (default ``RANGES[name]``).
    label : str, optional
        How the message names the value (default `name`).
    hint : str
        Appended to the message (how to override, where there is a way).
    """
    rng = rng or RANGES[name]
    if rng.contains(value):
        return None
    return (f"{label or name} {_fmt(value)}{_unit(rng)} is outside the plausible range {range_text(rng)} "
            f"({rng.what}){hint}")


def check_value(name: str, value, rng: Range | None = None, **kwargs) -> str | None:
    """:func:`out_of_range` for a value that may not even be a finite number (then: None; other checks
    report it)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        value = float(value)
    except OverflowError:
        return None
    if not math.isfinite(value):
        return None
    return out_of_range(name, value, rng, **kwargs)


def check_option(option: str, value) -> None:
    """Refuse a command option's value outside :data:`OPTION_RANGES` (or not a finite number).

    Raises
    ------
    InputError
        Naming the option, in one line.
    """
    from ..errors import InputError

    rng = OPTION_RANGES[option]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(option, f"must be a finite number, got {value!r}")
    if not rng.contains(value):
        raise InputError(option, f"{_fmt(value)}{_unit(rng)} is outside {range_text(rng)} ({rng.what})")
