"""The extended tire FMU at run time: importers, FMU state, robustness, packaging, leaks."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from extended_tire_cases import (BOOL_PARAMS, INPUTS, KIND, OPTION_SETS, OUTPUTS, REAL_OUTPUTS, REAL_PARAMS,
                                 law_outputs, random_inputs, random_parameters, read_outputs, set_parameters)
from fmu_helpers import (LEAK_LIMIT, assert_fmpy_matches_the_reference, assert_host_survives_errors,
                         assert_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path,
                         assert_libcosim_matches_fmpy, assert_state_round_trip, assert_value_rejected, kind_fixtures,
                         packaged_modules, reinitialise_and_step, rss_growth, run_steps)

import identification.model.tire_law as law
from build_scripts import build_fmu, load_kind
from build_scripts.kinds import module_source
from build_scripts.runners import open_fmpy_slave


fmu, vr, slave = kind_fixtures(KIND)


# -- importers ----------------------------------------------------------------------------------

def test_default_experiment_with_fmpy_and_libcosimpy_matches_the_reference(fmu):
    kind = load_kind(KIND)
    starts = kind.reference_start_values
    assert_fmpy_matches_the_reference(fmu, kind, INPUTS, OUTPUTS, REAL_OUTPUTS, start_values=starts)
    assert_libcosim_matches_fmpy(fmu, KIND, INPUTS, OUTPUTS, start_values=starts)


def test_two_fmus_of_the_kind_keep_their_own_parameters(fmu, tmp_path, vr):
    other_p = {**law.EXTENDED_DEFAULTS, "stiffness": 123456.0, "unilateral": True, "footprint_length": 0.2,
               "cleat_x": 0.1, "cleat_height": 0.03, "parabolic_pressure": True}
    other = build_fmu(KIND, tmp_path / "FR.fmu", start_values={n: other_p[n] for n in
                                                               ("stiffness", "unilateral", "footprint_length",
                                                                "cleat_x", "cleat_height", "parabolic_pressure")})
    a, b = open_fmpy_slave(fmu, instance_name="a"), open_fmpy_slave(other, instance_name="b")
    try:
        u = [0.76, -0.1, 0.0, 0.0, 0.15, 2.0]
        for s in (a, b):
            s.setReal([vr[n] for n in INPUTS], u)
        assert read_outputs(a, vr) == law_outputs(u, law.EXTENDED_DEFAULTS)  # bilateral: pulls
        assert read_outputs(b, vr) == law_outputs(u, other_p)
        assert read_outputs(a, vr)[0] < 0 and read_outputs(b, vr)[-1] is True
        assert a.getBoolean([vr[n] for n in BOOL_PARAMS]) == [0, 0, 0]
        assert b.getBoolean([vr[n] for n in BOOL_PARAMS]) == [1, 1, 0]
    finally:
        a.freeInstance()
        b.freeInstance()


def test_the_co_simulation_master_reads_and_sets_both_booleans(tmp_path):
    from identification.fmu.cosim import TireFmu

    fmu = build_fmu(KIND, tmp_path / "RL.fmu", start_values={"parabolic_pressure": True, "footprint_length": 0.3})
    with TireFmu(fmu) as tire:
        tire.initialize(0.0)
        params = tire.parameters()
        assert {n: params[n] for n in BOOL_PARAMS} == {"unilateral": False, "parabolic_pressure": True,
                                                       "ring_envelope": False}
        assert all(type(params[n]) is float for n in REAL_PARAMS)
    with TireFmu(fmu, start_values={"unilateral": True, "parabolic_pressure": False, "ring_envelope": True,
                                    "static_load": 12000.0}) as tire:
        tire.initialize(0.0)
        assert {n: tire.parameters()[n] for n in BOOL_PARAMS} == {"unilateral": True, "parabolic_pressure": False,
                                                                   "ring_envelope": True}


# -- FMU state and reset ------------------------------------------------------------------------

def test_state_round_trip_is_bit_identical_and_carries_the_parameters(fmu, vr):
    rng = np.random.default_rng(3)
    p = random_parameters(rng, OPTION_SETS[-1])
    inputs = [random_inputs(rng, p) for _ in range(60)]

    def prepare(s):
        set_parameters(s, vr, p)
        s.setReal([vr[n] for n in INPUTS], inputs[0])

    def restored(s):
        assert s.getReal([vr[n] for n in INPUTS]) == inputs[0]

    def copied(t):  # t started with the default (bilateral, uniform footprint, linear) parameters
        assert t.getBoolean([vr[n] for n in BOOL_PARAMS]) == [1, 1, 0]

    first = assert_state_round_trip(fmu, prepare, lambda s: run_steps(s, vr, INPUTS, inputs,
                                                                      lambda s: read_outputs(s, vr)),
                                    check_restored=restored, check_copied=copied)
    assert first == [law_outputs(u, p) for u in inputs]


def test_reset_returns_to_the_start_values(slave, vr):
    s, _ = slave
    reals, flags = INPUTS + REAL_PARAMS + REAL_OUTPUTS, BOOL_PARAMS + ["in_contact"]

    def values():
        return s.getReal([vr[n] for n in reals]), s.getBoolean([vr[n] for n in flags])

    before = values()
    assert before[1][:2] == [0, 0]
    set_parameters(s, vr, random_parameters(np.random.default_rng(1), OPTION_SETS[-1]))
    s.setReal([vr[n] for n in INPUTS], [0.6, 1.0, 0.1, -1.0, 0.3, 2.0])
    assert values() != before and values()[1][:2] == [1, 1]
    s.reset()
    assert values() == before
    reinitialise_and_step(s)


# -- robustness ---------------------------------------------------------------------------------

@pytest.mark.parametrize("name, value, reason", [
    ("stiffness", 0.0, "stiffness k must be > 0"), ("damping", -1.0, "damping c must be >= 0"),
    ("footprint_length", -0.1, "footprint_length must be >= 0"), ("cleat_height", -0.01, "cleat_height must be >= 0"),
    ("cleat_width", 0.0, "cleat_width must be > 0"), ("stiffness_exponent", 0.0, "stiffness_exponent must be > 0"),
    ("static_load", -1.0, "static_load must be >= 0"), ("friction_force", -5.0, "friction_force must be >= 0"),
    ("friction_velocity", 0.0, "friction_velocity must be > 0"), ("lug_pitch", -0.25, "lug_pitch must be > 0"),
    ("cleat_x", math.nan, "cleat_x = nan"), ("lug_phase", math.inf, "lug_phase = inf"),
    ("cleat_bevel", -0.01, "cleat_bevel must be >= 0 m"), ("cleat_bevel", math.nan, "cleat_bevel = nan"),
    ("hub_x", math.nan, "hub_x = nan"), ("hub_vx", -math.inf, "hub_vx = -inf"), ("road_z", math.nan, "road_z = nan"),
])
def test_invalid_values_give_an_error_status_with_the_reason(slave, vr, name, value, reason):
    s, messages = slave
    assert_value_rejected(s, messages, vr, INPUTS + REAL_PARAMS, name, value, reason)


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
    assert_host_survives_errors(fmu, [
        'lambda s: s.setReal([vr["cleat_width"]], [math.nan])',
        'lambda s: s.setReal([vr["friction_velocity"]], [0.0])',
        'lambda s: s.setBoolean([vr["in_contact"]], [True])',
        'lambda s: (s.setReal([vr["stiffness_exponent"]], [1.5]), s.doStep(0.0, 1e-3))',
        'lambda s: (s.setReal([vr["hub_z"]], [-1e304]), s.getReal([vr["force_z"]]))',  # force overflows
    ], """
        s.setReal([vr["stiffness_exponent"], vr["hub_z"]], [1.0, 0.7])
        s.setBoolean([vr["unilateral"]], [bool(i % 2)])
        s.doStep(0.0, 1e-3)
        assert s.getReal([vr["force_z"]])[0] > 0
    """, iterations=250)


# -- packaging and leaks ------------------------------------------------------------------------

def test_fmu_contains_the_law_and_shared_modules_verbatim_and_only_kind_prefixed_modules(fmu):
    entry, modules = packaged_modules(fmu)
    assert entry.startswith("cleatfmu_extended_tire_b") and len(entry) == len("cleatfmu_extended_tire_b") + 10
    assert modules[f"{entry}_law"] == Path(law.__file__).read_bytes()
    assert modules[f"{entry}_table"] == module_source("fmu_src.table_slave")
    assert modules[f"{entry}_wrapper"] == module_source("fmu_src.pythonfmu_wrapper")
    assert set(modules) == {entry, f"{entry}_slave", f"{entry}_table", f"{entry}_law", f"{entry}_wrapper"}


def test_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path(fmu, tmp_path):
    from fmpy import extract

    assert_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path(
        fmu, extract(str(fmu), unzipdir=tmp_path / "unzipped"))


def test_failing_calls_and_resets_leak_at_most_1_mb(slave, vr):
    from fmpy.fmi1 import FMICallException

    s, _ = slave

    def cycle():
        try:
            s.setReal([vr["lug_pitch"]], [0.0])
        except FMICallException:
            pass
        s.reset()

    growth = rss_growth(cycle, warmup=100)
    assert growth <= LEAK_LIMIT, f"RSS grew by {growth / 1024:.0f} kB over 1000 failing calls and resets"
