"""Completion of the modelDescription.xml that pythonfmu writes.

pythonfmu 0.7 writes no units, lists outputs without their input dependencies,
writes no ``InitialUnknowns`` (so calculated outputs fail validation), rounds
start values to 16 significant digits and declares the FMU-state capabilities
as false.  :func:`complete_model_description` rewrites these parts from the
kind's variable table, in the element order of the FMI 2.0 schema.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from .kinds import FmuKind
from .units import base_unit_exponents

__all__ = ["complete_model_description"]

_SCHEMA_ORDER = ("ModelExchange", "CoSimulation", "UnitDefinitions", "TypeDefinitions", "LogCategories",
                 "DefaultExperiment", "VendorAnnotations", "ModelVariables", "ModelStructure")
_INITIAL_KINDS = {"constant": "constant"}  # InitialUnknowns allow only "dependent" and "constant"


def _insert_in_schema_order(root: ET.Element, element: ET.Element) -> None:
    rank = _SCHEMA_ORDER.index(element.tag)
    for i, child in enumerate(list(root)):
        if child.tag in _SCHEMA_ORDER and _SCHEMA_ORDER.index(child.tag) > rank:
            root.insert(i, element)
            return
    root.append(element)


def _unknown(parent: ET.Element, index: int, deps: list[tuple[int, str]], *, explicit: bool = False) -> None:
    """An ``Unknown`` element; without `deps` it depends on every known, unless `explicit` (then on none)."""
    attrib = {"index": str(index)}
    if explicit and not deps:
        attrib["dependencies"] = ""
    if deps:
        deps = sorted(deps)
        attrib["dependencies"] = " ".join(str(i) for i, _ in deps)
        attrib["dependenciesKind"] = " ".join(k for _, k in deps)
    ET.SubElement(parent, "Unknown", attrib)


def complete_model_description(xml: bytes, kind: FmuKind, *, start_values: dict[str, float],
                               description: str, version: str, generation_tool: str) -> bytes:
    """Return the completed modelDescription.xml.

    Parameters
    ----------
    xml : bytes
        modelDescription.xml as written by pythonfmu for `kind`.
    kind : FmuKind
        The kind (variable table: units, descriptions, dependencies).
    start_values : dict of str to float
        Start value of every input and parameter (written with full precision).
    description, version, generation_tool : str
        Model-level attributes.

    Raises
    ------
    ValueError
        If the XML does not match the kind's table (names, causality, variability, type).
    """
    root = ET.fromstring(xml)
    root.set("description", description)
    root.set("version", version)
    root.set("generationTool", generation_tool)

    cs = root.find("CoSimulation")
    if cs is None or cs.get("modelIdentifier") != kind.model_identifier:
        raise ValueError(f"modelDescription.xml: CoSimulation modelIdentifier is not {kind.model_identifier!r}")
    flag = "true" if kind.fmu_state else "false"
    cs.set("canGetAndSetFMUstate", flag)
    cs.set("canSerializeFMUstate", flag)
    if root.find("DefaultExperiment") is None:
        raise ValueError(f"kind {kind.name}: the slave class declares no default_experiment")

    scalars = root.find("ModelVariables").findall("ScalarVariable")
    if [s.get("name") for s in scalars] != [v.name for v in kind.variables]:
        raise ValueError(f"kind {kind.name}: the variables written by pythonfmu differ from VARIABLES")
    index = {}
    for pos, (scalar, var) in enumerate(zip(scalars, kind.variables), start=1):
        index[var.name] = pos
        typed = scalar.find(var.type)
        if (typed is None or int(scalar.get("valueReference")) != var.value_reference
                or scalar.get("causality") != var.causality or scalar.get("variability", "continuous") != var.variability):
            raise ValueError(f"kind {kind.name}: variable {var.name!r} does not match its VARIABLES row")
        if not var.description:
            raise ValueError(f"kind {kind.name}: variable {var.name!r} has no description")
        scalar.set("description", var.description)
        if var.type == "Real":
            base_unit_exponents(var.unit)  # known SI unit, or ValueError
            typed.set("unit", var.unit)
        if var.causality in ("input", "parameter"):
            value = start_values[var.name]
            typed.set("start", repr(bool(value)).lower() if var.type == "Boolean" else repr(float(value)))

    units = ET.Element("UnitDefinitions")
    for name in sorted({v.unit for v in kind.variables if v.type == "Real"}):
        unit = ET.SubElement(units, "Unit", {"name": name})
        ET.SubElement(unit, "BaseUnit", {k: str(e) for k, e in base_unit_exponents(name).items()})
    old = root.find("UnitDefinitions")
    if old is not None:
        root.remove(old)
    _insert_in_schema_order(root, units)

    structure = root.find("ModelStructure")
    if structure is not None:
        root.remove(structure)
    structure = ET.Element("ModelStructure")
    outputs = ET.SubElement(structure, "Outputs")
    initial = ET.SubElement(structure, "InitialUnknowns")
    knowns = {v.name: v.causality for v in kind.variables}
    for var in kind.variables:
        if var.causality != "output":
            continue
        for dep in var.depends:
            if knowns.get(dep) not in ("input", "parameter"):
                raise ValueError(f"kind {kind.name}: output {var.name!r} depends on {dep!r}, "
                                 f"which is not an input or parameter")
        _unknown(outputs, index[var.name],
                 [(index[d], k) for d, k in var.depends.items() if knowns[d] == "input"], explicit=True)
        _unknown(initial, index[var.name],
                 [(index[d], _INITIAL_KINDS.get(k, "dependent")) for d, k in var.depends.items()])
    if not len(initial):
        structure.remove(initial)
    root.append(structure)

    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"
