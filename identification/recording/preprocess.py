"""Preprocessing of cleat recordings, as in the cleat-test paper (section 2.3.3).

Stages, per tire channel:

1. **Low-pass**: 5th-order Butterworth, 100 Hz cut-off by default, applied
   forward and backward (``scipy.signal.sosfiltfilt``).  The filter is
   therefore *zero-phase*: peak times are not delayed, the magnitude response
   is the Butterworth response squared (-6 dB at the cut-off).
2. **Impact detection**: the front axle's impact is the onset of the first
   burst of a front channel; the rear axle reaches the cleat ``L / v`` later,
   and a rear channel's impact is searched only from there on, so that the
   front axle's impact, seen through the body, is never taken for it.
3. **Free-vibration peaks**: positive maxima of the filtered acceleration after
   the tire has left the cleat (impact + cleat width / speed, plus the filter's
   settling guard :func:`filter_guard_s`), starting with the largest one within
   1.5 periods of that time (the paper's "first peak"), then each following
   peak about one period (0.65–1.35 dominant periods) after the previous one,
   down to five times the noise RMS or 1 % of the impact.  For a front tire the analysis
   window ends where the rear axle arrives (impact + L / v), less the same
   guard, because the zero-phase filter spreads the rear impact backwards in
   time.  For a rear tire it ends with the record.

Everything is in SI units: time in s, acceleration in m/s², frequency in Hz.
"""

from __future__ import annotations

import functools

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .record import FRONT_TIRES, REAR_TIRES, STANDARD_GRAVITY, Recording

__all__ = [
    "DEFAULT_CUTOFF_HZ", "FILTER_ORDER", "TireSignal", "default_cutoff_hz",
    "lowpass", "lowpass_design", "MAX_TIRE_RADIUS_M", "cleat_clear_time_s", "filter_guard_s", "noise_rms",
    "broadband_noise", "check_clipping", "preprocess",
]

DEFAULT_CUTOFF_HZ = 100.0
FILTER_ORDER = 5
#: Without a cut-off given, at most this fraction of the sampling rate (a 200 Hz recording: 80 Hz).
_DEFAULT_CUTOFF_FRACTION = 0.4


def default_cutoff_hz(sample_rate_hz: float) -> float:
    """The commands' low-pass cut-off when none is given: 100 Hz, or 0.4 x the sampling rate when lower."""
    return min(DEFAULT_CUTOFF_HZ, _DEFAULT_CUTOFF_FRACTION * float(sample_rate_hz))
#: Rise threshold for impact detection, relative to the burst maximum.
_RISE_FRACTION = 0.3
#: The onset is where the signal first left this fraction of the burst maximum.
_ONSET_FRACTION = 0.05
#: An impact must stand this many noise RMS above the noise, or this many times the largest value of the
#: stretch before it (a steady vibration - an engine line, the lugs - raises the RMS, not the transient).
_MIN_SNR = 10.0
_MIN_STEADY_RATIO = 3.0
#: Peaks smaller than this many noise RMS (or 1 % of the impact) are not used.
_PEAK_SNR = 5.0
_PEAK_FRACTION = 0.01
#: Largest accepted hub acceleration, m/s² (about 100,000 g): a larger value is no hub acceleration in m/s²
#: (and would overflow the filter and the fits).
MAX_ACCEL_M_S2 = 1e6
#: Search window for a rear impact starts this long before the expected L / v
#: (the speed is known to about 1 %, i.e. ±15 ms at 7 km/h).
_REAR_TOLERANCE_S = 0.1
#: Ringing from the front axle's impact is measured over this span before the window.
_BACKGROUND_S = 0.3


