"""The extended tire FMU: the law it runs, its options, FMI behaviour, importers, robustness, leaks."""

from __future__ import annotations

import gc
import math
import os
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

import identification.tire_law as law
from build_scripts import build_fmu, load_kind
from build_scripts.compliance import compliance_problems
from build_scripts.reference import closed_form_outputs, read_reference
from build_scripts.runners import open_fmpy_slave, run_fmpy_loop, run_libcosim, simulate_fmpy, variable_refs
from test_fmu_point_contact import _fresh_cycle, rss_bytes

KIND = "extended_tire"
INPUTS = ["hub_z", "hub_vz", "road_z", "road_vz", "hub_x", "hub_vx"]
REAL_PARAMS = [n for n in law.EXTENDED_DEFAULTS if n != "unilateral"]
REAL_OUTPUTS = ["force_z", "deflection", "deflection_rate", "road_effective_z"]
OUTPUTS = REAL_OUTPUTS + ["in_contact"]
OPTION_SETS = [("footprint",), ("point_cleat",), ("unilateral",), ("progressive",), ("friction",), ("lugs",),
               ("footprint", "unilateral", "progressive", "friction", "lugs")]


@pytest.fixture(scope="module")
def fmu(tmp_path_factory) -> Path:
    """The extended tire FMU with the kind's default start values, built once."""
    return build_fmu(KIND, tmp_path_factory.mktemp("extended") / "extended_tire.fmu")


@pytest.fixture(scope="module")
def vr(fmu) -> dict:
    return {name: ref for name, (ref, _type) in variable_refs(fmu).items()}


@pytest.fixture
def slave(fmu):
    """An initialised instance with a logger; yields (slave, messages)."""
    messages = []
    s = open_fmpy_slave(fmu, logger=lambda status, category, message: messages.append((status, message)))
    yield s, messages
    s.terminate()
    s.freeInstance()


def random_parameters(rng, options) -> dict:
    """A valid parameter set with random k, c, r0 and the given options switched on."""
    p = dict(law.EXTENDED_DEFAULTS, stiffness=rng.uniform(1e5, 1.5e6), damping=rng.uniform(0.0, 2e4),
             unloaded_radius=rng.uniform(0.4, 1.0))
    if "footprint" in options or "point_cleat" in options:
        p.update(footprint_length=rng.uniform(0.05, 0.5) if "footprint" in options else 0.0,
                 cleat_x=rng.uniform(-1.0, 1.0), cleat_height=rng.uniform(0.01, 0.08),
                 cleat_width=rng.uniform(0.02, 0.3))
    if "unilateral" in options:
        p["unilateral"] = True
    if "progressive" in options:
        p.update(stiffness_exponent=rng.uniform(0.6, 2.0), static_load=rng.uniform(5e3, 4e4))
    if "friction" in options:
        p.update(friction_force=rng.uniform(10.0, 2000.0), friction_velocity=rng.uniform(0.001, 0.2))
    if "lugs" in options:
        p.update(lug_amplitude=rng.uniform(-0.005, 0.005), lug_pitch=rng.uniform(0.1, 0.5),
                 lug_phase=rng.uniform(-math.pi, math.pi))
    assert law.extended_parameter_problem(p) is None
    return p


def random_inputs(rng, p) -> list[float]:
    return [p["unloaded_radius"] + rng.uniform(-0.08, 0.03), rng.uniform(-2.0, 2.0), rng.uniform(-0.02, 0.04),
            rng.uniform(-1.0, 1.0), p["cleat_x"] + rng.uniform(-0.6, 0.9), rng.uniform(-4.0, 4.0)]


def set_parameters(s, vr, p) -> None:
    s.setReal([vr[n] for n in REAL_PARAMS], [float(p[n]) for n in REAL_PARAMS])
    s.setBoolean([vr["unilateral"]], [p["unilateral"]])


def read_outputs(s, vr) -> tuple:
    return (*s.getReal([vr[n] for n in REAL_OUTPUTS]), bool(s.getBoolean([vr["in_contact"]])[0]))


def law_outputs(u, p) -> tuple:
    """tire_law.extended_tire in the FMU's output order."""
    force, deflection, rate, contact, road = law.extended_tire(u[0], u[1], u[4], u[5], u[2], u[3], p)
    return force, deflection, rate, road, contact


