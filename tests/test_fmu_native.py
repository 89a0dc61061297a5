"""The native (C) tire FMUs: compliance, the law against the Python law, importers, a host without Python."""

from __future__ import annotations

import math
import re
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmu_helpers import assert_fmpy_matches_the_reference, assert_libcosim_matches_fmpy, assert_runs_match_the_law
from native_fixtures import AWKWARD_DIR, assert_step_response, c_host, extract, guid, native_fmus, run_host  # noqa: F401,E501

from build_scripts import build_fmu, load_kind
from build_scripts.binary_exports import exported_names, fmi_function_names
from build_scripts.check import state_round_trip_problems
from build_scripts.compliance import compliance_problems
from build_scripts.native import _fmpy_headers
from build_scripts.reference import read_reference
from build_scripts.runners import open_fmpy_slave, variable_refs
from identification.model import tire_law

KINDS = ("point_contact", "extended_tire")
G = 9.80665


@pytest.mark.parametrize("kind", KINDS)
def test_compliant_and_reproduces_the_python_reference_in_fmpy_and_libcosim(native_fmus, kind):
    fmu, k = native_fmus[kind], load_kind(kind)
    assert compliance_problems(fmu) == []
    inputs, outputs = k.names("input"), k.names("output")
    reals = [n for n in outputs if k.variable(n).type == "Real"]
    assert_fmpy_matches_the_reference(fmu, k, inputs, outputs, reals, start_values=k.reference_start_values)
    assert_libcosim_matches_fmpy(fmu, kind, inputs, outputs, start_values=k.reference_start_values)
    ref = read_reference(kind)
    signals = {n: ref[n] for n in ["time", *inputs]}
    assert state_round_trip_problems(fmu, signals, outputs, k.reference_start_values) == []


@pytest.mark.parametrize("kind", KINDS)
def test_default_experiment_shows_the_static_equilibrium(native_fmus, kind):
    from fmpy import simulate_fmu

    res = simulate_fmu(str(native_fmus[kind]), output=["force_z", "deflection", "in_contact"])
    assert float(res["time"][-1]) > 0.0
    np.testing.assert_allclose(res["force_z"], 15000.0, rtol=1e-12)       # the default wheel load, N
    np.testing.assert_allclose(res["deflection"], 15000.0 / 400e3, rtol=1e-12)  # W / k, m
    assert res["in_contact"].all()


def test_progressive_tire_starts_at_its_equilibrium_off_the_built_in_cleat(tmp_path):
    from fmpy import simulate_fmu

    starts = {"stiffness_exponent": 1.5, "static_load": 12000.0, "cleat_height": 0.04, "cleat_x": 0.0,
              "footprint_length": 0.3, "lug_amplitude": 0.0}
    fmu = build_fmu("extended_tire", tmp_path / "p.fmu", start_values=starts, backend="native",
                    platforms=["linux64"])
    res = simulate_fmu(str(fmu), output=["force_z", "deflection", "road_effective_z"])
    np.testing.assert_allclose(res["force_z"], 12000.0, rtol=1e-12)
    np.testing.assert_allclose(res["deflection"], 1.5 * 12000.0 / 400e3, rtol=1e-12)  # n W / k
    assert np.all(res["road_effective_z"] == 0.0)  # not on the cleat


