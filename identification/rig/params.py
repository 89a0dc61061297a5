"""Parameters of the virtual cleat-test rig, declared in one table.

Every value has a flat key (``--param key=value`` on the command line), a
default taken from the cleat-test paper (Tables 1, 2 and 4) where the paper
gives one, a unit and a description.  Units are part of the key names; the
only non-SI input is the speed in km/h, as on the test track.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ..errors import InputError

__all__ = ["EFFECTS", "PARAMS", "Param", "RANGES", "MAX_SAMPLES", "resolve", "parse_assignments", "parse_effects",
           "describe"]

TIRES = ("FL", "FR", "RL", "RR")

#: Effect names, exactly as the pipeline's diagnosis names them.
EFFECTS = ("enveloping", "lift_off", "axle_coupling", "nonlinear_stiffness", "friction_damping",
           "periodic_disturbance")


@dataclass(frozen=True)
class Param:
    default: Any
    unit: str
    description: str
    check: str = "positive"  # positive | nonnegative | int>=0 | int>=1 | flag | channels | channels? | profile | any


def _table() -> dict[str, Param]:
    p: dict[str, Param] = {
        "speed_kmh": Param(7.0, "km/h", "driving speed over the cleat"),
        "duration_s": Param(5.0, "s", "length of the recording"),
        "t0_s": Param(0.5, "s", "time the front axle's contact point reaches the cleat's leading edge"),
        "cleat.height_m": Param(0.040, "m", "cleat height"),
        "cleat.width_m": Param(0.100, "m", "cleat width in the driving direction"),
        "cleat.bevel_m": Param(0.0, "m", "bevel of the cleat's edges: the height rises over this length "
                                         "(a trapezoid; 0: rectangular, vertical edges)", "nonnegative"),
        "cleat.profile_mm": Param("", "mm", "the cleat's cross-section as x:z points from the leading edge, "
                                            "e.g. 0:0,10:40,90:40,100:0 (overrides the bevel; empty: none)",
                                  "profile"),
        "cleat.stagger_m": Param(0.0, "m", "right-hand cleat placed this far beyond the left one "
                                           "(negative: the left one beyond the right)", "any"),
        "vehicle.wheelbase_m": Param(2.77, "m", "wheelbase"),
        "vehicle.track_m": Param(1.90, "m", "track width (front and rear)"),
        "vehicle.mass_kg": Param(5528.0, "kg", "total mass; must equal the sum of wheel loads / g within 1 %"),
        "tire.front.diameter_m": Param(1.357, "m", "front tire overall diameter (380/85 R 28)"),
        "tire.rear.diameter_m": Param(1.747, "m", "rear tire overall diameter (460/85 R 38)"),
        "tire.front.lugs": Param(21, "-", "front tire lug bars per circumference (lug pitch = pi D / lugs)", "int>=1"),
        "tire.rear.lugs": Param(23, "-", "rear tire lug bars per circumference", "int>=1"),
    }
    loads = {"FL": 11460.0, "FR": 11600.0, "RL": 15650.0, "RR": 15510.0}
    ks = {"FL": 550e3, "FR": 520e3, "RL": 420e3, "RR": 450e3}
    cs = {"FL": 4200.0, "FR": 4300.0, "RL": 2400.0, "RR": 2500.0}
    for t in TIRES:
        p[f"tire.{t}.load_N"] = Param(loads[t], "N", f"static wheel load {t}")
        p[f"tire.{t}.k_N_m"] = Param(ks[t], "N/m", f"tire vertical stiffness {t} (tangent at the static load)")
        p[f"tire.{t}.c_Ns_m"] = Param(cs[t], "N s/m", f"tire viscous damping {t}", "nonnegative")
    p.update({
        "enveloping.footprint_front_m": Param(0.30, "m", "front footprint length (parabolic contact pressure)"),
        "enveloping.footprint_rear_m": Param(0.38, "m", "rear footprint length"),
        "axle_coupling.pitch_dynamic_index": Param(0.8, "-", "pitch inertia / (M a b); 1 decouples the axles"),
        "axle_coupling.roll_gyration_m": Param(0.65, "m", "roll radius of gyration about the centre of gravity"),
        "axle_coupling.front_axle_pivot": Param(0, "-", "0: front axle bolted to the body; 1: it rolls freely "
                                                        "about a longitudinal pivot at the track centre", "flag"),
        "axle_coupling.front_axle_roll_inertia_kg_m2": Param(120.0, "kg m2", "roll inertia of the front axle "
                                                                             "about its pivot (with the pivot)"),
        "nonlinear_stiffness.exponent": Param(1.5, "-", "n in F = K delta^n (progressive for n > 1)"),
        "friction_damping.force_N": Param(300.0, "N", "Coulomb friction force of the tire"),
        "friction_damping.slip_velocity_m_s": Param(0.002, "m/s", "velocity scale of the tanh friction law"),
        "periodic_disturbance.amplitude_m": Param(0.001, "m", "lug-passing road-equivalent amplitude"),
        "periodic_disturbance.frequency_hz": Param(0.0, "Hz", "excitation frequency; 0: lug passing "
                                                              "frequency speed / lug pitch of each axle",
                                                   "nonnegative"),
        "sensor.rate_hz": Param(1000.0, "Hz", "sampling rate"),
        "sensor.aa_order": Param(4, "-", "anti-alias Butterworth order (0: no anti-alias filter)", "int>=0"),
        "sensor.aa_cutoff_hz": Param(0.0, "Hz", "anti-alias cut-off; 0: a quarter of the sampling rate",
                                     "nonnegative"),
        "sensor.highpass_hz": Param(0.05, "Hz", "AC-coupling first-order high-pass corner (0: off)", "nonnegative"),
        "sensor.noise_m_s2": Param(0.05, "m/s2", "white measurement noise RMS", "nonnegative"),
        "sensor.lsb_m_s2": Param(0.0, "m/s2", "quantization step (0: none)", "nonnegative"),
        "sensor.channels": Param("FL,FR,RL,RR", "-", "recorded channels", "channels"),
        # Field artifacts: each is off at its default (see :mod:`identification.rig.artifacts`).
        "engine.frequency_hz": Param(0.0, "Hz", "engine vibration at the hubs: firing frequency, independent of "
                                                "speed (typically 25-80 Hz; 0: off)", "nonnegative"),
        "engine.amplitude_m_s2": Param(1.0, "m/s2", "engine vibration: amplitude of the first order at the hubs "
                                                    "(order m has amplitude / m)", "nonnegative"),
        "engine.orders": Param(3, "-", "engine vibration: number of orders (1, 2, ... x the frequency)", "int>=1"),
        "sensor.offset_m_s2": Param(0.0, "m/s2", "DC offset of every channel after the AC coupling (the "
                                                 "amplifier's), drawn per channel within +-this", "nonnegative"),
        "sensor.drift_m_s2_per_s": Param(0.0, "m/s2/s", "slow linear drift of every channel, drawn per channel "
                                                        "within +-this", "nonnegative"),
        "sensor.flipped": Param("", "-", "channels whose accelerometer is mounted upside down (sign reversed), "
                                         "e.g. FR or FL,RR", "channels?"),
        "speed_error": Param(0.0, "-", "relative error of the speed written in the sidecar (GPS): 0.05 writes "
                                       "1.05 x the true speed", "any"),
        "solver.rtol": Param(1e-9, "-", "relative tolerance of the DOP853 integrator"),
        "solver.oversample": Param(4, "-", "sensor-chain grid points per sample", "int>=1"),
    })
    return p


PARAMS: dict[str, Param] = _table()


def _coerce(key: str, value: Any) -> Any:
    spec = PARAMS[key]
    if spec.check == "profile":
        text = str(value).strip()
        try:
            pts = [[float(v) for v in item.split(":")] for item in text.split(",")] if text else []
        except ValueError:
            pts = None
        if pts is None or any(len(p) != 2 for p in pts):
            raise InputError("--param", f"{key} must be x:z points in mm separated by commas, got {value!r}")
        return ",".join(f"{x:g}:{z:g}" for x, z in pts)
    if spec.check in ("channels", "channels?"):
        names = [s.strip().upper() for s in str(value).split(",") if s.strip()]
        if spec.check == "channels?" and not names:
            return ""
        if not names or any(n not in TIRES for n in names) or len(set(names)) != len(names):
            raise InputError("--param", f"{key} must be a comma-separated subset of FL,FR,RL,RR, got {value!r}")
        return ",".join(names)
    try:
        num = float(value)
    except (TypeError, ValueError):
        raise InputError("--param", f"{key} must be a number, got {value!r}") from None
    if not math.isfinite(num):
        raise InputError("--param", f"{key} must be finite, got {value!r}")
    if spec.check == "flag":
        if num not in (0.0, 1.0):
            raise InputError("--param", f"{key} must be 0 or 1, got {value!r}")
        return int(num)
    if spec.check.startswith("int"):
        if num != int(num) or num < int(spec.check[-1]):
            raise InputError("--param", f"{key} must be an integer >= {spec.check[-1]}, got {value!r}")
        return int(_in_range(key, num))
    if spec.check == "positive" and num <= 0:
        raise InputError("--param", f"{key} must be > 0 {spec.unit}, got {value!r}")
    if spec.check == "nonnegative" and num < 0:
        raise InputError("--param", f"{key} must be >= 0 {spec.unit}, got {value!r}")
    return _in_range(key, num)


#: Plausible range (low, high, what) of each numeric option, in the option's unit; every default lies inside.
#: The quantities a recording carries have the ranges of :data:`identification.recording.plausibility.RANGES` (the rig
#: shares no code with the pipeline but the recording format; ``tests/test_plausibility.py`` compares them).
RANGES: dict[str, tuple[float, float, str]] = {
    "speed_kmh": (0.5, 60.0, "a tractor's speed over a cleat"),
    "duration_s": (1.0, 600.0, "the length of the recording"),
    "t0_s": (0.0, 600.0, "the front axle's arrival at the cleat"),
    "cleat.height_m": (0.002, 0.2, "a cleat's height"),
    "cleat.width_m": (0.005, 1.0, "a cleat's width in the driving direction"),
    "cleat.bevel_m": (0.0, 0.5, "a cleat's bevel"),
    "cleat.stagger_m": (-5.0, 5.0, "the right cleat beyond the left one"),
    "vehicle.wheelbase_m": (0.5, 10.0, "a tractor's wheelbase"),
    "vehicle.track_m": (0.5, 5.0, "a tractor's track width"),
    "vehicle.mass_kg": (4 * 100.0 / 9.80665, 4 * 100e3 / 9.80665, "a tractor's mass"),
    "tire.front.diameter_m": (0.2, 4.0, "a tractor tire's diameter"),
    "tire.rear.diameter_m": (0.2, 4.0, "a tractor tire's diameter"),
    "tire.front.lugs": (1, 200, "lug bars per circumference"),
    "tire.rear.lugs": (1, 200, "lug bars per circumference"),
    **{f"tire.{t}.load_N": (100.0, 100e3, "a tractor wheel's static load") for t in TIRES},
    **{f"tire.{t}.k_N_m": (10e3, 10e6, "a tractor tire's vertical stiffness") for t in TIRES},
    **{f"tire.{t}.c_Ns_m": (0.0, 100e3, "a tractor tire's vertical damping") for t in TIRES},
    "enveloping.footprint_front_m": (0.01, 1.5, "a footprint's length"),
    "enveloping.footprint_rear_m": (0.01, 1.5, "a footprint's length"),
    "axle_coupling.pitch_dynamic_index": (0.05, 5.0, "a pitch dynamic index"),
    "axle_coupling.roll_gyration_m": (0.05, 5.0, "a roll radius of gyration"),
    "axle_coupling.front_axle_roll_inertia_kg_m2": (1.0, 1e4, "a front axle's roll inertia"),
    "nonlinear_stiffness.exponent": (0.3, 4.0, "a progressive law's exponent"),
    "friction_damping.force_N": (0.0, 1e4, "a tire's friction force"),
    "friction_damping.slip_velocity_m_s": (1e-5, 1.0, "a friction law's velocity scale"),
    "periodic_disturbance.amplitude_m": (0.0, 0.05, "a lug's road-equivalent amplitude"),
    "periodic_disturbance.frequency_hz": (0.0, 500.0, "a lug-passing frequency"),
    "sensor.rate_hz": (50.0, 100e3, "a hub accelerometer's sampling rate"),
    "sensor.aa_order": (0, 12, "an anti-alias filter's order"),
    "sensor.highpass_hz": (0.0, 10.0, "an AC coupling's corner, below the tire's mode"),
    "sensor.noise_m_s2": (0.0, 10.0, "an accelerometer's noise RMS"),
    "sensor.lsb_m_s2": (0.0, 1.0, "a quantization step"),
    "engine.frequency_hz": (0.0, 500.0, "an engine's firing frequency"),
    "engine.amplitude_m_s2": (0.0, 100.0, "engine vibration at a hub"),
    "engine.orders": (1, 20, "engine orders"),
    "sensor.offset_m_s2": (0.0, 100.0, "an accelerometer's DC offset"),
    "sensor.drift_m_s2_per_s": (0.0, 10.0, "an accelerometer's drift"),
    "speed_error": (-0.3, 0.3, "a GPS speed's relative error"),
    "solver.rtol": (1e-13, 1e-3, "the integrator's relative tolerance"),
    "solver.oversample": (1, 64, "sensor-chain grid points per sample"),
}
#: The longest run, samples (duration x rate): what the solver and the sensor chain hold in memory.
MAX_SAMPLES = 2_000_000


def _in_range(key: str, num: float) -> float:
    """`num` if within the plausible range of `key` (:data:`RANGES`), else InputError naming ``--param``."""
    if key in RANGES:
        low, high, what = RANGES[key]
        if not low <= num <= high:
            unit = "" if PARAMS[key].unit == "-" else f" {PARAMS[key].unit}"
            raise InputError("--param", f"{key} {num:.6g}{unit} is outside the plausible range "
                                        f"{low:.6g}-{high:.6g}{unit} ({what})")
    return num


def resolve(overrides: dict[str, Any] | None = None) -> dict[str, Any]:
    """Defaults updated with `overrides` (checked); unknown keys are refused."""
    values = {k: v.default for k, v in PARAMS.items()}
    for key, value in (overrides or {}).items():
        if key not in PARAMS:
            raise InputError("--param", f"unknown parameter {key!r} (cleatfmu rig --list-params shows them)")
        values[key] = _coerce(key, value)
    from ..recording import MIN_SAMPLES

    samples = values["duration_s"] * values["sensor.rate_hz"]
    if samples > MAX_SAMPLES:
        raise InputError("--param", f"duration_s x sensor.rate_hz = {samples:.6g} samples, more than the rig's "
                                    f"{MAX_SAMPLES} (shorten the run or lower the rate)")
    if samples < MIN_SAMPLES:
        raise InputError("--param", f"duration_s x sensor.rate_hz = {samples:.6g} samples, fewer than a "
                                    f"recording's {MIN_SAMPLES} (lengthen the run or raise the rate)")
    return values


def parse_assignments(items: list[str] | None) -> dict[str, str]:
    """``["key=value", ...]`` from the command line to a dict."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise InputError("--param", f"expected key=value, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def parse_effects(text: str | list[str] | None) -> tuple[str, ...]:
    """``"enveloping,lift_off"`` (or a list of such) to a tuple of effect names."""
    items = text if isinstance(text, list) else [text or ""]
    names: list[str] = []
    for item in items:
        for name in (s.strip() for s in item.split(",")):
            if not name or name == "none":
                continue
            if name not in EFFECTS:
                raise InputError("--effect", f"unknown effect {name!r} (known: {', '.join(EFFECTS)})")
            if name not in names:
                names.append(name)
    return tuple(names)


def describe() -> str:
    """The parameter table as text (``cleatfmu rig --list-params``)."""
    width = max(len(k) for k in PARAMS)
    rows = [f"{k:<{width}} {str(v.default):>12} {v.unit:<6} {v.description}" for k, v in PARAMS.items()]
    return "\n".join(rows)