def model_description(fmu) -> ET.Element:
    return ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))


# -- the law ------------------------------------------------------------------------------------

def test_parameters_are_the_laws_with_its_defaults(fmu):
    kind = load_kind(KIND)
    params = {v.name: v for v in kind.variables if v.causality == "parameter"}
    assert list(params) == list(law.EXTENDED_DEFAULTS)
    for name, default in law.EXTENDED_DEFAULTS.items():
        assert params[name].start == default and type(params[name].start) is type(default), name
        assert params[name].type == ("Boolean" if isinstance(default, bool) else "Real")
    starts = {}
    for sv in model_description(fmu).iter("ScalarVariable"):
        typed = sv[0]
        if sv.get("causality") == "parameter":
            starts[sv.get("name")] = (typed.get("start") == "true" if typed.tag == "Boolean"
                                      else float(typed.get("start")))
    assert starts == law.EXTENDED_DEFAULTS


@pytest.mark.parametrize("options", OPTION_SETS, ids=["+".join(o) for o in OPTION_SETS])
def test_outputs_are_the_law_for_random_inputs_and_parameters(slave, vr, options):
    s, _ = slave
    rng = np.random.default_rng(OPTION_SETS.index(options))
    seen_contact, active = set(), 0
    for _ in range(6):
        p = random_parameters(rng, options)
        set_parameters(s, vr, p)
        for _ in range(25):
            u = random_inputs(rng, p)
            s.setReal([vr[n] for n in INPUTS], u)
            expected = law_outputs(u, p)
            assert read_outputs(s, vr) == expected  # before doStep: direct feedthrough, bit for bit
            s.doStep(0.0, 1e-3)
            assert read_outputs(s, vr) == expected
            seen_contact.add(expected[-1])
            plain = {**law.EXTENDED_DEFAULTS, **{n: p[n] for n in ("stiffness", "damping", "unloaded_radius")}}
            active += law_outputs(u, plain)[0] != expected[0]
    assert seen_contact == {True, False}
    assert active >= 10  # the options change the force


def test_with_every_option_at_its_default_the_force_is_the_point_contact_force(fmu, vr, tmp_path):
    point = build_fmu("point_contact", tmp_path / "point_contact.fmu")
    pvr = {name: ref for name, (ref, _type) in variable_refs(point).items()}
    rng = np.random.default_rng(11)
    a, b = open_fmpy_slave(fmu, instance_name="extended"), open_fmpy_slave(point, instance_name="point")
    try:
        for _ in range(200):
            kcr = [rng.uniform(5e4, 2e6), rng.uniform(0.0, 2e4), rng.uniform(0.3, 1.0)]
            u = random_inputs(rng, {"unloaded_radius": kcr[2], "cleat_x": 0.0})
            for s, refs in ((a, vr), (b, pvr)):
                s.setReal([refs[n] for n in ("stiffness", "damping", "unloaded_radius")], kcr)
                s.setReal([refs[n] for n in INPUTS if n in refs], [x for n, x in zip(INPUTS, u) if n in refs])
            names = ["force_z", "deflection", "deflection_rate"]
            assert a.getReal([vr[n] for n in names]) == b.getReal([pvr[n] for n in names])
            assert a.getBoolean([vr["in_contact"]]) == b.getBoolean([pvr["in_contact"]])
            assert a.getReal([vr["road_effective_z"]]) == [u[2]]
    finally:
        a.freeInstance()
        b.freeInstance()


# Footprint l = 0.3 m centred on hub_x, cleat H = 0.05 m, w = 0.1 m from x_c = 0.5 m: the cleat enters the
# footprint at hub_x = 0.35 m, fills it (plateau H w / l) from 0.45 m to 0.65 m and leaves it at 0.75 m.
CLEAT = {"footprint_length": 0.3, "cleat_x": 0.5, "cleat_height": 0.05, "cleat_width": 0.1}


