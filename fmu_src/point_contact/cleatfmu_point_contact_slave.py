"""Slave class of the point-contact tire FMU (FMI 2.0 co-simulation): spring k parallel to damper c.

A force element between road and hub in absolute vertical coordinates (SI
units, z upwards): inputs are the hub height and vertical velocity and the
road height and its rate under the contact point; the output force is
F = k δ + c δ̇ with δ = r0 − (z_hub − z_road), compressive positive.  An
importer whose body model includes gravity finds the static equilibrium
δ = m g / k by itself.

The outputs are direct feedthrough: they are evaluated from the inputs and
parameters set last, whenever they are read (no lag of one step).  The slave
has no internal state besides its variables.

Runtime contract (this file runs inside the FMU, on the importing machine):

* imports only the standard library, pythonfmu (embedded in the FMU) and
  modules the build places beside this file: ``cleatfmu_point_contact_law``,
  a verbatim copy of the project's tire law; ``cleatfmu_point_contact_table``,
  the table-driven slave base class shared by the kinds (a copy of
  ``fmu_src/table_slave.py``: outputs as direct feedthrough, checks, FMU
  state, error reporting; read its docstring);
  ``cleatfmu_point_contact_wrapper``, the workarounds for pythonfmu 0.7's FMI
  wrapper;
* the start values of this FMU instance are read from its own resources folder
  (``cleatfmu_point_contact_start.json``), never from module-level state, so
  that several FMUs of this kind in one process each keep their values;
* invalid values (non-finite inputs, k <= 0, c < 0, r0 <= 0, non-finite
  parameters) are rejected before they are stored: the FMU logs the reason
  with status error (delivered when the importer instantiated it with logging
  on) and the FMI call fails (pythonfmu 0.7 reports fmi2Fatal for every
  failing call); the instance keeps its previous valid values.  Reading an
  output fails the same way when the inputs are so extreme that the force
  overflows.
"""

from pythonfmu import DefaultExperiment

import cleatfmu_point_contact_law as _law
import cleatfmu_point_contact_table as _table
import cleatfmu_point_contact_wrapper as _wrapper

#: File in the FMU's resources folder with this instance's start values,
#: ``{"start": {name: value, ...}, "provenance": {...}}``.
START_FILE = "cleatfmu_point_contact_start.json"

#: Format tag of the FMU state (``fmi2GetFMUstate`` / serialization).
STATE_FORMAT = "cleatfmu_point_contact/1"

#: Every variable of the FMU, in value-reference order, with the columns of
#: ``cleatfmu_point_contact_table`` (read its docstring).  The build reads this
#: literal, without importing this file, to write units, descriptions and the
#: model structure.
VARIABLES = (
    ("hub_z", "Real", "input", "continuous", "m", "unloaded_radius", {},
     "Hub (wheel centre) height, absolute, m (z upwards); starts at the unloaded radius, "
     "i.e. zero deflection on a road at 0 m"),
    ("hub_vz", "Real", "input", "continuous", "m/s", 0.0, {},
     "Hub vertical velocity, m/s (upwards positive)"),
    ("road_z", "Real", "input", "continuous", "m", 0.0, {},
     "Road height under the contact point, absolute, m (z upwards)"),
    ("road_vz", "Real", "input", "continuous", "m/s", 0.0, {},
     "Rate of the road height under the contact point, m/s (upwards positive)"),
    ("stiffness", "Real", "parameter", "tunable", "N/m", 400000.0, {},
     "Vertical tire stiffness k, N/m (must be > 0)"),
    ("damping", "Real", "parameter", "tunable", "N.s/m", 2000.0, {},
     "Vertical tire damping coefficient c, N.s/m (must be >= 0)"),
    ("unloaded_radius", "Real", "parameter", "tunable", "m", 0.75, {},
     "Unloaded tire radius r0, m (must be > 0)"),
    ("force_z", "Real", "output", "continuous", "N", None,
     {"hub_z": "tunable", "hub_vz": "tunable", "road_z": "tunable", "road_vz": "tunable",
      "stiffness": "dependent", "damping": "dependent", "unloaded_radius": "dependent"},
     "Vertical tire force on the hub, N, compressive positive (pushes the hub up): "
     "stiffness*deflection + damping*deflection_rate; linear and bilateral (negative when lifted off)"),
    ("deflection", "Real", "output", "continuous", "m", None,
     {"hub_z": "constant", "road_z": "constant", "unloaded_radius": "constant"},
     "Tire deflection unloaded_radius - (hub_z - road_z), m (positive = compressed)"),
    ("deflection_rate", "Real", "output", "continuous", "m/s", None,
     {"hub_vz": "constant", "road_vz": "constant"},
     "Deflection rate road_vz - hub_vz, m/s (positive = compressing)"),
    ("in_contact", "Boolean", "output", "discrete", "", None,
     {"hub_z": "dependent", "road_z": "dependent", "unloaded_radius": "dependent"},
     "Contact flag, dimensionless: true when deflection > 0 m"),
)

_VR = {row[0]: vr for vr, row in enumerate(VARIABLES)}
_HUB_Z, _HUB_VZ, _ROAD_Z, _ROAD_VZ = _VR["hub_z"], _VR["hub_vz"], _VR["road_z"], _VR["road_vz"]
_K, _C, _R0 = _VR["stiffness"], _VR["damping"], _VR["unloaded_radius"]
_FORCE, _DEFL, _RATE, _CONTACT = _VR["force_z"], _VR["deflection"], _VR["deflection_rate"], _VR["in_contact"]


class CleatfmuPointContact(_table.TableSlave):
    """Point-contact tire: F = k (r0 - (z_hub - z_road)) + c (vz_road - vz_hub)."""

    author = "cleatfmu"
    description = "Point-contact tire (spring k parallel to damper c) between hub and road, SI units"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=0.5, step_size=0.001)

    variables = VARIABLES
    start_file = START_FILE
    state_format = STATE_FORMAT
    wrapper = _wrapper

    def evaluate(self, values):
        """Write force_z, deflection, deflection_rate and in_contact into `values` (see the base class)."""
        v = values
        v[_FORCE], v[_DEFL], v[_RATE], v[_CONTACT] = _law.point_contact(
            v[_HUB_Z], v[_HUB_VZ], v[_ROAD_Z], v[_ROAD_VZ], v[_K], v[_C], v[_R0])

    def set_problem(self, values):
        """Why k, c or r0 of `values` is invalid, or None (see the base class)."""
        return _law.parameter_problem(values[_K], values[_C], values[_R0])
