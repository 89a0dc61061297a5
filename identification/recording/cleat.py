"""The cleat's cross-section: rectangular, bevelled or any piecewise-linear profile.

A recording's sidecar may carry ``"cleat_profile"``:

* ``"rectangular"`` (the default): height H over the whole width w, vertical edges;
* ``{"bevel_mm": b}``: a trapezoid, rising linearly from 0 to H over b at the leading edge and
  falling over b at the trailing edge (0 < b <= w / 2);
* ``[[x_mm, z_mm], ...]``: the profile through these points, x from the leading edge (0) on, not
  decreasing (a repeated x is a vertical edge); z = 0 before the first and after the last point.

The profile's highest point must be the sidecar's ``cleat_height_mm`` and its last x the
``cleat_width_mm`` (to 1 %).  Inside, a profile is its vertices (x, z) in m, vertical edges as two
vertices at one x.  :meth:`CleatProfile.averaged` gives the profile seen through a footprint with a
parabolic contact pressure, in closed form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["CleatProfile", "parse_profile"]

#: Agreement required between a profile's extent and the sidecar's height and width.
_MATCH = 0.01


@dataclass(frozen=True)
class CleatProfile:
    """A cleat cross-section through its vertices ``xs``, ``zs`` (m); see the module docstring."""

    xs: tuple
    zs: tuple
    kind: str = "points"          # "rectangular" | "bevel" | "points"
    bevel_m: float = 0.0

    @classmethod
    def rectangular(cls, height_m: float, width_m: float) -> "CleatProfile":
        return cls((0.0, 0.0, width_m, width_m), (0.0, height_m, height_m, 0.0), "rectangular")

    @classmethod
    def bevelled(cls, height_m: float, width_m: float, bevel_m: float) -> "CleatProfile":
        return cls((0.0, bevel_m, width_m - bevel_m, width_m), (0.0, height_m, height_m, 0.0), "bevel", bevel_m)

    @property
    def height_m(self) -> float:
        return max(self.zs)

    @property
    def width_m(self) -> float:
        return self.xs[-1]

    @property
    def is_rectangular(self) -> bool:
        return self.kind == "rectangular"

    def height(self, x) -> np.ndarray:
        """z at positions `x` (m) from the leading edge; at a vertical edge the value after it."""
        x = np.asarray(x, dtype=float)
        xs, zs = np.array(self.xs), np.array(self.zs)
        out = np.zeros_like(x)
        for k in range(len(xs) - 1):
            x0, x1, z0, z1 = xs[k], xs[k + 1], zs[k], zs[k + 1]
            if x1 > x0:
                inside = (x >= x0) & (x < x1)
                out = np.where(inside, z0 + (z1 - z0) * (x - x0) / (x1 - x0), out)
        return out

    def slope(self, x) -> np.ndarray:
        """dz/dx at `x` (0 at vertical edges and outside the cleat)."""
        x = np.asarray(x, dtype=float)
        xs, zs = np.array(self.xs), np.array(self.zs)
        out = np.zeros_like(x)
        for k in range(len(xs) - 1):
            x0, x1 = xs[k], xs[k + 1]
            if x1 > x0:
                out = np.where((x >= x0) & (x < x1), (zs[k + 1] - zs[k]) / (x1 - x0), out)
        return out

    def steps(self) -> list:
        """Vertical edges: [(x m, height change m)], including a first point above 0 or a last one."""
        out = []
        xs, zs = (0.0, *self.xs, self.xs[-1]), (0.0, *self.zs, 0.0)
        for k in range(len(xs) - 1):
            if xs[k + 1] == xs[k] and zs[k + 1] != zs[k]:
                out.append((float(xs[k]), float(zs[k + 1] - zs[k])))
        return out

    def vertices(self) -> list:
        """The x of every vertex, m (where the profile or its slope is not smooth)."""
        return sorted(set(float(x) for x in self.xs))

    def averaged(self, s, footprint_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Height (m) and d/ds (-) of the profile averaged over a footprint of length ℓ centred at `s` (m past
        the leading edge), under a parabolic contact pressure 3/(2ℓ) (1 − u²), u = 2 (x − s) / ℓ."""
        s = np.asarray(s, dtype=float)
        half = 0.5 * footprint_m
        r = np.zeros_like(s)
        dr = np.zeros_like(s)
        xs, zs = (0.0, *self.xs, self.xs[-1]), (0.0, *self.zs, 0.0)

        def cum(u):        # ∫_{-1}^{u} 3/4 (1 − v²) dv − 1/2, and the first moment ∫ 3/4 (1 − v²) v dv
            return 0.75 * (u - u ** 3 / 3.0), 0.75 * (u * u / 2.0 - u ** 4 / 4.0)

        for k in range(len(xs) - 1):
            x0, x1, z0, z1 = xs[k], xs[k + 1], zs[k], zs[k + 1]
            if x1 == x0:
                if z1 != z0:      # a vertical edge: a step of the averaged height's slope source
                    u = np.clip((x0 - s) / half, -1.0, 1.0)
                    dr += (z1 - z0) * np.where(np.abs(u) < 1.0, 0.75 * (1 - u * u) / half, 0.0)
                continue
            m = (z1 - z0) / (x1 - x0)
            u0 = np.clip((x0 - s) / half, -1.0, 1.0)
            u1 = np.clip((x1 - s) / half, -1.0, 1.0)
            a = z0 + m * (s - x0)                 # z at the footprint's centre, on this segment's line
            p1, q1 = cum(u1)
            p0, q0 = cum(u0)
            r += a * (p1 - p0) + m * half * (q1 - q0)
            dr += m * (p1 - p0)
        return r, dr

    @property
    def builtin_bevel_m(self) -> float:
        """The bevel of the trapezoid a tire's built-in cleat takes for this profile (m): 0 for a rectangle, the
        bevel of a bevelled cleat, and for a profile through points the bevel of the trapezoid of the same
        height, width and area (see :attr:`builtin_exact`)."""
        if self.kind == "rectangular":
            return 0.0
        if self.kind == "bevel":
            return self.bevel_m
        xs, zs = np.array(self.xs), np.array(self.zs)
        area = float(np.sum(np.diff(xs) * (zs[1:] + zs[:-1]) / 2))
        return min(max(self.width_m - area / self.height_m, 0.0), self.width_m / 2)

    @property
    def builtin_exact(self) -> bool:
        """Whether a built-in cleat (a trapezoid, see :attr:`builtin_bevel_m`) is this very profile."""
        if self.kind != "points":
            return True
        b = self.builtin_bevel_m
        ref = CleatProfile.bevelled(self.height_m, self.width_m, b) if b > 0 else \
            CleatProfile.rectangular(self.height_m, self.width_m)
        x = np.linspace(0.0, self.width_m, 401)
        return bool(np.max(np.abs(self.height(x) - ref.height(x))) <= 1e-3 * self.height_m)

    def on_grid(self, time_s, *, arrival_s: float, speed_m_s: float, step_s: float):
        """Road height (m) and rate (m/s) under a contact point crossing the profile, at grid times `time_s`.

        The contact point reaches the leading edge at `arrival_s`.  On slopes the rate is v dz/dx (at a kink
        the mean of its two sides); a vertical edge lies on the grid point nearest to it as a ramp of one step
        centred on the edge (the height the fraction of the step reached, the rate dz / h), which the stepping
        applies as an impulse.

        Returns
        -------
        road_m, rate_m_s : ndarray
        edges : list of (grid index, edge time s)
        """
        t = np.asarray(time_s, dtype=float)
        s = speed_m_s * (t - arrival_s)
        eps = 1e-9 * self.width_m
        road = self.height(s)
        rate = 0.5 * speed_m_s * (self.slope(s - eps) + self.slope(s + eps))
        edges = []
        for x_e, dz in self.steps():
            t_e = arrival_s + x_e / speed_m_s
            i = int(math.floor((t_e - t[0]) / step_s + 0.5))
            if 0 <= i < t.size:
                frac = (t[i] - t_e) / step_s + 0.5
                road[i] = self.height(np.array([x_e]))[0] - dz + dz * frac
                rate[i] = dz / step_s
                edges.append((i, t_e))
        return road, rate, edges

    def to_json(self):
        """The sidecar's ``cleat_profile`` value (mm)."""
        if self.kind == "rectangular":
            return "rectangular"
        if self.kind == "bevel":
            return {"bevel_mm": self.bevel_m * 1e3}
        return [[x * 1e3, z * 1e3] for x, z in zip(self.xs, self.zs)]