@pytest.mark.parametrize("hub_x, expected", [  # H s / l with s the length of cleat inside the footprint
    (0.2, 0.0), (0.349, 0.0), (0.36, 0.05 * 0.01 / 0.3), (0.4, 0.05 * 0.05 / 0.3), (0.44, 0.05 * 0.09 / 0.3),
    (0.451, 0.05 * 0.1 / 0.3), (0.55, 0.05 * 0.1 / 0.3), (0.649, 0.05 * 0.1 / 0.3), (0.66, 0.05 * 0.09 / 0.3),
    (0.7, 0.05 * 0.05 / 0.3), (0.74, 0.05 * 0.01 / 0.3), (0.751, 0.0), (1.2, 0.0),
])
def test_enveloped_cleat_is_the_footprint_average_of_the_rectangle(slave, vr, hub_x, expected):
    s, _ = slave
    s.setReal([vr[n] for n in CLEAT], list(CLEAT.values()))
    road_z, speed = 0.012, 2.0
    s.setReal([vr[n] for n in INPUTS], [0.74, 0.0, road_z, 0.0, hub_x, speed])
    road, rate = s.getReal([vr["road_effective_z"], vr["deflection_rate"]])
    assert road - road_z == pytest.approx(expected, rel=1e-12, abs=1e-15)
    ramp = 0.05 / 0.3 * speed  # d(road)/dt on the ramps: (H / l) * hub_vx
    slope = ramp if 0.35 < hub_x < 0.45 else -ramp if 0.65 < hub_x < 0.75 else 0.0
    assert rate == pytest.approx(slope, rel=1e-12, abs=1e-15)


def test_without_footprint_the_cleat_is_felt_under_the_contact_point_only(slave, vr):
    s, _ = slave
    s.setReal([vr[n] for n in CLEAT], [0.0, *list(CLEAT.values())[1:]])
    for hub_x, height in ((0.499, 0.0), (0.5, 0.05), (0.55, 0.05), (0.6, 0.0)):
        s.setReal([vr["hub_x"], vr["hub_vx"]], [hub_x, 2.0])
        assert s.getReal([vr["road_effective_z"], vr["deflection_rate"]]) == [height, 0.0]


def test_unilateral_contact_never_pulls(slave, vr):
    s, _ = slave
    k, c, r0 = s.getReal([vr[n] for n in ("stiffness", "damping", "unloaded_radius")])
    cases = [  # (hub_z, hub_vz, sign of δ, sign of the bilateral force, in contact when unilateral)
        (r0 + 0.01, 0.0, -1, -1, False),  # lifted off
        (r0 + 0.01, -3.0, -1, 1, False),  # lifted off, even while the damper pushes
        (r0, -0.5, 0, 1, False),  # δ = 0
        (r0 - 0.01, 3.0, 1, -1, False),  # δ > 0 but the damper pulls harder than the spring pushes
        (r0 - 0.01, 1.0, 1, 1, True),  # δ > 0, pushing
    ]
    for hub_z, hub_vz, deflection_sign, force_sign, contact in cases:
        s.setReal([vr["hub_z"], vr["hub_vz"]], [hub_z, hub_vz])
        s.setBoolean([vr["unilateral"]], [False])
        bilateral, deflection = s.getReal([vr["force_z"], vr["deflection"]])
        assert bilateral == k * (r0 - hub_z) + c * (-hub_vz)
        assert (np.sign(deflection), np.sign(bilateral)) == (deflection_sign, force_sign)
        s.setBoolean([vr["unilateral"]], [True])
        force, (flag,) = s.getReal([vr["force_z"]])[0], s.getBoolean([vr["in_contact"]])
        assert bool(flag) is contact
        assert force == (bilateral if contact else 0.0)