def _draw_extended(rng):
    """Random parameters (each option on or off, the footprint's pressure uniform or parabolic, or in 30 % of
    the cases the ring's envelope, the built-in cleat rectangular or, in half the cases, bevelled with
    b in (0, w/2]) and inputs near the built-in cleat."""
    on = rng.random(6) < 0.6
    p = {"stiffness": rng.uniform(1e5, 1e6), "damping": rng.uniform(0.0, 8e3), "unloaded_radius": rng.uniform(0.4, 1.0),
         "footprint_length": rng.uniform(0.05, 0.5) if on[0] else 0.0, "cleat_x": rng.uniform(-0.5, 0.5),
         "cleat_height": rng.uniform(0.01, 0.08) if on[1] else 0.0, "cleat_width": rng.uniform(0.02, 0.3),
         "unilateral": bool(on[2]), "stiffness_exponent": rng.uniform(0.6, 2.5) if on[3] else 1.0,
         "static_load": rng.uniform(5e3, 3e4), "friction_force": rng.uniform(0.0, 800.0) if on[4] else 0.0,
         "friction_velocity": rng.uniform(1e-3, 0.1), "lug_amplitude": rng.uniform(-3e-3, 3e-3) if on[5] else 0.0,
         "lug_pitch": rng.uniform(0.1, 0.5), "lug_phase": rng.uniform(-4.0, 4.0),
         "parabolic_pressure": bool(rng.random() < 0.5), "ring_envelope": bool(rng.random() < 0.3)}
    p["cleat_bevel"] = 0.5 * p["cleat_width"] * (1.0 - rng.random()) if rng.random() < 0.5 else 0.0
    deflection = p["stiffness_exponent"] * p["static_load"] / p["stiffness"]
    u = {"hub_z": p["unloaded_radius"] - deflection + rng.uniform(-0.08, 0.08), "hub_vz": rng.normal(0, 0.5),
         "road_z": rng.uniform(-0.02, 0.02), "road_vz": rng.normal(0, 0.3),
         "hub_x": p["cleat_x"] + rng.uniform(-0.4, 0.6), "hub_vx": rng.uniform(0.0, 4.0)}
    return p, u


def _agree(got, want, what):
    assert abs(got - want) <= 1e-12 * abs(want), f"{what}: C {got!r}, Python {want!r}"


def test_c_law_agrees_with_the_python_law_on_random_inputs_over_every_option(native_fmus):
    fmu = native_fmus["extended_tire"]
    refs = variable_refs(fmu)
    flags = ["unilateral", "parabolic_pressure", "ring_envelope"]
    real_params = [n for n in tire_law.EXTENDED_DEFAULTS if n not in flags]
    outputs = ["force_z", "deflection", "deflection_rate", "road_effective_z"]
    rng = np.random.default_rng(20261123)
    rings = 0
    s = open_fmpy_slave(fmu)
    seen_contact, footprints = set(), {False: 0, True: 0}
    bevels = {"point contact": 0, "uniform": 0, "parabolic": 0}
    try:
        for i in range(8000):
            p, u = _draw_extended(rng)
            s.setReal([refs[n][0] for n in real_params], [p[n] for n in real_params])
            s.setBoolean([refs[n][0] for n in flags], [p[n] for n in flags])
            s.setReal([refs[n][0] for n in u], list(u.values()))
            got = s.getReal([refs[n][0] for n in outputs])
            contact = s.getBoolean([refs["in_contact"][0]])[0]
            f, d, dd, c, road = tire_law.extended_tire(u["hub_z"], u["hub_vz"], u["hub_x"], u["hub_vx"], u["road_z"],
                                                       u["road_vz"], p)
            for name, a, b in zip(outputs, got, (f, d, dd, road)):
                _agree(a, b, f"draw {i}: {name}")
            assert bool(contact) == bool(c), f"draw {i}"
            seen_contact.add((p["unilateral"], bool(c)))
            if p["ring_envelope"] and p["footprint_length"] > 0.0 and p["cleat_height"] > 0.0:
                rings += road != u["road_z"] + tire_law.lug_road(u["hub_x"], p["lug_amplitude"], p["lug_pitch"],
                                                                  p["lug_phase"])[0]   # the ring on the cleat
                continue
            cleat, slope = tire_law.footprint_cleat(u["hub_x"], p["footprint_length"], p["cleat_x"],
                                                    p["cleat_height"], p["cleat_width"], p["parabolic_pressure"],
                                                    p["cleat_bevel"])
            on_ramp = cleat > 0.0 and slope != 0.0
            if p["footprint_length"] > 0.0 and on_ramp and p["cleat_bevel"] == 0.0:  # partly in the footprint
                footprints[p["parabolic_pressure"]] += 1
            if p["cleat_bevel"] > 0.0 and on_ramp:  # on a bevel, or a bevel partly in the footprint
                bevels["point contact" if p["footprint_length"] == 0.0 else
                       "parabolic" if p["parabolic_pressure"] else "uniform"] += 1
        s.terminate()
    finally:
        s.freeInstance()
    assert seen_contact == {(False, False), (False, True), (True, False), (True, True)}
    assert rings >= 300, rings   # the ring's envelope on the cleat
    assert min(footprints.values()) >= 100, footprints  # both footprint pressures on the cleat's ramps
    # bevelled cleats on the ramps: under the contact point (on a bevel) and partly in both footprint pressures
    assert bevels["point contact"] >= 40 and min(bevels["uniform"], bevels["parabolic"]) >= 150, bevels


