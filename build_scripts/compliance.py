"""Compliance checks of a built FMU beyond what pythonfmu guarantees.

:func:`compliance_problems` returns a list of problems (empty = compliant):

* ``fmpy.validation.validate_fmu`` (schema, model structure, start values, units);
* every variable has a description; every Real variable has a unit defined in
  ``UnitDefinitions`` with its SI base-unit exponents;
* the model itself has a description, and a ``DefaultExperiment`` with start,
  stop and step size;
* every output lists its input dependencies (direct feedthrough exposed);
* every Python module in the FMU's resources (pythonfmu's own excepted) has a
  name starting with the FMU's slave module name (pythonfmu FMUs), and the
  model identifier names the binaries;
* canGetAndSetFMUstate implies canSerializeFMUstate (the pair is declared
  only when both round-trip, which :mod:`build_scripts.check` verifies).
"""

from __future__ import annotations

import zipfile
from pathlib import PurePosixPath

__all__ = ["compliance_problems"]


def compliance_problems(fmu) -> list[str]:
    """Problems of `fmu` (path to a .fmu file); an empty list means compliant."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    problems = list(validate_fmu(str(fmu)))
    if problems:
        return problems
    md = read_model_description(str(fmu))
    units = {u.name: u for u in md.unitDefinitions}
    for name, unit in units.items():
        if unit.baseUnit is None:
            problems.append(f"unit {name!r} has no BaseUnit (SI exponents)")
    if not md.description:
        problems.append("the model has no description")
    de = md.defaultExperiment
    if de is None or None in (de.startTime, de.stopTime, de.stepSize):
        problems.append("no DefaultExperiment with startTime, stopTime and stepSize")
    for v in md.modelVariables:
        if not v.description:
            problems.append(f"variable {v.name!r} has no description")
        if v.type in ("Real", "Float64") and (v.unit is None or v.unit not in units):
            problems.append(f"Real variable {v.name!r} has no unit defined in UnitDefinitions")
    inputs = {v for v in md.modelVariables if v.causality == "input"}
    for unknown in md.outputs:
        if inputs and unknown.dependencies is None:
            problems.append(f"output {unknown.variable.name!r} does not list its input dependencies")
    cs = md.coSimulation
    if cs is None:
        return problems + ["not a co-simulation FMU"]
    if cs.canGetAndSetFMUstate != cs.canSerializeFMUstate:
        problems.append("canGetAndSetFMUstate and canSerializeFMUstate differ")
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
        slave_module = (z.read("resources/slavemodule.txt").decode("utf-8").strip()
                        if "resources/slavemodule.txt" in names else None)
    for name in names:
        path = PurePosixPath(name)
        if (slave_module is not None and len(path.parts) == 2 and path.parts[0] == "resources"
                and path.suffix == ".py"):
            if path.stem != slave_module and not path.stem.startswith(slave_module + "_"):
                problems.append(f"module {path.stem!r} in the FMU does not start with {slave_module!r}")
    binaries = [n for n in names if n.startswith("binaries/") and not n.endswith("/")]
    for name in binaries:
        if PurePosixPath(name).stem != cs.modelIdentifier:
            problems.append(f"binary {name} is not named after the model identifier {cs.modelIdentifier!r}")
    return problems
