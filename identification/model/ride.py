"""The model record of the whole tractor on a road profile (a ride), and the seat's place on its body.

The record is the whole-tractor one (:class:`~identification.model.tractor.TractorModel`: body, four tire
laws, arrivals) with the cleat replaced by a road profile of two tracks: each tire rolls on its side's
track at its own distance behind the front axle, so the rear tires meet the front tires' road a wheelbase
later (the front/rear delay L / v), and the left and right tracks are as coherent as the profile makes
them.  The same record runs in the compiled stepping and in the FMU master, so a parameter set and its
exported FMUs ride the same road (:mod:`identification.comfort.ride`).

A tire whose law has a footprint (``footprint_length`` ℓ > 0, the diagnosis's ``enveloping``) rolls on its
track averaged over the footprint with the law's contact pressure (:func:`enveloped_track`: uniform, or
parabolic ∝ 1 − u², u = 2ξ/ℓ, as the law averages its built-in cleat,
:func:`~identification.model.tire_law.footprint_cleat`): waves shorter than the footprint are filtered out,
with the spatial frequency response :func:`footprint_response`.

The seat is a point of the body, ``seat_x_m`` behind the front axle and ``seat_y`` (a fraction of the
half-track, + left) from the centre line: its vertical displacement is the row of the body's generalized
coordinates q that places it, z + (a − x) θ + (y − ȳ) w (:func:`seat_row`; with a pivoting front axle the
seat is on the body, not the axle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..recording import FRONT_TIRES
from .tractor import LEFT_TIRES, Body, Cleat, Inputs, TractorModel

__all__ = ["RideModel", "ride_model", "seat_row", "RAMP_M", "footprint_weights", "footprint_response",
           "enveloped_track"]

#: Length over which the profile is faded in from zero under every tire, m (the tractor starts at rest on
#: level ground).
RAMP_M = 5.0


@dataclass(frozen=True, eq=False)
class RideModel(TractorModel):
    """A model record whose road is a profile of two tracks (see the module docstring).

    Parameters
    ----------
    road_x_m, road_left_m, road_right_m : ndarray
        The profile: positions along the road (increasing, m) and the left and right track heights (m).
    offsets_m : tuple of float
        Each tire's distance behind the front axle, m (0 front, the wheelbase rear).
    tire_tracks : tuple of (ndarray, ndarray)
        Each tire's road (positions, heights): its side's track, averaged over its footprint where its law has
        one (:func:`ride_model` fills them).
    """

    road_x_m: np.ndarray = None
    road_left_m: np.ndarray = None
    road_right_m: np.ndarray = None
    offsets_m: tuple = ()
    tire_tracks: tuple = ()

    def inputs(self, start_s: float, step_s: float, n: int) -> Inputs:
        """Road height and rate under every tire on the grid start + i h (no cleat edges)."""
        base = super().inputs(start_s, step_s, n)   # flat road and the longitudinal positions
        v = self.cleat.speed_m_s
        t = start_s + step_s * np.arange(n)
        x0 = float(self.road_x_m[0])
        z = np.zeros((len(self.tires), n))
        vz = np.zeros_like(z)
        for j, tire in enumerate(self.tires):
            xs, track = self.tire_tracks[j] if self.tire_tracks else \
                (self.road_x_m, self.road_left_m if tire in LEFT_TIRES else self.road_right_m)
            x = x0 + v * t - self.offsets_m[j]
            height = np.interp(x, xs, track, left=0.0, right=0.0)
            slope = np.interp(x, xs, np.gradient(track, xs), left=0.0, right=0.0)
            # faded in over RAMP_M from the tire's first metre on the profile
            s = np.clip((x - x0) / RAMP_M, 0.0, 1.0)
            fade = s * s * (3.0 - 2.0 * s)
            dfade = np.where((s > 0) & (s < 1), 6.0 * s * (1.0 - s) / RAMP_M, 0.0)
            z[j] = fade * height
            vz[j] = v * (fade * slope + dfade * height)
        return Inputs(z, vz, base.hub_x, base.hub_vx, edges=())


def ride_model(body: Body, laws, *, speed_m_s: float, road_x_m, road_left_m, road_right_m) -> RideModel:
    """The model record of `body` on its tires' `laws` driving the profile at `speed_m_s`.

    Parameters
    ----------
    body : Body
        The tractor (rigid or with a pivoting front axle), four tires.
    laws : sequence of dict
        Extended tire-law parameters per tire (point contact: no built-in cleat).
    speed_m_s : float
    road_x_m, road_left_m, road_right_m : array_like
        The road profile (see :class:`RideModel`).
    """
    if body.kind not in ("rigid", "pivot"):
        raise ValueError(f"a ride needs the whole tractor (rigid or pivoting front axle), got {body.kind!r}")
    if not (speed_m_s > 0 and math.isfinite(speed_m_s)):
        raise ValueError(f"speed_m_s must be finite and > 0, got {speed_m_s!r}")
    x = np.asarray(road_x_m, dtype=float)
    left, right = np.asarray(road_left_m, dtype=float), np.asarray(road_right_m, dtype=float)
    if x.ndim != 1 or x.size < 2 or left.shape != x.shape or right.shape != x.shape or np.any(np.diff(x) <= 0):
        raise ValueError("the road needs increasing positions and one height per position on each track")
    if any(law["cleat_height"] > 0 for law in laws):
        raise ValueError("a ride's tires have no built-in cleat: the road is the profile")
    offsets = tuple(0.0 if t in FRONT_TIRES else float(body.wheelbase_m) for t in body.tires)
    tracks = tuple(enveloped_track(x, left if t in LEFT_TIRES else right, float(law.get("footprint_length", 0.0)),
                                   parabolic=bool(law.get("parabolic_pressure", False)))
                   for t, law in zip(body.tires, laws))
    return RideModel(body=body, laws=tuple(laws), cleat=Cleat(0.0, 0.1, float(speed_m_s)),
                     arrivals_s=tuple(0.0 for _ in body.tires), road_x_m=x, road_left_m=left,
                     road_right_m=right, offsets_m=offsets, tire_tracks=tracks)


def footprint_weights(spacing_m: float, footprint_m: float, *, parabolic: bool = True) -> np.ndarray:
    """The contact pressure over a footprint of length `footprint_m` sampled every `spacing_m` (odd length,
    centred, summing to 1): uniform, or parabolic ∝ 1 − (2ξ/ℓ)²."""
    if not (spacing_m > 0 and footprint_m >= 0):
        raise ValueError(f"spacing_m must be > 0 and footprint_m >= 0, got {spacing_m!r}, {footprint_m!r}")
    half = int(math.floor(0.5 * footprint_m / spacing_m))
    xi = np.arange(-half, half + 1) * spacing_m
    w = 1.0 - (2.0 * xi / footprint_m) ** 2 if parabolic and half > 0 else np.ones(xi.size)
    return w / w.sum()


def footprint_response(wavenumber_cpm, footprint_m: float, *, parabolic: bool = True) -> np.ndarray:
    """The footprint average's response to a road wave of `wavenumber_cpm` cycles per metre (real, 1 at 0):
    sin a / a for a uniform pressure, 3 (sin a − a cos a) / a³ for a parabolic one, a = π n ℓ."""
    a = np.pi * np.asarray(wavenumber_cpm, dtype=float) * float(footprint_m)
    out = np.ones_like(a)
    big = np.abs(a) > 1e-4
    ab = a[big]
    out[big] = 3.0 * (np.sin(ab) - ab * np.cos(ab)) / ab ** 3 if parabolic else np.sin(ab) / ab
    small = a[~big] ** 2
    out[~big] = 1.0 - small / 10.0 if parabolic else 1.0 - small / 6.0
    return out


def enveloped_track(x_m, height_m, footprint_m: float, *, parabolic: bool = True) -> tuple:
    """A track (positions `x_m`, heights `height_m`) as a tire with a footprint `footprint_m` rolls on it:
    (positions, heights) averaged over the footprint (:func:`footprint_weights`); the track itself for
    ``footprint_m`` 0.  A track that is not evenly spaced is first resampled at its finest spacing; beyond its
    ends the road is level (height 0)."""
    x, z = np.asarray(x_m, dtype=float), np.asarray(height_m, dtype=float)
    if not footprint_m > 0:
        return x, z
    dx = np.diff(x)
    if np.ptp(dx) > 1e-6 * dx.mean():
        step = float(dx.min())
        grid = x[0] + step * np.arange(int(math.floor((x[-1] - x[0]) / step)) + 1)
        x, z = grid, np.interp(grid, x, z)
        dx = np.diff(x)
    w = footprint_weights(float(dx.mean()), footprint_m, parabolic=parabolic)
    if w.size > z.size:
        raise ValueError(f"a footprint of {footprint_m:g} m is longer than the road ({x[-1] - x[0]:g} m)")
    return x, np.convolve(z, w, mode="same")


def seat_row(body: Body, *, seat_x_m: float, seat_y: float = 0.0) -> np.ndarray:
    """The seat's vertical displacement per generalized coordinate of `body` (one row like J's).

    Parameters
    ----------
    body : Body
        Rigid or pivoting-front-axle tractor.
    seat_x_m : float
        Seat position behind the front axle, m.
    seat_y : float
        Seat position from the centre line as a fraction of the half-track (+ left).
    """
    if body.kind not in ("rigid", "pivot"):
        raise ValueError(f"a seat needs the whole tractor, got a {body.kind!r} body")
    W = np.array(body.loads_n, dtype=float)
    front = np.array([t in FRONT_TIRES for t in body.tires])
    a = body.wheelbase_m * W[~front].sum() / W.sum()
    ybar = float(sum((1.0 if t in LEFT_TIRES else -1.0) * w for t, w in zip(body.tires, W)) / W.sum())
    row = [1.0, a - seat_x_m, seat_y - ybar]
    if body.pivot:
        row.append(0.0)
    return np.array(row)