def test_parabolic_footprint_step_run_reproduces_the_python_law_in_both_backends(native_fmus, tmp_path):
    """The reference experiment (every option on) with a parabolic footprint pressure, stepped by fmpy: the
    native FMU (built with the option, or switched to it before initialization) and the pythonfmu FMU give
    the Python law's outputs for the inputs held over each step, and the independent closed form's."""
    from build_scripts.reference import closed_form_outputs

    kind = load_kind("extended_tire")
    inputs, outputs = kind.names("input"), kind.names("output")
    starts = {**kind.reference_start_values, "parabolic_pressure": True}
    p = {**tire_law.EXTENDED_DEFAULTS, **starts}
    ref = read_reference("extended_tire")
    signals = {n: ref[n] for n in ["time", *inputs]}
    held = {n: np.concatenate([signals[n][:1], signals[n][:-1]]) for n in inputs}  # fmpy's alignment
    rows = [tire_law.extended_tire(*(float(held[n][k]) for n in ("hub_z", "hub_vz", "hub_x", "hub_vx", "road_z",
                                                                 "road_vz")), p) for k in range(ref["time"].size)]
    law = {name: np.array([row[j] for row in rows]) for j, name in
           enumerate(("force_z", "deflection", "deflection_rate", "in_contact", "road_effective_z"))}
    closed = closed_form_outputs("extended_tire", signals, p)
    # the option matters in this run: another road under the tire, another force than the reference's
    assert np.abs(law["road_effective_z"] - ref["road_effective_z"]).max() > 1e-3
    assert np.abs(law["force_z"] - ref["force_z"]).max() > 1000.0
    runs = {"native built with the option": (build_fmu("extended_tire", tmp_path / "native.fmu", backend="native",
                                                       start_values=starts, platforms=["linux64"]), None),
            "native switched before initialization": (native_fmus["extended_tire"], starts),
            "pythonfmu built with the option": (build_fmu("extended_tire", tmp_path / "py.fmu", start_values=starts),
                                                None)}
    assert_runs_match_the_law(runs, signals, outputs, law, closed, kind)


def test_c_point_contact_agrees_with_the_python_law(native_fmus):
    fmu = native_fmus["point_contact"]
    refs = variable_refs(fmu)
    names = ["hub_z", "hub_vz", "road_z", "road_vz", "stiffness", "damping", "unloaded_radius"]
    rng = np.random.default_rng(7)
    s = open_fmpy_slave(fmu)
    try:
        for _ in range(1000):
            v = [rng.uniform(0.5, 1.0), rng.normal(0, 1), rng.uniform(-0.05, 0.05), rng.normal(0, 1),
                 rng.uniform(1e5, 1e6), rng.uniform(0, 1e4), rng.uniform(0.5, 1.0)]
            s.setReal([refs[n][0] for n in names], v)
            got = s.getReal([refs[n][0] for n in ("force_z", "deflection", "deflection_rate")])
            want = tire_law.point_contact(*v)
            for a, b in zip(got, want[:3]):
                _agree(a, b, "point contact")
            assert bool(s.getBoolean([refs["in_contact"][0]])[0]) == bool(want[3])
        s.terminate()
    finally:
        s.freeInstance()


