"""Packaging of the native (C) tire FMUs: model description, resources, sources, binaries.

The FMU is reproducible: the same kind, start values, description and
platforms give a byte-identical file.  Its GUID is derived from a hash of its
content; the zip entries are sorted, dated 1980-01-01 and have mode 0644; it
holds no absolute path, host name or time stamp.  The start values (exact, as
the bits of each double) and the GUID are in ``resources/cleatfmu_start.txt``,
read by the binary at instantiation, so one compiled binary per platform and
law version serves every FMU of a kind.
"""

from __future__ import annotations

import json
import math
import struct
import xml.etree.ElementTree as ET

from .kinds import FmuKind
from .model_description import complete_model_description
from .model_description3 import build_description_fmi3, log_categories, model_description_fmi3
from .native import PLATFORMS, c_sources, compile_binaries, source_files
from .reproducible import GUID_PLACEHOLDER, content_guid, zip_bytes

__all__ = ["DEFAULT_STATIC_LOAD_N", "equilibrium_starts", "native_fmu_bytes", "START_FILE"]

#: Wheel load at which the hub starts when neither the start values nor static_load give one, N.
DEFAULT_STATIC_LOAD_N = 15000.0
START_FILE = "resources/cleatfmu_start.txt"
_HUB_Z_DESCRIPTION = ("Hub (wheel centre) height, absolute, m (z upwards); starts at the static equilibrium under "
                      "the static wheel load, so that the default experiment shows force_z = that load")


def equilibrium_starts(kind: FmuKind, starts: dict, given: dict, static_load_n: float | None = None) -> dict:
    """Start values with the hub at its static equilibrium (unless hub_z / hub_x are given).

    The load is `static_load_n`, else the kind's ``static_load`` if > 0, else
    :data:`DEFAULT_STATIC_LOAD_N`; the deflection carrying it is W / k (n W / k
    for a progressive spring, whose force is W there).  A hub whose footprint
    touches the built-in cleat is moved 1 m before it, so that the default
    experiment does not park the tire on the cleat.
    """
    from identification.model.tire_law import (footprint_cleat, lug_road, ring_cleat, ring_envelope_on,
                                               static_deflection)

    out = dict(starts)
    load = static_load_n
    if load is None:
        load = starts.get("static_load", 0.0) or DEFAULT_STATIC_LOAD_N
    n = starts.get("stiffness_exponent", 1.0)
    deflection = (n if n != 1.0 else 1.0) * load / starts["stiffness"]
    road = starts.get("road_z", 0.0)
    if "hub_x" in starts:
        ring = ring_envelope_on(starts) and starts["static_load"] > 0.0
        sink = static_deflection(starts["stiffness"], n, starts["static_load"]) if ring else 0.0
        if starts.get("cleat_height", 0.0) and "hub_x" not in given:
            reach = starts["cleat_x"] - 0.5 * starts["footprint_length"]
            if ring:   # the ring touches a cleat sqrt(2 R (deflection + H)) ahead, R = footprint^2 / (8 sink)
                radius = starts["footprint_length"] ** 2 / (8.0 * sink)
                reach = (starts["cleat_x"] + 0.5 * starts.get("cleat_bevel", 0.0)
                         - math.sqrt(2.0 * radius * (max(deflection, 0.0) + starts["cleat_height"])))
            if starts["hub_x"] >= reach - 1e-9:
                out["hub_x"] = reach - 1.0
        if ring:
            cleat, _ = ring_cleat(out["hub_x"], deflection, starts["footprint_length"], starts["cleat_x"],
                                  starts["cleat_height"], starts["cleat_width"], sink, starts.get("cleat_bevel", 0.0))
        else:
            cleat, _ = footprint_cleat(out["hub_x"], starts["footprint_length"], starts["cleat_x"],
                                       starts["cleat_height"], starts["cleat_width"],
                                       starts.get("parabolic_pressure", False), starts.get("cleat_bevel", 0.0))
        lug, _ = lug_road(out["hub_x"], starts["lug_amplitude"], starts["lug_pitch"], starts["lug_phase"])
        road = road + cleat + lug
    if "hub_z" not in given:
        out["hub_z"] = road + starts["unloaded_radius"] - deflection
    return out


def _bits(value: float) -> str:
    return struct.pack(">d", float(value)).hex()


def _start_file(kind: FmuKind, starts: dict, guid: str) -> bytes:
    lines = [f"cleatfmu-start 1 {kind.name}",
             "# start value of every input and parameter: name, IEEE 754 bits of the double (big-endian hex)",
             f"guid {guid}"]
    for v in kind.variables:
        if v.causality in ("input", "parameter"):
            value = float(bool(starts[v.name])) if v.type == "Boolean" else float(starts[v.name])
            lines.append(f"# {v.name} = {value!r} {v.unit}".rstrip())
            lines.append(f"{v.name} {_bits(value)}")
    return ("\n".join(lines) + "\n").encode("ascii")


