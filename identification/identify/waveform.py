"""Waveform identification: a least-squares damped-sinusoid fit of the free decay.

Beside the paper's two-peak method, cleatfmu fits the whole free vibration
after the tire has left the cleat (the window of
:mod:`identification.recording.preprocess`), sample by sample, on the recorded (not
low-passed) acceleration:

    a(t) = e^{-σ τ} (A cos ω_d τ + B sin ω_d τ) + D,   τ = t - t_free,

then ω_n² = ω_d² + σ², ζ = σ / ω_n, k = m ω_n² and c = 2 m σ.

95 % confidence intervals come from the Gauss-Newton covariance
s² (JᵀJ)⁻¹, inflated by the long-run variance ratio of the residuals
(Bartlett window), so that coloured residuals - filtered noise, unmodelled
dynamics - widen the intervals instead of being taken as independent
samples, and mapped to k and c by the delta method with Student's t quantile.

The window starts at the first free-vibration peak.  At a slow pass a large tire can still touch the
cleat there (its footprint reaches past the cleat's edges; the peak-picking assumes a point contact): where
one damped mode does not explain that window (R² < :data:`ONE_MODE_R2`) the fit starts at the next peak,
up to :data:`MAX_SKIPPED_PEAKS` of them, as long as the skipped ones lie before the latest time a tractor
tire can still touch the cleat (``TireSignal.cleat_clear_s``), and keeps the first window one mode
explains.  On the independent simulator's tuning seeds this took 12 of 64 corner tires from k errors of
2-13 % and R² 0.81-0.97 to k within 0.7 % and c within 1.3 % at R² >= 0.987 (``skipped_peaks``).

That covariance holds only if one damped mode is the whole story.  Where the window's start still holds
something else (the tire not yet clear of a footprint that envelopes the cleat, a larger amplitude
at which a real tire is a little stiffer or softer than the small-amplitude tire the estimate stands
for), the estimates move when the window starts later.  The fit is repeated from
:data:`WINDOW_SHIFT_PERIODS` of a period later, and each half-width grows by that move in quadrature
(``window_shift``): measured on recordings of an independent simulator (tuning seeds 100-139), the
intervals of the 90 free decays clean enough for the diagnosis' check (R² >= 0.985) held the true k for
46 % of the tires without the move and 56 % with it, the true c for 57 % and 74 % (what is left: a real
tire's equivalent linear k depends a little on the amplitude).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from ..errors import InputError
from .paper import PaperResult, identify_paper
from ..recording.preprocess import DEFAULT_CUTOFF_HZ, TireSignal, preprocess
from ..recording import Recording

__all__ = ["WaveformResult", "fit_free_decay", "identify_waveform", "long_run_variance_ratio", "decay_misfit",
           "with_floor", "DECAY_FLOOR", "AMPLITUDE_MOVE_FACTOR",
           "WINDOW_SHIFT_PERIODS", "ONE_MODE_R2", "MAX_SKIPPED_PEAKS", "decay_to_noise"]

#: The window-shift check starts the fit this many damped periods after the free decay's first peak.
WINDOW_SHIFT_PERIODS = 0.5
#: One damped mode explains a free decay to this R² (below it: a forced response, a progressive or coupled
#: hub); the diagnosis takes the free decay as a check only above it.
ONE_MODE_R2 = 0.985
#: :func:`decay_to_noise` takes the noise RMS of the raw channel before this margin ahead of the first impact, s.
NOISE_MARGIN_S = 0.05
#: Peaks the fit may skip while the tire can still touch the cleat.
MAX_SKIPPED_PEAKS = 2
#: Relative half-width added in quadrature to the 95 % intervals of k and c: how far a rolling tire's
#: free-decay equivalent stands from the standing tire's (a wheel released on flat ground, the definition of k
#: and c) beyond what the decay's noise explains.  Measured on the independent simulator's tuning seeds
#: (``benchmarks/free_decay_floor.py``: 67 clean corner decays, R² >= 0.985, linear tires without friction):
#: the decay's noise intervals held the truth's k for 60 % and c for 94 %, with 1 % added for 100 % and 96 %
#: (median k half-width 1.01 %; 0.5 % added: 79 %); the k error is the same in the decay's first and second
#: halves, no amplitude effect the data could correct.
DECAY_FLOOR = {"k": 0.01, "c": 0.01}
#: The halves' move (:attr:`WaveformResult.amplitude_move`) is this many times their difference beyond the
#: noise: the whole window's estimate lies near the first half's (the larger amplitude weighs more), the
#: small amplitude the standing tire's k and c stand for beyond the second half's.  On an analytic decay whose
#: frequency rises 2-4 % at its start the whole window's k stood 1.4 times the difference from the
#: small-amplitude k (``tests/test_waveform_window.py``).
AMPLITUDE_MOVE_FACTOR = 2.0


@dataclass(frozen=True)
class WaveformResult(PaperResult):
    """The paper's quantities from the waveform fit, plus 95 % intervals.

    Attributes (in addition to :class:`~identification.identify.paper.PaperResult`)
    ------------------------------------------------------------------------
    k_ci, c_ci : tuple of float
        95 % confidence intervals of k (N/m) and c (N·s/m).
    n_samples : int
        Samples in the fitted window.
    window_s : tuple of float
        Start and end of the fitted window, s.
    variance_inflation : float
        Long-run variance ratio applied to the covariance (1 for white residuals).
    window_shift : tuple of float
        How far k (N/m) and c (N·s/m) move when the fit starts :data:`WINDOW_SHIFT_PERIODS` of a period
        later; added to each half-width in quadrature.  NaN where the later window is too short to fit
        (then nothing is added, and the intervals hold only if the decay is one damped mode).
    skipped_peaks : int
        Free-vibration peaks skipped at the window's start (the tire could still touch the cleat there).
    amplitude_move : tuple of float
        :data:`AMPLITUDE_MOVE_FACTOR` times how far the window's two halves (the larger amplitude and the
        smaller) give k (N/m) and c (N·s/m) apart beyond their noise, √max(0, (x₂ − x₁)² − h₁² − h₂²), h
        their 95 % half-widths (0 where a half cannot be fitted): a tire whose stiffness or damping depends
        on the amplitude (progressive, rubbing), whose small-amplitude values lie beyond the second half.
        Added to each half-width in quadrature, with :data:`DECAY_FLOOR`.
    envelope_ratio : float
        The decay rate over the window's second half divided by that over its first (the same two refits;
        NaN where a half cannot be fitted).  About 1 for a viscous damper, whose decay rate does not depend on
        the amplitude; away from 1 where a friction force F acts: its equivalent damping 4 F / (π ω X) grows as
        the amplitude X falls, and the oscillation stops once the spring no longer overcomes F.
    """

    k_ci: tuple[float, float] = (math.nan, math.nan)
    c_ci: tuple[float, float] = (math.nan, math.nan)
    n_samples: int = 0
    window_s: tuple[float, float] = (math.nan, math.nan)
    variance_inflation: float = 1.0
    window_shift: tuple[float, float] = (math.nan, math.nan)
    skipped_peaks: int = 0
    amplitude_move: tuple[float, float] = (0.0, 0.0)
    envelope_ratio: float = math.nan

    def warning(self) -> str | None:
        """The one-mode fit's warning (:meth:`PaperResult.warning`), and where the fit skipped peaks, why."""
        base = super().warning()
        if not self.skipped_peaks:
            return base
        note = (f"the waveform fit starts at the free vibration's peak {self.skipped_peaks + 1}: from the first, "
                f"where the tire can still touch the cleat at this speed, one damped mode does not explain it")
        return f"channel {self.tire}: {note}" if base is None else f"{base}; {note}"

    def to_json(self) -> dict:
        doc = super().to_json()
        doc["k_ci"] = [float(v) for v in self.k_ci]
        doc["c_ci"] = [float(v) for v in self.c_ci]
        doc["window_shift"] = {q: (float(v) if math.isfinite(v) else None) for q, v in zip("kc", self.window_shift)}
        doc["skipped_peaks"] = int(self.skipped_peaks)
        doc["amplitude_move"] = {q: float(v) for q, v in zip("kc", self.amplitude_move)}
        doc["floor"] = {q: float(DECAY_FLOOR[q]) for q in "kc"}
        return doc


