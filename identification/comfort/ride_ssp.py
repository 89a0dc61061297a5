"""The ride as systems of FMUs: one SSP 1.0 archive per tire parameter set (``cleatfmu ride --ssp DIR``).

Each archive is the ride's model record (:func:`identification.model.ride.ride_model`) as written by
:func:`identification.fmu.ssp.write_tractor_ssp`: the body FMU, four tire FMUs with the set's k and c and
the road profile FMU with the ride's two tracks, default experiment over the ride's duration.  In a host
that steps the body, then the road and the tires (sequential exchange) it reproduces ``ride`` to
round-off; fixed-step hosts that exchange once after all steps add a one-step force delay.
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path
from .._files import temp_prefix

__all__ = ["ssp_file_name", "write_ride_ssps"]


def ssp_file_name(name: str) -> str:
    """A file name for parameter set `name` (``static=300e3`` -> ``static_300e3.ssp``; a path keeps its stem)."""
    if "=" in name:
        kind, value = name.split("=", 1)
        value = Path(value).stem if ("/" in value or "\\" in value or value.lower().endswith(".csv")) else value
        name = f"{kind}_{value}"
    return re.sub(r"[^A-Za-z0-9_.+-]", "_", name) + ".ssp"


def write_ride_ssps(folder, body, sets: dict, *, road, speed_m_s: float, duration_s: float, seat_x_m: float,
                    seat_y: float = 0.0, step_s: float = 1e-3) -> dict:
    """Write ``folder/<set>.ssp`` for every set ``name -> (k, c)``, all together or none; returns name -> Path."""
    from .._files import publish_files
    from ..fmu.ssp import write_tractor_ssp
    from ..model.ride import ride_model
    from .ride import _point_contact

    folder = Path(folder)
    names = {name: ssp_file_name(name) for name in sets}
    if len(set(names.values())) != len(names):
        raise ValueError(f"two parameter sets give the same SSP file name: {sorted(names.values())}")
    with tempfile.TemporaryDirectory(prefix=temp_prefix("ridessp")) as tmp:
        staged = {}
        for name, (k, c) in sets.items():
            laws = [_point_contact(k[t], c[t], load) for t, load in zip(body.tires, body.loads_n)]
            model = ride_model(body, laws, speed_m_s=speed_m_s, road_x_m=road.x_m, road_left_m=road.left_m,
                               road_right_m=road.right_m)
            path = Path(tmp, names[name])
            write_tractor_ssp(path, model, start_s=0.0, stop_s=float(duration_s), step_s=step_s,
                              seat_x_m=seat_x_m, seat_y=seat_y, name=path.stem,
                              description=f"Ride on {_road_name(road)} at "
                                          f"{speed_m_s * 3.6:.3g} km/h, tire set {name}")
            staged[folder / names[name]] = path
        publish_files(staged)
    return {name: folder / names[name] for name in sets}


def _road_name(road) -> str:
    return "a road read from a file" if road.road_class == "file" else f"an ISO 8608 class {road.road_class} road"
