"""Long recordings: the window that holds the cleat impacts.

A cleat run lasts a few seconds, but an acquisition may run for minutes
(2 M rows are 33 min at 1 kHz).  The identification and the diagnosis need
only the impacts and the free decay after them, so a recording longer than
:data:`LONG_RECORD_S` (or with more than :data:`LONG_RECORD_SAMPLES` samples)
is analysed on that window only, and the commands say so: a note on stderr
and the window in their JSON (``"analysed_s"``, with the file's span in
``"record_s"``).  Shorter recordings are analysed whole, as before.

The window, found on every channel low-passed as in
:mod:`identification.recording.preprocess` (envelope over 10 ms blocks, noise RMS of
the whole record by the median absolute deviation):

* **first impact**: the earliest rise of a front channel to 30 % of its
  largest value (the preprocessing's own impact criterion), the channel
  standing at least 10 noise RMS above its noise; without a front channel,
  the rear ones';
* **last impact**: the rear axle's arrival, first impact + wheelbase / speed
  (when rear channels are recorded), or the latest rise of a rear channel
  near it (from 0.1 s before to 0.5 s or 20 % of wheelbase / speed after);
* **start**: :data:`LEAD_S` before the first impact (quiet samples for the
  noise floor);
* **end**: once every channel has stayed below :data:`QUIET_LEVEL` noise RMS
  (the paper's peak threshold) for :data:`QUIET_S` after the last impact, the
  free decay is over; the window ends there, at most :data:`MAX_DECAY_S` after
  the last impact.

Times keep the file's time base (a window from 1000.5 s starts at 1000.5 s),
so arrivals found on the window (``diagnose --json``) hold for the file.
"""

from __future__ import annotations

import sys
from dataclasses import replace

import numpy as np

from .preprocess import DEFAULT_CUTOFF_HZ, lowpass, noise_rms
from .record import FRONT_TIRES, MIN_SAMPLES, REAR_TIRES, Recording

__all__ = ["LONG_RECORD_S", "LONG_RECORD_SAMPLES", "LEAD_S", "QUIET_S", "QUIET_LEVEL", "MAX_DECAY_S",
           "ANALYSIS_RATE_FACTOR", "is_long", "impact_window", "focus", "decimate", "window_json"]

#: A recording longer than this (s) is analysed on its impact window.
LONG_RECORD_S = 30.0
#: A recording with more samples than this is analysed on its impact window.
LONG_RECORD_SAMPLES = 500_000
#: Quiet lead kept before the first impact, s.
LEAD_S = 2.0
#: The free decay is over when every channel stays this long below the quiet level, s.
QUIET_S = 1.0
#: Quiet level, in noise RMS of each low-passed channel (the paper's peak threshold, 5 x noise).
QUIET_LEVEL = 5.0
#: The window ends at most this long after the last impact, s.
MAX_DECAY_S = 20.0
#: :func:`decimate` keeps at least this many samples per second per hertz of the analysis cut-off (2 kHz at
#: the default 100 Hz).
ANALYSIS_RATE_FACTOR = 20
#: Order of the zero-phase Butterworth low-pass applied before decimating (at 0.4 x the new rate).
_DECIMATION_ORDER = 8
#: The rear axle's impact is searched from this long before its expected arrival first impact + L / v ...
_REAR_BEFORE_S = 0.1
#: ... to this long after it, or 20 % of L / v if longer (the sidecar's speed may be a few percent off), s.
_REAR_AFTER_S = 0.5
#: Envelope block, s.
_BLOCK_S = 0.01
#: Impact criteria of :mod:`identification.recording.preprocess`: rise to 30 % of the maximum, 10 noise RMS above noise.
_RISE_FRACTION = 0.3
_MIN_SNR = 10.0


def is_long(rec: Recording) -> bool:
    """Whether `rec` is long enough to be analysed on its impact window only."""
    t = rec.time_s
    return t[-1] - t[0] > LONG_RECORD_S or t.size > LONG_RECORD_SAMPLES


def _envelopes(rec: Recording, cutoff_hz: float) -> tuple[int, dict, dict]:
    """The block length (samples), and per channel the block envelope of |low-passed| and its noise RMS."""
    fs = rec.sample_rate_hz
    block = max(1, int(round(_BLOCK_S * fs)))
    starts = np.arange(0, rec.time_s.size, block)
    env, noise = {}, {}
    for name in rec.tires:  # one channel at a time: memory stays a few copies of one channel
        y = lowpass(rec.accel_m_s2[name], sample_rate_hz=fs, cutoff_hz=cutoff_hz, source=rec.source)
        noise[name] = noise_rms(y)
        env[name] = np.maximum.reduceat(np.abs(y, out=y), starts)
        del y
    return block, env, noise


