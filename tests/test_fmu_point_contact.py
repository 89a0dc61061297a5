"""The point-contact tire FMU at run time: physics, FMI behaviour, importers, robustness, leaks."""

from __future__ import annotations

import json
import math
from fractions import Fraction

import numpy as np
import pytest
from fmu_helpers import (LEAK_LIMIT, assert_fmpy_matches_the_reference, assert_host_survives_errors,
                         assert_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path,
                         assert_libcosim_matches_fmpy, assert_state_round_trip, assert_value_rejected, kind_fixtures,
                         model_description, packaged_modules, reinitialise_and_step, rewrite_fmu, rss_growth,
                         run_steps)

from build_scripts import build_fmu, load_kind
from build_scripts.reference import closed_form_outputs, read_reference
from build_scripts.runners import open_fmpy_slave, simulate_fmpy

INPUTS = ["hub_z", "hub_vz", "road_z", "road_vz"]
PARAMS = ["stiffness", "damping", "unloaded_radius"]
REAL_OUTPUTS = ["force_z", "deflection", "deflection_rate"]


fmu, vr, slave = kind_fixtures("point_contact", scope="session")


def exact_outputs(zh, vh, zr, vr_, k, c, r0):
    zh, vh, zr, vr_, k, c, r0 = (Fraction(float(x)) for x in (zh, vh, zr, vr_, k, c, r0))
    d = r0 - (zh - zr)
    dd = vr_ - vh
    return k * d + c * dd, d, dd


def rel(value, exact):
    return 0.0 if value == exact else abs(float((Fraction(value) - exact) / exact))


# -- physics ------------------------------------------------------------------------------------

def test_force_equals_closed_form_for_random_inputs_and_parameters(slave, vr):
    s, _ = slave
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(300):
        r0 = rng.uniform(0.3, 1.0)
        u = [r0 + rng.uniform(-0.08, 0.03), rng.uniform(-2, 2), rng.uniform(-0.02, 0.06), rng.uniform(-3, 3)]
        p = [rng.uniform(5e4, 2e6), rng.uniform(0.0, 2e4), r0]
        s.setReal([vr[n] for n in PARAMS], p)
        s.setReal([vr[n] for n in INPUTS], u)
        force, defl, rate = s.getReal([vr[n] for n in REAL_OUTPUTS])  # before doStep: direct feedthrough
        (contact,) = s.getBoolean([vr["in_contact"]])
        f_x, d_x, dd_x = exact_outputs(*u, *p)
        worst = max(worst, rel(force, f_x), rel(defl, d_x), rel(rate, dd_x))
        assert bool(contact) == (d_x > 0)
        s.doStep(0.0, 1e-3)
        assert s.getReal([vr["force_z"]]) == [force]
    assert worst <= 1e-12


def test_outputs_follow_the_current_inputs_not_the_previous_step(slave, vr):
    s, _ = slave
    k, c, r0 = s.getReal([vr[n] for n in PARAMS])
    s.setReal([vr[n] for n in INPUTS], [r0 - 0.01, 0.0, 0.0, 0.0])
    s.doStep(0.0, 1e-3)
    assert s.getReal([vr["force_z"]])[0] == pytest.approx(k * 0.01, rel=1e-12)
    s.setReal([vr[n] for n in INPUTS], [r0 - 0.03, -0.2, 0.0, 0.0])
    assert s.getReal([vr["force_z"]])[0] == pytest.approx(k * 0.03 + c * 0.2, rel=1e-12)


def test_start_values_in_xml_are_the_instance_values(fmu, vr):
    root = model_description(fmu)
    starts = {sv.get("name"): float(sv.find("Real").get("start")) for sv in root.iter("ScalarVariable")
              if sv.find("Real") is not None and sv.find("Real").get("start") is not None}
    assert set(starts) == set(INPUTS + PARAMS)
    s = open_fmpy_slave(fmu)
    try:
        assert s.getReal([vr[n] for n in starts]) == list(starts.values())
        assert starts["hub_z"] == starts["unloaded_radius"]  # at rest, untouched
        assert s.getReal([vr["force_z"]]) == [0.0]
    finally:
        s.freeInstance()


