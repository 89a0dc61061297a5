"""The road profile table of a ``road_profile`` FMU: ``resources/cleatfmu_road.txt``.

Format: ``cleatfmu-road 1``, ``points N``, then N lines of five doubles written
as the 16 hexadecimal digits of their IEEE 754 bits (exact, locale-independent):
position x (increasing, m), left and right track heights (m) and their slopes
dh/dx (``numpy.gradient`` of each track over x, as the ride's model record uses).
"""

from __future__ import annotations

import math
import struct

import numpy as np

__all__ = ["ROAD_FILE", "road_table_bytes", "read_road_table", "default_road"]

ROAD_FILE = "cleatfmu_road.txt"


def _bits(value: float) -> str:
    return struct.pack(">d", float(value)).hex()


def road_table_bytes(x_m, left_m, right_m) -> bytes:
    """The table file of a two-track profile (slopes by ``numpy.gradient``)."""
    x = np.asarray(x_m, dtype=float)
    left, right = np.asarray(left_m, dtype=float), np.asarray(right_m, dtype=float)
    if x.ndim != 1 or x.size < 2 or left.shape != x.shape or right.shape != x.shape or np.any(np.diff(x) <= 0):
        raise ValueError("a road profile needs at least two increasing positions and one height per track each")
    if not all(np.all(np.isfinite(a)) for a in (x, left, right)):
        raise ValueError("a road profile must be finite")
    columns = (x, left, right, np.gradient(left, x), np.gradient(right, x))
    lines = ["cleatfmu-road 1", f"points {x.size}"]
    lines += [" ".join(_bits(c[i]) for c in columns) for i in range(x.size)]
    return ("\n".join(lines) + "\n").encode("ascii")


def read_road_table(data: bytes) -> dict:
    """``{"x", "left", "right", "left_slope", "right_slope"}`` of a table file."""
    lines = data.decode("ascii").splitlines()
    if lines[:1] != ["cleatfmu-road 1"]:
        raise ValueError("not a road profile table")
    n = int(lines[1].split()[1])
    rows = np.array([[struct.unpack(">d", bytes.fromhex(f))[0] for f in line.split()] for line in lines[2:2 + n]])
    return dict(zip(("x", "left", "right", "left_slope", "right_slope"), rows.T))


def default_road() -> tuple:
    """The profile of a road FMU built without one: 0-5 m, 2 cm grid, two sine tracks (m)."""
    x = np.linspace(0.0, 5.0, 251)
    return x, 0.01 * np.sin(2 * math.pi * x / 1.3), 0.008 * np.sin(2 * math.pi * x / 0.9 + 1.0)
