"""The acquisition chain: its modes against scipy's analog filters, its exact response against lsim, and a
fitting model seen through it against the virtual rig's own sensor chain (DOP853 solver, exact modal chain)."""

import dataclasses
import json

import numpy as np
import pytest
from scipy import signal

from identification.model.acquisition import Acquisition, apply_chain, chain_modes, sensed_acceleration
from identification.model.fitting import TractorFitModel, TractorProblem
from identification.recording import read_recording, write_recording
from identification.rig import run_rig


@pytest.mark.parametrize("order, cutoff_hz, highpass_hz", [(4, 250.0, 0.05), (2, 120.0, 0.0), (6, 400.0, 1.0),
                                                          (0, 0.0, 0.5)])
def test_modes_are_the_analog_butterworth_and_high_pass(order, cutoff_hz, highpass_hz):
    poles, residues, direct = chain_modes(order, cutoff_hz, highpass_hz)
    w = 2 * np.pi * np.array([0.01, 1.0, 10.0, 100.0, 250.0, 1000.0])
    modal = direct + (residues[None, :] / (1j * w[:, None] - poles[None, :])).sum(axis=1)
    ref = np.ones_like(w, dtype=complex)
    if order:
        b, a = signal.butter(order, 2 * np.pi * cutoff_hz, analog=True)
        ref *= signal.freqs(b, a, worN=w)[1]
    if highpass_hz:
        ref *= 1j * w / (1j * w + 2 * np.pi * highpass_hz)
    np.testing.assert_allclose(modal, ref, rtol=1e-9, atol=1e-12)


def test_exact_response_to_a_piecewise_linear_input_with_a_jump_and_an_impulse():
    """apply_chain against scipy's lsim on a fine grid (first-order hold), with the jump placed off the grid."""
    poles, residues, direct = chain_modes(4, 50.0, 0.5)
    h, n = 1e-3, 400
    t = np.arange(n) * h
    t_jump, a_jump, impulse = 0.1234, 3.0, 0.02
    x = np.sin(2 * np.pi * 7 * t) + a_jump * (t >= t_jump)
    before = np.sin(2 * np.pi * 7 * t_jump)
    y = apply_chain(x[None, :], 0.0, h, [(t_jump, before, before + a_jump, impulse)], poles, residues, direct)[0]
    # reference: the same input, linear between points of a 100x finer grid that holds the jump time
    fine = np.linspace(0, t[-1], 1000 * (n - 1) + 1)
    after = fine >= t_jump
    xf = np.sin(2 * np.pi * 7 * fine) + a_jump * after
    b, a = signal.butter(4, 2 * np.pi * 50.0, analog=True)
    b, a = np.polymul(b, [1, 0]), np.polymul(a, [1, 2 * np.pi * 0.5])
    _, yf, _ = signal.lsim((b, a), xf, fine, interp=True)
    # an impulse J at t_jump adds J times the impulse response
    _, imp = signal.impulse((b, a), T=fine[after] - t_jump)
    yf[after] += impulse * imp
    ref = np.interp(t, fine, yf)
    assert np.max(np.abs(y - ref)) < 2e-4 * np.max(np.abs(ref))   # measured 4.5e-5; without the impulse 0.63