def test_reference_run_exercises_every_option_and_obeys_the_closed_form():
    kind = load_kind(KIND)
    ref = read_reference(KIND)
    p = {**law.EXTENDED_DEFAULTS, **kind.reference_start_values}
    assert p["footprint_length"] > p["cleat_width"] and p["cleat_height"] > 0 and p["unilateral"]
    assert p["stiffness_exponent"] != 1 and p["friction_force"] > 0 and p["lug_amplitude"] != 0
    expected = closed_form_outputs(KIND, {n: ref[n] for n in ["time", *INPUTS]}, p)
    for name in REAL_OUTPUTS:
        np.testing.assert_allclose(ref[name], expected[name], rtol=kind.reference_rtol, atol=kind.reference_atol)
    assert np.array_equal(ref["in_contact"], expected["in_contact"])
    held_x = np.concatenate([ref["hub_x"][:1], ref["hub_x"][:-1]])  # fmpy's alignment (see runners)
    held_road = np.concatenate([ref["road_z"][:1], ref["road_z"][:-1]])
    lug = p["lug_amplitude"] * np.sin(2 * np.pi * held_x / p["lug_pitch"] + p["lug_phase"])
    cleat = ref["road_effective_z"] - held_road - lug
    plateau = p["cleat_height"] * p["cleat_width"] / p["footprint_length"]
    assert np.isclose(cleat, plateau, rtol=1e-9).sum() > 50 and np.isclose(cleat, 0.0, atol=1e-12).sum() > 50
    assert ((cleat > 1e-4) & (cleat < plateau - 1e-4)).sum() > 50  # both ramps
    lifted, pulled = ref["deflection"] <= 0, (ref["deflection"] > 0) & ~ref["in_contact"]
    assert lifted.sum() > 50 and pulled.sum() > 5 and ref["in_contact"].sum() > 50
    assert np.all(ref["force_z"][~ref["in_contact"]] == 0.0) and np.all(ref["force_z"][ref["in_contact"]] > 0)
    assert np.abs(ref["deflection_rate"]).max() > 10 * p["friction_velocity"]  # friction saturates
    linear = closed_form_outputs(KIND, {n: ref[n] for n in ["time", *INPUTS]}, {**p, "stiffness_exponent": 1.0})
    assert np.abs(linear["force_z"] - ref["force_z"]).max() > 1000.0  # the progressive spring matters


# -- model description --------------------------------------------------------------------------

EXPECTED_UNITS = {"hub_z": "m", "hub_vz": "m/s", "road_z": "m", "road_vz": "m/s", "hub_x": "m", "hub_vx": "m/s",
                  "stiffness": "N/m", "damping": "N.s/m", "unloaded_radius": "m", "footprint_length": "m",
                  "cleat_x": "m", "cleat_height": "m", "cleat_width": "m", "stiffness_exponent": "1",
                  "static_load": "N", "friction_force": "N", "friction_velocity": "m/s", "lug_amplitude": "m",
                  "lug_pitch": "m", "lug_phase": "rad", "force_z": "N", "deflection": "m", "deflection_rate": "m/s",
                  "road_effective_z": "m"}
EXPECTED_INPUT_DEPENDENCIES = {"force_z": set(INPUTS), "in_contact": set(INPUTS),
                               "deflection": {"hub_z", "road_z", "hub_x"},
                               "deflection_rate": {"hub_vz", "road_vz", "hub_x", "hub_vx"},
                               "road_effective_z": {"road_z", "hub_x"}}


def test_compliance_units_descriptions_and_experiment(fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu)) == []
    assert compliance_problems(fmu) == []
    root = model_description(fmu)
    units = {u.get("name") for u in root.find("UnitDefinitions")}
    variables = {sv.get("name"): sv for sv in root.iter("ScalarVariable")}
    assert set(variables) == set(EXPECTED_UNITS) | {"unilateral", "in_contact"}
    for name, sv in variables.items():
        assert sv.get("description"), name
        if name in EXPECTED_UNITS:
            assert sv.find("Real").get("unit") == EXPECTED_UNITS[name] and EXPECTED_UNITS[name] in units
    unilateral = variables["unilateral"]
    assert (unilateral.get("causality"), unilateral.get("variability"), unilateral.find("Boolean").get("start")) \
        == ("parameter", "tunable", "false")
    de = root.find("DefaultExperiment")
    assert (float(de.get("startTime")), float(de.get("stopTime")), float(de.get("stepSize"))) == (0.0, 0.6, 0.001)
    cs = root.find("CoSimulation")
    assert cs.get("modelIdentifier") == "CleatfmuExtendedTire"
    assert (cs.get("canGetAndSetFMUstate"), cs.get("canSerializeFMUstate")) == ("true", "true")


