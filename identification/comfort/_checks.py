"""Argument checks shared by the comfort modules."""

from __future__ import annotations

import math

from ..errors import InputError

__all__ = ["positive"]


def positive(source: str, value) -> float:
    """`value` as a float, or InputError naming `source` unless it is a finite number > 0."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(source, f"must be a number, got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise InputError(source, f"must be a finite number > 0, got {value!r}")
    return v
