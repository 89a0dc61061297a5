"""The rigid tractor's free decay against a reference integrated here from Newton's equations, not the package's.

The reference: a rigid body (heave, pitch, roll; centre of gravity from the static loads) on four
spring-dampers (and, for one case, a Coulomb friction beside each), integrated by scipy's DOP853 from an
initial state; the hubs' accelerations, with white noise, are the four channels.  The free-decay fit of
:mod:`identification.diagnose.body_decay` must return each tire's k and c and hold them in its intervals,
and must say where a friction makes the decay's damping depend on its amplitude.
"""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from identification.diagnose.body_decay import body_decay, why_not

G = 9.80665
TIRES = ("FL", "FR", "RL", "RR")
LOADS = {"FL": 11_500.0, "FR": 12_300.0, "RL": 15_600.0, "RR": 16_400.0}
K = {"FL": 560e3, "FR": 510e3, "RL": 430e3, "RR": 470e3}
C = {"FL": 4200.0, "FR": 3600.0, "RL": 2400.0, "RR": 2900.0}
WHEELBASE, HALF_TRACK, PITCH_INDEX, ROLL_GYRATION = 2.6, 0.9, 1.05, 0.62


def _reference(friction_n: float = 0.0, noise: float = 0.03, rate_hz: float = 1000.0, seconds: float = 3.0,
               seed: int = 1):
    """Hub accelerations (m/s²) of the rigid body ringing from an initial heave, pitch and roll."""
    total = sum(LOADS.values())
    mass = total / G
    a = WHEELBASE * (LOADS["RL"] + LOADS["RR"]) / total          # centre of gravity behind the front axle
    b = WHEELBASE - a
    y_cg = HALF_TRACK * (LOADS["FL"] + LOADS["RL"] - LOADS["FR"] - LOADS["RR"]) / total
    i_pitch = PITCH_INDEX * mass * a * b
    i_roll = mass * ROLL_GYRATION ** 2
    x = {t: (a if t[0] == "F" else -b) for t in TIRES}            # forward of the centre of gravity
    y = {t: (HALF_TRACK if t[1] == "L" else -HALF_TRACK) - y_cg for t in TIRES}

    def hub(state, t):
        z, th, ph = state[:3]
        return z + x[t] * th + y[t] * ph

    def rhs(_, s):
        pos, vel = s[:3], s[3:]
        fz = mz = mx = 0.0
        for t in TIRES:
            d, v = hub(pos, t), hub(vel, t)
            f = -K[t] * d - C[t] * v - friction_n * np.tanh(v / 0.005)
            fz += f
            mz += x[t] * f                          # pitch (nose up positive with hub = z + x θ)
            mx += y[t] * f
        return np.concatenate([vel, [fz / mass, mz / i_pitch, mx / i_roll]])

    t = np.arange(0.0, seconds, 1.0 / rate_hz)
    s0 = np.array([0.012, -0.004, 0.006, 0.0, 0.03, 0.0])
    sol = solve_ivp(rhs, (0.0, t[-1]), s0, method="DOP853", t_eval=t, rtol=1e-10, atol=1e-12)
    acc = np.array([rhs(0.0, sol.y[:, i])[3:] for i in range(t.size)]).T
    rng = np.random.default_rng(seed)
    channels = {tt: acc[0] + x[tt] * acc[1] + y[tt] * acc[2] + rng.normal(0.0, noise, t.size) for tt in TIRES}
    truth = {"pitch_index": PITCH_INDEX, "roll_index": i_roll / (mass * HALF_TRACK ** 2)}
    return t, channels, truth


def _problem(t, channels, noise):
    """The fields of a diagnosis problem the free-decay fit reads; the impact long before the record starts."""
    rec = SimpleNamespace(time_s=t, sample_rate_hz=1.0 / (t[1] - t[0]), speed_m_s=2.5, cleat_width_m=0.1,
                          wheel_load_N=dict(LOADS), wheelbase_m=WHEELBASE,
                          mass_kg=lambda tire: LOADS[tire] / G)
    return SimpleNamespace(rec=rec, channels=TIRES, measured=channels, noise={c: noise for c in TIRES},
                           onsets={c: -1.0 for c in TIRES}, cutoff_hz=100.0)


def test_the_free_decay_of_a_rigid_body_returns_every_tire_s_k_and_c():
    t, channels, truth = _reference()
    fit = body_decay(_problem(t, channels, 0.03), kind="rigid")
    assert why_not(fit) is None, why_not(fit)
    for tire in TIRES:
        assert fit.params[f"k_{tire}"] == pytest.approx(K[tire], rel=0.01)
        assert fit.params[f"c_{tire}"] == pytest.approx(C[tire], rel=0.05)
    assert fit.params["pitch_index"] == pytest.approx(truth["pitch_index"], rel=0.02)
    assert fit.params["roll_index"] == pytest.approx(truth["roll_index"], rel=0.02)
    assert fit.residual_to_noise == pytest.approx(1.0, abs=0.1)      # the residual is the noise
    # the decay's scales from its second half hold 1: a linear tire
    for q in ("k", "c"):
        _, lo, hi = fit.extra["scales"][q]
        assert lo <= 1.0 <= hi


@pytest.mark.sweep
def test_the_free_decay_s_95_percent_intervals_hold_k_and_c_about_95_percent_of_the_time():
    held = total = 0
    for seed in range(10, 22):
        t, channels, _ = _reference(seed=seed)
        fit = body_decay(_problem(t, channels, 0.03), kind="rigid")
        for tire in TIRES:
            for q, true in (("k", K[tire]), ("c", C[tire])):
                lo, hi = fit.ci[f"{q}_{tire}"]
                held += lo <= true <= hi
                total += 1
    # 96 quantities: a 95 % interval holds 91 of them on average, 86 or more in 99 % of such runs
    assert held >= 86, f"{held} of {total}"


def test_four_independent_corners_do_not_fit_a_rigid_body_s_decay():
    t, channels, _ = _reference()
    problem = _problem(t, channels, 0.03)
    rigid, corners = body_decay(problem, kind="rigid"), body_decay(problem, kind="corners")
    assert corners.residual_to_noise > 3 * rigid.residual_to_noise
    assert why_not(rigid) is None


def test_a_friction_beside_the_dampers_is_said_not_taken_for_damping():
    t, channels, _ = _reference(friction_n=250.0)
    fit = body_decay(_problem(t, channels, 0.03), kind="rigid")
    reason = why_not(fit)
    assert reason is not None and ("amplitude" in reason or "noise" in reason or "determine" in reason), reason


def test_a_tail_too_short_gives_no_decay():
    t, channels, _ = _reference(seconds=0.6)
    assert body_decay(_problem(t, channels, 0.03), kind="rigid") is None