def test_model_structure_lists_exactly_the_inputs_each_output_depends_on(fmu):
    root = model_description(fmu)
    name = {i: sv.get("name") for i, sv in enumerate(root.iter("ScalarVariable"), start=1)}
    outputs = {name[int(u.get("index"))]: u for u in root.find("ModelStructure/Outputs")}
    declared = {out: {name[int(i)] for i in u.get("dependencies", "").split()} for out, u in outputs.items()}
    assert declared == EXPECTED_INPUT_DEPENDENCIES
    initial = {name[int(u.get("index"))] for u in root.find("ModelStructure/InitialUnknowns")}
    assert initial == set(OUTPUTS)


def test_declared_dependencies_hold_numerically(slave, vr):
    """Perturbing an input changes only outputs that declare it; a "constant" kind has coefficient +-1."""
    s, _ = slave
    kinds = {v.name: v.depends for v in load_kind(KIND).variables if v.causality == "output"}
    rng = np.random.default_rng(5)
    changed = {(out, i): False for out in OUTPUTS for i in EXPECTED_INPUT_DEPENDENCIES[out]}
    for _ in range(40):
        p = random_parameters(rng, OPTION_SETS[-1])
        set_parameters(s, vr, p)
        u = random_inputs(rng, p)
        s.setReal([vr[n] for n in INPUTS], u)
        base = dict(zip(OUTPUTS, read_outputs(s, vr)))
        for j, name in enumerate(INPUTS):
            h = 1e-6
            s.setReal([vr[name]], [u[j] + h])
            moved = dict(zip(OUTPUTS, read_outputs(s, vr)))
            s.setReal([vr[name]], [u[j]])
            for out in OUTPUTS:
                if name not in EXPECTED_INPUT_DEPENDENCIES[out]:
                    assert moved[out] == base[out], (out, name)
                    continue
                changed[out, name] |= moved[out] != base[out]
                if kinds[out][name] == "constant":
                    assert abs(moved[out] - base[out]) == pytest.approx(h, rel=1e-6), (out, name)
    assert all(changed[out, i] for out in REAL_OUTPUTS for i in EXPECTED_INPUT_DEPENDENCIES[out])


def test_build_writes_every_start_value_including_the_boolean_and_the_description(tmp_path, vr):
    starts = {"stiffness": 312345.6789012345, "damping": 1234.5, "unloaded_radius": 0.8, "footprint_length": 0.25,
              "cleat_x": -0.3, "cleat_height": 0.04, "cleat_width": 0.08, "unilateral": True,
              "stiffness_exponent": 1.25, "static_load": 12000.0, "friction_force": 300.0,
              "friction_velocity": 0.02, "lug_amplitude": 0.003, "lug_pitch": 0.3, "lug_phase": 0.7}
    fmu = build_fmu(KIND, tmp_path / "FL.fmu", start_values=starts, description="front left, test day 3")
    root = model_description(fmu)
    assert root.get("description") == "front left, test day 3"
    written = {}
    for sv in root.iter("ScalarVariable"):
        typed = sv[0]
        if sv.get("name") in starts:
            start = typed.get("start")
            written[sv.get("name")] = start == "true" if typed.tag == "Boolean" else float(start)
    assert written == starts
    s = open_fmpy_slave(fmu)
    try:
        assert s.getReal([vr[n] for n in REAL_PARAMS]) == [starts[n] for n in REAL_PARAMS]
        assert s.getBoolean([vr["unilateral"]]) == [1]
        assert s.getReal([vr["hub_z"]]) == [0.8]
    finally:
        s.freeInstance()


@pytest.mark.parametrize("starts, match", [
    ({"unilateral": 1}, "True or False"), ({"stiffness_exponent": True}, "finite number"),
    ({"lug_phase": math.nan}, "finite"), ({"stiffness_exponent": 1.4}, "static_load must be > 0"),
    ({"cleat_width": 0.0}, "cleat_width must be > 0"),
])
def test_build_rejects_invalid_start_values(tmp_path, starts, match):
    with pytest.raises(ValueError, match=match):
        build_fmu(KIND, tmp_path / "bad.fmu", start_values=starts)
    assert list(tmp_path.iterdir()) == []


# -- importers ----------------------------------------------------------------------------------

