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


def _decays(pb):
    from identification.identify.waveform import identify_waveform
    from identification.recording.preprocess import preprocess

    out = {}
    for tire in pb.channels:
        sig = preprocess(pb.rec, [tire], cutoff_hz=pb.cutoff_hz, min_peaks=1)[tire]
        out[tire] = sig, identify_waveform(sig, pb.rec.mass_kg(tire), source=pb.rec.source)
    return out


def test_the_decays_halves_move_with_friction_and_widen_its_c_interval(viscous, rubbing):
    """The amplitude term of the free decay's interval (``WaveformResult.amplitude_move``): on the rig's viscous
    corners the halves agree within their noise (c's move under 1 % of c); with a 150 N friction force c moves
    by more than 5 % between the decay's halves on every ringing channel (friction's equivalent damping
    4F/(πωX) grows as the amplitude X falls), and the c interval holds that move beyond the floor."""
    from identification.identify.waveform import DECAY_FLOOR

    long, _ = viscous_decays(viscous)
    for tire, (sig, wave) in _decays(viscous).items():
        if tire in long:
            assert wave.amplitude_move[1] < 0.01 * wave.c, tire
    long, _ = viscous_decays(rubbing)
    assert len(long) >= 2
    for tire, (sig, wave) in _decays(rubbing).items():
        if tire not in long:
            continue
        moved = wave.amplitude_move[1]
        assert moved > 0.05 * wave.c > DECAY_FLOOR["c"] * wave.c, (tire, moved)
        assert min(wave.c - wave.c_ci[0], wave.c_ci[1] - wave.c) >= moved