def test_refused_values_are_fmi2Error_with_a_logged_reason_and_the_instance_stays_usable(native_fmus):
    from fmpy.fmi1 import FMICallException

    fmu = native_fmus["extended_tire"]
    refs = {n: r for n, (r, _) in variable_refs(fmu).items()}
    messages = []
    s = open_fmpy_slave(fmu, logger=lambda status, category, message: messages.append((status, category, message)))
    try:
        before = s.getReal([refs["stiffness"], refs["force_z"]])
        for name, value, reason in (("stiffness", -1.0, "stiffness must be > 0"), ("hub_z", math.nan, "finite"),
                                    ("damping", math.inf, "finite"), ("force_z", 1.0, "is not a Real"),
                                    ("cleat_bevel", -0.01, "cleat_bevel must be >= 0 m"),
                                    ("cleat_bevel", math.nan, "cleat_bevel = nan")):
            with pytest.raises(FMICallException) as info:
                s.setReal([refs[name]], [value])
            assert info.value.status == 3  # fmi2Error, not fmi2Fatal
            assert any(st == 3 and cat == "logStatusError" and reason in m for st, cat, m in messages), messages
            assert s.getReal([refs["stiffness"], refs["force_z"]]) == before
        s.doStep(0.0, 1e-3)
        s.setReal([refs["stiffness_exponent"]], [1.5])  # needs static_load > 0 (default 0)
        with pytest.raises(FMICallException):
            s.getReal([refs["force_z"]])
        assert "static_load must be > 0 N" in messages[-1][2]
        s.setReal([refs["static_load"]], [15000.0])
        assert s.getReal([refs["force_z"]])[0] > 0.0
        s.doStep(1e-3, 1e-3)
        s.setReal([refs["cleat_bevel"]], [0.08])  # > cleat_width / 2 (0.05 m) until the width is set: accepted
        for call in (lambda: s.getReal([refs["force_z"]]), lambda: s.doStep(2e-3, 1e-3)):
            with pytest.raises(FMICallException) as info:
                call()
            assert info.value.status == 3
            assert "cleat_bevel must be <= cleat_width / 2" in messages[-1][2], messages[-1]
        s.setReal([refs["cleat_width"]], [0.16])
        assert s.getReal([refs["cleat_bevel"]]) == [0.08] and s.getReal([refs["force_z"]])[0] > 0.0
        s.doStep(2e-3, 1e-3)
        s.terminate()
    finally:
        s.freeInstance()


def test_byte_identical_re_export_with_content_guid_fixed_dates_mode_0644_and_no_build_machine_paths(tmp_path):
    import os
    import socket

    starts = {"stiffness": 512345.0, "damping": 3210.0}
    a = build_fmu("point_contact", tmp_path / "a.fmu", start_values=starts, backend="native")
    (tmp_path / "sub").mkdir()
    b = build_fmu("point_contact", tmp_path / "sub" / "b.fmu", start_values=starts, backend="native")
    c = build_fmu("point_contact", tmp_path / "c.fmu", start_values={**starts, "damping": 3211.0}, backend="native")
    assert a.read_bytes() == b.read_bytes()
    assert guid(a) != guid(c)
    with zipfile.ZipFile(a) as z:
        infos = z.infolist()
        blob = b"".join(z.read(i) for i in infos)
    assert [i.filename for i in infos] == sorted(i.filename for i in infos)
    assert all(i.date_time == (1980, 1, 1, 0, 0, 0) and (i.external_attr >> 16) & 0o777 == 0o644 for i in infos)
    for secret in {str(tmp_path), os.path.expanduser("~"), os.getcwd(), socket.gethostname(), "cleatfmu_cc_"} - {
            "/", ""}:
        assert secret.encode() not in blob, secret


