"""Slave class of the extended tire FMU (FMI 2.0 co-simulation): the project's extended tire law.

A force element between road and hub in absolute coordinates (SI units, z
upwards, x along the travel): the point-contact spring k parallel to damper c,
with the options of ``identification/model/tire_law.py`` (:func:`extended_tire`),
each a tunable parameter whose default switches it off — a built-in
cleat, rectangular or bevelled (a trapezoid, ``cleat_bevel``), enveloped by a
footprint (uniform contact pressure, or parabolic with
``parabolic_pressure``, or a rigid ring over an elastic bed with ``ring_envelope``), road-equivalent lugs, progressive
stiffness, regularised Coulomb friction and unilateral contact.  With every
option at its default the force is the point-contact tire's.

Runtime contract (this file runs inside the FMU, on the importing machine):

* imports only the standard library, pythonfmu (embedded in the FMU) and
  modules the build places beside this file: ``cleatfmu_extended_tire_law``,
  a verbatim copy of the project's tire law; ``cleatfmu_extended_tire_table``,
  the table-driven slave base class shared by the kinds (a copy of
  ``fmu_src/table_slave.py``: outputs as direct feedthrough, checks, FMU
  state, error reporting; read its docstring); ``cleatfmu_extended_tire_wrapper``,
  the workarounds for pythonfmu 0.7's FMI wrapper;
* the start values of this FMU instance are read from its own resources
  folder (``cleatfmu_extended_tire_start.json``), never from module-level
  state, so that several FMUs of this kind in one process each keep theirs;
* importers set parameters one at a time, so a value is refused when set only
  if it is invalid by itself (:func:`_value_problem`); the constraints
  between parameters (static_load > 0 N when stiffness_exponent != 1 or
  ring_envelope, cleat_bevel <= cleat_width / 2) make the next evaluation, step or exit
  from initialization mode fail until they hold.
"""

from pythonfmu import DefaultExperiment

import cleatfmu_extended_tire_law as _law
import cleatfmu_extended_tire_table as _table
import cleatfmu_extended_tire_wrapper as _wrapper

#: File in the FMU's resources folder with this instance's start values.
START_FILE = "cleatfmu_extended_tire_start.json"

#: Format tag of the FMU state (``fmi2GetFMUstate`` / serialization).
STATE_FORMAT = "cleatfmu_extended_tire/1"