@dataclass(frozen=True, eq=False)
class TireSignal:
    """One tire channel after preprocessing.

    Attributes
    ----------
    tire : str
    time_s, raw_m_s2, filtered_m_s2 : ndarray
        Time (s), recorded and low-pass filtered hub acceleration (m/s²).
    sample_rate_hz, cutoff_hz : float
    impact_s : float
        Onset of this tire's cleat impact, s.
    free_start_s, window_end_s : float
        Analysis window of the free vibration, s.
    noise_m_s2 : float
        RMS of the filtered signal's noise, m/s².
    dominant_hz : float
        Dominant frequency of the free vibration (spectral peak), Hz.
    peak_index : ndarray of int
        Sample index of each successive positive peak.
    peak_times_s, peak_values_m_s2 : ndarray
        Peak times and values, refined by a least-squares parabola over
        ±15 % of the dominant period around each peak sample.
    cleat_clear_s : float
        The latest time a tire of unloaded radius up to :data:`MAX_TIRE_RADIUS_M` can still touch the cleat
        (:func:`cleat_clear_time_s`): a peak before it may still be forced.
    """

    tire: str
    time_s: np.ndarray
    raw_m_s2: np.ndarray
    filtered_m_s2: np.ndarray
    sample_rate_hz: float
    cutoff_hz: float
    impact_s: float
    free_start_s: float
    window_end_s: float
    noise_m_s2: float
    dominant_hz: float
    peak_index: np.ndarray
    peak_times_s: np.ndarray
    peak_values_m_s2: np.ndarray
    cleat_clear_s: float = math.nan


#: The largest unloaded radius of a tractor tire, m: it bounds how long a footprint can still touch the cleat.
MAX_TIRE_RADIUS_M = 0.9


def cleat_clear_time_s(rec: Recording, impact_s: float, dominant_hz: float,
                       radius_m: float = MAX_TIRE_RADIUS_M) -> float:
    """The latest time a tire that first touched the cleat at `impact_s` can still touch it.

    A tire of unloaded radius R deflected δ0 on flat ground reaches a cleat of height h from
    d = √(R² − (R − h − δ0)²) ahead of its edge, and leaves it d past the far edge: from the first touch
    it rolls w + 2d (w the cleat's width).  δ0 = g / ω² is the static deflection of a corner ringing at
    `dominant_hz` (k = m ω², δ0 = m g / k); R is `radius_m` (default: the largest tractor tire's).
    """
    omega = 2 * math.pi * dominant_hz
    deflection = STANDARD_GRAVITY / (omega * omega) if omega > 0 else 0.0
    r, reach = radius_m, min(radius_m, rec.cleat_height_m + deflection)
    d = math.sqrt(max(0.0, r * r - (r - reach) ** 2))
    return impact_s + (rec.cleat_width_m + 2 * d) / rec.speed_m_s


def lowpass(x, *, sample_rate_hz: float, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
            order: int = FILTER_ORDER, source=None) -> np.ndarray:
    """Zero-phase Butterworth low-pass (forward-backward ``sosfiltfilt``).

    Parameters
    ----------
    x : array_like
        Signal sampled at `sample_rate_hz`.
    sample_rate_hz, cutoff_hz : float
        Sampling rate and -3 dB cut-off of the single-pass filter, Hz.
    order : int
        Butterworth order of the single pass (the paper: 5).
    source : str, optional
        Named in the error message.

    Raises
    ------
    InputError
        If the cut-off is not below the Nyquist frequency.
    """
    sos, zi, edge = lowpass_design(sample_rate_hz=sample_rate_hz, cutoff_hz=cutoff_hz, order=order, source=source)
    from scipy import signal   # here, not at import: a second of start-up for commands that never filter

    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size <= edge:      # scipy's checks and messages for what the fast path does not take
        return signal.sosfiltfilt(sos, x)
    # scipy.signal.sosfiltfilt (odd extension, steady-state initial conditions), with the design's
    # initial-condition vector computed once per design instead of on every call
    ext = np.concatenate((2 * x[0] - x[edge:0:-1], x, 2 * x[-1] - x[-2:-(edge + 2):-1]))
    y, _ = signal.sosfilt(sos, ext, zi=zi * ext[0])
    y, _ = signal.sosfilt(sos, y[::-1], zi=zi * y[-1])
    return y[::-1][edge:-edge].copy()