def test_default_experiment_with_fmpy_and_libcosimpy_matches_the_reference(fmu):
    kind = load_kind(KIND)
    ref = read_reference(KIND)
    signals = {n: ref[n] for n in ["time", *INPUTS]}
    starts = kind.reference_start_values
    sim = simulate_fmpy(fmu, signals, OUTPUTS, start_values=starts)
    for name in ["time", *REAL_OUTPUTS]:
        np.testing.assert_allclose(sim[name], ref[name], rtol=kind.reference_rtol, atol=kind.reference_atol)
    assert np.array_equal(sim["in_contact"], ref["in_contact"])
    fmpy_out = run_fmpy_loop(fmu, signals, OUTPUTS, start_values=starts)
    cosim_out = run_libcosim(fmu, signals, OUTPUTS, start_values=starts)
    for name in OUTPUTS:
        assert np.array_equal(cosim_out[name], fmpy_out[name]), name
        assert np.array_equal(cosim_out[name], ref[name][1:]), name  # = fmpy.simulate_fmu, one row later


def test_two_fmus_of_the_kind_keep_their_own_parameters(fmu, tmp_path, vr):
    other_p = {**law.EXTENDED_DEFAULTS, "stiffness": 123456.0, "unilateral": True, "footprint_length": 0.2,
               "cleat_x": 0.1, "cleat_height": 0.03}
    other = build_fmu(KIND, tmp_path / "FR.fmu", start_values={n: other_p[n] for n in
                                                               ("stiffness", "unilateral", "footprint_length",
                                                                "cleat_x", "cleat_height")})
    a, b = open_fmpy_slave(fmu, instance_name="a"), open_fmpy_slave(other, instance_name="b")
    try:
        u = [0.76, -0.1, 0.0, 0.0, 0.15, 2.0]
        for s in (a, b):
            s.setReal([vr[n] for n in INPUTS], u)
        assert read_outputs(a, vr) == law_outputs(u, law.EXTENDED_DEFAULTS)  # bilateral: pulls
        assert read_outputs(b, vr) == law_outputs(u, other_p)
        assert read_outputs(a, vr)[0] < 0 and read_outputs(b, vr)[-1] is True
        assert a.getBoolean([vr["unilateral"]]) == [0] and b.getBoolean([vr["unilateral"]]) == [1]
    finally:
        a.freeInstance()
        b.freeInstance()


# -- FMU state and reset ------------------------------------------------------------------------

def test_state_round_trip_is_bit_identical_and_carries_the_parameters(fmu, vr):
    rng = np.random.default_rng(3)
    p = random_parameters(rng, OPTION_SETS[-1])
    inputs = [random_inputs(rng, p) for _ in range(60)]

    def run(s):
        out = []
        for i, u in enumerate(inputs):
            s.setReal([vr[n] for n in INPUTS], u)
            s.doStep(i * 1e-3, 1e-3)
            out.append(read_outputs(s, vr))
        return out

    s, t = open_fmpy_slave(fmu), open_fmpy_slave(fmu, instance_name="copy")
    try:
        set_parameters(s, vr, p)
        s.setReal([vr[n] for n in INPUTS], inputs[0])
        state = s.getFMUstate()
        first = run(s)
        assert first == [law_outputs(u, p) for u in inputs]
        s.setFMUstate(state)
        assert s.getReal([vr[n] for n in INPUTS]) == inputs[0]
        assert run(s) == first
        blob = s.serializeFMUstate(state)
        s.freeFMUstate(state)
        copy = t.deSerializeFMUstate(blob)  # t starts with the default (bilateral, linear) parameters
        t.setFMUstate(copy)
        t.freeFMUstate(copy)
        assert t.getBoolean([vr["unilateral"]]) == [1]
        assert run(t) == first
    finally:
        s.freeInstance()
        t.freeInstance()


def test_reset_returns_to_the_start_values(slave, vr):
    s, _ = slave
    names = INPUTS + REAL_PARAMS
    before = s.getReal([vr[n] for n in names + REAL_OUTPUTS]), s.getBoolean([vr["unilateral"], vr["in_contact"]])
    set_parameters(s, vr, random_parameters(np.random.default_rng(1), OPTION_SETS[-1]))
    s.setReal([vr[n] for n in INPUTS], [0.6, 1.0, 0.1, -1.0, 0.3, 2.0])
    assert (s.getReal([vr[n] for n in names + REAL_OUTPUTS]),
            s.getBoolean([vr["unilateral"], vr["in_contact"]])) != before
    s.reset()
    assert (s.getReal([vr[n] for n in names + REAL_OUTPUTS]), s.getBoolean([vr["unilateral"], vr["in_contact"]])) \
        == before
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 1e-3)


