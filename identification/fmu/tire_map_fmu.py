"""A tire map -> the map FMU of one tire (native C, kind ``map_tire``).

The FMU is the point-contact tire whose k and c follow its input ``speed``: the map's nodes (speed, k, c)
and tested speed range go into its resources (``cleatfmu_map.txt``, :mod:`build_scripts.map_table`); it
interpolates them linearly and holds them outside the nodes, and flags a speed outside the tested range
(output ``extrapolating``, a warning in the FMI log once per excursion).  Its outputs ``stiffness`` and
``damping`` show the values in use.  The speed starts at the middle of the tested range and the hub at
the static equilibrium of the tire's mean tested wheel load there.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._files import OutputFolders, make_folders
from ..errors import InputError
from .export import DEFAULT_UNLOADED_RADIUS_M

__all__ = ["MAP_FMU_KIND", "export_map_fmu"]

#: The FMU kind (folder of ``fmu_src``) of a map FMU.
MAP_FMU_KIND = "map_tire"


def export_map_fmu(doc: dict, tire: str, output_path, *, unloaded_radius_m: float | None = None,
                   fmi_version: int = 2, platforms=None) -> Path:
    """Build the map FMU of `tire` from a tire map document.

    Parameters
    ----------
    doc : dict
        A checked tire map (:func:`identification.identify.tire_map.check_map`).
    tire : str
        One of its tires.
    output_path : path-like
        The ``.fmu`` to write (atomically); missing folders are created.
    unloaded_radius_m : float, optional
        r0, m (default :data:`identification.fmu.export.DEFAULT_UNLOADED_RADIUS_M`, an assumption).
    fmi_version : int
        2 or 3.
    platforms : list of str, optional
        Platforms (default: all).

    Returns
    -------
    Path
        `output_path`.
    """
    from build_scripts import build_fmu
    from build_scripts.map_table import MAP_FILE, map_table_bytes

    if tire not in doc["tires"]:
        raise InputError(None, f"the map has no tire {tire} (it has {', '.join(doc['tires'])})")
    m = doc["tires"][tire]
    nodes, (low, high) = m["nodes"], m["tested_speed_m_s"]
    radius = DEFAULT_UNLOADED_RADIUS_M if unloaded_radius_m is None else float(unloaded_radius_m)
    speed = 0.5 * (low + high)
    load = float(np.mean(m["wheel_load_N"]))
    k0 = float(np.interp(speed, nodes["speed_m_s"], nodes["k"]))
    starts = {"speed": speed, "unloaded_radius": radius, "hub_z": radius - load / k0}
    table = map_table_bytes(nodes["speed_m_s"], nodes["k"], nodes["c"], (low, high))
    provenance = {"command": "cleatfmu map", "tire": tire, "map": {key: doc.get(key) for key in
                                                                    ("source", "values", "rule", "outside")},
                  "tire_map": m, "unloaded_radius_m": radius,
                  "unloaded_radius_source": "given" if unloaded_radius_m is not None else "default assumption"}
    description = (f"Tire {tire} map (cleatfmu map): point-contact tire whose k and c follow the input speed, "
                   f"tested {3.6 * low:.3g}-{3.6 * high:.3g} km/h ({low:.4g}-{high:.4g} m/s; outside: "
                   f"extrapolation, flagged); k degree {m['k']['degree']}, c degree {m['c']['degree']} in speed; "
                   f"unloaded radius {radius:g} m "
                   f"({'given' if unloaded_radius_m is not None else 'default assumption'}); SI units; native C")
    output_path = Path(output_path)
    try:
        with OutputFolders():
            make_folders(output_path.parent)
            return build_fmu(MAP_FMU_KIND, output_path, start_values=starts, provenance=provenance,
                             description=description, backend="native", fmi_version=fmi_version,
                             platforms=platforms, resources={MAP_FILE: table})
    except OSError as exc:
        raise InputError(output_path, f"cannot write: {exc.strerror or exc}") from None
