"""A tire's stiffness exponent from the second harmonic of its free decay.

A corner of mass m = W / g on a tire whose elastic force is F = W (δ / δ₀)ⁿ (δ₀ = n W / k the static
deflection, k the tangent stiffness there: the law of ``nonlinear_stiffness``) rings, for a deflection
x = δ - δ₀ of amplitude X, as

    x'' + ω² x + α x² + ... = 0,   ω² = k / m,   α = ω² (n - 1) / (2 δ₀).

To second order in X (Lindstedt; Landau & Lifshitz, *Mechanics*, §28) x = X cos θ - α X² / (2 ω²) +
α X² / (6 ω²) cos 2θ, so the hub's acceleration (up positive, -x'') is

    a(t) = A cos θ + B cos 2θ,   A = ω² X,   B / A = (n - 1) A / (3 ω² δ₀) = (n - 1) / n · A / (3 g),

since ω² δ₀ = n g.  The second harmonic is in phase with the square of the fundamental (it sharpens the
compression peaks of a progressive tire, n > 1, and blunts them for a degressive one), its size fixed by n
and the fundamental's amplitude in units of g alone: no k, no mass, no static deflection enters.  A linear
tire (n = 1) rings without it.  Damped, both decay together (the harmonic as the square of the fundamental's
envelope), and a damping force that depends on the deflection (a contact patch that grows with it) adds a
second harmonic in quadrature, which the in-phase part leaves out.

:func:`decay_exponent` fits, over the free decay's window with the waveform fit's decay rate σ and damped
frequency ω_d (:func:`~identification.identify.waveform.identify_waveform`), the linear model

    a(τ) = Re(c₁ e^{λτ} + c₂ e^{2λτ}) + C e^{-2στ} + D,   λ = -σ + i ω_d,

with c₁, c₂ complex.  With the damping the second harmonic is the response of the damped corner
P(s) = s² + 2σ s + ω_n² to the square of the decaying fundamental, so that exactly (to second order in the
amplitude) g c₂ / c₁² = u K, u = (n - 1) / n, K = ω_n⁴ / (λ² P(2λ)), real and 1/3 without damping: the
fit gives u from g c₂ / (c₁² K), n = 1 / (1 - u).  Without the factor K the damping would turn the harmonic
by about 10ζ/3 rad (15° at ζ = 0.08).  A damper that grows with the deflection, c (1 + γ x) (a contact patch
that lengthens), forces the harmonic through x x' and adds v λ (v real, λ = -σ + i ω_d): with it
g c₂ / (c₁² K) = u - v σ + i v ω_d, so u = Re + (σ / ω_d) Im of it, and v ω_d (the imaginary part, in the
units of u) is reported as the quadrature.
The 95 % interval of u comes from the linear fit's covariance, inflated by the residual's long-run variance
ratio (as the waveform fit's).  The window starts where the fundamental has fallen below
:data:`MAX_AMPLITUDE_G` g: at an amplitude near g a linear tire unloads (a unilateral contact clips the
extension peaks, a second harmonic of its own) and the expansion loses its accuracy.

Measured on the independent simulator's tuning seeds (bristle-bed tires whose law integrates to
F ∝ δ^(p + 1/2) on flat ground, and point-contact ones): of the 54 corner decays one mode explains
(R² >= 0.985), the interval held that exponent for 53; the 10 progressive decays gave 1.10-1.38 (truth
1.21-1.34), the 44 linear ones 0.84-1.11 (point-contact tires 0.99-1.02).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..recording import STANDARD_GRAVITY
from .waveform import long_run_variance_ratio

__all__ = ["DecayExponent", "decay_exponent", "harmonic_exponent", "MAX_AMPLITUDE_G", "MIN_PERIODS"]

#: The fit starts where the fundamental's amplitude has fallen below this many g.
MAX_AMPLITUDE_G = 0.8
#: ... and needs this many damped periods from there.
MIN_PERIODS = 1.5


@dataclass(frozen=True)
class DecayExponent:
    """The stiffness exponent a free decay's second harmonic gives.

    Attributes
    ----------
    n : float
        Exponent of the elastic law F = W (δ / δ₀)ⁿ (1: linear; inf where the harmonic is too large for any).
    n_ci : tuple of float
        Its 95 % interval.
    u, u_half : float
        (n - 1) / n and its 95 % half-width (the quantity the fit is linear in).
    quadrature : float
        The second harmonic's part in quadrature, in the units of u (a damper that depends on the deflection).
    amplitude_m_s2 : float
        The fundamental's amplitude at the window's start, m/s².
    window_s : tuple of float
        The fitted window, s.
    fundamental : complex
        c₁ = A₁ - i B₁, the fundamental at the window's start, m/s².
    """

    n: float
    n_ci: tuple
    u: float
    u_half: float
    quadrature: float
    amplitude_m_s2: float
    window_s: tuple
    fundamental: complex = 0j

    def to_json(self) -> dict:
        return {"n": _finite(self.n), "n_ci": [_finite(v) for v in self.n_ci], "quadrature": self.quadrature,
                "amplitude_m_s2": self.amplitude_m_s2, "window_s": list(self.window_s)}


def _finite(v: float):
    return v if math.isfinite(v) else None


def _n_of(u: float) -> float:
    return 1.0 / (1.0 - u) if u < 1.0 else math.inf


def harmonic_exponent(time_s, accel_m_s2, *, decay_rate_1_s: float, omega_d_rad_s: float,
                      gravity_m_s2: float = STANDARD_GRAVITY, fundamental: complex | None = None
                      ) -> DecayExponent | None:
    """The stiffness exponent of a free decay from its second harmonic (see the module's text).

    Parameters
    ----------
    time_s, accel_m_s2 : array_like
        The free decay's window (hub acceleration, up positive, offset allowed).
    decay_rate_1_s, omega_d_rad_s : float
        Its decay rate σ > 0 (1/s) and damped angular frequency ω_d > 0 (rad/s), e.g. the waveform fit's.
    gravity_m_s2 : float
        g, m/s².
    fundamental : complex, optional
        The fundamental c₁ to refer the second harmonic to (another signal's over the same window, e.g. the
        measured decay's where `accel_m_s2` is a model's residual); the window is then taken as given.

    Returns
    -------
    DecayExponent or None
        None where less than :data:`MIN_PERIODS` periods remain once the fundamental is below
        :data:`MAX_AMPLITUDE_G` g, or the fit is degenerate.
    """
    t = np.asarray(time_s, dtype=float)
    y = np.asarray(accel_m_s2, dtype=float)
    if t.shape != y.shape or t.ndim != 1:
        raise ValueError("time_s and accel_m_s2 must be 1-D arrays of one length")
    if not (decay_rate_1_s > 0 and omega_d_rad_s > 0):
        raise ValueError(f"decay_rate_1_s ({decay_rate_1_s}) and omega_d_rad_s ({omega_d_rad_s}) must be > 0")
    period = 2 * math.pi / omega_d_rad_s
    start = float(t[0]) if t.size else 0.0
    fit = None
    for attempt in range(2):   # from the window's start, then from where the fundamental is below the limit
        sel = t >= start
        if t[sel].size < 12 or t[sel][-1] - start < MIN_PERIODS * period:
            return None
        fit = _fit(t[sel], y[sel], decay_rate_1_s, omega_d_rad_s)
        if fit is None:
            return None
        limit = MAX_AMPLITUDE_G * gravity_m_s2
        if attempt or fundamental is not None or abs(fit[0]) <= limit:
            break
        start += math.log(abs(fit[0]) / limit) / decay_rate_1_s
    c1, c2, cov, n_obs = fit
    if fundamental is not None:
        c1 = complex(fundamental)
    lam = complex(-decay_rate_1_s, omega_d_rad_s)
    wn2 = omega_d_rad_s ** 2 + decay_rate_1_s ** 2
    w = gravity_m_s2 * (lam * lam) * ((2 * lam) ** 2 + 2 * decay_rate_1_s * (2 * lam) + wn2) / (wn2 * wn2 * c1 * c1)
    # w c2 = u + v λ: the elastic part u, and v of a damper growing with the deflection (its force ∝ x x');
    # u = Re(w c2) + (σ/ω_d) Im(w c2) = Re(w' c2), w' = w (1 - i σ/ω_d); quadrature: v ω_d = Im(w c2)
    quad = float((w * c2).imag)
    w = w * complex(1.0, -decay_rate_1_s / omega_d_rad_s)
    # u = Re(w c2) = A2 Re(w) + B2 Im(w), c2 = A2 - i B2
    grad = np.zeros(cov.shape[0])
    grad[2], grad[3] = w.real, w.imag
    q = float(stats.t.ppf(0.975, max(1, n_obs - cov.shape[0])))
    u, u_half = (w * c2).real, q * math.sqrt(max(0.0, float(grad @ cov @ grad)))
    return DecayExponent(n=_n_of(u), n_ci=(_n_of(u - u_half), _n_of(u + u_half)), u=float(u), u_half=float(u_half),
                         quadrature=quad, amplitude_m_s2=float(abs(c1)),
                         window_s=(float(t[t >= start][0]), float(t[-1])), fundamental=c1)


def _fit(t, y, sigma, wd):
    tau = t - t[0]
    e1, e2 = np.exp(-sigma * tau), np.exp(-2.0 * sigma * tau)
    X = np.column_stack([e1 * np.cos(wd * tau), e1 * np.sin(wd * tau), e2 * np.cos(2 * wd * tau),
                         e2 * np.sin(2 * wd * tau), e2, np.ones_like(tau)])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    res = y - X @ coef
    dof = y.size - X.shape[1]
    if dof < 1 or not np.all(np.isfinite(coef)):
        return None
    cov = np.linalg.pinv(X.T @ X) * float(res @ res) / dof * long_run_variance_ratio(res)
    c1, c2 = complex(coef[0], -coef[1]), complex(coef[2], -coef[3])
    if abs(c1) == 0.0:
        return None
    return c1, c2, cov, y.size


def decay_exponent(sig, wave, *, gravity_m_s2: float = STANDARD_GRAVITY) -> DecayExponent | None:
    """:func:`harmonic_exponent` over a waveform fit's window.

    Parameters
    ----------
    sig : TireSignal
        The preprocessed channel (its recorded acceleration is fitted).
    wave : WaveformResult
        Its waveform fit (window, decay rate, period).
    """
    t = sig.time_s
    sel = (t >= wave.window_s[0]) & (t <= wave.window_s[1])
    return harmonic_exponent(t[sel], sig.raw_m_s2[sel], decay_rate_1_s=-wave.decay_rate,
                             omega_d_rad_s=2 * math.pi / wave.T, gravity_m_s2=gravity_m_s2)
