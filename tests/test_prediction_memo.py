"""The memory of recent predictions: a repeated run returns the very bits a fresh run gives, parameters that
a model could see differently never share an entry, and the memory stays within its bounds."""

import numpy as np
import pytest

from identification.model.fitting import PREDICTIONS, TractorFitModel, TractorProblem
from identification.model.memo import PredictionMemo, parameters_key
from identification.rig import run_rig


@pytest.fixture(scope="module")
def problem_and_theta():
    run = run_rig(("enveloping",), {"duration_s": 3.0}, seed=3)
    pb = TractorProblem.from_recording(run.recording)
    model = TractorFitModel(("enveloping",), pb)
    t = run.truth["tires"]
    theta = {f"{kind}_{tire}": t[tire][kind] for tire in pb.channels for kind in ("k", "c")}
    theta.update(arrival=t["FL"]["arrival_s"], stagger=t["FR"]["arrival_s"] - t["FL"]["arrival_s"],
                 delay=t["RL"]["arrival_s"] - t["FL"]["arrival_s"], footprint_front=0.25, footprint_rear=0.3)
    return model, {n: theta[n] for n in model.names}


def _fresh(model, theta, **kw):
    PREDICTIONS.clear()
    out = model.predict(theta, **kw)
    PREDICTIONS.clear()
    return out


def test_a_repeated_prediction_is_a_fresh_runs_bits(problem_and_theta):
    model, theta = problem_and_theta
    PREDICTIONS.clear()
    hits = PREDICTIONS.hits
    first = model.predict(theta)
    again = model.predict(dict(reversed(list(theta.items()))))    # the same parameters in another order
    assert PREDICTIONS.hits == hits + 1
    fresh = _fresh(model, theta)
    for c in model.problem.channels:
        assert np.array_equal(again[c], fresh[c]) and np.array_equal(first[c], fresh[c])
        assert not again[c].flags.writeable                      # shared: nobody may change them
    # another step, another model over the same problem, another value: each its own run
    for other, kw, th in ((model, {"step_s": model.default_step_s() / 2}, theta),
                          (TractorFitModel(("enveloping", "friction_damping"), model.problem), {},
                           {**theta, "friction": 50.0}),
                          (model, {}, {**theta, "k_FL": theta["k_FL"] * 1.01})):
        hits = PREDICTIONS.hits
        got = other.predict(th, **kw)
        assert PREDICTIONS.hits == hits
        assert any(not np.array_equal(got[c], first[c]) for c in model.problem.channels)


def test_the_same_run_under_an_explicit_default_step_is_remembered(problem_and_theta):
    model, theta = problem_and_theta
    PREDICTIONS.clear()
    model.predict(theta)
    hits = PREDICTIONS.hits
    model.predict(theta, step_s=model.default_step_s())
    assert PREDICTIONS.hits == hits + 1


def test_keys_tell_apart_what_a_model_could_see_differently():
    assert parameters_key({"a": 0.0}) != parameters_key({"a": -0.0})
    assert parameters_key({"a": 1.0, "b": 2.0}) == parameters_key({"b": 2.0, "a": np.float64(1.0)})
    assert parameters_key({"a": 1}) != parameters_key({"a": 1.0})
    assert parameters_key({"a": {"nested": 1}}) is None           # not a key: such a run is not remembered
    memo = PredictionMemo()
    assert memo.get(None) is None
    out = memo.put(None, {"FL": np.zeros(3)})
    assert len(memo) == 0 and not out["FL"].flags.writeable


def test_the_memory_keeps_within_its_bytes_and_entries():
    memo = PredictionMemo(max_bytes=10 * 800, max_entries=4)
    for i in range(6):
        memo.put(("run", i), {"FL": np.full(100, float(i))})      # 800 bytes each
    assert len(memo) == 4 and memo.nbytes == 4 * 800
    assert memo.get(("run", 0)) is None and memo.get(("run", 1)) is None
    assert np.array_equal(memo.get(("run", 5))["FL"], np.full(100, 5.0))
    memo.get(("run", 2))                                          # used: kept over the older ones
    memo.put(("run", 6), {"FL": np.zeros(100)})
    assert memo.get(("run", 2)) is not None and memo.get(("run", 3)) is None
    big = PredictionMemo(max_bytes=1000)
    big.put("large", {"FL": np.zeros(200)})                       # 1600 bytes: over the budget, not kept
    assert len(big) == 0 and big.nbytes == 0
    with pytest.raises(ValueError, match="max_bytes"):
        PredictionMemo(max_bytes=-1)

