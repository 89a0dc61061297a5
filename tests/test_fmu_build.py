"""Building FMU kinds from fmu_src: model description, compliance checks, module names, the check entry."""

from __future__ import annotations

import re
import shlex
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from fmu_helpers import initial_unknowns, model_description, output_dependencies, packaged_modules, rewrite_fmu

from build_scripts import build_fmu, kind_names, load_kind, resolve_start_values
from build_scripts.check import check_variant_apart, main as check_main
from build_scripts.compliance import compliance_problems
from build_scripts.kinds import module_name_conflicts, module_source
from build_scripts.reference import read_reference
from build_scripts.runners import run_fmpy_loop, run_libcosim_apart
from build_scripts.units import SI_UNITS

EXPECTED_UNITS = {"hub_z": "m", "hub_vz": "m/s", "road_z": "m", "road_vz": "m/s", "stiffness": "N/m",
                  "damping": "N.s/m", "unloaded_radius": "m", "force_z": "N", "deflection": "m",
                  "deflection_rate": "m/s"}
SI_EXPONENTS = {"m": {"m": 1}, "m/s": {"m": 1, "s": -1}, "N": {"kg": 1, "m": 1, "s": -2},
                "N/m": {"kg": 1, "s": -2}, "N.s/m": {"kg": 1, "s": -1}}


@pytest.fixture(scope="session")
def fmu(tmp_path_factory) -> Path:
    return build_fmu("point_contact", tmp_path_factory.mktemp("build") / "point_contact.fmu",
                     start_values={"stiffness": 312345.6789012345, "damping": 1234.5, "unloaded_radius": 0.8})


def rewrite_model_description(fmu, dest, edit) -> Path:
    """Copy `fmu` to `dest` with ``edit(root)`` applied to its modelDescription.xml."""
    def edited(data):
        root = ET.fromstring(data)
        edit(root)
        return ET.tostring(root, encoding="UTF-8", xml_declaration=True)

    return rewrite_fmu(fmu, dest, "modelDescription.xml", edited)


def test_validate_fmu_is_empty_and_compliance_passes(fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu)) == []
    assert compliance_problems(fmu) == []


def test_every_variable_has_description_and_si_unit_with_base_unit_exponents(fmu):
    root = model_description(fmu)
    units = {u.get("name"): {k: int(v) for k, v in u.find("BaseUnit").attrib.items()}
             for u in root.find("UnitDefinitions")}
    assert {u: units[u] for u in SI_EXPONENTS} == SI_EXPONENTS
    for sv in root.iter("ScalarVariable"):
        assert sv.get("description"), sv.get("name")
        real = sv.find("Real")
        if real is not None:
            assert real.get("unit") == EXPECTED_UNITS[sv.get("name")]
            assert real.get("unit") in units
    assert root.get("description")


def test_default_experiment_and_state_flags(fmu):
    root = model_description(fmu)
    de = root.find("DefaultExperiment")
    assert (float(de.get("startTime")), float(de.get("stopTime")), float(de.get("stepSize"))) == (0.0, 0.5, 0.001)
    cs = root.find("CoSimulation")
    assert cs.get("modelIdentifier") == "CleatfmuPointContact"
    assert (cs.get("canGetAndSetFMUstate"), cs.get("canSerializeFMUstate")) == ("true", "true")


def test_outputs_declare_direct_feedthrough_and_initial_unknowns(fmu):
    root = model_description(fmu)
    outputs = output_dependencies(root)
    assert outputs["force_z"][0] == {"hub_z", "hub_vz", "road_z", "road_vz"}
    assert set(outputs["force_z"][1]) == {"tunable"}
    assert outputs["deflection"][0] == {"hub_z", "road_z"}
    assert initial_unknowns(root) == {"force_z", "deflection", "deflection_rate", "in_contact"}


