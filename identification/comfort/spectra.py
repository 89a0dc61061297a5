"""One-third-octave band spectra of a (weighted) acceleration record, as vibration is usually read.

The bands are IEC 61260-1's base-10 one-third-octave bands: centre frequencies f_m = 10^(n/10) Hz
(nominal values 0.5, 0.63, 0.8, 1, 1.25, ... 80 Hz for ISO 2631-1's range), edges f_m 10^(±1/20).  A band's
RMS is the square root of the acceleration's power in the band, integrated over its exact edges from the
record's one-sided power spectral density (Welch's method with a Hann window, segments of at least 8 periods
of the lowest band's centre; the power of a bin that straddles an edge is split in proportion), so that the
bands' powers add up to the signal's power between the first and the last edge.  Levels are given in dB
re 10⁻⁶ m/s² (ISO 1683).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["ThirdOctave", "band_centres", "third_octave", "expected_bands", "REFERENCE_M_S2"]

#: Reference acceleration of the levels, m/s² (ISO 1683).
REFERENCE_M_S2 = 1e-6
_NOMINAL = (1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0)


def band_centres(low_hz: float, high_hz: float) -> tuple[np.ndarray, list[str]]:
    """Exact base-10 centres 10^(n/10) Hz of the one-third-octave bands from `low_hz` to `high_hz` (inclusive,
    within 1 %), and their nominal labels (0.5, 0.63, 0.8, 1, 1.25, ...)."""
    n = np.arange(math.ceil(10 * math.log10(low_hz) - 0.05), math.floor(10 * math.log10(high_hz) + 0.05) + 1)
    exact = 10.0 ** (n / 10.0)
    labels = []
    for k in n:
        decade, step = divmod(int(k), 10)
        value = _NOMINAL[step] * 10.0 ** decade
        labels.append(f"{value:.3g}")
    return exact, labels


@dataclass(frozen=True)
class ThirdOctave:
    """Band centres (exact, Hz), nominal labels, band RMS (m/s²) and levels (dB re 1e-6 m/s²)."""

    centre_hz: np.ndarray
    labels: list
    rms_m_s2: np.ndarray

    @property
    def level_db(self) -> np.ndarray:
        with np.errstate(divide="ignore"):
            return 20.0 * np.log10(self.rms_m_s2 / REFERENCE_M_S2)

    def to_json(self) -> dict:
        return {"centre_hz": self.centre_hz.tolist(), "nominal_hz": list(self.labels),
                "rms_m_s2": self.rms_m_s2.tolist(),
                "level_db_re_1e-6_m_s2": [None if not math.isfinite(v) else float(v) for v in self.level_db]}


def third_octave(acc_m_s2, sample_rate_hz: float, *, low_hz: float = 0.5, high_hz: float = 80.0) -> ThirdOctave:
    """The one-third-octave band RMS of `acc_m_s2` between the bands of `low_hz` and `high_hz`.

    Parameters
    ----------
    acc_m_s2 : array_like
        Acceleration (weighted or not), m/s², uniformly sampled.
    sample_rate_hz : float
        Sampling rate, Hz; the highest band's upper edge must lie below half of it.
    low_hz, high_hz : float
        Centres of the first and last band (default: ISO 2631-1's 0.5-80 Hz).

    Raises
    ------
    InputError
        A record too short for 8 periods of the lowest band, or a sampling rate too low for the highest.
    """
    from scipy.signal import welch

    x = np.asarray(acc_m_s2, dtype=float)
    fs = float(sample_rate_hz)
    centres, labels = band_centres(low_hz, high_hz)
    lower, upper = centres * 10.0 ** (-1 / 20), centres * 10.0 ** (1 / 20)
    if upper[-1] >= fs / 2:
        raise InputError("sample_rate_hz", f"{fs:g} Hz is too low for the {labels[-1]} Hz band (its upper edge "
                                           f"{upper[-1]:.4g} Hz must be below half the sampling rate)")
    nper = int(2 ** math.ceil(math.log2(8.0 * fs / centres[0])))
    if nper > x.size:
        raise InputError("acc_m_s2", f"a record of {x.size / fs:.3g} s is too short for the {labels[0]} Hz band "
                                     f"(8 of its periods: {nper / fs:.3g} s)")
    f, psd = welch(x - x.mean(), fs=fs, window="hann", nperseg=nper, noverlap=nper // 2, detrend=False,
                   scaling="density")
    df = f[1] - f[0]
    lo_bin, hi_bin = f - df / 2, f + df / 2
    power = np.empty(centres.size)
    for i, (a, b) in enumerate(zip(lower, upper)):
        overlap = np.clip(np.minimum(hi_bin, b) - np.maximum(lo_bin, a), 0.0, None)
        power[i] = float(np.sum(psd * overlap))
    return ThirdOctave(centres, labels, np.sqrt(power))


def expected_bands(spectra) -> ThirdOctave:
    """The expected band spectrum of several records of one process (rides on road realisations): each band's
    RMS is the root of the mean of the records' band mean squares (their bands must be the same)."""
    spectra = list(spectra)
    first = spectra[0]
    if any(s.centre_hz.shape != first.centre_hz.shape or not np.allclose(s.centre_hz, first.centre_hz)
           for s in spectra):
        raise ValueError("the spectra have different bands")
    return ThirdOctave(first.centre_hz, list(first.labels),
                       np.sqrt(np.mean([s.rms_m_s2 ** 2 for s in spectra], axis=0)))