def test_reference_csv_obeys_the_closed_form_law():
    kind = load_kind("point_contact")
    ref = read_reference("point_contact")
    starts = {v.name: v.start for v in kind.variables if v.causality == "parameter"}
    expected = closed_form_outputs("point_contact", {n: ref[n] for n in ["time", *INPUTS]}, starts)
    for name in REAL_OUTPUTS:
        np.testing.assert_allclose(ref[name], expected[name], rtol=1e-12, atol=1e-12)
    assert np.array_equal(ref["in_contact"], expected["in_contact"])
    assert ref["in_contact"].any() and not ref["in_contact"].all()  # the run includes a lift-off


# -- importers ----------------------------------------------------------------------------------

def test_default_experiment_with_fmpy_matches_the_reference(fmu):
    assert_fmpy_matches_the_reference(fmu, load_kind("point_contact"), INPUTS, REAL_OUTPUTS + ["in_contact"],
                                      REAL_OUTPUTS)


def test_libcosimpy_gives_the_same_outputs_as_fmpy(fmu):
    assert_libcosim_matches_fmpy(fmu, "point_contact", INPUTS, REAL_OUTPUTS + ["in_contact"])


def test_results_are_deterministic(fmu):
    ref = read_reference("point_contact")
    signals = {n: ref[n] for n in ["time", *INPUTS]}
    a = simulate_fmpy(fmu, signals, REAL_OUTPUTS)
    b = simulate_fmpy(fmu, signals, REAL_OUTPUTS)
    for name in REAL_OUTPUTS:
        assert a[name].tobytes() == b[name].tobytes()


def test_two_fmus_of_the_kind_keep_their_own_parameters(fmu, tmp_path, vr):
    other = build_fmu("point_contact", tmp_path / "FR.fmu", start_values={"stiffness": 123456.0, "damping": 7.0})
    a, b = open_fmpy_slave(fmu, instance_name="a"), open_fmpy_slave(other, instance_name="b")
    try:
        for s in (a, b):
            s.setReal([vr[n] for n in INPUTS], [0.74, 0.0, 0.0, 0.0])
        assert a.getReal([vr["stiffness"]]) == [400000.0] and b.getReal([vr["stiffness"]]) == [123456.0]
        assert a.getReal([vr["force_z"]])[0] == pytest.approx(4000.0, rel=1e-12)
        assert b.getReal([vr["force_z"]])[0] == pytest.approx(1234.56, rel=1e-12)
    finally:
        a.freeInstance()
        b.freeInstance()


# -- FMU state and reset ------------------------------------------------------------------------

def test_state_round_trip_is_bit_identical(fmu, vr):
    cs = model_description(fmu).find("CoSimulation")
    assert cs.get("canGetAndSetFMUstate") == "true" and cs.get("canSerializeFMUstate") == "true"
    rng = np.random.default_rng(3)
    inputs = [[0.75 + rng.uniform(-0.05, 0.01), rng.uniform(-1, 1), rng.uniform(0, 0.05), rng.uniform(-1, 1)]
              for _ in range(50)]

    def prepare(s):
        s.setReal([vr["stiffness"], vr["damping"]], [250000.0, 1500.0])
        s.setReal([vr[n] for n in INPUTS], [0.72, 0.1, 0.01, 0.0])

    def restored(s):
        assert s.getReal([vr["stiffness"], vr["hub_z"]]) == [250000.0, 0.72]

    def read(s):
        return s.getReal([vr[n] for n in REAL_OUTPUTS]) + list(s.getBoolean([vr["in_contact"]]))

    assert_state_round_trip(fmu, prepare, lambda s: run_steps(s, vr, INPUTS, inputs, read), check_restored=restored)


def test_reset_returns_to_the_start_values(slave, vr):
    s, _ = slave
    names = INPUTS + PARAMS
    before = s.getReal([vr[n] for n in names + ["force_z"]])
    s.setReal([vr[n] for n in names], [0.6, 1.0, 0.1, -1.0, 1e5, 10.0, 0.7])
    assert s.getReal([vr["force_z"]]) != before[-1:]
    s.reset()
    assert s.getReal([vr[n] for n in names + ["force_z"]]) == before
    reinitialise_and_step(s)


