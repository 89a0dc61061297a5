"""The friction gate's check against the free decays: a viscous damper's decay rate holds as the amplitude
falls, friction's grows; a friction named on viscous corners is refused, one on a coupled body is not
judged by the channels' own decays (they are the body's modes)."""

from types import SimpleNamespace

import pytest

from identification.diagnose.joint_evidence import MIN_DECAY_CYCLES, check_tractor, viscous_decays
from identification.model.fitting import TractorProblem
from identification.rig import run_rig


def _problem(effects=(), seed=3, **overrides):
    run = run_rig(effects, dict({"duration_s": 4.0, "speed_kmh": 10.0}, **overrides), seed=seed)
    return TractorProblem.from_recording(run.recording)


@pytest.fixture(scope="module")
def viscous():
    return _problem()


@pytest.fixture(scope="module")
def rubbing():
    return _problem(("friction_damping",), **{"friction_damping.force_N": 150.0})


@pytest.mark.parametrize("seed", [3, 8])
def test_viscous_corners_decay_at_one_rate_and_friction_corners_do_not(seed):
    """The rig's corners (viscous dampers, its truth): every channel ringing MIN_DECAY_CYCLES cycles or more
    decays at one rate (second half / first half within 2 % of 1); with a 150 N friction force (a tenth of
    the decay's initial spring force) none of them passes as viscous."""
    long, visc = viscous_decays(_problem(seed=seed))
    assert len(long) >= 2 and set(visc) == set(long), (long, visc)
    assert all(abs(r - 1) < 0.02 for r in visc.values()), visc
    long, visc = viscous_decays(_problem(("friction_damping",), seed=seed, **{"friction_damping.force_N": 150.0}))
    assert len(long) >= 2 and not visc, (long, visc)


def _fit(pb, effects):
    """A fitted model with a clear friction force (200 N, interval 150-250 N): what the gate sees of it."""
    model = SimpleNamespace(effects=frozenset(effects), problem=pb)
    return SimpleNamespace(model=model, params={"friction": 200.0}, ci={"friction": (150.0, 250.0)})


def test_a_friction_the_free_decays_refute_is_refused_on_corners_only(viscous, rubbing):
    ok, text = check_tractor("friction_damping", _fit(viscous, ["friction_damping"]), None)
    assert not ok and "refuted by the free decays" in text and f"{MIN_DECAY_CYCLES:g} cycles" in text, text
    ok, text = check_tractor("friction_damping", _fit(rubbing, ["friction_damping"]), None)
    assert ok and "refuted" not in text, text
    # under a coupled body a channel's own decay is the body's mode: no verdict from it
    ok, _ = check_tractor("friction_damping", _fit(viscous, ["axle_coupling", "friction_damping"]), None)
    assert ok
    # the force's own conditions still hold: an interval reaching 0 is no friction
    weak = _fit(rubbing, ["friction_damping"])
    weak.ci["friction"] = (0.0, 400.0)
    assert not check_tractor("friction_damping", weak, None)[0]
