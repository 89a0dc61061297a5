"""The stiffness exponent from a free decay's second harmonic, against decays of known laws integrated by
scipy's ODE solver (an independent reference: the elastic law F = W (δ/δ₀)ⁿ written out here)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from identification.identify.decay_exponent import MAX_AMPLITUDE_G, harmonic_exponent
from identification.identify.waveform import fit_free_decay

G = 9.80665


def _decay(n: float, *, k=600e3, mass=1200.0, zeta=0.08, start_g=0.6, rate_hz=1000.0, duration_s=1.2,
           noise=0.02, seed=0, damping_growth=0.0):
    """Hub acceleration (up positive) of a corner released from rest, deflected beyond its static point so
    that the first swing reaches about `start_g` g; a damper c (1 + damping_growth x/δ₀) where asked."""
    W = mass * G
    d0 = n * W / k
    c = 2 * zeta * math.sqrt(k * mass)

    def rhs(_, s):
        d, v = s
        force = W * math.copysign(abs(d / d0) ** n, d) + c * (1 + damping_growth * (d - d0) / d0) * v
        return [v, (W - force) / mass]

    x0 = start_g * G / (k / mass)
    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    sol = solve_ivp(rhs, (0.0, duration_s), [d0 + x0, 0.0], t_eval=t, rtol=1e-10, atol=1e-13, method="DOP853")
    d, v = sol.y
    force = W * np.sign(d) * np.abs(d / d0) ** n + c * (1 + damping_growth * (d - d0) / d0) * v
    accel = -(W - force) / mass                       # the hub goes up when the tire compresses
    rng = np.random.default_rng(seed)
    return t, accel + 0.3 + noise * rng.standard_normal(t.size)


def _exponent(t, a):
    p, *_ = fit_free_decay(t, a, sigma0=0.08 * 22.0, omega_d0=22.0)
    return harmonic_exponent(t, a, decay_rate_1_s=float(p[0]), omega_d_rad_s=abs(float(p[1])))


@pytest.mark.parametrize("n", [0.85, 1.0, 1.25, 1.5])
def test_the_second_harmonic_gives_the_law_s_exponent(n):
    t, a = _decay(n)
    est = _exponent(t, a)
    assert est is not None
    assert est.n == pytest.approx(n, abs=0.04), est
    assert est.n_ci[0] <= n <= est.n_ci[1], est
    assert est.n_ci[1] - est.n_ci[0] < 0.25, est
    if n == 1.0:
        assert est.n_ci[0] < 1.0 < est.n_ci[1]
    else:
        assert not est.n_ci[0] <= 1.0 <= est.n_ci[1], est


@pytest.mark.parametrize("seed", range(4))
def test_the_phase_at_which_the_window_starts_does_not_matter(seed):
    t, a = _decay(1.3, seed=seed)
    skip = int(np.random.default_rng(seed).integers(0, 40))   # the window starts anywhere in a period
    est = _exponent(t[skip:], a[skip:])
    assert est.n == pytest.approx(1.3, abs=0.05), (skip, est)


def test_a_damper_that_grows_with_the_deflection_is_left_in_quadrature():
    t, a = _decay(1.0, damping_growth=1.0)
    est = _exponent(t, a)
    assert est.n_ci[0] <= 1.0 <= est.n_ci[1], est
    assert abs(est.quadrature) > 3 * est.u_half, est


def test_a_swing_beyond_the_limit_is_fitted_from_where_it_has_fallen_below_it():
    t, a = _decay(1.25, start_g=1.1, zeta=0.1)
    est = _exponent(t, a)
    assert est.window_s[0] > t[0] + 0.05
    assert est.amplitude_m_s2 <= MAX_AMPLITUDE_G * G * 1.05
    assert est.n == pytest.approx(1.25, abs=0.05), est


def test_too_short_a_window_gives_none_and_bad_arguments_say_which():
    t, a = _decay(1.0)
    assert harmonic_exponent(t[:200], a[:200], decay_rate_1_s=1.7, omega_d_rad_s=22.0) is None   # < 1.5 periods
    with pytest.raises(ValueError, match="decay_rate_1_s"):
        harmonic_exponent(t, a, decay_rate_1_s=-1.0, omega_d_rad_s=22.0)
    with pytest.raises(ValueError, match="1-D"):
        harmonic_exponent(t, a[:-1], decay_rate_1_s=1.0, omega_d_rad_s=22.0)