# -- robustness ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name, value, reason", [
    ("stiffness", 0.0, "stiffness k must be > 0"), ("stiffness", -1.0, "stiffness k must be > 0"),
    ("stiffness", math.nan, "stiffness = nan"), ("damping", -1.0, "damping c must be >= 0"),
    ("unloaded_radius", math.inf, "unloaded_radius = inf"), ("hub_z", math.nan, "hub_z = nan"),
    ("road_vz", -math.inf, "road_vz = -inf"),
])
def test_invalid_values_give_an_error_status_with_the_reason(slave, vr, name, value, reason):
    s, messages = slave
    assert_value_rejected(s, messages, vr, INPUTS + PARAMS, name, value, reason)


def test_setting_an_output_or_unknown_reference_fails(slave, vr):
    from fmpy.fmi1 import FMICallException

    s, messages = slave
    for refs in ([vr["force_z"]], [vr["in_contact"]], [99]):
        with pytest.raises(FMICallException):
            s.setReal(refs, [1.0])
    with pytest.raises(FMICallException):
        s.getReal([99])
    with pytest.raises(FMICallException):
        s.setFMUstate(s.deSerializeFMUstate(b"not a state"))
    assert sum(status == 3 for status, _ in messages) == 5
    assert s.getReal([vr["force_z"]]) == [0.0]


def test_overflowing_outputs_fail_with_a_reason(slave, vr):
    from fmpy.fmi1 import FMICallException

    s, messages = slave
    s.setReal([vr["hub_z"]], [-1e304])  # finite, but stiffness * deflection overflows
    with pytest.raises(FMICallException):
        s.getReal([vr["force_z"]])
    assert any(status == 3 and "cannot be evaluated" in m and "force_z = inf" in m for status, m in messages), messages
    s.setReal([vr["hub_z"]], [0.7])
    assert s.getReal([vr["force_z"]])[0] > 0


def test_host_survives_repeated_errors_and_frees_cleanly(fmu):
    assert_host_survives_errors(
        fmu, ['lambda s: s.setReal([vr["stiffness"]], [math.nan])', 'lambda s: s.setReal([vr["stiffness"]], [-1.0])'],
        """
        s.setReal([vr["hub_z"]], [0.7])
        s.doStep(0.0, 1e-3)
        assert s.getReal([vr["force_z"]])[0] > 0
        """, iterations=200)


def test_tampered_start_file_fails_instantiation_without_crashing(fmu, tmp_path):
    def negative_stiffness(data):
        doc = json.loads(data)
        doc["start"]["stiffness"] = -5.0
        return json.dumps(doc).encode()

    entry, _ = packaged_modules(fmu)
    bad = rewrite_fmu(fmu, tmp_path / "bad.fmu", f"resources/{entry}_start.json", negative_stiffness)
    messages = []
    with pytest.raises(Exception, match="instantiate"):
        open_fmpy_slave(bad, logger=lambda status, category, message: messages.append(message))
    assert any("stiffness k must be > 0" in m for m in messages), messages
    s = open_fmpy_slave(fmu)  # the process and the kind still work
    s.freeInstance()


# -- leaks --------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def unzipped(fmu, tmp_path_factory) -> str:
    from fmpy import extract

    return extract(str(fmu), unzipdir=tmp_path_factory.mktemp("unzipped"))


def test_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path(fmu, unzipped):
    assert_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path(fmu, unzipped)


def test_fmi_level_instantiate_free_cycles_on_one_library_leak_at_most_1_mb(fmu, unzipped):
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu), validate=False)
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier)

    def cycle():
        s.instantiate()
        s.fmi2FreeInstance(s.component)

    try:
        growth = rss_growth(cycle, warmup=100)
    finally:
        s.freeLibrary()
    assert growth <= LEAK_LIMIT, f"RSS grew by {growth / 1024:.0f} kB over 1000 fmi2Instantiate/fmi2FreeInstance"


def test_reset_cycles_leak_at_most_1_mb(slave):
    s, _ = slave
    growth = rss_growth(s.reset, warmup=100)
    assert growth <= LEAK_LIMIT, f"RSS grew by {growth / 1024:.0f} kB over 1000 resets"
