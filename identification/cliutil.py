"""Argument checks shared by the command-line commands (one-line InputErrors)."""

from __future__ import annotations

import os

from .errors import InputError

__all__ = ["choose_tire", "check_output"]


def choose_tire(rec, tire: str | None) -> str:
    """The channel to work on: the one given, or the recording's only one."""
    if tire is None:
        if len(rec.tires) != 1:
            raise InputError(rec.source, f"holds channels {', '.join(rec.tires)}; choose one with --tire")
        return rec.tires[0]
    if tire not in rec.accel_m_s2:
        raise InputError(rec.source, f"tire {tire} is not in the recording (channels: {', '.join(rec.tires)})")
    return tire


def check_output(path, suffix: str, what: str) -> None:
    """Refuse an output path with the wrong suffix or in a missing directory (before any work is done)."""
    if path is None:
        return
    if not str(path).lower().endswith(suffix):
        raise InputError(path, f"the {what} file name must end with {suffix}")
    if not os.path.isdir(os.path.dirname(os.path.abspath(path))):
        raise InputError(path, "output directory does not exist")
