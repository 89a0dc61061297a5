"""The cleat-test paper's identification of tire stiffness and damping.

Point-contact tire (spring k parallel to damper c) under the corner mass
m = W / g.  From the successive free-vibration peaks (t_i, a_i) of the hub
acceleration (:mod:`identification.recording.preprocess`):

* period T = t_2 - t_1 and logarithmic decrement δ = ln(a_1 / a_2) from the
  first two peaks;
* damping ratio ζ = δ / sqrt(4π² + δ²)                 (paper eq. 7);
* undamped natural frequency ω_n = sqrt(4π² + δ²) / T   (eq. 8);
* stiffness k = m ω_n² = m (4π² + δ²) / T²             (eq. 9);
* decay rate d̂ of y_i = ln a_i by least squares constrained through the first
  peak, d̂ = Σ (y_i - y_1)(t_i - t_1) / Σ (t_i - t_1)²  (eq. 16), over all
  valid peaks (at least 3), and c = -2 m d̂               (eq. 17);
* R² = 1 - Σ (y_i - ŷ_i)² / Σ (y_i - ȳ)² of that semi-log regression, over
  all peaks.

Units: k in N/m, c in N·s/m, T in s, ω_n in rad/s, m in kg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..recording.preprocess import DEFAULT_CUTOFF_HZ, TireSignal, preprocess
from ..recording import Recording

__all__ = [
    "PaperResult", "damping_ratio", "natural_frequency", "stiffness",
    "decay_rate_through_first_peak", "identify_paper", "identify",
]

_TWO_PI_SQ = 4 * math.pi ** 2


def damping_ratio(delta):
    """Damping ratio from the logarithmic decrement (paper eq. 7)."""
    delta = np.asarray(delta, dtype=float)
    return delta / np.sqrt(_TWO_PI_SQ + delta ** 2)


def natural_frequency(period_s, delta):
    """Undamped natural frequency, rad/s, from period (s) and log decrement (eq. 8)."""
    return np.sqrt(_TWO_PI_SQ + np.asarray(delta, dtype=float) ** 2) / np.asarray(period_s, dtype=float)


def stiffness(mass_kg, period_s, delta):
    """Stiffness k = m (4π² + δ²) / T², N/m (eq. 9)."""
    return np.asarray(mass_kg, dtype=float) * natural_frequency(period_s, delta) ** 2


def decay_rate_through_first_peak(times_s, log_peaks):
    """Least-squares slope of ln(peak) vs time through the first point (eq. 16).

    Parameters
    ----------
    times_s : array_like, shape (n,)
        Peak times, s (n ≥ 2).
    log_peaks : array_like, shape (n,)
        Natural logarithm of the peak values.

    Returns
    -------
    d : float
        Decay rate d̂ = -ζ ω_n, 1/s (negative for a decaying signal).
    r2 : float
        Coefficient of determination of the constrained regression over all n
        points (centred total sum of squares).
    """
    t = np.asarray(times_s, dtype=float)
    y = np.asarray(log_peaks, dtype=float)
    if t.size < 2 or t.size != y.size:
        raise ValueError("need at least two peaks, with one time per value")
    dt, dy = t[1:] - t[0], y[1:] - y[0]
    d = float(np.sum(dy * dt) / np.sum(dt * dt))
    fit = y[0] + d * (t - t[0])
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - fit) ** 2)) / ss_tot if ss_tot > 0 else 1.0
    return d, r2


#: Above this misfit of the one-mode free-decay fit (:attr:`PaperResult.decay_misfit`) a channel's k and c are
#: reported with a warning.  Tuned on the independent generator's seeds 100-139; measured on its acceptance
#: seeds 1-40 (``identify --json`` of every recording, 158 tires): of the tires whose k is off by > 3 % or c by
#: > 10 %, 84 of 97 (paper's method) and 84 of 98 (waveform) are warned; of those within both, 33 of 61 and
#: 33 of 60 are warned too (their decay is not one mode either; their k and c happen to be near the truth).
#: On the virtual rig: 1.0-1.2 on one-mode decays, 17-52 where a body, a progressive or lifting tire or
#: friction shapes the decay.
SINGLE_MODE_RATIO = 2.0


@dataclass(frozen=True)
class PaperResult:
    """The paper's Table-4 quantities for one tire (SI units).

    Attributes
    ----------
    tire : str
    k : float      stiffness, N/m
    c : float      damping coefficient (regression, eq. 17), N·s/m
    T : float      period from the first two peaks, s
    delta : float  logarithmic decrement, -
    zeta : float   damping ratio (eq. 7), -
    omega_n : float  undamped natural frequency (eq. 8), rad/s
    r2 : float     R² of the semi-log regression, -
    n_peaks : int  peaks used in the regression
    mass : float   corner mass W / g, kg
    decay_rate : float  fitted d̂ (eq. 16), 1/s
    window : dict or None
        For a long recording analysed on its impact window
        (:func:`identification.recording.window.focus`): ``{"analysed_s": [start, end],
        "record_s": [start, end]}``, s; None: the whole recording.
    decay_misfit : float or None
        How far the free decay is from one damped mode: the long-run variance ratio of the residual of
        the one-mode waveform fit (:func:`identification.identify.waveform.decay_misfit`; about 1 for one
        mode in white noise); None where that fit is not made.
    """

    tire: str
    k: float
    c: float
    T: float
    delta: float
    zeta: float
    omega_n: float
    r2: float
    n_peaks: int
    mass: float
    decay_rate: float
    window: dict | None = None
    decay_misfit: float | None = None

    def warning(self) -> str | None:
        """What the one-mode fit says against these values, or None (see :data:`SINGLE_MODE_RATIO`)."""
        if self.decay_misfit is None or not self.decay_misfit > SINGLE_MODE_RATIO:
            return None
        return (f"channel {self.tire}: the free decay is not one damped mode (the one-mode fit's residual "
                f"correlation is {self.decay_misfit:.0f}, about 1 for one mode): k and c may be biased beyond "
                f"their interval by a coupled body, a progressive or lifting tire or friction; "
                f"'cleatfmu diagnose' names the cause and fits it")

    def to_json(self) -> dict:
        """The ``identify --json`` entry of this tire (with the window analysed, for a long recording)."""
        doc = {"k": self.k, "c": self.c, "T": self.T, "delta": self.delta, "zeta": self.zeta,
               "omega_n": self.omega_n, "r2": self.r2, "n_peaks": self.n_peaks, "mass": self.mass}
        if self.window is not None:
            doc.update(self.window)
        if self.decay_misfit is not None:
            doc["decay_misfit"] = self.decay_misfit
            doc["warning"] = self.warning()
        return doc


def identify_paper(sig: TireSignal, mass_kg: float, *, source=None, window: dict | None = None) -> PaperResult:
    """Identify k and c from one preprocessed channel by the paper's method.

    Parameters
    ----------
    sig : TireSignal
        Output of :func:`identification.recording.preprocess.preprocess` (≥ 3 peaks).
    mass_kg : float
        Corner mass m = W / g, kg.
    source : str, optional
        Named in error messages.
    window : dict, optional
        The window of a long recording the signal comes from (:attr:`PaperResult.window`).
    """
    t, a = sig.peak_times_s, sig.peak_values_m_s2
    if t.size < 3:
        raise InputError(source, f"channel {sig.tire}: fewer than 3 free-vibration peaks above the noise (found "
                                 f"{t.size} between {sig.free_start_s:.3f} s and {sig.window_end_s:.3f} s)")
    period = float(t[1] - t[0])
    delta = float(math.log(a[0] / a[1]))
    if delta <= 0:
        raise InputError(source, f"channel {sig.tire}: the second peak ({a[1]:.3g} m/s^2) is not smaller than "
                                 f"the first ({a[0]:.3g} m/s^2); no decay to identify")
    d, r2 = decay_rate_through_first_peak(t, np.log(a))
    if d >= 0:
        raise InputError(source, f"channel {sig.tire}: the peaks do not decay (fitted rate {d:.3g} 1/s)")
    omega_n = float(natural_frequency(period, delta))
    return PaperResult(tire=sig.tire, k=mass_kg * omega_n ** 2, c=-2.0 * mass_kg * d, T=period, delta=delta,
                       zeta=float(damping_ratio(delta)), omega_n=omega_n, r2=r2, n_peaks=int(t.size),
                       mass=mass_kg, decay_rate=d, window=window)


def identify(rec: Recording, tires=None, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ) -> dict[str, PaperResult]:
    """Preprocess a recording and identify every requested tire (paper's method).

    A long recording is analysed on its impact window (:func:`identification.recording.window.focus`,
    which says so on stderr); the results then name the window.

    Returns
    -------
    dict of str to PaperResult, in the order of `tires` (default: file order).
    """
    from ..recording.window import focus, window_json

    rec = focus(rec, cutoff_hz=cutoff_hz, single_line=True)
    signals = preprocess(rec, tires, cutoff_hz=cutoff_hz)
    window = window_json(rec)
    return {name: identify_paper(sig, rec.mass_kg(name), source=rec.source, window=window)
            for name, sig in signals.items()}
