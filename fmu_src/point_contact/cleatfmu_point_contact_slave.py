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

* imports only the standard library, pythonfmu (embedded in the FMU) and two
  modules the build places beside this file: ``cleatfmu_point_contact_law``, a
  verbatim copy of the project's tire law, and ``cleatfmu_point_contact_wrapper``,
  the workarounds for pythonfmu 0.7's FMI wrapper (read its docstring);
* the start values of this FMU instance are read from its own resources folder
  (``cleatfmu_point_contact_start.json``), never from module-level state, so
  that several FMUs of this kind in one process each keep their values;
* invalid values (non-finite inputs, k <= 0, c < 0, r0 <= 0, non-finite
  parameters) are rejected before they are stored: the FMU logs the reason
  with status error (delivered when the importer instantiated it with logging
  on) and the FMI call fails (pythonfmu 0.7 reports fmi2Fatal for every
  failing call); the instance keeps its previous valid values;
* an instance holds no reference cycle (the pythonfmu variable objects, whose
  getters would refer back to it, are only created to write the model
  description), so it is freed as soon as the importer frees or resets it.
"""

import json
import math
import os

from pythonfmu import Boolean, DefaultExperiment, Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Status

import cleatfmu_point_contact_law as _law
import cleatfmu_point_contact_wrapper as _wrapper

#: File in the FMU's resources folder with this instance's start values,
#: ``{"start": {name: value, ...}, "provenance": {...}}``.
START_FILE = "cleatfmu_point_contact_start.json"

#: Format tag of the FMU state (``fmi2GetFMUstate`` / serialization).
STATE_FORMAT = "cleatfmu_point_contact/1"

#: Every variable of the FMU, in value-reference order (value reference = row
#: index).  Columns: name, type, causality, variability, unit, start, depends,
#: description.  ``start`` may name another variable whose start it copies.
#: ``depends`` (outputs only) maps each input and parameter the output depends
#: on to the FMI dependency kind of that input (constant: linear with a
#: constant coefficient; tunable: linear with a coefficient that is a tunable
#: parameter; dependent: anything else).  This table is also read (as a
#: literal, without importing this file) by the build to write units,
#: descriptions and the model structure.
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
_REAL = frozenset(vr for vr, row in enumerate(VARIABLES) if row[1] == "Real")
_BOOLEAN = frozenset(vr for vr, row in enumerate(VARIABLES) if row[1] == "Boolean")
_SETTABLE = frozenset(vr for vr, row in enumerate(VARIABLES) if row[2] in ("input", "parameter"))
_PARAMETERS = frozenset(vr for vr, row in enumerate(VARIABLES) if row[2] == "parameter")
_STATE_VRS = tuple(sorted(_SETTABLE))

_isfinite = math.isfinite


def _start_values(resources):
    """Start value of every input and parameter: table defaults, then the resources file."""
    values = {row[0]: row[5] for row in VARIABLES if row[5] is not None}
    path = os.path.join(resources, START_FILE) if resources else None
    if path and os.path.isfile(path):
        with open(path, encoding="utf-8") as f:
            overrides = json.load(f).get("start", {})
        for name, value in overrides.items():
            if name not in values or VARIABLES[_VR[name]][2] not in ("input", "parameter"):
                raise ValueError(f"{START_FILE}: {name!r} is not an input or parameter")
            values[name] = value
    for name, value in values.items():
        if isinstance(value, str):
            values[name] = values[value]
    return values


class CleatfmuPointContact(Fmi2Slave):
    """Point-contact tire: F = k (r0 - (z_hub - z_road)) + c (vz_road - vz_hub)."""

    author = "cleatfmu"
    description = "Point-contact tire (spring k parallel to damper c) between hub and road, SI units"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=0.5, step_size=0.001)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        # The FMI wrapper passes its logger; pythonfmu's builder (writing the model description) does not.
        self._under_wrapper = "logger" in kwargs
        _wrapper.forget_duplicate_path(self.resources)
        try:
            starts = _start_values(self.resources)
            values = [0.0] * len(VARIABLES)
            values[_CONTACT] = False
            for name, value in starts.items():
                values[_VR[name]] = value
            problem = self._problem(values)
            if problem is not None:
                raise ValueError(f"invalid start values in {START_FILE}: {problem}")
        except Exception:
            # No log message here: the wrapper cannot deliver one from a failing constructor.
            if self._under_wrapper:
                _wrapper.before_failing_construction(self)
            raise
        for vr in _SETTABLE:
            values[vr] = float(values[vr])
        self._values = values
        self._stale = True

    def to_xml(self, model_options=None):
        """Register the variables of :data:`VARIABLES`, then write the model description."""
        if not self.vars:
            for vr, (name, typ, causality, variability, _unit, _start, _dep, description) in enumerate(VARIABLES):
                cls = Real if typ == "Real" else Boolean
                getter = self._getter(vr, cls)
                self.register_variable(cls(name, causality=Fmi2Causality[causality],
                                           variability=Fmi2Variability[variability],
                                           initial=Fmi2Initial.calculated if causality == "output" else None,
                                           description=description, getter=getter))
        return super().to_xml(model_options or {})

    def _getter(self, vr, cls):
        if cls is Boolean:
            return lambda: self.get_boolean([vr])[0]
        return lambda: self.get_real([vr])[0]

    # -- helpers ---------------------------------------------------------------------------
    @staticmethod
    def _problem(values):
        """Why a full value list is invalid (non-finite Real input/parameter, bad parameters), or None."""
        for vr in _SETTABLE:
            value = values[vr]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not _isfinite(value):
                return f"{VARIABLES[vr][0]} = {value!r} {VARIABLES[vr][4]}: must be a finite number"
        return _law.parameter_problem(values[_K], values[_C], values[_R0])

    def _fail(self, message):
        """Log `message` with status error and make the current FMI call fail."""
        self.log(message, Fmi2Status.error)
        if self._under_wrapper:
            _wrapper.before_failing(self)
        raise ValueError(message)

    def _update(self):
        v = self._values
        v[_FORCE], v[_DEFL], v[_RATE], v[_CONTACT] = _law.point_contact(
            v[_HUB_Z], v[_HUB_VZ], v[_ROAD_Z], v[_ROAD_VZ], v[_K], v[_C], v[_R0])
        self._stale = False

    # -- FMI -------------------------------------------------------------------------------
    def do_step(self, current_time, step_size):
        return True

    def get_real(self, vrs):
        if self._stale:
            self._update()
        if not _REAL.issuperset(vrs):
            self._fail(f"fmi2GetReal: value references {sorted(set(vrs) - _REAL)} are not Real variables")
        v = self._values
        return [v[vr] for vr in vrs]

    def get_boolean(self, vrs):
        if self._stale:
            self._update()
        if not _BOOLEAN.issuperset(vrs):
            self._fail(f"fmi2GetBoolean: value references {sorted(set(vrs) - _BOOLEAN)} are not Boolean variables")
        v = self._values
        return [v[vr] for vr in vrs]

    def set_real(self, vrs, values):
        if not _SETTABLE.issuperset(vrs) or not _REAL.issuperset(vrs):
            self._fail(f"fmi2SetReal: value references {sorted(set(vrs) - (_SETTABLE & _REAL))} "
                       f"are not Real inputs or parameters")
        for vr, value in zip(vrs, values):
            if not _isfinite(value):
                self._fail(f"{VARIABLES[vr][0]} = {value!r} {VARIABLES[vr][4]} rejected: must be finite")
        v = self._values
        if not _PARAMETERS.isdisjoint(vrs):
            trial = list(v)
            for vr, value in zip(vrs, values):
                trial[vr] = value
            problem = _law.parameter_problem(trial[_K], trial[_C], trial[_R0])
            if problem is not None:
                self._fail(f"parameter rejected: {problem}")
        for vr, value in zip(vrs, values):
            v[vr] = value
        self._stale = True

    def set_boolean(self, vrs, values):
        self._fail(f"fmi2SetBoolean: value references {list(vrs)} are not Boolean inputs or parameters")

    def set_integer(self, vrs, values):
        self._fail(f"fmi2SetInteger: value references {list(vrs)} are not Integer inputs or parameters")

    def set_string(self, vrs, values):
        self._fail(f"fmi2SetString: value references {list(vrs)} are not String inputs or parameters")

    def get_integer(self, vrs):
        self._fail(f"fmi2GetInteger: value references {list(vrs)} are not Integer variables")

    def get_string(self, vrs):
        self._fail(f"fmi2GetString: value references {list(vrs)} are not String variables")

    @staticmethod
    def _fmu_state_from_bytes(state):
        # Never raise here (no instance to keep consistent): a bad state fails in _set_fmu_state.
        try:
            return json.loads(state.decode("utf-8"))
        except (UnicodeDecodeError, ValueError):
            return {"format": None}

    def _get_fmu_state(self):
        # Inputs and parameters are the whole state; outputs are recomputed from them.
        return {"format": STATE_FORMAT, "values": [self._values[vr] for vr in _STATE_VRS]}

    def _set_fmu_state(self, state):
        try:
            ok = state["format"] == STATE_FORMAT and len(state["values"]) == len(_STATE_VRS)
        except (TypeError, KeyError):
            ok = False
        if not ok:
            self._fail(f"fmi2SetFMUstate: not a {STATE_FORMAT} state")
        values = list(self._values)
        for vr, value in zip(_STATE_VRS, state["values"]):
            values[vr] = value
        problem = self._problem(values)
        if problem is not None:
            self._fail(f"fmi2SetFMUstate: invalid state: {problem}")
        for vr in _SETTABLE:
            values[vr] = float(values[vr])
        self._values = values
        self._stale = True
