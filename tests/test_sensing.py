"""The all-channel compiled pass of a model's sensed, low-passed acceleration against the reference, channel by
channel with the public functions (``sensed_acceleration`` then ``lowpass``), to round-off."""

import dataclasses
import itertools

import numpy as np
import pytest

from identification.model.acquisition import Acquisition
from identification.model.fitting import BODY_EFFECTS, TIRE_EFFECTS, TractorFitModel, TractorProblem
from identification.errors import InputError
from identification.model.sensing import sensed_lowpassed, sensed_lowpassed_reference
from identification.rig import run_rig
from identification.model.scheme import Trajectory

TOL = 1e-12
CHAINS = {"rig": "rig", "none": None, "highpass_only": Acquisition(0, 0.0, 0.05),
          "anti_alias_only": Acquisition(2, 120.0, 0.0), "odd_order": Acquisition(5, 300.0, 1.0)}
BODIES = [(), ("axle_coupling",), ("roll_coupling",), ("axle_coupling", "roll_coupling"), BODY_EFFECTS]
TIRE_SETS = [()] + [(e,) for e in TIRE_EFFECTS] + [("enveloping", "lift_off"), TIRE_EFFECTS]


def _relative(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.fixture(scope="module")
def run():
    return run_rig(("axle_coupling", "lift_off"), {"cleat.stagger_m": 0.2, "duration_s": 3.0}, seed=11)


def _theta(model, truth):
    tires = truth["tires"]
    theta = dict(pitch_index=0.8, roll_index=0.5, pivot_index=0.06, footprint_front=0.3, footprint_rear=0.38,
                 exponent=1.3, friction=200.0, lug_frequency_front=9.0, lug_frequency_rear=7.5,
                 arrival=tires["FL"]["arrival_s"] + 1.3e-4,
                 stagger=tires["FR"]["arrival_s"] - tires["FL"]["arrival_s"] + 2.1e-4,
                 delay=tires["RL"]["arrival_s"] - tires["FL"]["arrival_s"] - 3.3e-4)
    for i, t in enumerate(model.problem.channels):
        theta.update({f"k_{t}": tires[t]["k"], f"c_{t}": tires[t]["c"], f"lug_amplitude_{t}": 1e-3,
                      f"lug_phase_{t}": 0.3 + 0.5 * i})
    return {n: theta[n] for n in model.names}


@pytest.mark.parametrize("chain", list(CHAINS))
def test_predict_equals_the_channel_by_channel_reference_for_every_effect(run, chain):
    rec = run.recording if CHAINS[chain] == "rig" else dataclasses.replace(run.recording, acquisition=CHAINS[chain])
    pb = TractorProblem.from_recording(rec)
    checked = 0
    for body, tires, resolve in itertools.product(BODIES, TIRE_SETS, (False, True)):
        effects = body + tires
        if not all(pb.available(e, effects[:i]) for i, e in enumerate(effects)):
            continue
        model = TractorFitModel(effects, pb, resolve_edges=resolve)
        theta = _theta(model, run.truth)
        traj = model.simulate(theta)
        fast, ref = model.predict(theta, trajectory=traj), model.predict_reference(theta, trajectory=traj)
        assert list(fast) == list(ref) == list(pb.channels)
        for t in pb.channels:
            assert _relative(fast[t], ref[t]) <= TOL, (effects, resolve, t)
        checked += 1
    assert checked >= 20


def test_a_subset_of_channels(run):
    pb = TractorProblem.from_recording(run.recording, channels=("FL", "RL"))
    model = TractorFitModel(("axle_coupling", "lift_off"), pb)
    theta = _theta(model, run.truth)
    fast, ref = model.predict(theta), model.predict_reference(theta)
    assert list(fast) == ["FL", "RL"]
    assert max(_relative(fast[t], ref[t]) for t in fast) <= TOL


def _synthetic_trajectory(step_s, n, seed=0):
    """Smooth hub velocities with impulses at awkward times: shared, repeated (merged), off the grid, on a grid
    point, exactly half a step from one (a dyadic step), before the grid and after it, out of time order."""
    rng = np.random.default_rng(seed)
    t = 0.25 + step_s * np.arange(n)
    v = np.array([0.05 * np.sin(2 * np.pi * f * t + p) for f, p in rng.uniform([3, 0], [20, 6], (3, 2))])
    mid = t[n // 2]
    impulses = (
        ((mid + 0.3 * step_s, 0.02), (t[100], -0.01), (mid + 0.3 * step_s, 0.005), (t[200] + 0.5 * step_s, 0.01)),
        ((t[-1] + 0.1, 0.03), (t[0] - 0.1, -0.02), (t[300] - 0.5 * step_s, 0.015), (t[1] - 1e-9, 0.01)),
        (),
    )
    zeros = np.zeros_like(v)
    return Trajectory(time_s=t, hub_z_m=zeros, hub_vz_m_s=v, hub_accel_m_s2=zeros, force_n=zeros, step_s=step_s,
                      static_hub_z_m=np.zeros(3), impulses=impulses)


@pytest.mark.parametrize("chain", [None, Acquisition(4, 250.0, 0.05), Acquisition(0, 0.0, 0.05),
                                   Acquisition(3, 200.0, 0.0)])
@pytest.mark.parametrize("per_sample", [1, 4])
def test_awkward_impulses_and_sample_times(chain, per_sample):
    fs = 1024.0
    traj = _synthetic_trajectory(1.0 / fs / per_sample, 2048 * per_sample)
    # samples from before the grid to after it, not all on grid points
    times = np.concatenate([np.arange(0.1, 2.3, 1.0 / fs), [2.3 + 1e-4, 2.4, 2.5]])
    fast = sensed_lowpassed(traj, times, fs, chain, cutoff_hz=100.0)
    ref = sensed_lowpassed_reference(traj, times, fs, chain, cutoff_hz=100.0)
    assert fast.shape == ref.shape == (3, times.size)
    for a, b in zip(fast, ref):
        assert _relative(a, b) <= TOL


def test_the_cutoff_is_checked():
    traj = _synthetic_trajectory(1.0 / 1024, 500)
    with pytest.raises(InputError, match="Nyquist"):
        sensed_lowpassed(traj, traj.time_s, 1024.0, None, cutoff_hz=600.0)


@pytest.mark.parametrize("rows", [1, 3, 4, 5, 9])
@pytest.mark.parametrize("order", [1, 2, 5, 8])
def test_the_rows_filter_is_scipys_sosfiltfilt_through_long_zero_stretches(rows, order):
    # a prediction is exactly zero before its impact: the backward pass's states decay through that stretch
    # (into subnormal numbers, where the compiled filter sets them to zero) and must still give scipy's result
    from scipy import signal

    from identification.model.sensing import _filtfilt_rows
    from identification.recording.preprocess import lowpass_design

    fs, n = 2000.0, 20000
    sos, zi, edge = lowpass_design(sample_rate_hz=fs, cutoff_hz=100.0, order=order)
    t = np.arange(n) / fs
    x = np.zeros((rows, n))
    for r in range(rows):
        onset = 7.0 + 0.2 * r
        after = t >= onset
        x[r, after] = (r + 1) * np.exp(-3.0 * (t[after] - onset)) * np.sin(2 * np.pi * (4 + r) * (t[after] - onset))
    fast = _filtfilt_rows(x, sos, zi, edge)
    for r in range(rows):
        ref = signal.sosfiltfilt(sos, x[r])
        assert np.max(np.abs(fast[r] - ref)) <= TOL * np.max(np.abs(ref))
        assert np.any(np.abs(ref[ref != 0]) < 2.3e-308)   # the stretch does reach subnormal numbers
