"""Whole-body vibration after ISO 2631-1:1997: frequency weightings, a_w, VDV, MTVV, daily exposure.

The frequency weightings Wk (vertical), Wd (horizontal), Wf (motion sickness) and the additional Wc
(seat-back fore-aft), We (rotational), Wj (vertical, under a recumbent person's head) are the analog
filters of the standard's Annex A, with the parameters of its Table A.1 (:data:`WEIGHTINGS`; tabulated
in ISO 8041 too).  :func:`weight` applies one to a sampled acceleration; :func:`comfort` evaluates a
record by the basic method (weighted RMS a_w) and the additional methods (running RMS with MTVV,
fourth-power vibration dose value VDV), and for Wk and Wd compares the daily exposure with the
whole-body values of EU directive 2002/44/EC.

Units are SI throughout: acceleration m/s², time s, frequency Hz, VDV m/s^1.75, MSDV m/s^1.5.  The
weightings are dimensionless gains: We weights rotational accelerations, rad/s² in and out (VDV in
rad/s^1.75); ISO 2631-1 clause 8.2.3 rates rotation for comfort only, each axis times its factor (0.63
m/rad roll, 0.4 pitch, 0.2 yaw).  Bad input raises :class:`~identification.errors.InputError` naming it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ._checks import positive

__all__ = ["Weighting", "WEIGHTINGS", "get_weighting", "weighting_response", "weight", "running_rms", "mtvv",
           "vdv", "crest_factor", "daily_exposure", "vdv_exposure", "Exposure", "ComfortResult", "comfort",
           "EU_A8_ACTION_M_S2", "EU_A8_LIMIT_M_S2", "EU_VDV_ACTION", "EU_VDV_LIMIT", "CREST_FACTOR_LIMIT",
           "MTVV_RATIO_LIMIT", "VDV_RATIO_LIMIT"]

#: EU directive 2002/44/EC, whole-body vibration: daily exposure A(8) action and limit values, m/s².
EU_A8_ACTION_M_S2 = 0.5
EU_A8_LIMIT_M_S2 = 1.15
#: The same for the daily vibration dose value, m/s^1.75.
EU_VDV_ACTION = 9.1
EU_VDV_LIMIT = 21.0
#: The largest acceleration a record may hold, m/s² (1e5 g: beyond any vibration a seat or floor sees; far
#: beyond it the ratings' fourth powers overflow).
MAX_ACCELERATION_M_S2 = 1e6

#: ISO 2631-1 clauses 6.2.1 and 6.3.3: above a crest factor of 9, or MTVV / a_w above 1.5, or
#: VDV / (a_w T^¼) above 1.75, the basic (weighted RMS) method may underestimate the effect of shocks.
CREST_FACTOR_LIMIT = 9.0
MTVV_RATIO_LIMIT = 1.5
VDV_RATIO_LIMIT = 1.75

_BUTTERWORTH_Q = 1.0 / math.sqrt(2.0)
_SETTLE = math.log(1e6)        # impulse-response decay (to 1e-6) before the FFT block wraps around
_INF = math.inf


@dataclass(frozen=True)
class Weighting:
    """Parameters of one frequency weighting (ISO 2631-1:1997 Table A.1).

    With ω_i = 2π f_i and s the Laplace variable, the weighting is the product of

    * band-limiting high-pass  H_h = s² / (s² + ω1 s / Q1 + ω1²)  and low-pass
      H_l = ω2² / (s² + ω2 s / Q2 + ω2²), Q1 = Q2 = 1/√2 (2nd-order Butterworth);
    * acceleration-velocity transition  H_t = (1 + s/ω3) / (1 + s/(Q4 ω4) + s²/ω4²)
      (numerator 1 when f3 is infinite);
    * upward step  H_s = (1 + s/(Q5 ω5) + s²/ω5²) / (1 + s/(Q6 ω6) + s²/ω6²) · (ω5/ω6)²
      (absent when f5 and f6 are infinite): gain (f5/f6)² below f5, 1 above f6.

    Attributes
    ----------
    f1_hz, f2_hz, f3_hz, f4_hz, q4, f5_hz, q5, f6_hz, q6 : float
        The parameters above (Hz); ``math.inf`` where the table has ∞.
    band_hz : tuple of float
        The frequency range the standard evaluates with this weighting (ISO 2631-1 clause 1), Hz.
        A record must be sampled at twice its upper end at least.
    k : float
        Multiplying factor of the evaluation (seated health: 1.0 vertical, 1.4 horizontal; 0.8 for
        the seat-back's Wc; 1.0 where the factor depends on the axis, as We's, ISO 2631-1 clause 8.2.3).
    exposure_limits : bool
        Whether the daily-exposure values of 2002/44/EC apply (health weightings Wk and Wd).
    unit : str
        Unit of the weighted quantity: ``"m/s²"``, or ``"rad/s²"`` for the rotational We.
    """

    name: str
    description: str
    f1_hz: float
    f2_hz: float
    f3_hz: float
    f4_hz: float
    q4: float
    f5_hz: float
    q5: float
    f6_hz: float
    q6: float
    band_hz: tuple[float, float]
    k: float
    exposure_limits: bool
    unit: str = "m/s²"

    def slowest_decay_rate(self) -> float:
        """Smallest |Re p| over the weighting's poles p, 1/s (sets how long its impulse response lasts)."""
        pairs = [(self.f1_hz, _BUTTERWORTH_Q), (self.f2_hz, _BUTTERWORTH_Q), (self.f4_hz, self.q4),
                 (self.f6_hz, self.q6)]
        return min(2.0 * math.pi * f * (z - math.sqrt(max(z * z - 1.0, 0.0)))
                   for f, q in pairs if math.isfinite(f) for z in [0.5 / q])