def long_run_variance_ratio(residual, max_lag: int | None = None) -> float:
    """Σ ρ_k weighted by a Bartlett window: the variance factor of a mean of correlated samples.

    Returns 1 for white residuals and grows with their correlation length.
    """
    r = np.asarray(residual, dtype=float)
    r = r - r.mean()
    n = r.size
    max_lag = max_lag or int(min(n - 1, max(10, 4 * n ** (1 / 3))))
    spec = np.fft.rfft(r, 2 * n)
    acov = np.fft.irfft(spec * np.conj(spec))[: max_lag + 1] / n
    if acov[0] <= 0:
        return 1.0
    rho = acov / acov[0]
    weights = 1 - np.arange(1, max_lag + 1) / (max_lag + 1)
    return float(max(1.0, 1 + 2 * np.sum(weights * rho[1:])))


def _model(p, tau):
    sigma, wd, A, B, D = p
    e = np.exp(-sigma * tau)
    c, s = np.cos(wd * tau), np.sin(wd * tau)
    return e * (A * c + B * s) + D


def _jacobian(p, tau):
    sigma, wd, A, B, _ = p
    e = np.exp(-sigma * tau)
    c, s = np.cos(wd * tau), np.sin(wd * tau)
    osc = e * (A * c + B * s)
    return np.column_stack([-tau * osc, tau * e * (-A * s + B * c), e * c, e * s, np.ones_like(tau)])