def test_two_compilations_give_byte_identical_binaries(tmp_path, monkeypatch):
    from build_scripts import native
    from build_scripts.native_fmu import _kind_for_native

    kind = _kind_for_native(load_kind("point_contact"))
    builds = []
    for run in ("first", "second"):
        monkeypatch.setenv("CLEATFMU_CACHE_DIR", str(tmp_path / run))  # empty: compile again
        builds.append(native.compile_binaries(kind, 2, ["linux64", "win64", "darwin64"]))
    assert builds[0] == builds[1]  # no link time, PDB signature or build path inside


def test_windows_and_macos_binaries_export_every_fmi2_function(native_fmus):
    required = fmi_function_names((_fmpy_headers() / "fmi2Functions.h").read_text())
    assert len(required) >= 40
    for kind, fmu in native_fmus.items():
        with zipfile.ZipFile(fmu) as z:
            names = [n for n in z.namelist() if n.startswith("binaries/")]
            assert sorted(n.split("/")[1] for n in names) == ["darwin64", "linux64", "win64"]
            for name in names:
                data = z.read(name)
                assert b"python" not in data.lower(), name  # no libpython, python3.dll or _Py symbols needed
                if name.endswith((".dll", ".dylib")):
                    assert required <= exported_names(data), name


def test_fmpy_runs_the_fmu_extracted_under_a_path_with_umlaut_hash_percent_and_spaces(native_fmus, tmp_path):
    from fmpy import simulate_fmu

    unzipped = extract(native_fmus["point_contact"], tmp_path / AWKWARD_DIR)
    res = simulate_fmu(str(unzipped), output=["force_z"])
    np.testing.assert_allclose(res["force_z"], 15000.0, rtol=1e-12)


def test_c_host_without_python_equilibrium_uri_forms_and_no_leak(native_fmus, c_host, tmp_path):
    fmu = native_fmus["point_contact"]
    unzipped = extract(fmu, tmp_path / AWKWARD_DIR)
    resources = unzipped / "resources"
    uris = [resources.as_uri(), resources.as_uri() + "/", f"file:{resources}", f"file://localhost{resources}/",
            str(resources)]
    for uri in uris:
        assert float(run_host(c_host, unzipped, uri, guid(fmu), "equilibrium")) == pytest.approx(15000.0, rel=1e-12)
    growth = int(run_host(c_host, unzipped, resources.as_uri(), guid(fmu), "leak", 10000))
    assert growth <= 1024 * 1024, f"RSS grew by {growth} bytes over 10000 instantiate/free cycles"


def test_c_host_step_response_matches_the_python_law_and_the_damped_oscillator(c_host, tmp_path):
    k, c, r0, load = 400e3, 20e3, 0.75, 15000.0
    mass = load / G
    fmu = build_fmu("point_contact", tmp_path / "pc.fmu", start_values={"damping": c}, backend="native",
                    platforms=["linux64"])
    unzipped = extract(fmu, tmp_path / AWKWARD_DIR)
    h, n, height = 1e-4, 30000, 0.01
    rows = np.array([[float(x) for x in line.split()] for line in
                     run_host(c_host, unzipped, (unzipped / "resources").as_uri(), guid(fmu), "step", mass, height,
                              n, h).splitlines()])
    assert_step_response(rows, k=k, c=c, r0=r0, load=load, height=height, h=h)


def test_binaries_are_cached_per_platform_and_law_version(native_fmus, tmp_path, monkeypatch):
    import subprocess
    import time

    from build_scripts import native

    # Warm cache (the session's FMUs): an export compiles nothing and takes under a second.
    def no_compiler(*args, **kwargs):
        raise AssertionError("compiled although the binaries are cached")

    real_run = subprocess.run
    monkeypatch.setattr(native.subprocess, "run", no_compiler)
    start = time.perf_counter()
    fmu = build_fmu("point_contact", tmp_path / "warm.fmu", backend="native")
    assert time.perf_counter() - start <= 1.0
    assert fmu.read_bytes() == native_fmus["point_contact"].read_bytes()
    # An empty cache folder (CLEATFMU_CACHE_DIR) makes the build compile, into that folder.
    monkeypatch.setattr(native.subprocess, "run", real_run)
    monkeypatch.setenv("CLEATFMU_CACHE_DIR", str(tmp_path / "cache"))
    build_fmu("point_contact", tmp_path / "cold.fmu", backend="native", platforms=["linux64"])
    cached = list((tmp_path / "cache").rglob("CleatfmuPointContact.so"))
    assert len(cached) == 1
    with zipfile.ZipFile(tmp_path / "cold.fmu") as z:
        assert z.read("binaries/linux64/CleatfmuPointContact.so") == cached[0].read_bytes()
    # The key is the law version: another source gives another folder.
    kind = load_kind("point_contact")
    assert native.law_version(kind, 2) != native.law_version(kind, 3)


