"""The paper's identification against its own tables and against closed forms."""

import math

import numpy as np
import pytest
from conftest import LOADS_N, analytic_recording, true_k

from identification.identify.paper import (damping_ratio, decay_rate_through_first_peak, identify, natural_frequency,
                                     stiffness)
from identification.recording import STANDARD_GRAVITY

# Table 4 of the cleat-test paper: speed, tire, T/s, zeta, delta, omega_n/(rad/s), K/(kN/m).
TABLE4 = [
    (7, "FL", 0.29, 0.15, 0.95, 21.65, 551.33),
    (7, "FR", 0.31, 0.09, 0.62, 20.27, 486.08),
    (7, "RL", 0.39, 0.09, 0.59, 16.02, 409.42),
    (7, "RR", 0.38, 0.03, 0.16, 16.47, 428.80),
    (10, "FL", 0.29, 0.15, 0.95, 22.03, 570.69),
    (10, "FR", 0.29, 0.15, 0.98, 21.75, 559.80),
    (10, "RL", 0.38, 0.13, 0.83, 16.53, 436.22),
    (10, "RR", 0.36, 0.06, 0.39, 17.49, 483.79),
]


@pytest.mark.parametrize("speed,tire,T,zeta,delta,wn,K", TABLE4)
def test_table4_reproduced_from_its_own_columns(speed, tire, T, zeta, delta, wn, K):
    mass = LOADS_N[tire] / STANDARD_GRAVITY
    assert abs(float(damping_ratio(delta)) - zeta) <= 0.01
    assert mass * wn ** 2 / 1e3 == pytest.approx(K, rel=0.01)            # k = m ωn²
    assert float(stiffness(mass, T, delta)) / 1e3 == pytest.approx(K, rel=0.025)  # eq. 9 from rounded T, δ


def test_equations_7_8_9_closed_form():
    delta, T, m = 0.7, 0.3, 1200.0
    zeta = delta / math.sqrt(4 * math.pi ** 2 + delta ** 2)
    wn = 2 * math.pi / (T * math.sqrt(1 - zeta ** 2))          # ω_d = ω_n sqrt(1 - ζ²) = 2π / T
    assert float(damping_ratio(delta)) == pytest.approx(zeta, rel=1e-14)
    assert float(natural_frequency(T, delta)) == pytest.approx(wn, rel=1e-12)
    assert float(stiffness(m, T, delta)) == pytest.approx(m * wn ** 2, rel=1e-12)


def test_constrained_regression_eq16_by_brute_force():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 2, 6))
    y = 2.0 - 1.7 * (t - t[0]) + rng.normal(0, 0.05, t.size)
    d, r2 = decay_rate_through_first_peak(t, y)
    # Independent reference: minimise the residual over a fine grid of slopes through (t1, y1).
    slopes = np.linspace(-3, 0, 300001)
    sse = ((y[None, 1:] - y[0] - slopes[:, None] * (t[None, 1:] - t[0])) ** 2).sum(axis=1)
    assert d == pytest.approx(slopes[np.argmin(sse)], abs=2e-5)
    fit = y[0] + d * (t - t[0])
    assert r2 == pytest.approx(1 - ((y - fit) ** 2).sum() / ((y - y.mean()) ** 2).sum(), rel=1e-12)
    assert decay_rate_through_first_peak(t, y[0] - 1.3 * (t - t[0]))[0] == pytest.approx(-1.3, rel=1e-12)


MODES = {"FL": (21.65, 0.08), "FR": (20.3, 0.15), "RL": (16.0, 0.05), "RR": (17.5, 0.03)}


@pytest.mark.parametrize("fs", [500.0, 1000.0, 2000.0])
@pytest.mark.parametrize("noise", [0.0, 0.02, 0.05])
@pytest.mark.parametrize("second_axle", [False, True])
def test_damped_sinusoids_k_within_1_percent(fs, noise, second_axle):
    rec = analytic_recording(fs=fs, noise=noise, modes=MODES, second_axle_impulse=second_axle, seed=int(fs))
    results = identify(rec)
    for tire, (wn, zeta) in MODES.items():
        r = results[tire]
        assert r.k == pytest.approx(true_k(tire, MODES[tire]), rel=0.01), tire
        assert r.n_peaks >= 3
        c_true = 2 * r.mass * zeta * wn
        assert r.c == pytest.approx(c_true, rel=0.05 if noise else 1e-3), tire
        if noise == 0:
            assert abs(r.zeta - zeta) <= 0.005, tire
            assert r.r2 > 0.9999


def test_second_axle_window_excludes_the_rear_impact():
    """Without the other-axle window the rear impulse would be taken as front peaks."""
    modes = {"FL": (21.65, 0.02)}  # light damping: the front still rings when the rear arrives
    rec = analytic_recording(modes=modes, tires=("FL",), second_axle_impulse=True)
    r = identify(rec)["FL"]
    t_rear = 0.5 + 2.77 / (7 / 3.6)
    from identification.recording.preprocess import preprocess
    peaks = preprocess(rec)["FL"].peak_times_s
    assert peaks.max() < t_rear
    assert r.k == pytest.approx(true_k("FL", modes["FL"]), rel=1e-3)
    assert r.c == pytest.approx(2 * r.mass * 0.02 * 21.65, rel=2e-3)


def test_rear_analysis_starts_at_its_own_impact():
    rec = analytic_recording()
    from identification.recording.preprocess import preprocess
    sig = preprocess(rec)
    t_rear = 0.5 + 2.77 / (7 / 3.6)
    for tire in ("RL", "RR"):
        assert sig[tire].impact_s == pytest.approx(t_rear, abs=0.01)
        assert sig[tire].peak_times_s.min() > t_rear
    for tire in ("FL", "FR"):
        assert sig[tire].impact_s == pytest.approx(0.5, abs=0.01)
