"""The embedded cleat-test day: how ``identification/data`` was made.

The default tractor over the 40 mm cleat at 7 and 10 km/h, four channels, with
what a real tractor tire shows: its footprint envelops the cleat
(``enveloping``), the tractor is one rigid body (``axle_coupling``), the tire
cannot pull the hub down (``lift_off``), the two cleats are not quite aligned,
and the accelerometers are noisy; and a compression test of its front tire
(:mod:`identification.rig.compression`), for the static stiffness.  Regenerate with
``python -m identification.rig.testday DIR``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .compression import write_compression
from .generate import run_rig, write_run

__all__ = ["TESTDAY", "COMPRESSION", "write_testday"]

_EFFECTS = ("enveloping", "axle_coupling", "lift_off")
_COMMON = {"cleat.stagger_m": 0.03, "sensor.noise_m_s2": 0.05}

#: File stem -> (effects, parameter overrides, seed).
TESTDAY = {
    "testday_7kmh": (_EFFECTS, dict(_COMMON, speed_kmh=7.0), 7),
    "testday_10kmh": (_EFFECTS, dict(_COMMON, speed_kmh=10.0), 10),
}

#: File stem of the front tire's compression test (the rig's default: FL's dynamic 550 kN/m, static 400 kN/m).
COMPRESSION = "testday_compression"


def write_testday(directory) -> list[Path]:
    """Write the test-day recordings (CSV, sidecar and truth) and the compression test into `directory`."""
    out = []
    for stem, (effects, overrides, seed) in TESTDAY.items():
        csv_path, _ = write_run(run_rig(effects, overrides, seed=seed), Path(directory) / stem, value_decimals=3)
        out.append(csv_path)
    out.append(write_compression(Path(directory) / COMPRESSION))
    return out


if __name__ == "__main__":  # pragma: no cover
    for path in write_testday(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parents[1] / "data"):
        print(path)
