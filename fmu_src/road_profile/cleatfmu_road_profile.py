"""Variable table of the road profile FMU (native C only: ``fmu_src/native/cleatfmu_road.c``).

A two-track road profile (a table in the FMU's resources, ``cleatfmu_road.txt``,
see :mod:`build_scripts.road_table`) under the four tires of the tractor: tire T
at x = start_x + speed t (a rear tire one wheelbase behind) on its side's track,
faded in over ``ramp_length`` from the profile's first point - the road of the
ride's model record (:class:`identification.comfort.ride.RideModel`).  The
outputs depend on time only.  The build reads this table with :mod:`ast`;
``config.h`` of the native kind must match it.
"""

START_FILE = "cleatfmu_start.txt"

VARIABLES = (
    ("speed", "Real", "parameter", "fixed", "m/s", 1.9444444444444444, {},
     "Driving speed, m/s: the hubs' longitudinal velocity"),
    ("start_x", "Real", "parameter", "fixed", "m", 0.2, {},
     "Position of the front axle on the profile at time 0, m"),
    ("wheelbase", "Real", "parameter", "fixed", "m", 2.5, {},
     "Wheelbase, m: the rear tires roll one wheelbase behind the front ones (>= 0)"),
    ("ramp_length", "Real", "parameter", "fixed", "m", 0.5, {},
     "The profile is faded in (smoothstep) over this distance from its first point, m (> 0)"),
    ("road_z_FL", "Real", "output", "continuous", "m", None, {}, "Road height under FL (left track), m"),
    ("road_z_FR", "Real", "output", "continuous", "m", None, {}, "Road height under FR (right track), m"),
    ("road_z_RL", "Real", "output", "continuous", "m", None, {}, "Road height under RL (left track), m"),
    ("road_z_RR", "Real", "output", "continuous", "m", None, {}, "Road height under RR (right track), m"),
    ("road_vz_FL", "Real", "output", "continuous", "m/s", None, {}, "Rate of the road height under FL, m/s"),
    ("road_vz_FR", "Real", "output", "continuous", "m/s", None, {}, "Rate of the road height under FR, m/s"),
    ("road_vz_RL", "Real", "output", "continuous", "m/s", None, {}, "Rate of the road height under RL, m/s"),
    ("road_vz_RR", "Real", "output", "continuous", "m/s", None, {}, "Rate of the road height under RR, m/s"),
)