# -- robustness ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name, value, reason", [
    ("stiffness", 0.0, "stiffness k must be > 0"), ("damping", -1.0, "damping c must be >= 0"),
    ("footprint_length", -0.1, "footprint_length must be >= 0"), ("cleat_height", -0.01, "cleat_height must be >= 0"),
    ("cleat_width", 0.0, "cleat_width must be > 0"), ("stiffness_exponent", 0.0, "stiffness_exponent must be > 0"),
    ("static_load", -1.0, "static_load must be >= 0"), ("friction_force", -5.0, "friction_force must be >= 0"),
    ("friction_velocity", 0.0, "friction_velocity must be > 0"), ("lug_pitch", -0.25, "lug_pitch must be > 0"),
    ("cleat_x", math.nan, "cleat_x = nan"), ("lug_phase", math.inf, "lug_phase = inf"),
    ("hub_x", math.nan, "hub_x = nan"), ("hub_vx", -math.inf, "hub_vx = -inf"), ("road_z", math.nan, "road_z = nan"),
])
def test_invalid_values_give_an_error_status_with_the_reason(slave, vr, name, value, reason):
    from fmpy.fmi1 import FMICallException

    s, messages = slave
    before = s.getReal([vr[n] for n in INPUTS + REAL_PARAMS])
    with pytest.raises(FMICallException) as info:
        s.setReal([vr[name]], [value])
    assert info.value.status >= 3  # fmi2Error or fmi2Fatal (pythonfmu 0.7 reports every failure as fatal)
    assert any(status == 3 and reason in message for status, message in messages), messages
    assert s.getReal([vr[n] for n in INPUTS + REAL_PARAMS]) == before  # nothing was stored
    s.doStep(0.0, 1e-3)


def test_parameters_may_be_set_in_any_order_but_an_inconsistent_set_fails_when_used(slave, vr):
    from fmpy.fmi1 import FMICallException

    s, messages = slave
    s.setReal([vr[n] for n in INPUTS], [0.72, -0.1, 0.0, 0.0, 0.0, 0.0])
    s.setReal([vr["stiffness_exponent"]], [1.5])  # static_load is still 0 N: accepted for now
    for call in (lambda: s.getReal([vr["force_z"]]), lambda: s.getBoolean([vr["in_contact"]]),
                 lambda: s.doStep(0.0, 1e-3)):
        with pytest.raises(FMICallException):
            call()
    assert sum(status == 3 and "static_load must be > 0 N when stiffness_exponent != 1" in m
               for status, m in messages) == 3
    s.setReal([vr["static_load"]], [20000.0])
    s.doStep(0.0, 1e-3)
    u = s.getReal([vr[n] for n in INPUTS])
    p = {**law.EXTENDED_DEFAULTS, "stiffness_exponent": 1.5, "static_load": 20000.0}
    assert s.getReal([vr["force_z"]])[0] == law_outputs(u, p)[0]
    s.reset()
    s.setupExperiment(startTime=0.0)
    s.setReal([vr["stiffness_exponent"]], [1.5])
    s.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.exitInitializationMode()
    assert sum("static_load must be > 0 N" in m for _, m in messages) == 4


def test_unevaluable_inputs_and_wrong_references_fail_with_a_reason(slave, vr):
    from fmpy.fmi1 import FMICallException

    s, messages = slave
    s.setReal([vr["stiffness_exponent"], vr["static_load"]], [2.0, 10000.0])
    s.setReal([vr["hub_z"]], [-1e200])  # finite, but (δ/δ_W)^n overflows
    with pytest.raises(FMICallException):
        s.getReal([vr["force_z"]])
    assert any(status == 3 and "cannot be evaluated" in m for status, m in messages), messages
    s.setReal([vr["hub_z"]], [0.7])
    assert s.getReal([vr["force_z"]])[0] > 0
    for call in (lambda: s.setBoolean([vr["in_contact"]], [True]), lambda: s.setReal([vr["unilateral"]], [1.0]),
                 lambda: s.setBoolean([vr["stiffness"]], [True]), lambda: s.getReal([vr["in_contact"]]),
                 lambda: s.setFMUstate(s.deSerializeFMUstate(b"not a state"))):
        with pytest.raises(FMICallException):
            call()
    assert sum(status == 3 for status, _ in messages) == 6