def test_a_fitting_model_seen_through_the_chain_is_the_rig():
    """With the true parameters, the model's sensed acceleration equals the rig's recording (no noise).

    The rig integrates its own force law with DOP853 and applies its sensor chain exactly; the model
    steps the master's scheme at 1 ms and filters its velocity.  Without the chain the same model is
    off by percent: the anti-alias filter is part of what a channel shows.
    """
    run = run_rig(("enveloping",), {"sensor.noise_m_s2": 0.0, "cleat.stagger_m": 0.05}, seed=3)
    rec, truth = run.recording, run.truth
    assert rec.acquisition == Acquisition(4, 250.0, 0.05)
    theta = {f"{q}_{t}": truth["tires"][t][q] for t in rec.tires for q in ("k", "c")}
    arrival = {t: truth["tires"][t]["arrival_s"] for t in rec.tires}
    theta.update(arrival=arrival["FL"], stagger=arrival["FR"] - arrival["FL"], delay=arrival["RL"] - arrival["FL"],
                 footprint_front=truth["tires"]["FL"]["footprint_m"], footprint_rear=truth["tires"]["RL"]["footprint_m"])
    errors = {}
    for label, acq in (("chain", rec.acquisition), ("none", None)):
        pb = TractorProblem.from_recording(dataclasses.replace(rec, acquisition=acq))
        pred = TractorFitModel(("enveloping",), pb).predict(theta)
        w = pb.window
        errors[label] = max(np.sqrt(np.mean((pred[t] - pb.measured[t])[w] ** 2) / np.mean(pb.measured[t][w] ** 2))
                            for t in rec.tires)
    assert errors["chain"] < 1e-3, errors
    assert errors["none"] > 10 * errors["chain"], errors


def test_sensed_acceleration_without_a_chain_is_the_interval_mean():
    run = run_rig((), {"sensor.noise_m_s2": 0.0, "speed_kmh": 10.0}, seed=1)
    pb = TractorProblem.from_recording(run.recording)
    model = TractorFitModel((), pb)
    theta = {n: 1.0 for n in model.names}
    theta.update({f"{q}_{t}": run.truth["tires"][t][q] for t in pb.channels for q in ("k", "c")},
                 arrival=0.5, stagger=0.0, delay=run.recording.rear_axle_delay_s())
    traj = model.simulate(theta)
    t = run.recording.time_s
    np.testing.assert_array_equal(sensed_acceleration(traj, 0, t, 1000.0, None), traj.mean_acceleration(0, t, 1e-3))
    np.testing.assert_array_equal(sensed_acceleration(traj, 0, t, 1000.0, Acquisition(0, 0.0, 0.05)),
                                  traj.mean_acceleration(0, t, 1e-3))


def test_sidecar_round_trip(tmp_path):
    run = run_rig((), {"sensor.rate_hz": 500}, seed=1)
    write_recording(run.recording, tmp_path / "r")
    meta = json.loads((tmp_path / "r.json").read_text())
    assert meta["acquisition"] == {"anti_alias_order": 4, "anti_alias_cutoff_hz": 125.0, "highpass_hz": 0.05}
    assert read_recording(tmp_path / "r.csv").acquisition == Acquisition(4, 125.0, 0.05)


@pytest.mark.parametrize("value, words", [
    ({"anti_alias_order": 4, "anti_alias_cutoff_hz": 600.0}, "not below half the sampling rate"),
    ({"anti_alias_order": -1, "anti_alias_cutoff_hz": 100.0}, "anti_alias_order must be an integer"),
    ({"anti_alias_order": 2.5, "anti_alias_cutoff_hz": 100.0}, "anti_alias_order must be an integer"),
    ({"anti_alias_order": 4}, "anti_alias_cutoff_hz must be > 0"),
    ({"anti_alias_order": 4, "anti_alias_cutoff_hz": 100.0, "highpass_hz": "x"}, "highpass_hz must be"),
    ({"anti_alias_order": 4, "anti_alias_cutoff_hz": 100.0, "gain": 2}, "unknown key 'gain'"),
    ([4, 100.0], "acquisition must be an object"),
])
def test_bad_acquisition_is_one_line_exit_2(cli, tmp_path, value, words):
    run = run_rig((), {}, seed=1)
    write_recording(run.recording, tmp_path / "r")
    meta = json.loads((tmp_path / "r.json").read_text())
    meta["acquisition"] = value
    (tmp_path / "r.json").write_text(json.dumps(meta))
    res = cli("identify", tmp_path / "r.csv")
    assert res.code == 2
    assert words in res.err and len(res.err.strip().splitlines()) == 1, res.err
    assert "Traceback" not in res.err
