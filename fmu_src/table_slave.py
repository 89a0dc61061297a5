"""Table-driven FMI 2.0 co-simulation slave for pythonfmu 0.7 (the part that knows no tire law).

This module runs inside FMUs, not in the cleatfmu package: like
``pythonfmu_wrapper.py``, the build copies it into every FMU of a kind that
uses it, under a module name unique to the kind (``"modules"`` of the kind's
``kind.json``, e.g. ``cleatfmu_point_contact_table``), so it imports only the
standard library and pythonfmu.  A slave class derives from
:class:`TableSlave`, sets the class attributes

* ``variables`` — the kind's variable table, rows ``(name, type, causality,
  variability, unit, start, depends, description)``, value reference = row
  index: type ``"Real"`` or ``"Boolean"``; causality ``"input"``,
  ``"parameter"`` or ``"output"``; variability and unit as in the model
  description; ``start`` (inputs and parameters) a value, or the name of
  another variable whose start it copies; ``depends`` (outputs, for the model
  structure the build writes) maps each input and parameter the output
  depends on to its FMI dependency kind (``"constant"``: linear with a
  constant coefficient; ``"tunable"``: linear with a coefficient that is a
  tunable parameter; ``"dependent"``: anything else);
* ``start_file`` — the file of the FMU's resources folder holding this FMU's
  start values, ``{"start": {name: value, ...}, "provenance": {...}}``;
* ``state_format`` — the format tag of its FMU state;
* ``wrapper`` — the kind's copy of ``fmu_src/pythonfmu_wrapper.py``;

and implements :meth:`~TableSlave.evaluate` (outputs from inputs and
parameters) and :meth:`~TableSlave.set_problem` (why a complete value list is
invalid), optionally :meth:`~TableSlave.value_problem` (what is checked when
an importer sets values; by default the same).

Behaviour:

* outputs are direct feedthrough: evaluated from the inputs and parameters
  set last, whenever they are read;
* a value is stored only if it has its variable's type (Real: a finite
  number; Boolean: a bool) and passes :meth:`~TableSlave.value_problem`;
  otherwise the FMI call fails and the instance keeps its previous values.
  :meth:`~TableSlave.set_problem` is checked for the start values, for an FMU
  state, and after a parameter change before the next evaluation, step or
  exit from initialization mode, which fail while it reports a problem;
* every failure logs its reason with status error (delivered when the
  importer turned logging on) and makes the FMI call fail (pythonfmu 0.7
  reports fmi2Fatal for every failing call) without harming the host, through
  the wrapper workarounds; an evaluation that raises or gives a non-finite
  Real output fails the same way;
* the FMU state is ``{"format": state_format, "values": [...]}``, the values
  of the inputs and parameters in value-reference order (outputs are
  recomputed from them);
* an instance holds no reference cycle (the pythonfmu variable objects, whose
  getters would refer back to it, are only created to write the model
  description), so it is freed as soon as the importer frees or resets it.
"""

import json
import math
import os

from pythonfmu import Boolean, Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Status

__all__ = ["TableSlave"]

_isfinite = math.isfinite
_SETTABLE_CAUSALITIES = ("input", "parameter")


def _type_problem(row, value):
    """Why `value` is not a value of the variable of a table row, or None.

    Parameters
    ----------
    row : tuple
        Row of a variable table (name, type, causality, variability, unit, ...).
    value : object
        Candidate value.

    Returns
    -------
    str or None
        One-line description of the problem.
    """
    if row[1] == "Boolean":
        return None if isinstance(value, bool) else f"{row[0]} = {value!r}: must be a Boolean"
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not _isfinite(value):
        return f"{row[0]} = {value!r} {row[4]}: must be a finite number"
    return None