def _base_model_description(kind: FmuKind, fmi_version: int, guid: str) -> bytes:
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": kind.model_identifier, "guid": guid, "author": "cleatfmu",
        "variableNamingConvention": "flat", "numberOfEventIndicators": "0"})
    cs = ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": kind.model_identifier, "needsExecutionTool": "false",
        "canHandleVariableCommunicationStepSize": "true", "canInterpolateInputs": "false",
        "maxOutputDerivativeOrder": "0", "canRunAsynchronuously": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false", "canNotUseMemoryManagementFunctions": "false",
        "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true", "providesDirectionalDerivative": "false"})
    files = ET.SubElement(cs, "SourceFiles")
    for name in c_sources(fmi_version):
        ET.SubElement(files, "File", {"name": name})
    cats = ET.SubElement(root, "LogCategories")
    for name, text in log_categories(kind):
        ET.SubElement(cats, "Category", {"name": name, "description": text})
    start, stop, step = kind.native["default_experiment"]
    ET.SubElement(root, "DefaultExperiment", {"startTime": repr(float(start)), "stopTime": repr(float(stop)),
                                               "stepSize": repr(float(step))})
    variables = ET.SubElement(root, "ModelVariables")
    for v in kind.variables:
        attrib = {"name": v.name, "valueReference": str(v.value_reference), "causality": v.causality,
                  "variability": v.variability}
        if v.causality == "output":
            attrib["initial"] = "calculated"
        sv = ET.SubElement(variables, "ScalarVariable", attrib)
        ET.SubElement(sv, v.type)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _kind_for_native(kind: FmuKind) -> FmuKind:
    """The kind with the native hub_z description (its start is the static equilibrium)."""
    import dataclasses

    rows = tuple(dataclasses.replace(v, description=_HUB_Z_DESCRIPTION) if v.name == "hub_z" else v
                 for v in kind.variables)
    return dataclasses.replace(kind, variables=rows)


def native_fmu_bytes(kind: FmuKind, starts: dict, *, description: str, version: str, fmi_version: int = 2,
                     platforms=None, provenance: dict | None = None, resources: dict | None = None) -> bytes:
    """The complete .fmu file (bytes) of a native FMU of `kind` with start values `starts`.

    Parameters
    ----------
    kind : FmuKind
        The kind.
    starts : dict
        Start value of every input and parameter (SI units, bool for Booleans).
    description, version : str
        Model description and version attributes.
    fmi_version : int
        2 (FMI 2.0) or 3 (FMI 3.0, with ``sources/buildDescription.xml``).
    platforms : iterable of str, optional
        Platform folders (default: all of :data:`build_scripts.native.PLATFORMS`).
    provenance : dict, optional
        Written to ``resources/provenance.json``.
    resources : dict of str to bytes, optional
        Further files of the resources folder (the road's profile table, the tire map's table).
    """
    if fmi_version not in PLATFORMS:
        raise ValueError(f"FMI version {fmi_version} is not supported by the native backend "
                         f"(supported: {', '.join(map(str, PLATFORMS))})")
    platforms = sorted(platforms) if platforms is not None else sorted(PLATFORMS[fmi_version])
    if not platforms:
        raise ValueError("no platform given")
    for name, value in starts.items():
        if not isinstance(value, bool) and not math.isfinite(value):
            raise ValueError(f"start value of {name!r} must be finite, got {value!r}")
    kind = _kind_for_native(kind)
    binaries = compile_binaries(kind, fmi_version, platforms)
    files = {}
    for platform, data in binaries.items():
        _, ext = PLATFORMS[fmi_version][platform]
        files[f"binaries/{platform}/{kind.model_identifier}{ext}"] = data
    for name, data in source_files(kind, fmi_version).items():
        files[f"sources/{name}"] = data
    for name, data in (resources or {}).items():
        files[f"resources/{name}"] = data
    if provenance:
        files["resources/provenance.json"] = (json.dumps(provenance, indent=2, sort_keys=True) + "\n").encode()
    generation_tool = f"cleatfmu {version} build_scripts (native C, zig cc)"

    def model_description(guid):
        return complete_model_description(_base_model_description(kind, fmi_version, guid), kind,
                                          start_values=starts, description=description, version=version,
                                          generation_tool=generation_tool)

    if fmi_version == 3:
        files["sources/buildDescription.xml"] = build_description_fmi3(kind, c_sources(fmi_version))

        def model_description(token):  # noqa: F811 - the FMI 3.0 one
            return model_description_fmi3(kind, starts, description=description, version=version,
                                          generation_tool=generation_tool, token=token)

    guid = content_guid({**files, "modelDescription.xml": model_description(GUID_PLACEHOLDER),
                         START_FILE: _start_file(kind, starts, GUID_PLACEHOLDER)})
    files["modelDescription.xml"] = model_description(guid)
    files[START_FILE] = _start_file(kind, starts, guid)
    return zip_bytes(files)
