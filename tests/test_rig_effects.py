"""Each rig effect shows its physical signature in the recorded hub acceleration."""

import numpy as np
import pytest

from identification.recording.preprocess import lowpass, preprocess
from identification.recording import STANDARD_GRAVITY
from identification.rig import EFFECTS, run_rig


def filtered(run, tire):
    rec = run.recording
    return rec.time_s, lowpass(rec.accel_m_s2[tire], sample_rate_hz=rec.sample_rate_hz)


def test_effect_names_are_exact():
    assert EFFECTS == ("enveloping", "lift_off", "axle_coupling", "nonlinear_stiffness", "friction_damping",
                       "periodic_disturbance")


@pytest.mark.parametrize("speed", [7.0, 10.0])
def test_lift_off_hub_falls_at_minus_g_while_contact_force_is_zero(speed):
    run = run_rig(("lift_off",), {"speed_kmh": speed}, seed=2)
    t = run.recording.time_s
    checked = 0
    for tire, truth in run.truth["tires"].items():
        for a, b in truth["contact_loss_s"]:
            inside = (t > a + 0.005) & (t < b - 0.005)  # away from the anti-alias filter's transitions
            if inside.sum() < 10:
                continue
            acc = run.recording.accel_m_s2[tire][inside]
            assert np.all(np.abs(acc / -STANDARD_GRAVITY - 1) < 0.05), (tire, a, b, acc.min(), acc.max())
            checked += inside.sum()
    assert checked > 50
    # the bilateral baseline never flies
    base = run_rig((), {"speed_kmh": speed}, seed=2)
    assert all(not tt["contact_loss_s"] for tt in base.truth["tires"].values())


def test_axle_coupling_rear_impact_appears_in_front_hubs():
    run = run_rig(("axle_coupling",), seed=4)
    base = run_rig((), seed=4)
    t_rear = run.truth["tires"]["RL"]["arrival_s"]
    assert run.truth["tires"]["FL"]["arrival_s"] + 2.77 / (7 / 3.6) == pytest.approx(t_rear)
    for tire in ("FL", "FR"):
        jerk = {}
        for name, r in (("coupled", run), ("corners", base)):
            t, x = r.recording.time_s, r.recording.accel_m_s2[tire]
            d = np.abs(np.diff(x))
            before = d[(t[1:] > t_rear - 0.3) & (t[1:] < t_rear - 0.01)].max()
            after_mask = (t[1:] >= t_rear) & (t[1:] < t_rear + 0.05)
            after = d[after_mask].max()
            jerk[name] = (before, after, t[1:][after_mask][np.argmax(d[after_mask])])
        before, after, t_peak = jerk["coupled"]
        assert after > 10 * before, jerk
        assert abs(t_peak - t_rear) < 0.005
        assert jerk["corners"][1] < 2 * jerk["corners"][0]  # independent corners: nothing at t_rear
    body = run.truth["body"]
    index = body["pitch_inertia_kg_m2"] / (body["mass_kg"] * body["cg_behind_front_axle_m"]
                                           * body["cg_ahead_of_rear_axle_m"])
    assert index == pytest.approx(0.8) and abs(index - 1) > 0.1


def _periods(t, x, t_a, t_b):
    m = (t >= t_a) & (t <= t_b)
    tt, xx = t[m], x[m]
    s = np.flatnonzero((xx[:-1] < 0) & (xx[1:] >= 0))
    crossings = tt[s] - xx[s] * (tt[s + 1] - tt[s]) / (xx[s + 1] - xx[s])
    return np.diff(crossings)


def test_nonlinear_stiffness_period_changes_with_amplitude():
    changes = {}
    for name, effects in (("nonlinear", ("nonlinear_stiffness",)), ("linear", ())):
        per = []
        for seed in range(3):
            run = run_rig(effects, {"nonlinear_stiffness.exponent": 2.0, "tire.RL.c_Ns_m": 1500.0}, seed=seed)
            t, x = filtered(run, "RL")
            T = _periods(t, x, run.truth["tires"]["RL"]["arrival_s"] + 0.2, 4.9)
            per.append((T[0] - np.mean(T[-3:])) / np.mean(T[-3:]))
        changes[name] = np.array(per)
    noise = np.abs(changes["linear"]).max()
    assert np.all(np.abs(changes["nonlinear"]) > 5 * noise), changes