def test_call_sequence_log_categories_and_reset(native_fmus, tmp_path):
    from fmpy import read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave

    fmu = native_fmus["point_contact"]
    md = read_model_description(str(fmu))
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu, tmp_path / "x"), modelIdentifier="CleatfmuPointContact",
                  instanceName="seq")
    # fmpy's default callbacks reach, through its logger proxy, the last Python logger any instance
    # registered (maybe freed by now): instantiate without logging.
    s.instantiate(loggingOn=False)
    try:
        with pytest.raises(FMICallException) as info:
            s.doStep(0.0, 1e-3)  # before initialization
        assert info.value.status == 3
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        with pytest.raises(FMICallException):
            s.setupExperiment(startTime=0.0)  # only once, before initialization
        with pytest.raises(FMICallException):
            s.setDebugLogging(True, ["logNothing"])
        s.setReal([4, 0], [5e5, 0.74])  # stiffness, hub_z
        assert s.getReal([7])[0] == pytest.approx(5e5 * 0.01, rel=1e-12)
        s.terminate()
        with pytest.raises(FMICallException):
            s.setReal([0], [0.7])  # after terminate
        s.reset()  # back to the start values: k = 400 kN/m, hub at the 15 kN equilibrium
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        assert s.getReal([4])[0] == 400e3 and s.getReal([7])[0] == pytest.approx(15000.0, rel=1e-12)
        s.terminate()
    finally:
        s.freeInstance()


def test_log_categories_reach_the_importer(native_fmus):
    from build_scripts.runners import open_fmpy_slave

    messages = []
    s = open_fmpy_slave(native_fmus["point_contact"],
                        logger=lambda status, category, message: messages.append((status, category, message)))
    try:
        s.setDebugLogging(True, ["logCalls"])
        s.doStep(0.0, 1e-3)
        assert (0, "logCalls", "fmi2DoStep") in messages
        s.setDebugLogging(False, ["logStatusError"])
        count = len(messages)
        with pytest.raises(Exception):
            s.setReal([4], [-1.0])
        assert not [m for m in messages[count:] if m[1] == "logStatusError"]  # category switched off
        s.terminate()
    finally:
        s.freeInstance()


def test_linux_binary_needs_only_libc_and_libm_of_glibc_2_17(native_fmus):
    import re

    with zipfile.ZipFile(native_fmus["extended_tire"]) as z:
        data = z.read("binaries/linux64/CleatfmuExtendedTire.so")
    versions = {tuple(map(int, v)) for v in re.findall(rb"GLIBC_(\d+)\.(\d+)", data)}
    assert versions and max(versions) <= (2, 17), versions
    assert b"libpython" not in data and b"_Py_NoneStruct" not in data


def test_closing_a_tire_fmu_that_was_never_initialized_frees_it_without_an_error(native_fmus):
    """FMI refuses fmi2Terminate before initialization (the native FMU says so): close() must not call it,
    or its error would hide the one that stopped the run and leave the other instances open."""
    from identification.fmu.cosim import TireFmu

    tire = TireFmu(native_fmus["extended_tire"])
    tire.close()
    assert tire.slave is None
    with TireFmu(native_fmus["point_contact"]) as other:
        other.initialize(0.0)
        assert other.parameters()["stiffness"] > 0
    assert other.slave is None


