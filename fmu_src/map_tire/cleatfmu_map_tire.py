"""Variable table of the tire-map FMU (native C only: ``fmu_src/native/cleatfmu_map.c``).

The point-contact tire (spring k parallel to damper c between hub and road, the
law of ``point_contact``) whose k and c follow the input ``speed`` through a
tire map: a table of nodes (speed, k, c) and the tested speed range in the FMU's
resources (``cleatfmu_map.txt``, see :mod:`build_scripts.map_table`), interpolated
linearly between the nodes and held at the first or last node outside them.  A
speed outside the tested range sets ``extrapolating`` and is logged once per
excursion (category ``logStatusWarning``).  The build reads this table with
:mod:`ast`; ``config.h`` of the native kind must match it.
"""

START_FILE = "cleatfmu_start.txt"

VARIABLES = (
    ("hub_z", "Real", "input", "continuous", "m", "unloaded_radius", {},
     "Hub (wheel centre) height, absolute, m (z upwards)"),
    ("hub_vz", "Real", "input", "continuous", "m/s", 0.0, {},
     "Hub vertical velocity, m/s (upwards positive)"),
    ("road_z", "Real", "input", "continuous", "m", 0.0, {},
     "Road height under the contact point, absolute, m (z upwards)"),
    ("road_vz", "Real", "input", "continuous", "m/s", 0.0, {},
     "Rate of the road height under the contact point, m/s (upwards positive)"),
    ("speed", "Real", "input", "continuous", "m/s", 2.5, {},
     "Driving speed, m/s: k and c are the map's at this speed (outside the tested range: extrapolation, "
     "the nearest node's values)"),
    ("unloaded_radius", "Real", "parameter", "tunable", "m", 0.75, {},
     "Unloaded tire radius r0, m (must be > 0)"),
    ("force_z", "Real", "output", "continuous", "N", None,
     {"hub_z": "tunable", "hub_vz": "tunable", "road_z": "tunable", "road_vz": "tunable", "speed": "dependent",
      "unloaded_radius": "dependent"},
     "Vertical tire force on the hub, N, compressive positive: stiffness*deflection + damping*deflection_rate "
     "with the map's k and c at the speed; linear and bilateral (negative when lifted off)"),
    ("deflection", "Real", "output", "continuous", "m", None,
     {"hub_z": "constant", "road_z": "constant", "unloaded_radius": "constant"},
     "Tire deflection unloaded_radius - (hub_z - road_z), m (positive = compressed)"),
    ("deflection_rate", "Real", "output", "continuous", "m/s", None,
     {"hub_vz": "constant", "road_vz": "constant"},
     "Deflection rate road_vz - hub_vz, m/s (positive = compressing)"),
    ("in_contact", "Boolean", "output", "discrete", "", None,
     {"hub_z": "dependent", "road_z": "dependent", "unloaded_radius": "dependent"},
     "Contact flag, dimensionless: true when deflection > 0 m"),
    ("stiffness", "Real", "output", "continuous", "N/m", None, {"speed": "dependent"},
     "Vertical tire stiffness k at the speed, N/m: the map's nodes interpolated linearly, held outside them"),
    ("damping", "Real", "output", "continuous", "N.s/m", None, {"speed": "dependent"},
     "Vertical tire damping c at the speed, N.s/m: the map's nodes interpolated linearly, held outside them"),
    ("extrapolating", "Boolean", "output", "discrete", "", None, {"speed": "dependent"},
     "True when the speed is outside the map's tested range: k and c are extrapolated (logged once per "
     "excursion, category logStatusWarning)"),
)