def test_start_values_are_written_with_full_precision(fmu):
    starts = {sv.get("name"): sv.find("Real").get("start") for sv in model_description(fmu).iter("ScalarVariable")
              if sv.find("Real") is not None and sv.find("Real").get("start") is not None}
    assert float(starts["stiffness"]) == 312345.6789012345  # pythonfmu alone writes 16 significant digits
    assert float(starts["hub_z"]) == float(starts["unloaded_radius"]) == 0.8


def test_fmpy_info_shows_every_parameter_with_unit_and_description(fmu):
    """``fmpy info`` prints inputs and outputs; the same function lists the parameters on request."""
    import subprocess

    from fmpy.util import fmu_info

    kind = load_kind("point_contact")
    text = fmu_info(str(fmu), causalities=["parameter"])
    for v in kind.variables:
        if v.causality == "parameter":
            line = next(line for line in text.splitlines() if line.strip().startswith(v.name))
            assert f" {v.unit} " in line and v.description in line
    fmpy_cli = Path(sys.executable).with_name("fmpy")
    shown = subprocess.run([str(fmpy_cli), "info", str(fmu)], capture_output=True, text=True, check=True).stdout
    for v in kind.variables:
        if v.causality in ("input", "output"):
            line = next(line for line in shown.splitlines() if line.strip().startswith(v.name))
            assert v.description in line and (v.type != "Real" or f" {v.unit} " in line)


def test_compliance_check_detects_missing_units_and_structure(fmu, tmp_path):
    def drop_units(root):
        for real in root.iter("Real"):
            real.attrib.pop("unit", None)

    def drop_initial_unknowns(root):
        structure = root.find("ModelStructure")
        structure.remove(structure.find("InitialUnknowns"))

    def drop_description(root):
        next(root.iter("ScalarVariable")).attrib.pop("description")

    assert any("unit" in p for p in compliance_problems(rewrite_model_description(fmu, tmp_path / "a.fmu", drop_units)))
    assert any("InitialUnknowns" in p for p in
               compliance_problems(rewrite_model_description(fmu, tmp_path / "b.fmu", drop_initial_unknowns)))
    assert any("description" in p for p in
               compliance_problems(rewrite_model_description(fmu, tmp_path / "c.fmu", drop_description)))


def test_fmu_contains_the_law_and_shared_modules_verbatim_and_only_kind_prefixed_modules(fmu):
    import identification.model.tire_law as law

    entry, modules = packaged_modules(fmu)
    assert re.fullmatch(r"cleatfmu_point_contact_b[0-9a-f]{10}", entry)  # unique to the build
    assert modules[f"{entry}_law"] == Path(law.__file__).read_bytes()
    assert modules[f"{entry}_table"] == module_source("fmu_src.table_slave")
    assert modules[f"{entry}_wrapper"] == module_source("fmu_src.pythonfmu_wrapper")
    assert set(modules) == {entry, f"{entry}_slave", f"{entry}_law", f"{entry}_table", f"{entry}_wrapper"}


def test_module_name_and_identifier_conflicts_between_kinds_are_found():
    kind = load_kind("point_contact")
    assert module_name_conflicts([load_kind(k) for k in kind_names()]) == []
    clone = type(kind)(**{**kind.__dict__, "name": "point"})  # "cleatfmu_point_contact" is now ambiguous
    problems = module_name_conflicts([kind, clone])
    assert any("cleatfmu_point_contact" in p and "used by kinds" in p for p in problems)
    assert any("model identifier" in p for p in problems)


def test_build_leaves_no_import_side_effects(tmp_path):
    path_before = list(sys.path)
    build_fmu("point_contact", tmp_path / "x.fmu")
    assert sys.path == path_before
    assert not [m for m in sys.modules if m.startswith("cleatfmu_point_contact")
                and "resources" not in str(getattr(sys.modules[m], "__file__", ""))]


def test_start_value_resolution():
    kind = load_kind("point_contact")
    starts = resolve_start_values(kind, {"unloaded_radius": 0.9})
    assert starts["hub_z"] == starts["unloaded_radius"] == 0.9
    with pytest.raises(ValueError, match="not an input or parameter"):
        resolve_start_values(kind, {"force_z": 1.0})
    with pytest.raises(ValueError, match="finite"):
        resolve_start_values(kind, {"stiffness": float("nan")})