def fit_free_decay(time_s, accel_m_s2, *, sigma0: float, omega_d0: float):
    """Least-squares fit of a damped sinusoid plus offset.

    Parameters
    ----------
    time_s, accel_m_s2 : ndarray
        The window to fit (τ is counted from its first sample).
    sigma0, omega_d0 : float
        Starting decay rate (1/s) and damped angular frequency (rad/s).

    Returns
    -------
    params : ndarray
        (σ 1/s, ω_d rad/s, A, B, D m/s²).
    cov : ndarray (5, 5)
        Covariance of the parameters, inflated for residual correlation.
    r2 : float
        Coefficient of determination of the fit.
    inflation : float
    """
    t = np.asarray(time_s, dtype=float)
    y = np.asarray(accel_m_s2, dtype=float)
    tau = t - t[0]
    basis = _jacobian(np.array([sigma0, omega_d0, 0.0, 0.0, 0.0]), tau)[:, 2:]
    lin, *_ = np.linalg.lstsq(basis * 1.0, y, rcond=None)
    p0 = np.array([sigma0, omega_d0, *lin])
    sol = optimize.least_squares(lambda p: _model(p, tau) - y, p0, jac=lambda p: _jacobian(p, tau),
                                 method="lm", x_scale="jac")
    resid = sol.fun
    n, npar = y.size, p0.size
    s2 = float(resid @ resid) / max(1, n - npar)
    J = sol.jac
    inflation = long_run_variance_ratio(resid)
    cov = np.linalg.pinv(J.T @ J) * s2 * inflation
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1 - float(resid @ resid) / ss_tot if ss_tot > 0 else 1.0
    return sol.x, cov, r2, inflation