def parse_profile(value, height_m: float, width_m: float, source=None) -> CleatProfile:
    """The sidecar's ``cleat_profile`` (see the module docstring) for a cleat of `height_m` x `width_m`.

    Raises
    ------
    InputError
        Naming ``cleat_profile`` and what is wrong with it.
    """
    key = "cleat_profile"
    if value is None or value == "rectangular":
        return CleatProfile.rectangular(height_m, width_m)
    if isinstance(value, dict):
        if set(value) != {"bevel_mm"}:
            raise InputError(source, f"{key}: expected {{\"bevel_mm\": number}}, got keys {sorted(value)}")
        b = value["bevel_mm"]
        if isinstance(b, bool) or not isinstance(b, (int, float)) or not math.isfinite(b) or b <= 0:
            raise InputError(source, f"{key}: bevel_mm must be a number > 0, got {b!r}")
        if b / 1e3 > width_m / 2 * (1 + 1e-9):
            raise InputError(source, f"{key}: bevel_mm {b:g} is more than half the cleat width "
                                     f"({width_m * 1e3 / 2:g} mm)")
        return CleatProfile.bevelled(height_m, width_m, min(b / 1e3, width_m / 2))
    if isinstance(value, list):
        pts = []
        for p in value:
            if not (isinstance(p, list) and len(p) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                                 and math.isfinite(v) for v in p)):
                raise InputError(source, f"{key}: each point must be [x_mm, z_mm] (finite numbers), got {p!r}")
            pts.append((p[0] / 1e3, p[1] / 1e3))
        if len(pts) < 2:
            raise InputError(source, f"{key}: needs at least 2 points, got {len(pts)}")
        xs, zs = [p[0] for p in pts], [p[1] for p in pts]
        if xs[0] != 0:
            raise InputError(source, f"{key}: the first point's x must be 0 (the leading edge), got {xs[0] * 1e3:g} mm")
        if any(b < a for a, b in zip(xs, xs[1:])):
            raise InputError(source, f"{key}: x must not decrease from point to point")
        if min(zs) < 0:
            raise InputError(source, f"{key}: z must be >= 0, got {min(zs) * 1e3:g} mm")
        if abs(max(zs) / height_m - 1) > _MATCH:
            raise InputError(source, f"{key}: its highest point {max(zs) * 1e3:g} mm is not cleat_height_mm "
                                     f"{height_m * 1e3:g}")
        if abs(xs[-1] / width_m - 1) > _MATCH:
            raise InputError(source, f"{key}: its last x {xs[-1] * 1e3:g} mm is not cleat_width_mm {width_m * 1e3:g}")
        return CleatProfile(tuple(xs), tuple(zs), "points")
    raise InputError(source, f"{key}: expected \"rectangular\", {{\"bevel_mm\": b}} or a list of [x_mm, z_mm], "
                             f"got {value!r}")