#: Every variable of the FMU, in value-reference order, with the columns of
#: ``cleatfmu_extended_tire_table`` (read its docstring); the parameters'
#: starts are ``tire_law.EXTENDED_DEFAULTS``.  The build reads this literal,
#: without importing this file, to write units, descriptions and the model
#: structure.  A new variable is appended (as ``parabolic_pressure``,
#: ``cleat_bevel`` and ``ring_envelope`` were), so that the value references of the others never
#: change; the native FMU's table (``fmu_src/native/extended_tire/config.h``)
#: must list the same rows.
VARIABLES = (
    ("hub_z", "Real", "input", "continuous", "m", "unloaded_radius", {},
     "Hub (wheel centre) height, absolute, m (z upwards); starts at the unloaded radius, "
     "i.e. zero deflection on a road at 0 m"),
    ("hub_vz", "Real", "input", "continuous", "m/s", 0.0, {},
     "Hub vertical velocity, m/s (upwards positive)"),
    ("road_z", "Real", "input", "continuous", "m", 0.0, {},
     "Road height under the contact point besides the built-in cleat and the lugs, absolute, m (z upwards)"),
    ("road_vz", "Real", "input", "continuous", "m/s", 0.0, {},
     "Rate of road_z, m/s (upwards positive)"),
    ("hub_x", "Real", "input", "continuous", "m", 0.0, {},
     "Hub longitudinal position, m, along the travel (the built-in cleat's leading edge is at cleat_x)"),
    ("hub_vx", "Real", "input", "continuous", "m/s", 0.0, {},
     "Hub longitudinal velocity, m/s (rate of hub_x)"),
    ("stiffness", "Real", "parameter", "tunable", "N/m", 400000.0, {},
     "Vertical tire stiffness k, N/m (> 0; the tangent stiffness at static_load when stiffness_exponent != 1)"),
    ("damping", "Real", "parameter", "tunable", "N.s/m", 2000.0, {},
     "Vertical tire damping coefficient c, N.s/m (>= 0)"),
    ("unloaded_radius", "Real", "parameter", "tunable", "m", 0.75, {},
     "Unloaded tire radius r0, m (> 0)"),
    ("footprint_length", "Real", "parameter", "tunable", "m", 0.0, {},
     "Length l of the footprint over which the built-in cleat is averaged, m (>= 0; "
     "0: the cleat is felt under the contact point only); contact pressure uniform, or parabolic "
     "when parabolic_pressure"),
    ("cleat_x", "Real", "parameter", "tunable", "m", 0.0, {},
     "Longitudinal position of the built-in cleat's leading edge, m"),
    ("cleat_height", "Real", "parameter", "tunable", "m", 0.0, {},
     "Height H of the built-in cleat (rectangular, or a trapezoid when cleat_bevel > 0), m (>= 0; "
     "0: no built-in cleat)"),
    ("cleat_width", "Real", "parameter", "tunable", "m", 0.1, {},
     "Width w of the built-in cleat along the travel, at its base, m (> 0)"),
    ("unilateral", "Boolean", "parameter", "tunable", "", False, {},
     "Unilateral contact, dimensionless: when true the force is 0 N unless deflection > 0 m and the force "
     "would push (the tire never pulls); when false the law is bilateral"),
    ("stiffness_exponent", "Real", "parameter", "tunable", "1", 1.0, {},
     "Exponent n of the progressive elastic force static_load*sign(d)*|d/d_W|^n, d_W = n*static_load/stiffness, "
     "dimensionless (> 0; 1: linear spring stiffness*d)"),
    ("static_load", "Real", "parameter", "tunable", "N", 0.0, {},
     "Static wheel load W at which stiffness is the tangent stiffness, N (>= 0; > 0 when stiffness_exponent != 1)"),
    ("friction_force", "Real", "parameter", "tunable", "N", 0.0, {},
     "Amplitude F_c of the regularised Coulomb force F_c*tanh(deflection_rate/friction_velocity), N (>= 0)"),
    ("friction_velocity", "Real", "parameter", "tunable", "m/s", 0.01, {},
     "Regularisation velocity v_f of the Coulomb force, m/s (> 0)"),
    ("lug_amplitude", "Real", "parameter", "tunable", "m", 0.0, {},
     "Amplitude A of the road-equivalent lug passing A*sin(2*pi*hub_x/lug_pitch + lug_phase), m (0: no lugs)"),
    ("lug_pitch", "Real", "parameter", "tunable", "m", 0.25, {},
     "Lug pitch p along the travel, m (> 0)"),
    ("lug_phase", "Real", "parameter", "tunable", "rad", 0.0, {},
     "Lug phase phi at hub_x = 0 m, rad"),
    ("force_z", "Real", "output", "continuous", "N", None,
     {"hub_z": "dependent", "hub_vz": "dependent", "road_z": "dependent", "road_vz": "dependent",
      "hub_x": "dependent", "hub_vx": "dependent", "stiffness": "dependent", "damping": "dependent",
      "unloaded_radius": "dependent", "footprint_length": "dependent", "cleat_x": "dependent",
      "cleat_height": "dependent", "cleat_width": "dependent", "unilateral": "dependent",
      "stiffness_exponent": "dependent", "static_load": "dependent", "friction_force": "dependent",
      "friction_velocity": "dependent", "lug_amplitude": "dependent", "lug_pitch": "dependent",
      "lug_phase": "dependent", "parabolic_pressure": "dependent", "cleat_bevel": "dependent", "ring_envelope": "dependent"},
     "Vertical tire force on the hub, N, compressive positive (pushes the hub up): elastic force + "
     "damping*deflection_rate + friction; 0 N when unilateral and not in_contact"),
    ("deflection", "Real", "output", "continuous", "m", None,
     {"hub_z": "dependent", "road_z": "dependent", "hub_x": "dependent", "unloaded_radius": "dependent",
      "footprint_length": "dependent", "cleat_x": "dependent", "cleat_height": "dependent",
      "cleat_width": "dependent", "lug_amplitude": "dependent", "lug_pitch": "dependent", "lug_phase": "dependent",
      "parabolic_pressure": "dependent", "cleat_bevel": "dependent", "ring_envelope": "dependent"},
     "Tire deflection unloaded_radius - (hub_z - road_effective_z), m (positive = compressed)"),
    ("deflection_rate", "Real", "output", "continuous", "m/s", None,
     {"hub_z": "dependent", "hub_vz": "constant", "road_z": "dependent", "road_vz": "constant",
      "hub_x": "dependent", "hub_vx": "dependent",
      "footprint_length": "dependent", "cleat_x": "dependent", "cleat_height": "dependent",
      "cleat_width": "dependent", "lug_amplitude": "dependent", "lug_pitch": "dependent", "lug_phase": "dependent",
      "parabolic_pressure": "dependent", "cleat_bevel": "dependent", "ring_envelope": "dependent"},
     "Deflection rate road_vz + (slope of cleat and lugs along x)*hub_vx - hub_vz, m/s (positive = compressing)"),
    ("in_contact", "Boolean", "output", "discrete", "", None,
     {"hub_z": "dependent", "hub_vz": "dependent", "road_z": "dependent", "road_vz": "dependent",
      "hub_x": "dependent", "hub_vx": "dependent", "stiffness": "dependent", "damping": "dependent",
      "unloaded_radius": "dependent", "footprint_length": "dependent", "cleat_x": "dependent",
      "cleat_height": "dependent", "cleat_width": "dependent", "unilateral": "dependent",
      "stiffness_exponent": "dependent", "static_load": "dependent", "friction_force": "dependent",
      "friction_velocity": "dependent", "lug_amplitude": "dependent", "lug_pitch": "dependent",
      "lug_phase": "dependent", "parabolic_pressure": "dependent", "cleat_bevel": "dependent", "ring_envelope": "dependent"},
     "Contact flag, dimensionless: deflection > 0 m, and when unilateral also force_z > 0 N"),
    ("road_effective_z", "Real", "output", "continuous", "m", None,
     {"hub_z": "dependent", "road_z": "dependent", "hub_x": "dependent", "footprint_length": "dependent",
      "cleat_x": "dependent",
      "cleat_height": "dependent", "cleat_width": "dependent", "lug_amplitude": "dependent",
      "lug_pitch": "dependent", "lug_phase": "dependent", "parabolic_pressure": "dependent",
      "cleat_bevel": "dependent", "ring_envelope": "dependent"},
     "Effective road height the tire feels, m: road_z + built-in cleat averaged over the footprint (with "
     "ring_envelope: its equivalent height at the hub's deflection) + lugs"),
    ("parabolic_pressure", "Boolean", "parameter", "tunable", "", False, {},
     "Parabolic footprint pressure, dimensionless: when true the built-in cleat is averaged over the footprint "
     "weighted by a contact pressure proportional to 1 - (2*xi/footprint_length)^2 (xi: distance from the "
     "footprint's centre), zero at the footprint's ends; when false the pressure is uniform (no effect when "
     "footprint_length = 0 m)"),
    ("cleat_bevel", "Real", "parameter", "tunable", "m", 0.0, {},
     "Bevel b of the built-in cleat, m (>= 0; <= cleat_width/2): the cleat rises linearly from 0 m to "
     "cleat_height over b from its leading edge cleat_x and falls linearly to 0 m over b to its trailing edge "
     "cleat_x + cleat_width, a trapezoid; 0: a rectangular cleat with vertical edges"),
    ("ring_envelope", "Boolean", "parameter", "tunable", "", False, {},
     "Rigid-ring envelope, dimensionless: when true (and footprint_length > 0 m) the built-in cleat is seen "
     "through a rigid ring of radius footprint_length^2/(8*d_W) over an elastic bed (pressure proportional to "
     "the square root of its compression; d_W = stiffness_exponent*static_load/stiffness, so footprint_length "
     "is the flat contact at the static load; static_load > 0 N): contact starts sqrt(2*R*(deflection + "
     "cleat_height)) ahead of the hub, and the cleat (as the rectangle of the same area when bevelled) acts as "
     "an equivalent height that depends on the deflection; parabolic_pressure is then not used"),
)