def identify_waveform(sig: TireSignal, mass_kg: float, *, source=None, window: dict | None = None) -> WaveformResult:
    """Identify k and c of one tire from the waveform of its free decay.

    Parameters
    ----------
    sig : TireSignal
        A preprocessed channel (its free-vibration window and peaks seed the fit).
    mass_kg : float
        Corner mass m = W / g, kg.
    source : str, optional
        Named in error messages.
    window : dict, optional
        The window of a long recording the signal comes from (see :class:`PaperResult`).
    """
    t = sig.time_s
    if sig.peak_times_s.size == 0:
        raise InputError(source, f"channel {sig.tire}: no free-vibration peak to start a waveform fit from")
    sel = (t >= sig.peak_times_s[0]) & (t <= sig.window_end_s)
    if sel.sum() < 20:
        raise InputError(source, f"channel {sig.tire}: free-decay window too short for a waveform fit")
    sigma0, wd0 = _seeds(sig, mass_kg, source)
    try:
        params, cov, r2, inflation = fit_free_decay(t[sel], sig.raw_m_s2[sel], sigma0=sigma0, omega_d0=wd0)
    except np.linalg.LinAlgError:  # e.g. accelerations so large that the sums of squares overflow
        raise InputError(source, f"channel {sig.tire}: the waveform fit did not converge") from None
    skipped = 0
    if r2 < ONE_MODE_R2 and params[0] > 0:
        later = _after_the_cleat(sig, params)
        if later is not None:
            sel, (params, cov, r2, inflation), skipped = later
    sigma, wd = float(params[0]), abs(float(params[1]))
    if not (sigma > 0 and wd > 0 and np.all(np.isfinite(cov))):
        raise InputError(source, f"channel {sig.tire}: the waveform fit found no decaying oscillation "
                                 f"(decay rate {sigma:.3g} 1/s)")
    wn2 = wd * wd + sigma * sigma
    k, c, hk, hc = _k_c(params, cov, int(sel.sum()), mass_kg)
    if not all(math.isfinite(v) for v in (k, c, hk, hc, r2)):
        raise InputError(source, f"channel {sig.tire}: the waveform fit gave no finite stiffness and damping "
                                 f"(k {k:.3g} N/m, c {c:.3g} N*s/m)")
    period = 2 * math.pi / wd
    shift = _window_shift(t, sig.raw_m_s2, float(t[sel][0]) + WINDOW_SHIFT_PERIODS * period, sig.window_end_s,
                          params, mass_kg, k, c)
    if all(math.isfinite(v) for v in shift):
        hk, hc = math.hypot(hk, shift[0]), math.hypot(hc, shift[1])
    t_sel = t[sel]
    first, second = _halves(t, sig.raw_m_s2, (float(t_sel[0]), float(t_sel[-1])), params, mass_kg)
    moved = _amplitude_move(first, second)
    ratio = math.nan if first is None or second is None else float(second[1] / first[1])   # c = 2 m σ
    hk = math.hypot(hk, DECAY_FLOOR["k"] * k, moved[0])
    hc = math.hypot(hc, DECAY_FLOOR["c"] * c, moved[1])
    return WaveformResult(
        tire=sig.tire, k=k, c=c, T=period, delta=sigma * period, zeta=sigma / math.sqrt(wn2),
        omega_n=math.sqrt(wn2), r2=r2, n_peaks=int(sig.peak_times_s.size), mass=mass_kg, decay_rate=-sigma,
        k_ci=(k - hk, k + hk), c_ci=(c - hc, c + hc), n_samples=int(sel.sum()),
        window_s=(float(t[sel][0]), float(t[sel][-1])), variance_inflation=inflation, window=window,
        decay_misfit=inflation, window_shift=shift, skipped_peaks=skipped, amplitude_move=moved,
        envelope_ratio=ratio)


def noise_before(time_s, accel_m_s2, first_impact_s: float) -> float:
    """RMS about its mean of the raw channel `accel_m_s2` before `first_impact_s` less :data:`NOISE_MARGIN_S`
    (the noise, where nothing has been hit yet); NaN where that stretch is shorter than 20 samples."""
    quiet = np.asarray(accel_m_s2)[np.asarray(time_s) < first_impact_s - NOISE_MARGIN_S]
    return float(np.std(quiet)) if quiet.size >= 20 else math.nan