#: The weightings of ISO 2631-1:1997 Table A.1, by name: the principal Wk, Wd, Wf and the additional Wc,
#: We, Wj (Table 2: Wc seat-back x; We rotational rx, ry, rz in rad/s²; Wj vertical under a recumbent
#: person's head): Wc, We as Wd with f3 = f4 = 8 Hz, 1 Hz; Wj no a-v transition, a step 3.75 -> 5.32 Hz.
WEIGHTINGS: dict[str, Weighting] = {
    "Wk": Weighting("Wk", "vertical (z), seated or standing", 0.4, 100.0, 12.5, 12.5, 0.63,
                    2.37, 0.91, 3.35, 0.91, band_hz=(0.5, 80.0), k=1.0, exposure_limits=True),
    "Wd": Weighting("Wd", "horizontal (x, y), seated or standing", 0.4, 100.0, 2.0, 2.0, 0.63,
                    _INF, 1.0, _INF, 1.0, band_hz=(0.5, 80.0), k=1.4, exposure_limits=True),
    "Wf": Weighting("Wf", "vertical (z), motion sickness", 0.08, 0.63, _INF, 0.25, 0.86,
                    0.0625, 0.80, 0.10, 0.80, band_hz=(0.1, 0.5), k=1.0, exposure_limits=False),
    "Wc": Weighting("Wc", "horizontal (x), seat-back", 0.4, 100.0, 8.0, 8.0, 0.63,
                    _INF, 1.0, _INF, 1.0, band_hz=(0.5, 80.0), k=0.8, exposure_limits=False),
    "We": Weighting("We", "rotational (rx, ry, rz), seated; rad/s²", 0.4, 100.0, 1.0, 1.0, 0.63,
                    _INF, 1.0, _INF, 1.0, band_hz=(0.5, 80.0), k=1.0, exposure_limits=False, unit="rad/s²"),
    "Wj": Weighting("Wj", "vertical (x), under the head, recumbent", 0.4, 100.0, _INF, _INF, 1.0,
                    3.75, 0.91, 5.32, 0.91, band_hz=(0.5, 80.0), k=1.0, exposure_limits=False),
}