def test_host_survives_repeated_errors_and_frees_cleanly(fmu):
    """Run in a child process, so that a crash shows as a failed test, not a dead test session."""
    script = textwrap.dedent(f"""
        import gc, math
        from fmpy.fmi1 import FMICallException
        from build_scripts.runners import open_fmpy_slave, variable_refs
        vr = {{n: r for n, (r, _) in variable_refs({str(fmu)!r}).items()}}
        calls = [
            lambda s: s.setReal([vr["cleat_width"]], [math.nan]),
            lambda s: s.setReal([vr["friction_velocity"]], [0.0]),
            lambda s: s.setBoolean([vr["in_contact"]], [True]),
            lambda s: (s.setReal([vr["stiffness_exponent"]], [1.5]), s.doStep(0.0, 1e-3)),
            lambda s: (s.setReal([vr["hub_z"]], [-1e304]), s.getReal([vr["force_z"]])),  # force overflows
        ]
        for round in range(3):
            s = open_fmpy_slave({str(fmu)!r}, instance_name=f"r{{round}}")
            for i in range(250):
                try:
                    calls[i % len(calls)](s)
                    raise SystemExit(f"call {{i % len(calls)}} did not fail")
                except FMICallException:
                    pass
                gc.collect()
                s.setReal([vr["stiffness_exponent"], vr["hub_z"]], [1.0, 0.7])
                s.setBoolean([vr["unilateral"]], [bool(i % 2)])
                s.doStep(0.0, 1e-3)
                assert s.getReal([vr["force_z"]])[0] > 0
            s.reset()
            s.freeInstance()
            gc.collect()
        print("survived")
    """)
    import build_scripts

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(build_scripts.__file__).parent.parent), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr[-2000:] + done.stdout[-2000:]
    assert done.stdout.strip().endswith("survived")


# -- packaging and leaks ------------------------------------------------------------------------

def test_fmu_contains_the_law_verbatim_and_only_kind_prefixed_modules(fmu):
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/cleatfmu_extended_tire_law.py") == Path(law.__file__).read_bytes()
        assert z.read("resources/slavemodule.txt").decode().strip() == "cleatfmu_extended_tire"
        modules = {Path(n).stem for n in z.namelist() if n.count("/") == 1 and n.endswith(".py")}
    assert modules == {"cleatfmu_extended_tire", "cleatfmu_extended_tire_slave", "cleatfmu_extended_tire_table",
                       "cleatfmu_extended_tire_law", "cleatfmu_extended_tire_wrapper"}


def test_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path(fmu, tmp_path):
    from fmpy import extract

    cycle = _fresh_cycle(fmu, extract(str(fmu), unzipdir=tmp_path / "unzipped"))
    for _ in range(300):  # warm-up: fmpy's and ctypes' own first-use allocations
        cycle()
    gc.collect()
    path_before, rss_before = list(sys.path), rss_bytes()
    for i in range(1000):
        cycle()
        if i % 100 == 99:  # fmpy's FMU2Slave objects are freed by the cyclic GC: collect, not count, them
            gc.collect()
    gc.collect()
    growth = rss_bytes() - rss_before
    assert sys.path == path_before
    assert growth <= 1024 * 1024, f"RSS grew by {growth / 1024:.0f} kB over 1000 instantiate/free cycles"


def test_failing_calls_and_resets_leak_at_most_1_mb(slave, vr):
    from fmpy.fmi1 import FMICallException

    s, _ = slave

    def cycle():
        try:
            s.setReal([vr["lug_pitch"]], [0.0])
        except FMICallException:
            pass
        s.reset()

    for _ in range(100):
        cycle()
    gc.collect()
    rss_before = rss_bytes()
    for _ in range(1000):
        cycle()
    gc.collect()
    growth = rss_bytes() - rss_before
    assert growth <= 1024 * 1024, f"RSS grew by {growth / 1024:.0f} kB over 1000 failing calls and resets"