class TableSlave(Fmi2Slave):
    """FMI 2.0 co-simulation slave whose variables are the rows of ``variables``.

    Parameters
    ----------
    **kwargs
        Passed on to :class:`pythonfmu.Fmi2Slave` (``instance_name``,
        ``resources``, and ``logger`` when the FMI wrapper instantiates).

    Raises
    ------
    ValueError
        If the start values (table defaults updated by ``start_file``) are
        invalid.
    """

    variables = ()
    start_file = ""
    state_format = ""
    wrapper = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        rows = cls.variables
        cls._vr = {row[0]: vr for vr, row in enumerate(rows)}
        cls._real = frozenset(vr for vr, row in enumerate(rows) if row[1] == "Real")
        cls._boolean = frozenset(vr for vr, row in enumerate(rows) if row[1] == "Boolean")
        cls._settable = frozenset(vr for vr, row in enumerate(rows) if row[2] in _SETTABLE_CAUSALITIES)
        cls._settable_real = cls._settable & cls._real
        cls._settable_boolean = cls._settable & cls._boolean
        cls._parameters = frozenset(vr for vr, row in enumerate(rows) if row[2] == "parameter")
        cls._real_inputs = cls._settable_real - cls._parameters
        cls._real_outputs = tuple(sorted(vr for vr, row in enumerate(rows) if row[2] == "output" and row[1] == "Real"))
        cls._state_vrs = tuple(sorted(cls._settable))

    # -- to be implemented by the kind -----------------------------------------------------
    def evaluate(self, values):
        """Compute the outputs from the inputs and parameters.

        Parameters
        ----------
        values : list
            Every variable's value, indexed by value reference; the outputs
            are written into it.

        Raises
        ------
        ArithmeticError, ValueError
            If the outputs cannot be evaluated (the FMI call then fails).
        """
        raise NotImplementedError

    def set_problem(self, values):
        """Why a complete value list is invalid.

        Parameters
        ----------
        values : list
            Every variable's value, indexed by value reference; inputs and
            parameters have their variables' types.

        Returns
        -------
        str or None
            One-line description of the first problem, None if valid.
        """
        raise NotImplementedError

    def value_problem(self, values):
        """Why values just set by an importer must be refused (default: :meth:`set_problem`).

        Parameters
        ----------
        values : list
            Every variable's value with the new ones, indexed by value reference.

        Returns
        -------
        str or None
            One-line description of the problem, None to accept the values.
        """
        return self.set_problem(values)

    # -- construction ----------------------------------------------------------------------
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        # The FMI wrapper passes its logger; pythonfmu's builder (writing the model description) does not.
        self._under_wrapper = "logger" in kwargs
        self.wrapper.forget_duplicate_path(self.resources)
        try:
            values = [False if row[1] == "Boolean" else 0.0 for row in self.variables]
            for name, value in self._start_values().items():
                values[self._vr[name]] = value
            problem = self._typed_problem(values)
            if problem is not None:
                raise ValueError(f"invalid start values in {self.start_file}: {problem}")
        except Exception:
            # No log message here: the wrapper cannot deliver one from a failing constructor.
            if self._under_wrapper:
                self.wrapper.before_failing_construction(self)
            raise
        self._values = self._normalised(values)
        self._stale = True
        self._unchecked = False

    def _start_values(self):
        """Start value of every input and parameter: table defaults, then the resources file."""
        values = {row[0]: row[5] for row in self.variables if row[2] in _SETTABLE_CAUSALITIES}
        path = os.path.join(self.resources, self.start_file) if self.resources else None
        if path and os.path.isfile(path):
            with open(path, encoding="utf-8") as f:
                overrides = json.load(f).get("start", {})
            for name, value in overrides.items():
                if name not in values:
                    raise ValueError(f"{self.start_file}: {name!r} is not an input or parameter")
                values[name] = value
        for name, value in values.items():
            if isinstance(value, str):
                values[name] = values[value]
        return values

    def to_xml(self, model_options=None):
        """Register the variables of the table, then write the model description.

        Parameters
        ----------
        model_options : dict, optional
            pythonfmu's model options.

        Returns
        -------
        xml.etree.ElementTree.Element
            The model description written by pythonfmu.
        """
        if not self.vars:
            for vr, (name, typ, causality, variability, _unit, _start, _dep, description) in enumerate(self.variables):
                cls = Real if typ == "Real" else Boolean
                self.register_variable(cls(name, causality=Fmi2Causality[causality],
                                           variability=Fmi2Variability[variability],
                                           initial=Fmi2Initial.calculated if causality == "output" else None,
                                           description=description, getter=self._getter(vr, cls)))
        return super().to_xml(model_options or {})

    def _getter(self, vr, cls):
        if cls is Boolean:
            return lambda: self.get_boolean([vr])[0]
        return lambda: self.get_real([vr])[0]

    # -- helpers ---------------------------------------------------------------------------
    def _typed_problem(self, values):
        """Why a full value list is invalid (a settable value of the wrong type, or set_problem), or None."""
        for vr in self._settable:
            problem = _type_problem(self.variables[vr], values[vr])
            if problem is not None:
                return problem
        return self.set_problem(values)

    def _normalised(self, values):
        values = list(values)
        for vr in self._settable_real:
            values[vr] = float(values[vr])
        return values

    def _fail(self, message):
        """Log `message` with status error and make the current FMI call fail."""
        self.log(message, Fmi2Status.error)
        if self._under_wrapper:
            self.wrapper.before_failing(self)
        raise ValueError(message)

    def _check_parameters(self):
        """Fail while set_problem reports a problem with the values set since the last check."""
        problem = self.set_problem(self._values)
        if problem is not None:
            self._fail(f"parameters rejected: {problem}")
        self._unchecked = False

    def _update(self):
        if self._unchecked:
            self._check_parameters()
        v = self._values
        try:
            self.evaluate(v)
            failed = None
        except (ArithmeticError, ValueError) as exc:
            failed = f"{type(exc).__name__}: {exc}"
        if failed is None:
            for vr in self._real_outputs:
                if not _isfinite(v[vr]):
                    failed = f"{self.variables[vr][0]} = {v[vr]!r}"
                    break
        if failed is not None:
            self._fail(f"the outputs cannot be evaluated for these inputs and parameters ({failed})")
        self._stale = False

    def _store(self, vrs, values, kind, settable):
        """Store `values` after the checks of the module docstring; `kind` names the FMI call."""
        if not settable.issuperset(vrs):
            self._fail(f"fmi2Set{kind}: value references {sorted(set(vrs) - settable)} "
                       f"are not {kind} inputs or parameters")
        rows = self.variables
        for vr, value in zip(vrs, values):
            problem = _type_problem(rows[vr], value)
            if problem is not None:
                self._fail(f"{problem}: rejected")
        v = self._values
        parameters = not self._parameters.isdisjoint(vrs)
        if parameters:
            trial = list(v)
            for vr, value in zip(vrs, values):
                trial[vr] = value
            problem = self.value_problem(trial)
            if problem is not None:
                self._fail(f"parameter rejected: {problem}")
        for vr, value in zip(vrs, values):
            v[vr] = value
        self._stale = True
        if parameters:
            self._unchecked = True

    # -- FMI -------------------------------------------------------------------------------
    def exit_initialization_mode(self):
        if self._unchecked:
            self._check_parameters()

    def do_step(self, current_time, step_size):
        if self._unchecked:
            self._check_parameters()
        return True

    def get_real(self, vrs):
        if not self._real.issuperset(vrs):
            self._fail(f"fmi2GetReal: value references {sorted(set(vrs) - self._real)} are not Real variables")
        if self._stale:
            self._update()
        v = self._values
        return [v[vr] for vr in vrs]

    def get_boolean(self, vrs):
        if not self._boolean.issuperset(vrs):
            self._fail(f"fmi2GetBoolean: value references {sorted(set(vrs) - self._boolean)} "
                       f"are not Boolean variables")
        if self._stale:
            self._update()
        v = self._values
        return [v[vr] for vr in vrs]

    def set_real(self, vrs, values):
        if self._real_inputs.issuperset(vrs):
            # Inputs only (the importer's per-step call): the checks of _store, without a value_problem.
            for value in values:
                if value.__class__ is not float or not _isfinite(value):
                    break
            else:
                v = self._values
                for vr, value in zip(vrs, values):
                    v[vr] = value
                self._stale = True
                return
        self._store(vrs, values, "Real", self._settable_real)

    def set_boolean(self, vrs, values):
        self._store(vrs, values, "Boolean", self._settable_boolean)

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
        return {"format": self.state_format, "values": [self._values[vr] for vr in self._state_vrs]}

    def _set_fmu_state(self, state):
        try:
            ok = state["format"] == self.state_format and len(state["values"]) == len(self._state_vrs)
        except (TypeError, KeyError):
            ok = False
        if not ok:
            self._fail(f"fmi2SetFMUstate: not a {self.state_format} state")
        values = list(self._values)
        for vr, value in zip(self._state_vrs, state["values"]):
            values[vr] = value
        problem = self._typed_problem(values)
        if problem is not None:
            self._fail(f"fmi2SetFMUstate: invalid state: {problem}")
        self._values = self._normalised(values)
        self._stale = True
        self._unchecked = False
