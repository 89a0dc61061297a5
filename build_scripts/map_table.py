"""The table of a ``map_tire`` FMU: ``resources/cleatfmu_map.txt``.

Format: ``cleatfmu-map 1``, ``tested LOW HIGH`` (the speed range the map's runs
covered, m/s), ``nodes N``, then N lines of three doubles: speed (increasing,
m/s), k (N/m, > 0) and c (N s/m, >= 0); every double written as the 16
hexadecimal digits of its IEEE 754 bits (exact, locale-independent).  The FMU
interpolates k and c linearly between the nodes and holds them outside
(``numpy.interp``); a speed outside the tested range is an extrapolation.
"""

from __future__ import annotations

import math
import struct

__all__ = ["MAP_FILE", "map_table_bytes", "read_map_table", "default_map", "map_table_problem"]

MAP_FILE = "cleatfmu_map.txt"


def _bits(value: float) -> str:
    return struct.pack(">d", float(value)).hex()


def map_table_problem(speed_m_s, k_n_m, c_ns_m, tested_m_s) -> str | None:
    """Why the nodes and the tested range make no map (one line), or None."""
    speed, k, c = list(map(float, speed_m_s)), list(map(float, k_n_m)), list(map(float, c_ns_m))
    low, high = map(float, tested_m_s)
    if not speed or len(k) != len(speed) or len(c) != len(speed):
        return "a tire map needs at least one node and one k and one c per node"
    if not all(math.isfinite(x) for x in (*speed, *k, *c, low, high)):
        return "a tire map's speeds, k and c must be finite"
    if any(b <= a for a, b in zip(speed, speed[1:])):
        return "a tire map's node speeds must increase"
    if not all(x > 0 for x in k) or not all(x >= 0 for x in c):
        return "a tire map needs k > 0 and c >= 0 at every node"
    if not low <= high:
        return "a tire map's tested range must be LOW <= HIGH"
    return None


def map_table_bytes(speed_m_s, k_n_m, c_ns_m, tested_m_s) -> bytes:
    """The table file of a tire map (nodes and the tested speed range, SI units).

    Raises
    ------
    ValueError
        For nodes or a range that make no map (:func:`map_table_problem`).
    """
    problem = map_table_problem(speed_m_s, k_n_m, c_ns_m, tested_m_s)
    if problem:
        raise ValueError(problem)
    low, high = tested_m_s
    lines = ["cleatfmu-map 1", f"tested {_bits(low)} {_bits(high)}", f"nodes {len(speed_m_s)}"]
    lines += [f"{_bits(v)} {_bits(k)} {_bits(c)}" for v, k, c in zip(speed_m_s, k_n_m, c_ns_m)]
    return ("\n".join(lines) + "\n").encode("ascii")


def read_map_table(data: bytes) -> dict:
    """``{"speed", "k", "c": lists, "tested": (low, high)}`` of a table file."""
    lines = data.decode("ascii").splitlines()
    if lines[:1] != ["cleatfmu-map 1"] or not lines[1].startswith("tested "):
        raise ValueError("not a tire map table")

    def number(field):
        return struct.unpack(">d", bytes.fromhex(field))[0]

    tested = tuple(number(f) for f in lines[1].split()[1:])
    n = int(lines[2].split()[1])
    rows = [[number(f) for f in line.split()] for line in lines[3:3 + n]]
    return {"speed": [r[0] for r in rows], "k": [r[1] for r in rows], "c": [r[2] for r in rows], "tested": tested}


def default_map() -> tuple:
    """The map of a ``map_tire`` FMU built without one: nodes at 1, 2, 3, 4 m/s, tested 1-4 m/s (SI units)."""
    return ((1.0, 2.0, 3.0, 4.0), (560e3, 548e3, 531e3, 509e3), (4600.0, 4200.0, 3900.0, 3300.0), (1.0, 4.0))
