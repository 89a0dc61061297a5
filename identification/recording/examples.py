"""Recordings embedded in the package: a small cleat-test day.

The default tractor of the virtual rig (:mod:`identification.rig`) crossing the
40 mm cleat at 7 and 10 km/h, four hub channels, with the effects a real
tractor tire shows, and a compression test of the front tire for its static
stiffness (:func:`compression_path`).  Their truth files sit beside them for
tests and documentation; the pipeline never reads them.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from ..errors import InputError

__all__ = ["EXAMPLES", "example_path", "truth_path", "compression_path"]

#: Example name -> file stem in ``identification/data``.
EXAMPLES = {"7kmh": "testday_7kmh", "10kmh": "testday_10kmh"}


def _data_dir() -> Path:
    return Path(str(resources.files("identification") / "data"))


def example_path(name: str = "7kmh") -> Path:
    """Path of an embedded recording's CSV file."""
    if name not in EXAMPLES:
        raise InputError("--example", f"unknown example {name!r} (available: {', '.join(EXAMPLES)})")
    return _data_dir() / f"{EXAMPLES[name]}.csv"


def truth_path(name: str = "7kmh") -> Path:
    """Path of the rig truth file of an embedded recording (tests only)."""
    return example_path(name).with_suffix(".truth.json")


def compression_path() -> Path:
    """Path of the embedded compression test of the test day's front tire (``cleatfmu static``)."""
    return _data_dir() / "testday_compression.csv"
