"""Field artifacts of the virtual rig: what real recordings carry besides the tire's response.

Each artifact is off at its parameter's default (:data:`identification.rig.params.PARAMS`):

* **Engine vibration** (``engine.frequency_hz`` > 0): the engine shakes the body at its firing frequency
  f_e (typically 25-80 Hz, independent of the driving speed) and its orders; each hub sees
  ``sum_m (A / m) sin(2 pi m f_e t + phi_im)`` with A = ``engine.amplitude_m_s2`` and a random phase per
  hub and order.  It is hub acceleration, so it passes the sensor chain (AC coupling and anti-alias
  filter) like the tire's response.
* **DC offset and drift** (``sensor.offset_m_s2``, ``sensor.drift_m_s2_per_s``): the amplifier after the
  AC coupling adds ``o_i + d_i t`` to channel i, o_i and d_i drawn uniformly within +- the parameters.
* **A sensor mounted upside down** (``sensor.flipped``): the listed channels are recorded with the sign
  reversed.
* **A GPS speed error** (``speed_error``): the sidecar states ``(1 + speed_error)`` x the true speed.

Steady lug excitation before and after the cleat is the rig's ``periodic_disturbance`` effect (the lugs'
road-equivalent input), not an artifact: it moves the hub, and the diagnosis names it.

The artifacts draw from their own random stream (seeded by the run's seed), so a run without them is the
same recording as before they existed.
"""

from __future__ import annotations

import numpy as np

__all__ = ["artifact_rng", "engine_vibration", "sensor_artifacts", "active"]


def artifact_rng(seed: int) -> np.random.Generator:
    """The artifacts' random stream of a run with `seed` (independent of the noise's)."""
    return np.random.default_rng([int(seed), 0xA7])


def active(v: dict) -> dict:
    """The active artifacts and their parameters (the truth file's ``artifacts``)."""
    out: dict = {}
    if v["engine.frequency_hz"] > 0 and v["engine.amplitude_m_s2"] > 0:
        out["engine"] = {"frequency_hz": v["engine.frequency_hz"], "amplitude_m_s2": v["engine.amplitude_m_s2"],
                         "orders": int(v["engine.orders"])}
    if v["sensor.offset_m_s2"] > 0 or v["sensor.drift_m_s2_per_s"] > 0:
        out["offset_drift"] = {"offset_m_s2": v["sensor.offset_m_s2"], "drift_m_s2_per_s": v["sensor.drift_m_s2_per_s"]}
    if v["sensor.flipped"]:
        out["flipped"] = v["sensor.flipped"].split(",")
    if v["speed_error"] != 0:
        out["speed_error"] = v["speed_error"]
    return out


def engine_vibration(time_s: np.ndarray, v: dict, rng: np.random.Generator) -> tuple[np.ndarray, dict]:
    """Engine vibration at the four hubs on `time_s`, m/s² (shape (4, n)), and its phases (rad) by hub.

    Zero when ``engine.frequency_hz`` is 0.
    """
    out = np.zeros((4, np.size(time_s)))
    f, amp, orders = v["engine.frequency_hz"], v["engine.amplitude_m_s2"], int(v["engine.orders"])
    if f <= 0 or amp <= 0:
        return out, {}
    phases = rng.uniform(0.0, 2 * np.pi, (4, orders))
    for m in range(1, orders + 1):
        out += (amp / m) * np.sin(2 * np.pi * m * f * np.asarray(time_s)[None, :] + phases[:, m - 1:m])
    return out, {"phases_rad": phases.tolist()}


def sensor_artifacts(y: np.ndarray, time_s: np.ndarray, tires, v: dict,
                     rng: np.random.Generator) -> tuple[np.ndarray, dict]:
    """`y` (channels of `tires`) read by sensors upside down where so, plus the amplifier's offsets and drifts."""
    y = np.array(y, dtype=float, copy=True)
    info: dict = {}
    flipped = [c for c in v["sensor.flipped"].split(",") if c]
    for c in flipped:                 # the sensor reads upside down; the amplifier after it adds the offset
        y[list(tires).index(c)] *= -1.0
    if flipped:
        info["flipped"] = flipped
    o, d = v["sensor.offset_m_s2"], v["sensor.drift_m_s2_per_s"]
    if o > 0 or d > 0:
        offsets = rng.uniform(-o, o, len(tires))
        drifts = rng.uniform(-d, d, len(tires))
        y += offsets[:, None] + drifts[:, None] * np.asarray(time_s)[None, :]
        info["offset_m_s2"] = dict(zip(tires, map(float, offsets)))
        info["drift_m_s2_per_s"] = dict(zip(tires, map(float, drifts)))
    return y, info
