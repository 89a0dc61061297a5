"""The seat's three axes: fore-aft (x), lateral (y) and vertical (z) acceleration, rated by ISO 2631-1.

The seat is a point of the rigid body (floor values: no seat suspension), ``seat_x_m`` behind the front
axle, ``seat_y`` (a fraction of the half-track, + left) from the centre line and ``height_m`` above the
plane of the axles (the hubs), which the body pitches and rolls about.  For small angles its
accelerations are rows of the body's generalized accelerations q̈ (:func:`axis_rows`):

* z (up): z̈ + (a − x) θ̈ + (y − ȳ) ẅ, as :func:`identification.model.ride.seat_row`;
* x (forward): −h θ̈, the pitch θ nose-up carrying a point h above the axles backwards;
* y (left): −h φ̈ with the roll angle φ = w / (B/2), w the model's roll coordinate (scaled by the
  half-track) and B the track width, the roll lifting the left side carrying the point to the right.

The body has no longitudinal or lateral degree of freedom, so these are the pitch's and the roll's parts
only, and the tilt's share of gravity (g θ, g φ, which an accelerometer on a tilting seat also senses) is
not included.  :func:`three_axis` weights x and y with Wd, z with Wk (ISO 2631-1 Table 1, seated) and
gives per axis a_w, VDV and MTVV, the vector sums a_v = (Σ k_i² a_wi²)^½ (ISO 2631-1 clause 6.5) with the
health factors k = 1.4, 1.4, 1 and the comfort factors k = 1, 1, 1 (seat surface, clause 8.2.3), and
the daily exposure of EU directive 2002/44/EC: A(8) and the daily VDV of the worst axis, each axis with
its k (1.4 horizontal, 1 vertical).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..model.ride import seat_row
from ..model.tractor import Body
from .iso2631 import (EU_A8_ACTION_M_S2, EU_A8_LIMIT_M_S2, EU_VDV_ACTION, EU_VDV_LIMIT, ComfortResult, comfort,
                      daily_exposure, vdv_exposure)

__all__ = ["DEFAULT_SEAT_HEIGHT_M", "AXES", "AXIS_WEIGHTINGS", "HEALTH_K", "axis_rows", "ThreeAxisResult",
           "three_axis"]

#: Default seat height above the plane of the axles, m: a mid-size tractor's seat surface about 1.65 m above
#: the ground, its hubs about 0.75 m.
DEFAULT_SEAT_HEIGHT_M = 0.9
#: The axes, in order.
AXES = ("x", "y", "z")
#: ISO 2631-1 weighting per axis, seated.
AXIS_WEIGHTINGS = {"x": "Wd", "y": "Wd", "z": "Wk"}
#: Health multiplying factors per axis (ISO 2631-1 clause 7.2.3; 2002/44/EC).
HEALTH_K = {"x": 1.4, "y": 1.4, "z": 1.0}


def axis_rows(body: Body, *, seat_x_m: float, seat_y: float = 0.0, height_m: float = DEFAULT_SEAT_HEIGHT_M,
              track_width_m: float) -> dict:
    """The seat's x, y and z accelerations per generalized acceleration of `body` (rows like J's).

    Parameters
    ----------
    body : Body
        Rigid or pivoting-front-axle tractor.
    seat_x_m, seat_y : float
        As for :func:`identification.model.ride.seat_row`.
    height_m : float
        Seat height above the plane of the axles, m.
    track_width_m : float
        Track width B, m (turns the model's roll coordinate into an angle).

    Returns
    -------
    dict of str to ndarray
        ``x``, ``y``, ``z``.
    """
    if not (math.isfinite(height_m) and -1.0 <= height_m <= 5.0):
        raise InputError("--seat-height-m", f"a seat height of -1 .. 5 m above the axles is expected, got {height_m!r}")
    if not (math.isfinite(track_width_m) and track_width_m > 0):
        raise InputError("track width", f"must be > 0 m, got {track_width_m!r}")
    z = seat_row(body, seat_x_m=seat_x_m, seat_y=seat_y)
    x, y = np.zeros_like(z), np.zeros_like(z)
    x[1] = -height_m                                  # pitch θ (column 1)
    y[2] = -height_m / (0.5 * track_width_m)          # roll w = (B/2) φ (column 2)
    return {"x": x, "y": y, "z": z}


def _status(value: float, action: float, limit: float) -> str:
    return "above_limit" if value > limit else "above_action" if value > action else "below_action"


@dataclass(frozen=True)
class ThreeAxisResult:
    """ISO 2631-1 rating of a seat's three axes (see the module docstring).

    Attributes: `axes` (axis -> :class:`~identification.comfort.iso2631.ComfortResult`), `vector_sum_health`
    and `vector_sum_comfort` (m/s²), and with an exposure time `exposure_h` (h), `a8` and `a8_axis` (the
    worst axis's k a_w √(T/8 h)), `daily_vdv` and `daily_vdv_axis`.
    """

    axes: dict
    vector_sum_health: float
    vector_sum_comfort: float
    exposure_h: float | None = None
    a8: float | None = None
    a8_axis: str | None = None
    daily_vdv: float | None = None
    daily_vdv_axis: str | None = None

    def values(self) -> dict:
        """The ratings as a flat dict (for the expected values over realisations), SI units."""
        out = {f"{a}_{key}": getattr(self.axes[a], key) for a in AXES for key in ("a_w", "vdv", "mtvv")}
        out.update(vector_sum_health=self.vector_sum_health, vector_sum_comfort=self.vector_sum_comfort)
        if self.a8 is not None:
            out.update(a8_worst_axis=self.a8, daily_vdv_worst_axis=self.daily_vdv)
        return out

    def to_json(self) -> dict:
        """A JSON-ready dict (SI units)."""
        doc = {"axes": {a: {"weighting": r.weighting, "k": HEALTH_K[a], "a_w": r.a_w, "vdv": r.vdv, "mtvv": r.mtvv,
                            "crest_factor": r.crest_factor if math.isfinite(r.crest_factor) else None}
                        for a, r in self.axes.items()},
               "vector_sum_health": self.vector_sum_health, "vector_sum_comfort": self.vector_sum_comfort,
               "vector_sum_k": HEALTH_K}
        if self.a8 is not None:
            doc["exposure"] = {"exposure_h": self.exposure_h, "a8": self.a8, "a8_axis": self.a8_axis,
                               "a8_status": _status(self.a8, EU_A8_ACTION_M_S2, EU_A8_LIMIT_M_S2),
                               "vdv": self.daily_vdv, "vdv_axis": self.daily_vdv_axis,
                               "vdv_status": _status(self.daily_vdv, EU_VDV_ACTION, EU_VDV_LIMIT),
                               "a8_action": EU_A8_ACTION_M_S2, "a8_limit": EU_A8_LIMIT_M_S2,
                               "vdv_action": EU_VDV_ACTION, "vdv_limit": EU_VDV_LIMIT}
        return doc


def three_axis(acc_x, acc_y, acc_z, sample_rate_hz: float, *, exposure_h: float | None = None,
               tau_s: float = 1.0) -> ThreeAxisResult:
    """Rate a seat's three axes by ISO 2631-1 and, with `exposure_h`, by 2002/44/EC.

    Parameters
    ----------
    acc_x, acc_y, acc_z : array_like
        Unweighted fore-aft, lateral and vertical accelerations, m/s², same length and sampling.
    sample_rate_hz : float
    exposure_h : float, optional
        Daily exposure time, h (0 < T <= 24).
    tau_s : float
        Integration time of the running RMS (MTVV), s.

    Returns
    -------
    ThreeAxisResult
    """
    signals = {"x": np.asarray(acc_x, dtype=float), "y": np.asarray(acc_y, dtype=float),
               "z": np.asarray(acc_z, dtype=float)}
    if len({s.shape for s in signals.values()}) != 1:
        raise InputError("acc", f"the three axes need the same number of samples, got "
                                f"{', '.join(str(s.shape) for s in signals.values())}")
    axes: dict[str, ComfortResult] = {a: comfort(signals[a], sample_rate_hz, AXIS_WEIGHTINGS[a], tau_s=tau_s,
                                                 exposure_h=exposure_h, k=HEALTH_K[a]) for a in AXES}
    health = math.sqrt(sum((HEALTH_K[a] * axes[a].a_w) ** 2 for a in AXES))
    plain = math.sqrt(sum(axes[a].a_w ** 2 for a in AXES))
    if exposure_h is None:
        return ThreeAxisResult(axes, health, plain)
    duration = axes["z"].duration_s
    a8 = {a: daily_exposure(axes[a].a_w, exposure_h, HEALTH_K[a]) for a in AXES}
    dv = {a: vdv_exposure(axes[a].vdv, duration, exposure_h, HEALTH_K[a]) for a in AXES}
    worst, worst_vdv = max(AXES, key=a8.get), max(AXES, key=dv.get)
    return ThreeAxisResult(axes, health, plain, float(exposure_h), a8[worst], worst, dv[worst_vdv], worst_vdv)