def _rise(env: np.ndarray, noise: float, start: int = 0) -> int | None:
    """First block from `start` where the envelope reaches 30 % of its maximum from there (None: no impact
    standing 10 noise RMS above the noise)."""
    seg = env[start:]
    if seg.size == 0:
        return None
    peak = float(seg.max())
    if peak <= 0 or peak < _MIN_SNR * noise:
        return None
    return start + int(np.argmax(seg >= _RISE_FRACTION * peak))


def impact_window(rec: Recording, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ) -> tuple[float, float] | None:
    """The span of `rec` that holds its cleat impacts and their free decay, s (None: no impact found).

    Parameters
    ----------
    rec : Recording
    cutoff_hz : float
        Low-pass cut-off of the analysis, Hz.

    Returns
    -------
    tuple of float or None
        (start, end) in the recording's time base, within its span.
    """
    t = rec.time_s
    block, env, noise = _envelopes(rec, cutoff_hz)
    block_s = block / rec.sample_rate_hz
    blocks = next(iter(env.values())).size

    def rises(channels, lo=0, hi=None):
        return [r for r in (_rise(env[c][:hi], noise[c], lo) for c in channels) if r is not None]

    fronts = [c for c in FRONT_TIRES if c in env]
    rears = [c for c in REAR_TIRES if c in env]
    found = rises(fronts)
    if not found:   # no front channel, or none shows an impact: the rear ones alone
        found, fronts = rises(rears), []
    if not found:
        return None
    first = last = min(found)
    if fronts and rears:   # the rear axle's arrival, searched near first + L / v only (a later pass is not it)
        expected = first + int(rec.rear_axle_delay_s() / block_s)
        lo = max(0, expected - int(_REAR_BEFORE_S / block_s))
        hi = expected + int(max(_REAR_AFTER_S, 0.2 * rec.rear_axle_delay_s()) / block_s)
        last = max([expected] + rises(rears, lo, hi))
    last = min(last, blocks - 1)
    quiet = np.ones(blocks, dtype=bool)
    for c in env:
        quiet &= env[c] < QUIET_LEVEL * noise[c]
    need = max(1, int(round(QUIET_S / block_s)))
    after = last + int(round((rec.cleat_width_m / rec.speed_m_s + 0.1) / block_s))
    end_block = cap = min(blocks, last + int(round(MAX_DECAY_S / block_s)))
    run = 0
    for i in range(min(after, cap), cap):   # blocks after the last impact, until a quiet second
        run = run + 1 if quiet[i] else 0
        if run >= need:
            end_block = i + 1
            break
    start_s = max(t[0], t[first * block] - LEAD_S)
    end_s = t[min(t.size - 1, end_block * block - 1)]
    return float(start_s), float(end_s)


def focus(rec: Recording, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ, announce: bool = True,
          single_line: bool = False) -> Recording:
    """The recording to analyse: for a long recording (:func:`is_long`) its impact window; conditioned.

    Every analysis starts here.  After the window, the recording is conditioned
    (:func:`identification.recording.condition.condition`: offsets and drifts, engine lines and flipped signs
    removed, the speed checked against the front/rear delay).  Calling it again returns its input.

    Parameters
    ----------
    rec : Recording
    cutoff_hz : float
        Low-pass cut-off of the analysis, Hz.
    announce : bool
        Print a note naming the window and the conditioning's warnings on stderr (``cleatfmu: note: ...``).
    single_line : bool
        Also remove a steady line without orders (the per-tire identification;
        :func:`identification.recording.condition.condition`).

    Returns
    -------
    Recording
        The window (its ``record_span_s`` is the file's span), or all of `rec` when it is not long or
        no impact stands out (the analysis then reports that itself); conditioned.
    """
    from .condition import condition

    return condition(_window(rec, cutoff_hz, announce), cutoff_hz=cutoff_hz, announce=announce,
                     single_line=single_line)


def _window(rec: Recording, cutoff_hz: float, announce: bool) -> Recording:
    """The impact window of a long recording, or `rec`."""
    if not is_long(rec) or rec.record_span_s is not None or rec.conditioning is not None:
        return rec
    span = impact_window(rec, cutoff_hz=cutoff_hz)
    if span is None:
        return rec
    t = rec.time_s
    a = int(np.searchsorted(t, span[0]))
    b = int(np.searchsorted(t, span[1], side="right"))
    if b - a >= t.size:
        return rec
    # copies, not views: the whole record's arrays can go once the caller lets go of `rec`
    out = replace(rec, time_s=t[a:b].copy(), accel_m_s2={c: x[a:b].copy() for c, x in rec.accel_m_s2.items()},
                  record_span_s=(float(t[0]), float(t[-1])))
    if announce:
        print(f"cleatfmu: note: {rec.source}: a {t[-1] - t[0]:.6g} s record of {t.size} samples; analysed "
              f"{out.time_s[0]:.3f}-{out.time_s[-1]:.3f} s ({b - a} samples), the cleat impacts and their free "
              f"decay", file=sys.stderr)
    return out


