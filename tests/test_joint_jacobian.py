"""The joint fit's grouped finite-difference Jacobian against scipy's dense one (``approx_derivative``,
least_squares' forward differences): the same numbers to the last bit, from fewer model runs; and a body
that couples the tires keeps every column on its own."""

import numpy as np
import pytest
from scipy.optimize._numdiff import approx_derivative

from identification.diagnose.joint_fit import fit_tractor
from identification.diagnose.joint_jacobian import (GroupedJacobian, channel_dependence, column_groups,
                                                    forward_steps)
from identification.model.fitting import TractorFitModel, TractorProblem
from identification.rig import run_rig


@pytest.fixture(scope="module")
def corners():
    run = run_rig(("enveloping",), {"duration_s": 4.0}, seed=5)
    return TractorProblem.from_recording(run.recording), run.truth


def _start(model, truth):
    theta = {}
    for name in model.names:
        kind, _, tire = name.rpartition("_")
        if kind in ("k", "c"):
            theta[name] = truth["tires"][tire][kind] * 1.1
    theta.update(arrival=truth["tires"]["FL"]["arrival_s"] + 0.002,
                 stagger=truth["tires"]["FR"]["arrival_s"] - truth["tires"]["FL"]["arrival_s"],
                 delay=truth["tires"]["RL"]["arrival_s"] - truth["tires"]["FL"]["arrival_s"],
                 footprint_front=0.25, footprint_rear=0.3)
    return {n: theta[n] for n in model.names}


def test_forward_steps_are_least_squares_own():
    x = np.array([0.0, 1e-300, -2.5, 13.1, -0.0])
    rel = np.array([1e-4, 1e-4, 1e-3, 2e-5, 1e-4])
    calls = []

    def f(v):
        calls.append(np.array(v))
        return np.zeros(2)
    approx_derivative(f, x, method="2-point", rel_step=rel, f0=np.zeros(2))
    steps = np.array([c - x for c in calls]).diagonal()
    assert np.array_equal(steps, (x + forward_steps(rel, x)) - x)


def test_grouped_jacobian_equals_scipys_dense_one_bit_for_bit(corners):
    pb, truth = corners
    model = TractorFitModel(("enveloping",), pb)
    theta = _start(model, truth)
    free = list(model.names)
    logs = [n not in ("arrival", "stagger") for n in free]
    w = pb.window
    meas = np.concatenate([pb.measured[c][w] for c in pb.channels])
    scale = np.concatenate([np.full(int(w.sum()), pb.noise[c]) for c in pb.channels])
    runs = []

    def residual(x):
        runs.append(1)
        th = {n: (np.exp(v) if lg else v) for n, v, lg in zip(free, x, logs)}
        pred = model.predict(th)
        return (np.concatenate([pred[c][w] for c in pb.channels]) - meas) / scale

    x0 = np.array([np.log(theta[n]) if lg else theta[n] for n, lg in zip(free, logs)])
    rel = np.where(logs, 1e-4, 2e-5)
    dependence = channel_dependence(model, free)
    groups = column_groups(dependence)
    assert len(groups) < len(free) / 2                # k of four tires in one run, c of four in another...
    grouped = GroupedJacobian(residual, rel, dependence, int(w.sum()))
    f0 = grouped.value(x0)
    runs.clear()
    jac = grouped(x0)
    assert len(runs) == len(groups)
    dense = approx_derivative(residual, x0, method="2-point", rel_step=rel, f0=f0)
    assert np.array_equal(jac, dense)
    assert np.count_nonzero(dense) < dense.size / 2   # the pattern is there to exploit


def test_a_body_coupling_every_tire_keeps_dense_columns(corners):
    pb, _ = corners
    for effects in (("axle_coupling",), ("roll_coupling", "enveloping"), ("axle_coupling", "front_axle_pivot")):
        model = TractorFitModel(effects, pb)
        assert channel_dependence(model, list(model.names)) is None


def test_fit_with_grouped_columns_is_the_dense_fit(corners, monkeypatch):
    pb, truth = corners
    model = TractorFitModel(("enveloping",), pb)
    start = _start(model, truth)
    grouped = fit_tractor(model, start, budget=300, step_check=True)
    import identification.diagnose.joint_fit as jf
    monkeypatch.setattr(jf, "channel_dependence", lambda m, f: None)
    dense = fit_tractor(model, start, budget=300, step_check=True)
    assert grouped.params == dense.params and grouped.ci == dense.ci
    assert grouped.evaluations < 0.7 * dense.evaluations