_VR = {row[0]: vr for vr, row in enumerate(VARIABLES)}
_HUB_Z, _HUB_VZ, _HUB_X, _HUB_VX = _VR["hub_z"], _VR["hub_vz"], _VR["hub_x"], _VR["hub_vx"]
_ROAD_Z, _ROAD_VZ = _VR["road_z"], _VR["road_vz"]
_FORCE, _DEFL, _RATE = _VR["force_z"], _VR["deflection"], _VR["deflection_rate"]
_CONTACT, _ROAD = _VR["in_contact"], _VR["road_effective_z"]
_PARAMETER_VRS = tuple((row[0], vr) for vr, row in enumerate(VARIABLES) if row[2] == "parameter")


def _parameters(values):
    """The law's parameter mapping from a value list indexed by value reference."""
    return {name: values[vr] for name, vr in _PARAMETER_VRS}


def _value_problem(p):
    """Why a parameter of `p` is invalid by itself, or None.

    The checks of ``extended_parameter_problem`` but the constraints between
    parameters, which cannot trigger with a linear spring and no bevel (the
    exponent and the bevel are checked on their own, so that a bevel set
    before a wider cleat_width is not refused).
    """
    return (_law.extended_parameter_problem({**p, "stiffness_exponent": 1.0, "cleat_bevel": 0.0})
            or _law.value_problem("stiffness_exponent", "-", p["stiffness_exponent"], strictly_positive=True)
            or _law.value_problem("cleat_bevel", "m", p["cleat_bevel"], strictly_positive=False))


class CleatfmuExtendedTire(_table.TableSlave):
    """Extended tire: point contact plus enveloped cleat, lugs, progressive stiffness, friction, lift-off."""

    author = "cleatfmu"
    description = ("Extended tire between hub and road, SI units: spring k parallel to damper c, with a built-in "
                   "cleat enveloped by the footprint, lugs, progressive stiffness, friction and unilateral contact")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=0.6, step_size=0.001)

    variables = VARIABLES
    start_file = START_FILE
    state_format = STATE_FORMAT
    wrapper = _wrapper

    def evaluate(self, values):
        """Write the five outputs into `values` from the extended law (see the base class)."""
        v = values
        v[_FORCE], v[_DEFL], v[_RATE], v[_CONTACT], v[_ROAD] = _law.extended_tire(
            v[_HUB_Z], v[_HUB_VZ], v[_HUB_X], v[_HUB_VX], v[_ROAD_Z], v[_ROAD_VZ], _parameters(v))

    def set_problem(self, values):
        """Why the parameters of `values` are invalid together, or None (see the base class)."""
        return _law.extended_parameter_problem(_parameters(values))

    def value_problem(self, values):
        """Why a parameter of `values` is invalid by itself, or None (see the base class)."""
        return _value_problem(_parameters(values))