@pytest.mark.parametrize("kwargs, match", [
    (dict(kind="no_such_kind"), "unknown FMU kind"),
    (dict(start_values={"stiffness": -1.0}), "stiffness k must be > 0"),
    (dict(start_values={"damping": -1.0}), "damping c must be >= 0"),
])
def test_build_errors_leave_nothing_behind(tmp_path, kwargs, match):
    kind = kwargs.pop("kind", "point_contact")
    with pytest.raises(ValueError, match=match):
        build_fmu(kind, tmp_path / "bad.fmu", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_build_failure_keeps_an_existing_file(tmp_path, monkeypatch):
    import build_scripts.build as build

    dest = tmp_path / "keep.fmu"
    dest.write_bytes(b"previous")

    def broken(*args, **kwargs):
        raise RuntimeError("simulated failure while completing the model description")

    monkeypatch.setattr(build, "complete_model_description", broken)
    with pytest.raises(RuntimeError):
        build_fmu("point_contact", dest)
    assert dest.read_bytes() == b"previous" and list(tmp_path.iterdir()) == [dest]


def test_units_of_every_kind_are_known_si_units():
    for name in kind_names():
        for v in load_kind(name).variables:
            assert v.type != "Real" or v.unit in SI_UNITS


def test_check_entry_passes_for_every_kind(capsys):
    assert check_main([]) == 0
    out = capsys.readouterr().out
    assert "all passed" in out and "libcosimpy" in out


def _wrapped_python(tmp_path, monkeypatch, when: str) -> None:
    """The check's children run through a shell wrapper that aborts them (SIGABRT) `when` ("before" or "after")
    the real interpreter has run the variant's checks."""
    wrapper = tmp_path / "python"
    real = shlex.quote(sys.executable)
    body = 'kill -ABRT $$\n' if when == "before" else f'{real} "$@"\nkill -ABRT $$\n'
    wrapper.write_text(f"#!/bin/sh\n{body}", encoding="utf-8")
    wrapper.chmod(0o755)
    monkeypatch.setattr(sys, "executable", str(wrapper))


@pytest.mark.parametrize("when", ["before", "after"])
def test_a_variant_whose_process_aborts_is_named(tmp_path, monkeypatch, capsys, when):
    """Each variant is checked in a process of its own: one aborted before writing its result is a problem of
    that variant; one aborted after writing it keeps its result, and a line says how it ended."""
    _wrapped_python(tmp_path, monkeypatch, when)
    problems = check_variant_apart("point_contact", "native", 2, tmp_path)
    out = capsys.readouterr().out
    if when == "before":
        assert problems == ["point_contact (native, FMI 2): its check process ended with signal SIGABRT before "
                            "writing its result"]
    else:
        assert problems == [] and "point_contact (native, FMI 2): OK" in out
        assert "then ended with signal SIGABRT" in out


@pytest.mark.parametrize("when", ["before", "after"])
def test_libcosim_in_a_process_that_aborts(fmu, tmp_path, monkeypatch, when):
    """libcosim's run in a child process: aborted after writing its outputs, they stand (the same as fmpy's
    loop) and the log line says how it ended; aborted before, it raises."""
    kind = load_kind("point_contact")
    ref = read_reference("point_contact")
    signals = {n: ref[n] for n in ["time", *kind.names("input")]}
    outputs = kind.names("output")
    expected = run_fmpy_loop(fmu, signals, outputs)
    _wrapped_python(tmp_path, monkeypatch, when)
    lines = []
    if when == "before":
        with pytest.raises(RuntimeError, match="ended before its result"):
            run_libcosim_apart(fmu, signals, outputs, log=lines.append)
        return
    got = run_libcosim_apart(fmu, signals, outputs, log=lines.append)
    assert all(np.array_equal(got[n], expected[n]) for n in outputs)
    assert lines == ["point_contact.fmu: libcosim's process wrote its result, then ended with signal SIGABRT"]
