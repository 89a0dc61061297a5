"""The whole-tractor co-simulation master on tire FMUs: the reference scheme exactly, FMI errors, one opening."""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from build_scripts import build_fmu
from identification.model import tire_law
from identification.fmu import tractor_cosim
from identification.fmu.cosim import TireFmu, step_fn
from identification.model import Body, Cleat, TractorModel
from identification.model.stepping import run_body, run_model_python

from tractor_cases import ARRIVALS, C, H, K, L, LOADS, TIRES, V, W  # noqa: F401
#: FL and RL place a cleat themselves (footprint, built-in cleat); FR and RR get the cleat as the road,
#: with its edges on grid points (impulses).
BUILTIN = (True, False, True, False)


def _laws():
    laws = []
    for i, (w, k, c) in enumerate(zip(LOADS, K, C)):
        p = dict(tire_law.EXTENDED_DEFAULTS, stiffness=k, damping=c, static_load=w, stiffness_exponent=1.3,
                 friction_force=150.0, lug_amplitude=5e-4, lug_pitch=0.21 + 0.02 * i, lug_phase=0.7 * i)
        if BUILTIN[i]:
            p.update(footprint_length=0.3, cleat_height=H, cleat_width=W)
        laws.append(p)
    return tuple(laws)


def _record(body_kw):
    body = Body(TIRES, LOADS, L, pitch_index=0.8, roll_index=0.47, pivot_index=0.06, **body_kw)
    return TractorModel(body, _laws(), Cleat(H, W, V), ARRIVALS)


@pytest.fixture(scope="module")
def fmu_sets(tmp_path_factory):
    """{backend: [FL, FR, RL, RR FMU paths]}, the laws of :func:`_laws`."""
    out = {}
    for backend in ("native", "pythonfmu"):
        folder = tmp_path_factory.mktemp(backend)
        out[backend] = [build_fmu("extended_tire", folder / f"t_{t}.fmu", backend=backend, start_values=law)
                        for t, law in zip(TIRES, _laws())]
    return out


def _reference(tires, **kwargs):
    """The master of the fitting models (plain Python) with the FMUs' force callbacks and doSteps."""
    return run_body([t.force_fn() for t in tires], before_step=step_fn(tires), **kwargs)


def _same(a, b):
    for name in ("hub_z_m", "hub_vz_m_s", "hub_accel_m_s2", "force_n", "static_hub_z_m", "time_s"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.impulses == b.impulses


@pytest.mark.parametrize("backend,body", [("native", {}), ("native", dict(pitch=True)),
                                          ("native", dict(pitch=True, roll=True, pivot=True)),
                                          ("pythonfmu", dict(pitch=True, roll=True))],
                         ids=["native-corners", "native-sides", "native-pivot", "pythonfmu-rigid"])
def test_fmu_master_is_the_reference_scheme_bit_for_bit(fmu_sets, monkeypatch, backend, body):
    record = _record(body)
    grid = record.grid(0.2, 2.6, 1e-3, 1e-3)
    assert record.inputs(*grid).edges  # the road's cleat edges: impulses, two force readings there
    fast = tractor_cosim.run_tractor_fmus(fmu_sets[backend], record, start_s=grid[0], step_s=grid[1], n=grid[2])
    assert all(fast.impulses[i] for i in (1, 3))
    with monkeypatch.context() as m:
        m.setattr(tractor_cosim, "step_body_fmus", _reference)
        ref = tractor_cosim.run_tractor_fmus(fmu_sets[backend], record, start_s=grid[0], step_s=grid[1], n=grid[2])
    _same(fast, ref)
    # and the FMUs are the law: the fitting model's stepping in Python agrees to round-off
    law = run_model_python(record, *grid)
    scale = np.max(np.abs(law.hub_accel_m_s2))
    assert np.max(np.abs(fast.hub_accel_m_s2 - law.hub_accel_m_s2)) < 1e-8 * scale


def test_open_fmus_are_initialized_afresh_and_left_open(fmu_sets):
    """simulate_tractor opens each FMU once: it reads the law, then the run resets and initializes it again."""
    record = _record(dict(pitch=True, roll=True))
    grid = dict(zip(("start_s", "step_s", "n"), record.grid(0.2, 1.5, 1e-3, 1e-3)))
    fresh = tractor_cosim.run_tractor_fmus(fmu_sets["native"], record, **grid)
    tires = [TireFmu(p, instance_name=t) for p, t in zip(fmu_sets["native"], TIRES)]
    try:
        for tire in tires:  # a used instance: initialized elsewhere, inputs set, stepped
            tire.initialize(0.0)
            tire.force_fn()(0.6, 0.3, 1.0, 2.0, 0.01, 0.5)
            step_fn([tire])(0.0, 0.01)
        again = tractor_cosim.run_tractor_fmus(tires, record, **grid)
        assert all(t.slave is not None for t in tires)
        _same(again, fresh)
    finally:
        for tire in tires:
            tire.close()


def test_a_failed_fmi_call_raises_fmpy_s_error(fmu_sets):
    with TireFmu(fmu_sets["native"][0]) as tire:
        with pytest.raises(FMICallException, match="fmi2DoStep"):
            step_fn([tire])(0.0, 1e-3)  # before initialization
        tire.initialize(0.0)
        force = tire.force_fn()
        assert force(0.7, 0.0, 0.0, 0.0, 0.0, 0.0) > 0
        tire.exchange_args()[3][0] = 10 ** 6  # an unknown value reference
        with pytest.raises(FMICallException, match="fmi2SetReal"):
            force(0.7, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_an_instance_extracts_what_it_loads(fmu_sets):
    with TireFmu(fmu_sets["native"][0]) as tire:
        from pathlib import Path

        files = {p.relative_to(tire._dir).as_posix() for p in Path(tire._dir).rglob("*") if p.is_file()}
    assert "modelDescription.xml" in files and any(f.startswith("resources/") for f in files)
    assert {f.split("/")[1] for f in files if f.startswith("binaries/")} == {tire_platform()}
    assert not any(f.startswith(("sources/", "documentation/")) for f in files)


def tire_platform():
    from fmpy import platform

    return platform