def get_weighting(weighting: str | Weighting) -> Weighting:
    """The :class:`Weighting` named `weighting` (a key of :data:`WEIGHTINGS`, any case), or `weighting` itself."""
    if isinstance(weighting, Weighting):
        return weighting
    for name, w in WEIGHTINGS.items():
        if isinstance(weighting, str) and weighting.lower() == name.lower():
            return w
    raise InputError("weighting", f"unknown weighting {weighting!r} (allowed: {', '.join(WEIGHTINGS)})")


def weighting_response(frequency_hz, weighting: str | Weighting = "Wk") -> np.ndarray:
    """Complex frequency response H(j 2π f) of a weighting (its magnitude: ``np.abs`` of the result).

    Parameters
    ----------
    frequency_hz : array_like
        Frequencies, Hz (finite, >= 0).
    weighting : {"Wk", "Wd", "Wf", "Wc", "We", "Wj"} or Weighting
        The weighting (ISO 2631-1:1997 Annex A).

    Returns
    -------
    ndarray of complex
        The response, shaped as `frequency_hz` (0 at 0 Hz).
    """
    w = get_weighting(weighting)
    f = np.asarray(frequency_hz, dtype=float)
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        raise InputError("frequency_hz", "frequencies must be finite and >= 0")
    s = 2j * np.pi * f
    w1, w2, w4 = (2.0 * np.pi * x for x in (w.f1_hz, w.f2_hz, w.f4_hz))
    q = _BUTTERWORTH_Q
    h = s * s / (s * s + s * w1 / q + w1 * w1) * (w2 * w2) / (s * s + s * w2 / q + w2 * w2)
    if math.isfinite(w.f4_hz):                  # Wj has no acceleration-velocity transition
        h = h * (1.0 + s / (2.0 * np.pi * w.f3_hz)) / (1.0 + s / (w.q4 * w4) + (s / w4) ** 2)
    if math.isfinite(w.f5_hz):
        w5, w6 = 2.0 * np.pi * w.f5_hz, 2.0 * np.pi * w.f6_hz
        h = h * (1.0 + s / (w.q5 * w5) + (s / w5) ** 2) / (1.0 + s / (w.q6 * w6) + (s / w6) ** 2) * (w5 / w6) ** 2
    return h


def _positive(name: str, value) -> float:
    return positive(name, value)


def _rate(sample_rate_hz, w: Weighting | None = None) -> float:
    fs = _positive("sample_rate_hz", sample_rate_hz)
    if w is not None and fs < 2.0 * w.band_hz[1]:
        raise InputError("sample_rate_hz", f"sampling rate {fs:g} Hz is too low for {w.name}: at least "
                                           f"{2.0 * w.band_hz[1]:g} Hz needed (twice the {w.band_hz[1]:g} Hz upper "
                                           f"end of its frequency range)")
    return fs