def decay_to_noise(sig, wave, quiet_until_s: float) -> tuple[float, float]:
    """The waveform fit's residual RMS and the RMS of what it explains (the decay), each over the noise RMS of
    the raw channel it fits before `quiet_until_s` less :data:`NOISE_MARGIN_S` (the recording's first impact:
    on a coupled tractor a later channel moves with the first impact before its own; NaN where that stretch
    is shorter than 20 samples)."""
    t = sig.time_s
    noise = noise_before(t, sig.raw_m_s2, quiet_until_s)
    window = sig.raw_m_s2[(t >= wave.window_s[0]) & (t <= wave.window_s[1])]
    spread = float(np.var(window)) if window.size else math.nan
    if not noise > 0:
        return math.nan, math.nan
    return math.sqrt(max(0.0, 1.0 - wave.r2) * spread) / noise, math.sqrt(max(0.0, wave.r2) * spread) / noise


def _k_c(params, cov, n: int, mass_kg: float) -> tuple[float, float, float, float]:
    """(k, c, 95 % half-width of k, of c) of a damped-sinusoid fit's `params` and covariance `cov` over `n`
    samples (the delta method, Student's t quantile)."""
    sigma, wd = float(params[0]), abs(float(params[1]))
    k, c = mass_kg * (wd * wd + sigma * sigma), 2 * mass_kg * sigma
    grad_k = np.array([2 * mass_kg * sigma, 2 * mass_kg * wd])
    grad_c = np.array([2 * mass_kg, 0.0])
    sub = cov[:2, :2]
    q = float(stats.t.ppf(0.975, max(1, n - len(params))))
    hk = q * math.sqrt(max(0.0, float(grad_k @ sub @ grad_k)))
    hc = q * math.sqrt(max(0.0, float(grad_c @ sub @ grad_c)))
    return k, c, hk, hc


def _refit_from(t, accel, start_s: float, end_s: float, params):
    """(selection, :func:`fit_free_decay`'s result) of the window [`start_s`, `end_s`] seeded with `params`, or
    None where it is too short or the fit fails or finds no decaying oscillation."""
    sel = (t >= start_s) & (t <= end_s)
    if sel.sum() < 20:
        return None
    try:
        fit = fit_free_decay(t[sel], accel[sel], sigma0=float(params[0]), omega_d0=abs(float(params[1])))
    except (np.linalg.LinAlgError, ValueError):
        return None
    sigma, wd = float(fit[0][0]), abs(float(fit[0][1]))
    if not (sigma > 0 and wd > 0 and math.isfinite(sigma) and math.isfinite(wd)):
        return None
    return sel, fit


def _after_the_cleat(sig: TireSignal, params):
    """The first window from a later peak that one damped mode explains (R² >= :data:`ONE_MODE_R2`), skipping
    only peaks before ``sig.cleat_clear_s``: (selection, fit, peaks skipped), or None."""
    peaks = sig.peak_times_s
    for j in range(1, min(MAX_SKIPPED_PEAKS, peaks.size - 1) + 1):
        if not peaks[j - 1] < sig.cleat_clear_s:      # NaN (not known): nothing skipped
            return None
        later = _refit_from(sig.time_s, sig.raw_m_s2, peaks[j], sig.window_end_s, params)
        if later is None:
            return None
        if later[1][2] >= ONE_MODE_R2:
            return later[0], later[1], j
    return None


def _window_shift(t, accel, start_s: float, end_s: float, params, mass_kg: float, k: float, c: float):
    """(Δk, Δc): the move of k and c when the fit starts at `start_s` (seeded with `params`); NaN where that
    window is too short or the fit finds no decaying oscillation there."""
    later = _refit_from(t, accel, start_s, end_s, params)
    if later is None:
        return math.nan, math.nan
    sigma, wd = float(later[1][0][0]), abs(float(later[1][0][1]))
    return mass_kg * (wd * wd + sigma * sigma) - k, 2 * mass_kg * sigma - c