def lowpass_design(*, sample_rate_hz: float, cutoff_hz: float = DEFAULT_CUTOFF_HZ, order: int = FILTER_ORDER,
                   source=None):
    """The design :func:`lowpass` filters with, after its checks: (sos, sosfilt_zi, pad length in samples).

    Raises
    ------
    InputError
        If the cut-off is not below the Nyquist frequency.
    """
    if not (cutoff_hz > 0):
        raise InputError(source, f"low-pass cut-off must be > 0 Hz, got {cutoff_hz}")
    if cutoff_hz >= sample_rate_hz / 2 * (1 - 1e-9):
        raise InputError(source, f"low-pass cut-off {cutoff_hz:g} Hz is not below the Nyquist frequency "
                                 f"{sample_rate_hz / 2:g} Hz (sampling rate {sample_rate_hz:g} Hz)")
    try:
        design = _butter_sos(order, float(cutoff_hz), float(sample_rate_hz))
    except (np.linalg.LinAlgError, ValueError, ZeroDivisionError):
        design = None
    if design is None or not (np.all(np.isfinite(design[0])) and np.all(np.isfinite(design[1]))):
        raise InputError(source, f"low-pass cut-off {cutoff_hz:g} Hz is too low for a filter at the sampling rate "
                                 f"{sample_rate_hz:g} Hz")
    return design


@functools.lru_cache(maxsize=64)
def _butter_sos(order: int, cutoff_hz: float, sample_rate_hz: float):
    """The Butterworth design, once per (order, cut-off, rate): (sos, sosfilt_zi, pad length)."""
    from scipy import signal

    sos = signal.butter(order, cutoff_hz, fs=sample_rate_hz, output="sos")
    zi = signal.sosfilt_zi(sos)
    ntaps = 2 * len(sos) + 1 - min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
    zi.setflags(write=False)      # (scipy's sosfilt needs a writable sos; it is never written)
    return sos, zi, 3 * ntaps


def filter_guard_s(cutoff_hz: float) -> float:
    """Time over which the zero-phase low-pass smears a step, s (2.5 / cut-off)."""
    return 2.5 / cutoff_hz


def noise_rms(x) -> float:
    """Robust RMS of a noise segment (1.4826 × median absolute deviation)."""
    x = np.asarray(x, dtype=float)
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


def broadband_noise(x, *, sample_rate_hz: float) -> tuple[float, float, float]:
    """The broadband part of a quiet segment, apart from steady spectral lines: (RMS, line share, line Hz).

    A quiet stretch can hold a steady periodic signal (lugs, an engine line the conditioning left) that
    is not noise: counted as noise, it would let a model that misses it pass as "at the noise floor".
    The Hann-windowed periodogram's broadband level is its running median over ±5 % of the band (at
    least ±4 bins), divided by ln 2 (a periodogram bin of noise is exponential: median = ln 2 x mean);
    its sum is the broadband variance.  The line share is 1 - broadband / total variance (about 0.05 or
    less for noise alone), and the line's frequency the periodogram's largest bin.
    """
    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    n = x.size
    if n < 16:
        return noise_rms(x), 0.0, 0.0
    w = np.hanning(n)
    p = np.abs(np.fft.rfft(x * w)) ** 2
    half = max(4, int(0.05 * p.size))
    pad = np.concatenate((np.full(half, np.nan), p[1:], np.full(half, np.nan)))
    windows = np.lib.stride_tricks.sliding_window_view(pad, 2 * half + 1)
    level = np.nanmedian(windows, axis=1) / np.log(2)
    total, broad = float(p[1:].sum()), float(level.sum())
    if total <= 0:
        return 0.0, 0.0, 0.0
    var = float(np.mean(x ** 2))
    share = 1.0 - min(broad / total, 1.0)
    line_hz = float(np.argmax(p[1:]) + 1) * sample_rate_hz / n
    return math.sqrt(var * (1.0 - share)), share, line_hz


