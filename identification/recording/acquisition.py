"""How a recording's channels were acquired: the sidecar's ``"acquisition"`` (anti-alias filter, AC coupling).

The model of this chain, applied to a model's hub motion, is :mod:`identification.model.acquisition`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import InputError

__all__ = ["Acquisition", "acquisition_from_sidecar", "MAX_ORDER"]

#: Highest accepted anti-alias filter order.
MAX_ORDER = 12


@dataclass(frozen=True)
class Acquisition:
    """How a channel was acquired (sidecar key ``"acquisition"``).

    Parameters
    ----------
    anti_alias_order : int
        Order N of the analog Butterworth anti-alias filter (0: none).
    anti_alias_cutoff_hz : float
        Its cut-off f_aa, Hz (below half the sampling rate).
    highpass_hz : float
        Corner of the AC coupling's first-order high-pass, Hz (0: none).
    """

    anti_alias_order: int = 0
    anti_alias_cutoff_hz: float = 0.0
    highpass_hz: float = 0.0

    def __post_init__(self):
        if isinstance(self.anti_alias_order, bool) or not isinstance(self.anti_alias_order, int) \
                or not 0 <= self.anti_alias_order <= MAX_ORDER:
            raise ValueError(f"anti_alias_order must be an integer 0..{MAX_ORDER}, got {self.anti_alias_order!r}")
        for name in ("anti_alias_cutoff_hz", "highpass_hz"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or value < 0:
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if self.anti_alias_order and not self.anti_alias_cutoff_hz > 0:
            raise ValueError("anti_alias_cutoff_hz must be > 0 with an anti-alias filter")

    def to_json(self) -> dict:
        return {"anti_alias_order": self.anti_alias_order, "anti_alias_cutoff_hz": float(self.anti_alias_cutoff_hz),
                "highpass_hz": float(self.highpass_hz)}


def acquisition_from_sidecar(path, value) -> Acquisition:
    """The sidecar's ``"acquisition"`` object as an :class:`Acquisition` (InputError naming `path`)."""
    if not isinstance(value, dict):
        raise InputError(path, 'acquisition must be an object such as {"anti_alias_order": 4, '
                               '"anti_alias_cutoff_hz": 250, "highpass_hz": 0.05}')
    unknown = set(value) - {"anti_alias_order", "anti_alias_cutoff_hz", "highpass_hz"}
    if unknown:
        raise InputError(path, f"acquisition: unknown key {sorted(unknown)[0]!r} (known: anti_alias_order, "
                               "anti_alias_cutoff_hz, highpass_hz)")
    order = value.get("anti_alias_order", 0)
    if isinstance(order, float) and order.is_integer():
        order = int(order)
    try:
        return Acquisition(anti_alias_order=order, anti_alias_cutoff_hz=value.get("anti_alias_cutoff_hz", 0.0),
                           highpass_hz=value.get("highpass_hz", 0.0))
    except ValueError as exc:
        raise InputError(path, f"acquisition: {exc}") from None