def _halves(t, accel, window_s, params, mass_kg: float) -> list:
    """[(k, c, half-width of k, of c)] of the first and the second half of the window `window_s`, each refitted
    from the whole window's `params`; None for a half that cannot be fitted."""
    t0, t1 = window_s
    mid = 0.5 * (t0 + t1)
    out = []
    for a, b in ((t0, mid), (mid, t1)):
        fit = _refit_from(t, accel, a, b, params)
        out.append(None if fit is None else _k_c(fit[1][0], fit[1][1], int(fit[0].sum()), mass_kg))
    return out


def _amplitude_move(first, second) -> tuple[float, float]:
    """(Δk, Δc): how far the window's halves (:func:`_halves`) stand apart beyond their noise
    (:attr:`WaveformResult.amplitude_move`)."""
    if first is None or second is None:
        return 0.0, 0.0
    out = []
    for i in range(2):
        excess = (second[i] - first[i]) ** 2 - first[i + 2] ** 2 - second[i + 2] ** 2
        out.append(AMPLITUDE_MOVE_FACTOR * float(math.sqrt(excess)) if math.isfinite(excess) and excess > 0
                   else 0.0)
    return out[0], out[1]


def with_floor(value: float, ci, q: str) -> list:
    """The interval `ci` of a free decay's `value` of quantity `q` ('k' or 'c') with :data:`DECAY_FLOOR` of the
    value added in quadrature on each side (for a decay fitted otherwise than by :func:`identify_waveform`,
    whose intervals carry it already)."""
    floor = DECAY_FLOOR[q] * abs(value)
    return [float(value - math.hypot(value - ci[0], floor)), float(value + math.hypot(ci[1] - value, floor))]


def decay_misfit(sig: TireSignal, mass_kg: float) -> float | None:
    """How far a channel's free decay is from one damped mode: the long-run variance ratio of the residual of
    its one-mode waveform fit (:func:`fit_free_decay`), or None where that fit cannot be made."""
    try:
        return identify_waveform(sig, mass_kg).variance_inflation
    except (InputError, ValueError, FloatingPointError):
        return None


def _seeds(sig: TireSignal, mass_kg: float, source) -> tuple[float, float]:
    """Starting decay rate (1/s) and damped frequency (rad/s): the paper's values where its rules are met;
    else the spectral peak and the decrement of the first two peaks (or a damping ratio of 0.1)."""
    try:
        paper = identify_paper(sig, mass_kg, source=source)
        return -paper.decay_rate, 2 * math.pi / paper.T
    except InputError:
        wd0 = 2 * math.pi * sig.dominant_hz
        a, t = sig.peak_values_m_s2, sig.peak_times_s
        if a.size >= 2 and 0 < a[1] < a[0]:
            return math.log(a[0] / a[1]) / float(t[1] - t[0]), wd0
        return 0.1 * wd0, wd0


def identify_waveform_recording(rec: Recording, tires=None, *,
                                cutoff_hz: float = DEFAULT_CUTOFF_HZ) -> dict[str, WaveformResult]:
    """Preprocess a recording and fit every requested tire's free decay.

    A long recording is analysed on its impact window, as by :func:`identification.identify.paper.identify`.
    The fit needs one free-vibration peak above the noise, not the paper's three.
    """
    from ..recording.window import focus, window_json

    rec = focus(rec, cutoff_hz=cutoff_hz)
    signals = preprocess(rec, tires, cutoff_hz=cutoff_hz, min_peaks=1)
    window = window_json(rec)
    return {name: identify_waveform(sig, rec.mass_kg(name), source=rec.source, window=window)
            for name, sig in signals.items()}