def decimate(rec: Recording, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ, announce: bool = True) -> Recording:
    """`rec` at the lowest integer fraction of its rate that keeps :data:`ANALYSIS_RATE_FACTOR` x `cutoff_hz`.

    The model fits of the diagnosis cost in proportion to the samples, but
    they compare signals low-passed at `cutoff_hz`: above 20 x the cut-off
    the samples add nothing but time.  Each channel is low-passed at 0.4 x the
    new rate (8 x the cut-off and more; zero-phase 8th-order Butterworth, so
    nothing is delayed and the band below the cut-off is kept to 1e-7) and
    every q-th sample kept.  An acquisition anti-alias filter at or above the
    new Nyquist frequency is left out of the model (its delay in the analysis
    band, a few tens of microseconds there, is neglected); the AC coupling is kept.

    Parameters
    ----------
    rec : Recording
    cutoff_hz : float
        Low-pass cut-off of the analysis, Hz.
    announce : bool
        Print a note on stderr (``cleatfmu: note: ...``) when decimating.

    Returns
    -------
    Recording
        `rec` itself below 2 x 20 x `cutoff_hz`, else the decimated recording (its ``decimated_from_hz``
        the original rate).
    """
    from .acquisition import Acquisition

    fs = rec.sample_rate_hz
    if not (cutoff_hz > 0) or rec.decimated_from_hz is not None:
        return rec
    q = int(fs // (ANALYSIS_RATE_FACTOR * cutoff_hz))
    if q < 2 or rec.time_s.size // q < 2 * MIN_SAMPLES:   # a cut-off so low that few samples would be left
        return rec
    new_fs = fs / q
    channels = {}
    for name, x in rec.accel_m_s2.items():
        y = lowpass(x, sample_rate_hz=fs, cutoff_hz=0.4 * new_fs, order=_DECIMATION_ORDER, source=rec.source)
        channels[name] = y[::q].copy()
    aa, dropped = rec.acquisition, None
    if aa is not None and aa.anti_alias_order and aa.anti_alias_cutoff_hz >= new_fs / 2:
        dropped = aa.anti_alias_cutoff_hz
        aa = Acquisition(0, 0.0, aa.highpass_hz)
    out = replace(rec, time_s=rec.time_s[::q].copy(), accel_m_s2=channels, acquisition=aa, decimated_from_hz=fs)
    if announce:
        extra = f"; the {dropped:g} Hz anti-alias filter is left out of the model" if dropped else ""
        print(f"cleatfmu: note: {rec.source}: sampled at {fs:.6g} Hz; analysed at {out.sample_rate_hz:.6g} Hz "
              f"(every {q}th sample after a zero-phase low-pass at {0.4 * new_fs:.6g} Hz), {ANALYSIS_RATE_FACTOR}x "
              f"the {cutoff_hz:g} Hz cut-off{extra}", file=sys.stderr)
    return out


def window_json(rec: Recording) -> dict | None:
    """What part of the file was analysed and how it was conditioned, or None for all of it, as recorded.

    Returns
    -------
    dict or None
        ``{"analysed_s": [start, end], "record_s": [start, end]}`` for a window of a long recording,
        with ``"sampling_rate_hz"`` and ``"decimated_from_hz"`` for decimated samples; ``"conditioning"``
        (:func:`identification.recording.condition.conditioning_json`) when conditioning found something.
    """
    from .condition import conditioning_json

    cond = conditioning_json(rec)
    if rec.record_span_s is None and rec.decimated_from_hz is None:
        return None if cond is None else {"conditioning": cond}
    span = rec.record_span_s or (float(rec.time_s[0]), float(rec.time_s[-1]))
    doc = {"analysed_s": [float(rec.time_s[0]), float(rec.time_s[-1])], "record_s": [float(v) for v in span]}
    if rec.decimated_from_hz is not None:
        doc.update(sampling_rate_hz=float(rec.sample_rate_hz), decimated_from_hz=float(rec.decimated_from_hz))
    if cond is not None:
        doc["conditioning"] = cond
    return doc