def _envelope_residuals(times, peaks):
    A = np.vstack([np.ones_like(times), times]).T
    lin = peaks - A @ np.linalg.lstsq(A, peaks, rcond=None)[0]
    exp = peaks - np.exp(A @ np.linalg.lstsq(A, np.log(peaks), rcond=None)[0])
    return np.sqrt(np.mean(lin ** 2)), np.sqrt(np.mean(exp ** 2))


def test_friction_damping_envelope_closer_to_linear_than_exponential():
    for seed in range(3):
        fric = preprocess(run_rig(("friction_damping",), seed=seed).recording, ["RL"])["RL"]
        lin, exp = _envelope_residuals(fric.peak_times_s, fric.peak_values_m_s2)
        assert lin < 0.7 * exp, (lin, exp)
        base = preprocess(run_rig((), seed=seed).recording, ["RL"])["RL"]
        lin, exp = _envelope_residuals(base.peak_times_s, base.peak_values_m_s2)
        assert exp < 0.1 * lin


@pytest.mark.parametrize("overrides", [{}, {"periodic_disturbance.frequency_hz": 23.5}])
def test_periodic_disturbance_spectral_line(overrides):
    run = run_rig(("periodic_disturbance",), overrides, seed=5)
    base = run_rig((), overrides, seed=5)
    t = run.recording.time_s
    pre = t < run.truth["tires"]["FL"]["excitation_s"][0] - 0.02  # steady state before the cleat
    f_line = run.truth["tires"]["FL"]["lug_frequency_hz"]
    if overrides:
        assert f_line == pytest.approx(23.5)
    else:  # lug passing: speed / (pi D / lugs)
        assert f_line == pytest.approx(7 / 3.6 / (np.pi * 1.357 / 21))
    for r, expect_line in ((run, True), (base, False)):
        x = r.recording.accel_m_s2["FL"][pre]
        n = 1 << 16
        spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size), n))
        f = np.fft.rfftfreq(n, 1 / r.recording.sample_rate_hz)
        band = (f > 1) & (f < 100)
        f_peak = f[band][np.argmax(spec[band])]
        near = np.abs(f - f_line) < 0.5
        line_to_floor = spec[near].max() / np.median(spec[band])
        if expect_line:
            assert abs(f_peak - f_line) < 0.3 and line_to_floor > 20
        else:
            assert line_to_floor < 5


def test_enveloping_spreads_the_cleat_over_footprint_plus_width():
    env = run_rig(("enveloping",), {"sensor.noise_m_s2": 0.01}, seed=6)
    point = run_rig((), {"sensor.noise_m_s2": 0.01}, seed=6)
    v = 7 / 3.6
    for tire in ("FL", "RL"):
        tt = env.truth["tires"][tire]
        fp = tt["footprint_m"]
        assert fp == pytest.approx(0.30 if tire == "FL" else 0.38)
        start, end = tt["excitation_s"]
        assert end - start == pytest.approx((fp + 0.10) / v, rel=1e-12)
        # the response starts when the footprint's leading edge meets the cleat, fp / 2v early
        t, x = filtered(env, tire)
        onset = t[np.argmax(np.abs(x) > 0.2)] if tire == "FL" else \
            t[(t > tt["arrival_s"] - 0.3)][np.argmax(np.abs(x[t > tt["arrival_s"] - 0.3]) > 0.2)]
        assert start - 0.005 < onset < start + 0.06
        assert onset < tt["arrival_s"] - 0.03
        # a smaller first peak than point contact
        win = (t > start - 0.05) & (t < end + 0.05)
        _, xp = filtered(point, tire)
        assert np.abs(x[win]).max() < 0.5 * np.abs(xp[win]).max()