def check_clipping(x, *, source=None, tire: str = "") -> None:
    """Refuse a channel whose extreme values sit on a flat rail.

    A run of three or more samples exactly at the channel's maximum (or
    minimum) is accepted only where a parabola fitted to the samples around
    the run tops out at the run's level, as a quantized smooth peak does; if the
    parabola overshoots the run by more than 2 % (or three quantization
    steps), the signal was clipped by the sensor or the acquisition.  A flat
    minimum within 5 % of -g is exempt: that is the hub in free flight after
    the tire has lost contact, which an AC-coupled accelerometer records as -g.
    """
    x = np.asarray(x, dtype=float)
    levels = np.unique(x)
    q = float(np.min(np.diff(levels))) if levels.size > 1 else 0.0
    for sign, word in ((1.0, "maximum"), (-1.0, "minimum")):
        y = sign * x
        top = y.max()
        at_top = np.flatnonzero(y == top)
        if at_top.size < 3:
            continue
        runs = np.split(at_top, np.flatnonzero(np.diff(at_top) > 1) + 1)
        run = max(runs, key=len)
        if run.size < 3:
            continue
        if sign < 0 and abs(top / STANDARD_GRAVITY - 1) < 0.05:
            continue  # a flat minimum at -g is a hub in free flight (lift-off), not a rail
        m = max(3, run.size // 2)
        left = np.arange(max(0, run[0] - m), run[0])
        right = np.arange(run[-1] + 1, min(y.size, run[-1] + 1 + m))
        if left.size + right.size < 3:
            continue
        idx = np.concatenate([left, right])
        centre = 0.5 * (run[0] + run[-1])
        a, b, c = np.polyfit(idx - centre, y[idx], 2)
        apex = c - b * b / (4 * a) if a < 0 else np.inf
        if apex > top + max(0.02 * abs(top), 3 * q):
            ch = f"channel {tire}: " if tire else ""
            raise InputError(source, f"{ch}signal clipped at {sign * top:g} m/s^2 ({run.size} samples on the "
                                     f"{word} rail from t-index {run[0]}); saturated data cannot be identified")


def _dominant_frequency(x, sample_rate_hz: float, lo_hz: float, hi_hz: float) -> float:
    x = np.asarray(x, dtype=float)
    x = (x - x.mean()) * np.hanning(x.size)
    n = max(1 << 15, 1 << int(np.ceil(np.log2(8 * x.size))))
    spec = np.abs(np.fft.rfft(x, n))
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    band = (f >= lo_hz) & (f <= hi_hz)
    return float(f[band][np.argmax(spec[band])])


def _parabolic_peak(y: np.ndarray, i: int, half_width: int) -> tuple[float, float]:
    """Sub-sample offset and value of the maximum at sample i.

    A least-squares parabola through the samples within ``half_width`` of i.
    Every peak of a damped sinusoid is a scaled copy of the first, so the
    estimator's small shape bias is the same on every peak and cancels in the
    period and in the logarithmic decrement, while the noise averages out.
    """
    h = int(min(max(1, half_width), i, y.size - 1 - i))
    if h < 1:
        return 0.0, float(y[i])
    k = np.arange(-h, h + 1, dtype=float)
    a, b, c = np.polyfit(k, y[i - h:i + h + 1], 2)
    if a >= 0 or abs(b / (2 * a)) > h:
        return 0.0, float(y[i])
    p = -b / (2 * a)
    return float(p), float(c - b * b / (4 * a))


def _onset(absx: np.ndarray, start: int, stop: int, floor: float, source, tire: str,
           background: float = 0.0, steady: float = 0.0) -> tuple[int, float]:
    """First rise of |x| in [start, stop) to 30 % of its maximum, walked back to the onset.

    `background` is the level of what was already ringing before `start`; the
    rise must also exceed 1.5 times it.  The impact must stand _MIN_SNR times
    the noise `floor` or _MIN_STEADY_RATIO times `steady`, the largest |x| of
    the stretch the floor was measured on.
    """
    seg = absx[start:stop]
    if seg.size == 0:
        raise InputError(source, f"channel {tire}: record ends before the expected impact")
    peak = float(seg.max())
    if peak <= 0 or (peak < _MIN_SNR * floor and not (steady > 0 and peak >= _MIN_STEADY_RATIO * steady)):
        raise InputError(source, f"channel {tire}: no detectable cleat impact "
                                 f"(largest filtered value {peak:.3g} m/s^2, noise {floor:.3g} m/s^2)")
    rise = start + int(np.argmax(seg >= min(peak, max(_RISE_FRACTION * peak, 1.5 * background))))
    quiet = max(_ONSET_FRACTION * peak, 3 * floor)
    i = rise
    while i > start and absx[i - 1] > quiet:
        i -= 1
    return i, peak


def preprocess(rec: Recording, tires=None, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
               min_peaks: int = 3) -> dict[str, TireSignal]:
    """Filter each channel, find its impact and its successive free-vibration peaks.

    Parameters
    ----------
    rec : Recording
    tires : sequence of str, optional
        Channels to analyse (default: all in the recording).
    cutoff_hz : float
        Low-pass cut-off, Hz (the paper: 100 Hz).
    min_peaks : int
        Fewest free-vibration peaks accepted (the paper's method needs 3; the
        diagnosis, which fits waveforms, accepts fewer).

    Returns
    -------
    dict of str to TireSignal

    Raises
    ------
    InputError
        Clipped signal, no detectable impact, fewer than 3 peaks, or a
        cut-off not below Nyquist.
    """
    src = rec.source
    tires = list(rec.tires if tires is None else tires)
    for tire in tires:
        if tire not in rec.accel_m_s2:
            raise InputError(src, f"tire {tire} is not in the recording (channels: {', '.join(rec.tires)})")
    fs, t = rec.sample_rate_hz, rec.time_s
    dt = 1.0 / fs
    lowpass_design(sample_rate_hz=fs, cutoff_hz=cutoff_hz, source=src)  # check the cut-off before any use
    guard = filter_guard_s(cutoff_hz)
    # Filter every channel: front channels are needed for a rear tire's timing.
    filt = {}
    for name in rec.tires:
        peak = float(np.max(np.abs(rec.accel_m_s2[name])))
        if peak > MAX_ACCEL_M_S2:
            raise InputError(src, f"channel {name}: acceleration {peak:.3g} m/s^2 is beyond {MAX_ACCEL_M_S2:g} m/s^2 "
                                  f"(about 100000 g): not a hub acceleration in m/s^2")
        if name in tires:
            check_clipping(rec.accel_m_s2[name], source=src, tire=name)
        filt[name] = lowpass(rec.accel_m_s2[name], sample_rate_hz=fs, cutoff_hz=cutoff_hz, source=src)

    def raw_noise(name):  # white-noise estimate from first differences, scaled to the filter band
        d = np.diff(rec.accel_m_s2[name])
        return noise_rms(d) / np.sqrt(2) * np.sqrt(min(1.0, 2 * cutoff_hz / fs))

    def quiet_before(name, t_end):   # (noise RMS, largest |x|) up to 50 ms before t_end; (raw_noise, 0) if < 0.1 s
        n = int(np.searchsorted(t, t_end - 0.05))
        if n * dt >= 0.1:
            return noise_rms(filt[name][:n]), float(np.max(np.abs(filt[name][:n])))
        return raw_noise(name), 0.0

    # Front-axle impact: earliest onset among the front channels present.
    fronts = [n for n in FRONT_TIRES if n in rec.accel_m_s2]
    onsets: dict[str, int] = {}
    noise: dict[str, float] = {}
    for name in fronts:
        absx = np.abs(filt[name])
        try:
            i, _ = _onset(absx, 0, absx.size, 0.0, src, name)
            noise[name], steady = quiet_before(name, t[i])
            onsets[name], _ = _onset(absx, 0, absx.size, noise[name], src, name, steady=steady)
        except InputError:
            if name in tires:
                raise  # a channel not asked for only serves the timing
    t_front = min(t[onsets[n]] for n in onsets) if onsets else None
    delay = rec.rear_axle_delay_s()
    for name in (n for n in REAR_TIRES if n in rec.accel_m_s2 and n in tires):
        absx = np.abs(filt[name])
        background = 0.0
        if t_front is not None:
            start = int(np.searchsorted(t, t_front + delay - _REAR_TOLERANCE_S))
            if start >= t.size - 1:
                raise InputError(src, f"channel {name}: record ends before the rear axle reaches the cleat "
                                      f"(expected at t = {t_front + delay:.3f} s)")
            noise[name], steady = quiet_before(name, t_front)
            before = absx[int(np.searchsorted(t, t[start] - _BACKGROUND_S)):start]
            background = float(before.max()) if before.size else 0.0
        else:
            start = 0
            i, _ = _onset(absx, 0, absx.size, 0.0, src, name)
            noise[name], steady = quiet_before(name, t[i])
        onsets[name], _ = _onset(absx, start, absx.size, noise[name], src, name, background, steady)

    out = {}
    for name in tires:
        x = filt[name]
        i0 = onsets[name]
        t_imp = float(t[i0])
        free_start = t_imp + rec.cleat_width_m / rec.speed_m_s + guard
        if name in FRONT_TIRES:
            window_end = min(t[-1] - guard, t_imp + delay - guard)
        else:
            window_end = t[-1] - guard
        out[name] = _free_peaks(rec, name, x, t_imp, free_start, window_end, noise[name], cutoff_hz, min_peaks)
    return out


def _free_peaks(rec, name, x, t_imp, free_start, window_end, sigma, cutoff_hz, min_peaks=3) -> TireSignal:
    from scipy import signal

    src, t, fs = rec.source, rec.time_s, rec.sample_rate_hz
    a = int(np.searchsorted(t, free_start))
    b = int(np.searchsorted(t, window_end, side="right"))
    if b - a < 8:
        raise InputError(src, f"channel {name}: no free vibration between the cleat exit "
                              f"({free_start:.3f} s) and the end of the analysis window ({window_end:.3f} s)")
    seg = x[a:b]
    f_dom = _dominant_frequency(seg, fs, 0.5, min(0.4 * cutoff_hz, fs / 4))
    impact_size = float(np.max(np.abs(x[int(np.searchsorted(t, t_imp)):b])))
    thr = max(_PEAK_SNR * sigma, _PEAK_FRACTION * impact_size)
    idx, _ = signal.find_peaks(seg, height=thr, prominence=thr, distance=max(1, int(0.6 * fs / f_dom)))
    # The first peak is the largest within 1.5 periods of the cleat exit (a tire
    # that envelops the cleat may show a smaller one before it); keep the run of
    # successive peaks about one dominant period apart from there on.
    period = 1.0 / f_dom
    early = idx[idx < 1.5 * period * fs]
    if early.size:
        idx = idx[int(np.argmax(seg[early])):]
    keep = list(idx[:1])
    for j in idx[1:]:
        if not (0.65 * period <= (j - keep[-1]) / fs <= 1.35 * period):
            break
        keep.append(j)
    if len(keep) < min_peaks:
        raise InputError(src, f"channel {name}: fewer than {min_peaks} free-vibration peaks above the noise "
                              f"(found {len(keep)} between {free_start:.3f} s and {window_end:.3f} s)")
    keep = np.asarray(keep, dtype=int) + a
    half = int(round(0.15 * fs / f_dom))
    refined = [_parabolic_peak(x, i, half) for i in keep]
    times = np.array([t[i] + p / fs for i, (p, _) in zip(keep, refined)])
    values = np.array([v for _, v in refined])
    return TireSignal(
        tire=name, time_s=t, raw_m_s2=rec.accel_m_s2[name], filtered_m_s2=x, sample_rate_hz=fs,
        cutoff_hz=cutoff_hz, impact_s=t_imp, free_start_s=free_start, window_end_s=float(window_end),
        noise_m_s2=float(sigma), dominant_hz=f_dom, peak_index=keep, peak_times_s=times, peak_values_m_s2=values,
        cleat_clear_s=cleat_clear_time_s(rec, t_imp, f_dom))