def test_an_fmu_state_of_another_kind_or_corrupted_is_refused(native_fmus):
    """States carry their kind: an extended-tire state set into a point-contact instance (and the reverse)
    is fmi2Error, never installed (it once installed k = -1.15 N/m); a serialized state with any bit flipped
    or cut short is refused by its checksum, one of another layout version (with a valid checksum) by its
    header, and the instance keeps its own state."""
    from fmpy.fmi1 import FMICallException

    messages = []
    log = (lambda status, category, message: messages.append(message))
    point = open_fmpy_slave(native_fmus["point_contact"], instance_name="point", logger=log)
    ext = open_fmpy_slave(native_fmus["extended_tire"], instance_name="ext", logger=log)
    try:
        k_vr = variable_refs(native_fmus["point_contact"])["stiffness"][0]
        k_before = point.getReal([k_vr])[0]
        for target, source in ((point, ext), (ext, point)):
            foreign = source.getFMUstate()
            with pytest.raises(FMICallException) as info:
                target.setFMUstate(foreign)
            assert info.value.status == 3
            source.freeFMUstate(foreign)
        assert sum("not an FMU state of this FMU" in m for m in messages) == 2, messages
        assert point.getReal([k_vr])[0] == k_before
        blob = bytes(point.serializeFMUstate(point.getFMUstate()))
        point.setFMUstate(point.deSerializeFMUstate(blob))       # the intact copy is accepted
        rng = np.random.default_rng(7)
        accepted = 0
        for trial in range(2000):
            bad = bytearray(blob)
            for bit in rng.choice(8 * len(bad), size=1 + trial % 4, replace=False):
                bad[bit // 8] ^= 1 << (bit % 8)
            try:
                point.deSerializeFMUstate(bytes(bad))
                accepted += 1
            except FMICallException:
                pass
        for cut in (1, 8, len(blob) // 2):
            with pytest.raises(FMICallException):
                point.deSerializeFMUstate(blob[:-cut])
        assert accepted == 0

        def fnv1a(data):            # the documented checksum, written out: FNV-1a 64 of all but the last 8 bytes
            h = 1469598103934665603
            for byte in data:
                h = ((h ^ byte) * 1099511628211) % (1 << 64)
            return h.to_bytes(8, "little")

        assert blob[-8:] == fnv1a(blob[:-8])
        other_version = bytearray(blob[:-8])
        other_version[8 + 32 + 3] ^= 0x01                       # the layout version, top byte of the header
        with pytest.raises(FMICallException):
            point.deSerializeFMUstate(bytes(other_version) + fnv1a(other_version))
        assert "not a serialized state of FMU kind point_contact" in messages[-1]
        assert point.getReal([k_vr])[0] == k_before
    finally:
        for s in (point, ext):
            s.terminate()
            s.freeInstance()


def test_every_kind_links_statically_into_one_program_from_its_sources(tmp_path):
    """The five kinds' sources/ (the files their model descriptions list), each compiled with its own
    FMI2_FUNCTION_PREFIX and warnings as errors, link into one C program without a clash (the shared names
    are the kind's own), and each kind run there gives its FMU's outputs (fmpy, the shipped binary)."""
    import shutil
    import subprocess

    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc is not installed")
    kinds = {"point_contact": "pc", "extended_tire": "ext", "tractor_body": "body", "road_profile": "road",
             "map_tire": "map"}
    objects, runs = [], {}
    for kind, prefix in kinds.items():
        fmu = build_fmu(kind, tmp_path / f"{kind}.fmu", backend="native")
        folder = extract(fmu, tmp_path / kind)
        md = read_model_description(str(fmu), validate=False)
        with zipfile.ZipFile(fmu) as z:   # the files the model description's SourceFiles lists
            sources = re.findall(r'<File name="([^"]+)"', z.read("modelDescription.xml").decode())
        assert sources and all(name.endswith(".c") for name in sources)
        for name in sources:
            obj = tmp_path / f"{prefix}_{name[:-2]}.o"
            subprocess.run([gcc, "-c", "-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror",
                            f"-DFMI2_FUNCTION_PREFIX={prefix}_", "-I", str(folder / "sources"), "-o", str(obj),
                            str(folder / "sources" / name)], check=True, capture_output=True)
            objects.append(str(obj))
        outputs = [v for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
        runs[kind] = (prefix, fmu, folder, md, outputs)
    host = tmp_path / "static_host"
    linked = subprocess.run([gcc, "-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror", "-I",
                             str(_fmpy_headers()), "-o", str(host),
                             str(Path(__file__).with_name("native_static_host.c")), *objects, "-lm"],
                            capture_output=True, text=True)
    assert linked.returncode == 0, linked.stderr[-3000:]
    steps, h = 40, 0.005
    for kind, (prefix, fmu, folder, md, outputs) in runs.items():
        vrs = [v.valueReference for v in outputs]
        done = subprocess.run([str(host), prefix, (folder / "resources").as_uri(), md.guid, str(steps), repr(h),
                               *map(str, vrs)], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, (kind, done.stderr)
        static = np.array([[float(x) for x in line.split()] for line in done.stdout.splitlines()])
        slave = FMU2Slave(guid=md.guid, unzipDirectory=str(folder), modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName=prefix)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        shipped = [slave.getReal(vrs)]
        for k in range(steps):
            slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            shipped.append(slave.getReal(vrs))
        slave.terminate()
        slave.freeInstance()
        shipped = np.array(shipped)
        assert static.shape == shipped.shape == (steps + 1, len(vrs)), kind
        scale = np.maximum(np.max(np.abs(shipped), axis=0), 1e-300)
        assert np.all(np.abs(static - shipped) <= 1e-12 * scale), (kind, np.max(np.abs(static - shipped) / scale))


def test_every_kind_compiles_for_fmi3_with_its_own_prefix_and_no_shared_global_name(tmp_path):
    """FMI 3.0: the five kinds' sources/ (their buildDescription.xml's files), each with its own
    FMI3_FUNCTION_PREFIX, define no global symbol twice between them, and every FMI function carries its
    kind's prefix (``nm`` on the objects)."""
    import shutil
    import subprocess

    gcc, nm = shutil.which("gcc"), shutil.which("nm")
    if gcc is None or nm is None:
        pytest.skip("gcc or nm is not installed")
    owners = {}
    for kind, prefix in {"point_contact": "pc", "extended_tire": "ext", "tractor_body": "body",
                         "road_profile": "road", "map_tire": "map"}.items():
        fmu = build_fmu(kind, tmp_path / f"{kind}.fmu", backend="native", fmi_version=3)
        folder = extract(fmu, tmp_path / kind)
        description = (folder / "sources" / "buildDescription.xml").read_text()
        sources = re.findall(r'<SourceFile name="([^"]+)"', description)
        assert sources
        for name in sources:
            obj = tmp_path / f"{prefix}_{name[:-2]}.o"
            subprocess.run([gcc, "-c", "-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror",
                            f"-DFMI3_FUNCTION_PREFIX={prefix}_", "-I", str(folder / "sources"), "-o", str(obj),
                            str(folder / "sources" / name)], check=True, capture_output=True)
            listed = subprocess.run([nm, "-g", "--defined-only", str(obj)], capture_output=True, text=True,
                                    check=True).stdout
            for symbol in (line.split()[-1] for line in listed.splitlines() if line.strip()):
                assert symbol not in owners, (symbol, owners.get(symbol), kind)
                owners[symbol] = kind
                assert not symbol.startswith("fmi3"), (kind, symbol)      # prefixed: pc_fmi3DoStep, ...
    assert {"pc_fmi3DoStep", "ext_fmi3DoStep", "body_fmi3DoStep", "road_fmi3DoStep", "map_fmi3DoStep"} <= set(owners)
