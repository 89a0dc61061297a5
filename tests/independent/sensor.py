"""The acquisition chain of the independent simulator, run on the integrator's fine grid.

hub acceleration + engine vibration -> analog anti-alias filter (Butterworth or Bessel) -> analog AC
coupling (first-order high-pass) -> sampling (every m-th fine point) -> noise -> quantisation ->
offset and drift.  The analog filters are state-space models discretised exactly for a signal held
over each fine step (zero-order hold) on a grid at least ten times the output rate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

__all__ = ["Chain", "acquire"]


@dataclass(frozen=True)
class Chain:
    rate_hz: float
    aa_kind: str = "butter"          # butter | bessel | none
    aa_order: int = 4
    aa_cutoff_hz: float = 250.0
    highpass_hz: float = 0.0
    noise_m_s2: float = 0.05
    lsb_m_s2: float = 0.0
    offset_m_s2: float = 0.0
    drift_m_s2_per_s: float = 0.0
    engine_hz: float = 0.0
    engine_m_s2: float = 0.0
    engine_orders: int = 3


def _run_analog(b, a, x, dt):
    num, den, _ = signal.cont2discrete((b, a), dt, method="zoh")
    return signal.lfilter(np.ravel(num), den, x)


def acquire(t_fine: np.ndarray, accel_fine: np.ndarray, chain: Chain, rng: np.random.Generator,
            *, record_from_s: float, duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Recorded samples (time from 0, values) of one channel."""
    dt = float(t_fine[-1] - t_fine[0]) / (len(t_fine) - 1)
    m = int(round(1.0 / (chain.rate_hz * dt)))
    if m < 10 or abs(m * dt * chain.rate_hz - 1) > 1e-4:
        raise ValueError("the fine grid must be an integer multiple >= 10 of the output rate")
    x = np.array(accel_fine, dtype=float)
    if chain.engine_hz > 0:
        phases = rng.uniform(0, 2 * np.pi, chain.engine_orders)
        for order in range(1, chain.engine_orders + 1):
            x += chain.engine_m_s2 / order * np.sin(2 * np.pi * order * chain.engine_hz * t_fine + phases[order - 1])
    if chain.aa_kind != "none" and chain.aa_order > 0:
        wc = 2 * np.pi * chain.aa_cutoff_hz
        if chain.aa_kind == "butter":
            b, a = signal.butter(chain.aa_order, wc, analog=True)
        else:
            b, a = signal.bessel(chain.aa_order, wc, analog=True, norm="mag")
        x = _run_analog(b, a, x, dt)
    if chain.highpass_hz > 0:
        wh = 2 * np.pi * chain.highpass_hz
        x = _run_analog([1.0, 0.0], [1.0, wh], x, dt)
    i0 = int(round(record_from_s / dt))
    n = int(round(duration_s * chain.rate_hz))
    idx = i0 + m * np.arange(n)
    idx = idx[idx < len(x)]
    y = x[idx] + rng.normal(0.0, chain.noise_m_s2, len(idx))
    t = np.arange(len(idx)) / chain.rate_hz
    y = y + chain.offset_m_s2 + chain.drift_m_s2_per_s * t
    if chain.lsb_m_s2 > 0:
        y = np.round(y / chain.lsb_m_s2) * chain.lsb_m_s2
    return t, y
