"""The FMI 3.0 modelDescription.xml and sources/buildDescription.xml of a native tire FMU.

Written from the kind's variable table (units, descriptions, dependencies) the
way :mod:`build_scripts.model_description` completes the FMI 2.0 one: the
independent variable ``time`` (value reference = number of the kind's
variables, read-only), Float64 and Boolean scalars, ``UnitDefinitions`` with SI base-unit exponents, outputs
with their dependencies (by value reference) as ``Output`` and
``InitialUnknown`` elements.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from .kinds import FmuKind
from .units import base_unit_exponents

__all__ = ["model_description_fmi3", "build_description_fmi3", "log_categories"]

_INITIAL_KINDS = {"constant": "constant"}
_LOG_CATEGORIES = (("logStatusError", "Why a call failed (status error)"), ("logCalls", "Every FMI function call"))
_WARNING_CATEGORY = ("logStatusWarning", "A value the model extrapolates (status warning): the tire map's speed "
                                         "outside its tested range, once per excursion")


def log_categories(kind: FmuKind) -> tuple:
    """(name, description) of the log categories of a native FMU of `kind` (``native.warnings``: with warnings)."""
    return _LOG_CATEGORIES + ((_WARNING_CATEGORY,) if kind.native.get("warnings") else ())


def _dependencies(element: ET.Element, deps: list[tuple[int, str]], *, explicit: bool = False) -> None:
    """Dependencies of an unknown; without `deps` it depends on every known, unless `explicit` (then on none)."""
    if explicit and not deps:
        element.set("dependencies", "")
    if deps:
        deps = sorted(deps)
        element.set("dependencies", " ".join(str(vr) for vr, _ in deps))
        element.set("dependenciesKind", " ".join(k for _, k in deps))


def model_description_fmi3(kind: FmuKind, starts: dict, *, description: str, version: str, generation_tool: str,
                           token: str) -> bytes:
    """modelDescription.xml (FMI 3.0 co-simulation) of a native FMU of `kind` with start values `starts`."""
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": kind.model_identifier, "instantiationToken": token,
        "description": description, "author": "cleatfmu", "version": version, "generationTool": generation_tool,
        "variableNamingConvention": "flat"})
    ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": kind.model_identifier, "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
        "canSerializeFMUState": "true", "providesDirectionalDerivatives": "false",
        "providesAdjointDerivatives": "false", "providesPerElementDependencies": "false",
        "canHandleVariableCommunicationStepSize": "true", "maxOutputDerivativeOrder": "0",
        "providesIntermediateUpdate": "false", "mightReturnEarlyFromDoStep": "false",
        "canReturnEarlyAfterIntermediateUpdate": "false", "hasEventMode": "false",
        "providesEvaluateDiscreteStates": "false"})
    units = ET.SubElement(root, "UnitDefinitions")
    for name in sorted({"s", *(v.unit for v in kind.variables if v.type == "Real")}):
        unit = ET.SubElement(units, "Unit", {"name": name})
        ET.SubElement(unit, "BaseUnit", {k: str(e) for k, e in base_unit_exponents(name).items()})
    cats = ET.SubElement(root, "LogCategories")
    for name, text in log_categories(kind):
        ET.SubElement(cats, "Category", {"name": name, "description": text})
    start, stop, step = kind.native["default_experiment"]
    ET.SubElement(root, "DefaultExperiment", {"startTime": repr(float(start)), "stopTime": repr(float(stop)),
                                               "stepSize": repr(float(step))})
    variables = ET.SubElement(root, "ModelVariables")
    ET.SubElement(variables, "Float64", {  # read-only, value reference one past the kind's variables
        "name": "time", "valueReference": str(len(kind.variables)), "description": "Simulation time, s",
        "causality": "independent", "variability": "continuous", "unit": "s"})
    for v in kind.variables:
        if not v.description:
            raise ValueError(f"kind {kind.name}: variable {v.name!r} has no description")
        attrib = {"name": v.name, "valueReference": str(v.value_reference), "description": v.description,
                  "causality": v.causality, "variability": v.variability}
        if v.type == "Real":
            attrib["unit"] = v.unit
        if v.causality in ("input", "parameter"):
            value = starts[v.name]
            attrib["start"] = repr(bool(value)).lower() if v.type == "Boolean" else repr(float(value))
        else:
            attrib["initial"] = "calculated"
        ET.SubElement(variables, "Float64" if v.type == "Real" else "Boolean", attrib)
    structure = ET.SubElement(root, "ModelStructure")
    vrs = {v.name: v.value_reference for v in kind.variables}
    causality = {v.name: v.causality for v in kind.variables}
    outputs = [v for v in kind.variables if v.causality == "output"]
    for v in outputs:
        _dependencies(ET.SubElement(structure, "Output", {"valueReference": str(v.value_reference)}),
                      [(vrs[d], k) for d, k in v.depends.items() if causality[d] == "input"], explicit=True)
    for v in outputs:
        _dependencies(ET.SubElement(structure, "InitialUnknown", {"valueReference": str(v.value_reference)}),
                      [(vrs[d], _INITIAL_KINDS.get(k, "dependent")) for d, k in v.depends.items()])
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"


def build_description_fmi3(kind: FmuKind, c_files: list[str]) -> bytes:
    """sources/buildDescription.xml: compile the C99 files of sources/ (include directory sources/), link libm."""
    root = ET.Element("fmiBuildDescription", {"fmiVersion": "3.0"})
    config = ET.SubElement(root, "BuildConfiguration", {
        "modelIdentifier": kind.model_identifier,
        "description": "C99, libm only; compile with floating-point contraction off (-ffp-contract=off)"})
    files = ET.SubElement(config, "SourceFileSet", {"language": "C99", "compilerOptions": "-ffp-contract=off"})
    for name in c_files:
        ET.SubElement(files, "SourceFile", {"name": name})
    ET.SubElement(files, "IncludeDirectory", {"name": "."})
    ET.SubElement(config, "Library", {"name": "m", "external": "true", "description": "C math library"})
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"
