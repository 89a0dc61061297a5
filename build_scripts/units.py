"""SI units known to the FMU build, as exponents of the SI base units.

Every Real variable of an FMU names one of these units; the build writes a
``<UnitDefinitions>`` entry with its ``<BaseUnit>`` exponents (FMI 2.0, 2.2.2),
so that importers can check and convert units.
"""

from __future__ import annotations

__all__ = ["SI_UNITS", "base_unit_exponents"]

#: unit name -> {base unit: exponent}; base units as in FMI 2.0 (kg, m, s, A, K, mol, cd, rad).
SI_UNITS: dict[str, dict[str, int]] = {
    "1": {},
    "m": {"m": 1},
    "s": {"s": 1},
    "kg": {"kg": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
}


def base_unit_exponents(unit: str) -> dict[str, int]:
    """Exponents of the SI base units of `unit`.

    Raises
    ------
    ValueError
        For a unit not in :data:`SI_UNITS`.
    """
    try:
        return SI_UNITS[unit]
    except KeyError:
        raise ValueError(f"unit {unit!r} is not a known SI unit (known: {', '.join(SI_UNITS)})") from None