def _signal(x, name: str, one_d: bool = True) -> np.ndarray:
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, "must be an array of numbers") from None
    if (one_d and a.ndim != 1) or a.ndim == 0 or a.shape[-1] < 2:
        raise InputError(name, f"must be a {'1-D ' if one_d else ''}array of at least 2 samples, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(name, f"holds non-finite values (first at index {int(np.argmin(np.isfinite(a.ravel())))})")
    return a


def weight(acc_m_s2, sample_rate_hz: float, weighting: str | Weighting = "Wk") -> np.ndarray:
    """The frequency-weighted acceleration a_w(t).

    The analog response (:func:`weighting_response`) is applied in the frequency domain: the
    record, less its mean, is zero-padded (to a power of 2) until the weighting's impulse response
    has decayed to 1e-6 (no wrap-around), transformed by FFT, multiplied by H(j 2π f) at every bin
    and transformed back.  Magnitude and phase are then those of the analog definition at every
    frequency up to Nyquist (a bilinear-transform IIR filter compresses the response near Nyquist,
    with an error growing with f / fs, exact only at its pre-warping frequency).  The output is
    that of the filter started at rest at the first sample, as an instrument would be; removing
    the mean changes only that start-up transient, the weighting's gain at 0 Hz being zero.

    Parameters
    ----------
    acc_m_s2 : array_like
        Acceleration, m/s², uniformly sampled along the last axis (at least 2 samples, finite).
    sample_rate_hz : float
        Sampling rate, Hz; at least twice the upper end of the weighting's frequency
        range (``WEIGHTINGS[name].band_hz``: 160 Hz for Wk, Wd, Wc, We, Wj; 1 Hz for Wf).
    weighting : {"Wk", "Wd", "Wf", "Wc", "We", "Wj"} or Weighting

    Returns
    -------
    ndarray
        a_w(t), m/s² (rad/s² for We, whose input is a rotational acceleration), the shape of `acc_m_s2`.
    """
    w = get_weighting(weighting)
    fs = _rate(sample_rate_hz, w)
    x = _signal(acc_m_s2, "acc_m_s2", one_d=False)
    x = x - x.mean(axis=-1, keepdims=True)
    n = x.shape[-1]
    n_fft = 1 << (n + int(math.ceil(_SETTLE / w.slowest_decay_rate() * fs)) - 1).bit_length()
    h = weighting_response(np.fft.rfftfreq(n_fft, 1.0 / fs), w)
    h[-1] = abs(h[-1])                 # the Nyquist bin (n_fft is even) of a real signal is real
    return np.fft.irfft(np.fft.rfft(x, n_fft, axis=-1) * h, n_fft, axis=-1)[..., :n]


def running_rms(aw_m_s2, sample_rate_hz: float, tau_s: float = 1.0) -> np.ndarray:
    """Running RMS with linear integration (ISO 2631-1 clause 6.3.1): a_w(t0) = [1/τ ∫_{t0-τ}^{t0} a_w²(t) dt]^½.

    `aw_m_s2` is the weighted acceleration (m/s², 1-D); the integration time `tau_s` (s; the
    standard recommends 1 s) spans m = round(τ fs) samples.  Returns one value per complete
    window: element i covers samples i .. i + m - 1.
    """
    fs = _rate(sample_rate_hz)
    a = _signal(aw_m_s2, "aw_m_s2")
    m = max(int(round(_positive("tau_s", tau_s) * fs)), 1)
    if m > a.size:
        raise InputError("aw_m_s2", f"record of {a.size / fs:g} s is shorter than the running-RMS "
                                    f"integration time {tau_s:g} s")
    c = np.concatenate(([0.0], np.cumsum(a * a)))
    return np.sqrt(np.maximum(c[m:] - c[:-m], 0.0) / m)


def mtvv(aw_m_s2, sample_rate_hz: float, tau_s: float = 1.0) -> float:
    """Maximum transient vibration value: the largest :func:`running_rms`, m/s²."""
    return float(np.max(running_rms(aw_m_s2, sample_rate_hz, tau_s)))


def vdv(aw_m_s2, sample_rate_hz: float) -> float:
    """Fourth-power vibration dose value (∫ a_w⁴ dt)^¼ over the record (ISO 2631-1 clause 6.3.2), m/s^1.75."""
    fs = _rate(sample_rate_hz)
    a = _signal(aw_m_s2, "aw_m_s2")
    return float(np.sum(a ** 4) / fs) ** 0.25


def crest_factor(aw_m_s2) -> float:
    """Peak |a_w| over the RMS of a_w (ISO 2631-1 clause 6.2.1); NaN for a zero signal."""
    a = _signal(aw_m_s2, "aw_m_s2")
    rms = float(np.sqrt(np.mean(a * a)))
    return float(np.max(np.abs(a))) / rms if rms > 0 else math.nan


def daily_exposure(a_w_m_s2: float, exposure_h: float, k: float = 1.0) -> float:
    """Daily exposure A(8) = k a_w √(T / 8 h), m/s² (2002/44/EC Annex B), for a_w (m/s²) over the
    daily exposure time T = `exposure_h` (h); k is 1.0 vertical (Wk), 1.4 horizontal (Wd), seated."""
    return _positive("k", k) * float(a_w_m_s2) * math.sqrt(_positive("exposure_h", exposure_h) / 8.0)


def vdv_exposure(vdv_m_s175: float, measured_s: float, exposure_h: float, k: float = 1.0) -> float:
    """Daily vibration dose value k VDV (T / T_meas)^¼, m/s^1.75: the VDV of a record `measured_s` long
    extended to the daily exposure T = `exposure_h` (h); k as for :func:`daily_exposure`."""
    ratio = _positive("exposure_h", exposure_h) * 3600.0 / _positive("measured_s", measured_s)
    return _positive("k", k) * float(vdv_m_s175) * ratio ** 0.25


def _status(value: float, action: float, limit: float) -> str:
    return "above_limit" if value > limit else "above_action" if value > action else "below_action"


@dataclass(frozen=True)
class Exposure:
    """Daily exposure of a health weighting against EU directive 2002/44/EC.

    Attributes: `exposure_h` the daily exposure time (h), `k` the multiplying factor applied,
    `a8` A(8) (m/s²), `vdv` the daily VDV (m/s^1.75).
    """

    exposure_h: float
    k: float
    a8: float
    vdv: float

    @property
    def a8_status(self) -> str:
        """``below_action``, ``above_action`` (> 0.5 m/s²) or ``above_limit`` (> 1.15 m/s²)."""
        return _status(self.a8, EU_A8_ACTION_M_S2, EU_A8_LIMIT_M_S2)

    @property
    def vdv_status(self) -> str:
        """``below_action``, ``above_action`` (> 9.1 m/s^1.75) or ``above_limit`` (> 21 m/s^1.75)."""
        return _status(self.vdv, EU_VDV_ACTION, EU_VDV_LIMIT)

    def to_json(self) -> dict:
        """A JSON-ready dict (SI units)."""
        return {"exposure_h": self.exposure_h, "k": self.k, "a8": self.a8, "a8_status": self.a8_status,
                "vdv": self.vdv, "vdv_status": self.vdv_status}


def _finite_or_none(x: float | None):
    return None if x is None or not math.isfinite(x) else x


@dataclass(frozen=True)
class ComfortResult:
    """ISO 2631-1 evaluation of one acceleration record.

    Attributes: `weighting`, `sample_rate_hz`, `duration_s` (s); `a_w` the weighted RMS
    acceleration (m/s²); `vdv` the record's vibration dose value (m/s^1.75); `mtvv` the maximum of
    the running RMS (m/s²); `crest_factor` peak |a_w(t)| / a_w (NaN when a_w = 0); `msdv` the
    motion sickness dose value (∫ a_w² dt)^½ of the record (m/s^1.5; Wf only, else None);
    `exposure` the daily :class:`Exposure` (Wk and Wd, when an exposure time is given, else None).
    """

    weighting: str
    sample_rate_hz: float
    duration_s: float
    a_w: float
    vdv: float
    mtvv: float
    crest_factor: float
    msdv: float | None = None
    exposure: Exposure | None = None

    @property
    def mtvv_ratio(self) -> float:
        """MTVV / a_w (above 1.5 the basic method may underestimate, ISO 2631-1 6.3.3)."""
        return self.mtvv / self.a_w if self.a_w > 0 else math.nan

    @property
    def vdv_ratio(self) -> float:
        """VDV / (a_w T^¼) (above 1.75 the basic method may underestimate)."""
        return self.vdv / (self.a_w * self.duration_s ** 0.25) if self.a_w > 0 else math.nan

    @property
    def rms_method_sufficient(self) -> bool:
        """Whether the weighted RMS suffices: crest factor <= 9 and both ratios within their limits."""
        return bool(self.crest_factor <= CREST_FACTOR_LIMIT and self.mtvv_ratio <= MTVV_RATIO_LIMIT
                    and self.vdv_ratio <= VDV_RATIO_LIMIT)

    def to_json(self) -> dict:
        """A JSON-ready dict (SI units; NaN as null)."""
        doc = {"weighting": self.weighting, "sample_rate_hz": self.sample_rate_hz, "duration_s": self.duration_s,
               "a_w": self.a_w, "vdv": self.vdv, "mtvv": self.mtvv,
               "crest_factor": _finite_or_none(self.crest_factor),
               "mtvv_ratio": _finite_or_none(self.mtvv_ratio), "vdv_ratio": _finite_or_none(self.vdv_ratio),
               "rms_method_sufficient": self.rms_method_sufficient}
        if self.msdv is not None:
            doc["msdv"] = self.msdv
        if self.exposure is not None:
            doc["exposure"] = self.exposure.to_json()
        return doc


def comfort(acc_m_s2, sample_rate_hz: float, weighting: str | Weighting = "Wk", *,
            exposure_h: float | None = None, k: float | None = None, tau_s: float = 1.0) -> ComfortResult:
    """Evaluate an acceleration record by ISO 2631-1 (and, with `exposure_h`, by 2002/44/EC).

    Parameters
    ----------
    acc_m_s2 : array_like
        Unweighted acceleration, m/s², 1-D, uniformly sampled, at least `tau_s` long.
    sample_rate_hz : float
        Sampling rate, Hz (see :func:`weight` for the lowest accepted).
    weighting : {"Wk", "Wd", "Wf", "Wc", "We", "Wj"} or Weighting
        Wk for vertical, Wd for horizontal vibration, Wf for motion sickness; Wc for the seat-back's
        fore-aft vibration, We for rotational vibration (input and results in rad/s²), Wj for the
        vertical vibration under a recumbent person's head.
    exposure_h : float, optional
        Daily exposure time, h (0 < T <= 24), for A(8) and the daily VDV (the record standing
        for the whole exposure).  Not for Wf.
    k : float, optional
        Multiplying factor for the exposure; default the weighting's (1.0 Wk, 1.4 Wd).
    tau_s : float
        Integration time of the running RMS (MTVV), s.

    Returns
    -------
    ComfortResult
    """
    w = get_weighting(weighting)
    fs = _rate(sample_rate_hz, w)
    acc = _signal(acc_m_s2, "acc_m_s2")
    if exposure_h is not None:
        if not w.exposure_limits:
            raise InputError("exposure_h", f"{w.name} ({w.description}) has no daily-exposure values; use Wk or Wd")
        if not 0 < _positive("exposure_h", exposure_h) <= 24.0:
            raise InputError("exposure_h", f"a daily exposure is at most 24 h, got {exposure_h!r}")
    if acc.size < round(_positive("tau_s", tau_s) * fs):
        raise InputError("acc_m_s2", f"record of {acc.size / fs:g} s is shorter than the running-RMS "
                                     f"integration time {tau_s:g} s")
    peak = float(np.max(np.abs(acc))) if acc.size else 0.0
    if peak > MAX_ACCELERATION_M_S2:        # its fourth power (VDV) would overflow: no vibration record in m/s²
        raise InputError("acc_m_s2", f"accelerations up to {peak:.3g} m/s^2 (more than "
                                     f"{MAX_ACCELERATION_M_S2:g} m/s^2): not a vibration record in m/s^2")
    aw = weight(acc, fs, w)
    duration = acc.size / fs
    a_w = float(np.sqrt(np.mean(aw * aw)))
    value = vdv(aw, fs)
    exposure = None
    if exposure_h is not None:                                  # the record stands for the whole exposure
        kk = w.k if k is None else _positive("k", k)
        exposure = Exposure(float(exposure_h), kk, daily_exposure(a_w, exposure_h, kk),
                            vdv_exposure(value, duration, exposure_h, kk))
    return ComfortResult(weighting=w.name, sample_rate_hz=fs, duration_s=duration, a_w=a_w, vdv=value,
                         mtvv=mtvv(aw, fs, tau_s), crest_factor=crest_factor(aw),
                         msdv=a_w * math.sqrt(duration) if w.name == "Wf" else None, exposure=exposure)
