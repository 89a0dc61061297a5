"""Cleat cross-sections as polylines, and the terrain height under a point.

The terrain is flat (z = 0) with a cleat on it: a trapezoid of base width ``width_m`` and height
``height_m`` whose edges rise over ``bevel_m`` (0: vertical), its two top edges rounded with radius
``round_m``.  The polyline starts at the cleat's leading edge (x = 0) and runs in the driving
direction, x forward, z up.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["cleat_polyline", "height_at"]


def _fillet(corner, d_in, d_out, radius, n_arc):
    """Points of a fillet of ``radius`` at ``corner`` between the unit directions d_in and d_out."""
    cos_a = float(np.clip(np.dot(-d_in, d_out), -1.0, 1.0))
    turn = math.pi - math.acos(cos_a)                  # the direction change at the corner
    if radius <= 0 or turn < 1e-9:
        return [corner]
    tangent = radius * math.tan(turn / 2)
    p1 = corner - tangent * d_in
    normal = np.array([-d_in[1], d_in[0]])            # left of d_in
    side = 1.0 if d_in[0] * d_out[1] - d_in[1] * d_out[0] > 0 else -1.0
    centre = p1 + side * radius * normal
    a0 = math.atan2(*(p1 - centre)[::-1])
    p2 = corner + tangent * d_out
    a1 = math.atan2(*(p2 - centre)[::-1])
    da = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi
    return [centre + radius * np.array([math.cos(a0 + da * i / n_arc), math.sin(a0 + da * i / n_arc)])
            for i in range(n_arc + 1)]


def cleat_polyline(height_m: float, width_m: float, bevel_m: float = 0.0, round_m: float = 0.0,
                   n_arc: int = 8) -> np.ndarray:
    """The cleat as an (n, 2) array of (x, z) points, m, from (0, 0) to (width_m, 0).

    Parameters
    ----------
    height_m, width_m : float
        Cleat height and base width, m.
    bevel_m : float
        Horizontal length over which each edge rises, m (0: vertical edges).
    round_m : float
        Radius of the two rounded top edges, m (limited to what the edge lengths allow).
    n_arc : int
        Segments per rounded edge.
    """
    if not (0 <= 2 * bevel_m < width_m):
        raise ValueError("bevel_m must leave a flat top: 0 <= 2 bevel < width")
    corners = np.array([[0.0, 0.0], [bevel_m, height_m], [width_m - bevel_m, height_m], [width_m, 0.0]])
    d_rise = (corners[1] - corners[0]) / np.linalg.norm(corners[1] - corners[0])
    d_top = np.array([1.0, 0.0])
    d_fall = (corners[3] - corners[2]) / np.linalg.norm(corners[3] - corners[2])
    edge, top = np.linalg.norm(corners[1] - corners[0]), width_m - 2 * bevel_m
    turn = math.atan2(height_m, bevel_m) if bevel_m > 0 else math.pi / 2
    r_max = min(edge, top / 2) / max(math.tan(turn / 2), 1e-9)
    r = min(round_m, 0.9 * r_max)
    pts = [corners[0]]
    pts += _fillet(corners[1], d_rise, d_top, r, n_arc)
    pts += _fillet(corners[2], d_top, d_fall, r, n_arc)
    pts.append(corners[3])
    return np.array(pts, dtype=float)


@njit(cache=True)
def height_at(x, seg_x, seg_z):
    """Terrain height at x (the cleat's polyline, relative x) and its slope dz/dx."""
    n = seg_x.shape[0]
    if x <= seg_x[0] or x >= seg_x[n - 1]:
        return 0.0, 0.0
    for j in range(n - 1):
        if seg_x[j] <= x < seg_x[j + 1]:
            dx = seg_x[j + 1] - seg_x[j]
            slope = (seg_z[j + 1] - seg_z[j]) / dx
            return seg_z[j] + slope * (x - seg_x[j]), slope
    return 0.0, 0.0
