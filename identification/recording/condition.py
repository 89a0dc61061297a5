"""Conditioning of field recordings: what a real acquisition adds that no tire model explains.

Applied once to a recording before any analysis (:func:`condition`; :func:`identification.recording.window.focus`
calls it), in this order:

1. **Engine harmonics.**  A steady spectral line in :data:`ENGINE_BAND_HZ` (below 0.45 fs; the tires
   and the lugs ring below it at test speeds) that stands :data:`LINE_PROMINENCE` x above its spectral
   neighbourhood on every channel, with at least one of its orders (2, 3, ... x;
   :data:`ORDER_PROMINENCE` x above their neighbourhood), is engine vibration (a single line may as
   well be a road or lug excitation, which the diagnosis names ``periodic_disturbance``).  Its
   frequency is refined on all orders and channels together, and each order's least-squares sinusoid
   (amplitude and phase per channel, fitted away from the impacts beside a constant and a drift, on
   the channels high-passed at half the band's lower end with zero phase, its gain divided out) is
   subtracted.  The spectra that find the lines are averaged over windows away from the impacts,
   whose impulses are broadband.  This step goes first: the vibration hides the quiet stretches the
   next steps look for.
2. **Offset and drift.**  Before the first impact and at the end of the record the hub's acceleration
   is noise (and any steady vibration) about zero: the line through the means of these quiet ends is
   the amplifier's DC offset and linear drift.  It is removed where it is significant (5 standard
   errors of those means) somewhere in the record.
3. **A flipped sensor.**  A cleat pushes the hub up: the first excursion of a channel's own impact
   (its first burst; a rear channel's after the front axle's impact, which the body carries to it)
   is positive.  A channel whose first excursion is negative was recorded with the sign reversed; it
   is corrected and named in a warning.  Where an axle's two channels rise, or start, at the same time
   (within :data:`_COINCIDENT_S`; a pivot's roll carries an impact across a few ms slower than the
   impact rises, so the far hub's rise lags while its onset does not) with opposite signs, the sizes of
   the two first excursions decide: one less
   than :data:`_CARRIED_RATIO` of the other was carried across by the body (whose roll gives the far
   hub about a quarter of the impact, opposite in sign) and says nothing of its sensor; two comparable
   ones are two own impacts, so the negative one is flipped, except on the front axle, where a
   pivoting axle also carries the whole impact across: that is warned of and left to the diagnosis
   (``flip_ambiguous``), as is a channel whose impact rises out of no quiet stretch
   (``sign_undetermined``): :mod:`identification.diagnose.joint_signs` fits each hypothesis.
4. **The speed from the front/rear delay.**  Where a front and a rear channel of one side are present,
   the delay between their impact onsets gives the speed (wheelbase / delay).  It is reported beside
   the sidecar's, with a warning when the two differ by more than :data:`SPEED_TOLERANCE` (and the two
   sides' delays agree to :data:`SIDES_AGREE`); it is not used: the onsets lead the wheel centre's
   arrival by half a footprint, so footprints of different lengths front and rear shift the delay (about
   1 % for 0.30 and 0.38 m at 7 km/h, 3 % for 0.44 and 0.32 m).  The diagnosis fits the delay with the
   footprints modelled and refits at that speed (:func:`identification.diagnose.joint_select.diagnose_tractor`).

What was done is kept in ``Recording.conditioning`` (:func:`conditioning_json` for the outputs).
Everything is in SI units.
"""

from __future__ import annotations

import sys
from dataclasses import replace

import numpy as np

from .preprocess import DEFAULT_CUTOFF_HZ, lowpass, noise_rms
from .record import FRONT_TIRES, Recording

__all__ = ["condition", "conditioning_json", "line_fit", "refine_line", "ENGINE_BAND_HZ", "LINE_PROMINENCE",
           "SPEED_TOLERANCE"]

#: Span around a channel's impact and its largest burst left out of the engine lines' fits, s (before, after).
_IMPACT_SPAN_S = (0.3, 0.2)
#: The quiet end of a record: its last this fraction.
_TAIL = 0.2
#: Band searched for engine lines, Hz (the upper end is also kept below the analysis cut-off and 0.45 fs).
ENGINE_BAND_HZ = (20.0, 200.0)
#: A spectral line must stand this many times above the median of its neighbourhood (amplitude spectrum).
LINE_PROMINENCE = 12.0
#: An order of an engine line found must stand this many times above its neighbourhood.
ORDER_PROMINENCE = 4.0
#: Length of the windows of the line search's spectra, s (their main lobe: ±2 / this).
_SEGMENT_S = 0.5
#: Width of the neighbourhood of a line, Hz.
_NEIGHBOURHOOD_HZ = 4.0
#: Most engine orders searched.
MAX_ORDERS = 6
#: Relative difference between the sidecar's speed and the onsets' above which a warning says so (the
#: footprints alone shift the onsets' by up to about 3 %).
SPEED_TOLERANCE = 0.035
#: The left and right delays must agree to this fraction for the warning.
SIDES_AGREE = 0.01
#: A burst rises where |x| first reaches this fraction of the channel's largest value.
_RISE_FRACTION = 0.3
#: A channel's own impact: its first excursion is where |x| first reaches this fraction of the burst maximum.
_FIRST_FRACTION = 0.3
#: The onset: where |x| was last below this fraction of the burst maximum (or 3 noise RMS).
_ONSET_FRACTION = 0.05
#: A quiet stretch before the onset lasts this long, s.
_QUIET_S = 0.06
#: Quiet is also below this many times the median of the record's envelope (its steady level).
_STEADY_FACTOR = 1.5
#: A burst stands this many noise RMS above the noise.
_MIN_SNR = 10.0
#: A rear channel's own impact is searched from this fraction of the sidecar's delay after the front's onset.
_REAR_SEARCH = 0.85
#: Impacts of an axle's two channels rising or starting closer than this are one event for the flip test, s.
_COINCIDENT_S = 0.005
#: Span of a first excursion, s.
_EXCURSION_S = 0.03
#: A first excursion smaller than this fraction of the other side's, in one event, was carried across.
_CARRIED_RATIO = 0.5
#: Longest rise from the onset to the burst maximum, s (a long footprint at a low speed).
_MAX_RISE_S = 0.4


def _raw_noise(x: np.ndarray) -> float:
    """White-noise RMS from first differences (robust)."""
    return noise_rms(np.diff(x)) / np.sqrt(2)


def _quiet_segments(t: np.ndarray, first_onset: float) -> tuple[np.ndarray, np.ndarray]:
    """Index masks of the record's quiet ends: before the first impact and its last :data:`_TAIL` part."""
    before = t < first_onset - 0.05
    tail = t >= t[-1] - _TAIL * (t[-1] - t[0])
    return before, tail


def _offset_drift(t: np.ndarray, x: np.ndarray, before: np.ndarray, tail: np.ndarray,
                  band_fraction: float) -> tuple[float, float, float, float]:
    """(offset at t[0], drift per s, largest |line| over the record, its significance threshold).

    The line passes through the means of the quiet ends (only the tail's mean, no drift, when the
    record starts less than 0.1 s before the impact); the threshold is 5 standard errors of those
    means (the segments' own spread, which holds any steady vibration, over their independent samples)
    or 0.1 % of the channel's largest value.
    """
    fs = (t.size - 1) / (t[-1] - t[0])
    m2, t2 = float(x[tail].mean()), float(t[tail].mean())
    n2 = max(1.0, tail.sum() * band_fraction)
    spread = float(x[tail].std())
    if before.sum() >= 0.1 * fs:
        m1, t1 = float(x[before].mean()), float(t[before].mean())
        slope = (m2 - m1) / (t2 - t1)
        n = min(n2, max(1.0, before.sum() * band_fraction))
        spread = max(spread, float(x[before].std()))
    else:
        slope, n = 0.0, n2
    start = m2 + slope * (t[0] - t2)
    end = m2 + slope * (t[-1] - t2)
    threshold = max(5 * spread / np.sqrt(n), 1e-3 * float(np.abs(x).max()))
    return start, slope, max(abs(start), abs(end)), threshold


def _quiet_spectra(x: np.ndarray, keep: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray, int]:
    """Mean amplitude spectra (channels, bins) over Hann windows of :data:`_SEGMENT_S` (half overlapping)
    laid in the runs of `keep` (away from the impacts, whose impulses are broadband), the whole record
    when no run is long enough: (frequencies Hz, spectra, window length in samples)."""
    n = max(8, int(_SEGMENT_S * fs))
    edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(np.int8), [0]])))
    starts = [a + j for a, b in zip(edges[::2], edges[1::2]) for j in range(0, b - a - n + 1, n // 2)]
    if not starts:
        starts, n = [0], x.shape[1]
    nfft = 1 << int(np.ceil(np.log2(4 * n)))
    w = np.hanning(n)
    segs = np.stack([x[:, a:a + n] for a in starts])                      # (segments, channels, n)
    segs = (segs - segs.mean(axis=2, keepdims=True)) * w
    spec = np.abs(np.fft.rfft(segs, nfft, axis=2)).mean(axis=0) * 2 / w.sum()
    return np.fft.rfftfreq(nfft, 1 / fs), spec, n


def line_fit(t: np.ndarray, channels: np.ndarray, f: float, orders=(1,)) -> tuple[np.ndarray, float]:
    """Least-squares sinusoids at ``m f`` for every m of `orders`, per channel, beside a constant and a drift:
    (cos and sin coefficients (orders, ch, 2), total power of the fitted sinusoids)."""
    cols = []
    for m in orders:
        arg = 2 * np.pi * m * f * t
        cols += [np.cos(arg), np.sin(arg)]
    k = len(cols)
    basis = np.stack(cols + [np.ones_like(t), t - t.mean()], axis=1)
    coef, *_ = np.linalg.lstsq(basis, channels.T, rcond=None)
    fitted = basis[:, :k] @ coef[:k]
    return coef[:k].T.reshape(channels.shape[0], len(orders), 2).transpose(1, 0, 2), float(np.sum(fitted * fitted))


def refine_line(t: np.ndarray, channels: np.ndarray, f0: float, width: float, orders=(1,)) -> float:
    """The fundamental within ``f0 +- width`` of the largest least-squares power of its `orders` on all
    channels."""
    from scipy.optimize import minimize_scalar

    def power(f):
        return line_fit(t, channels, f, orders)[1]

    # a grid finer than the record's resolution (1 / its span) finds the main lobe, Brent's method its top
    step = 0.2 / (t[-1] - t[0])
    grid = np.arange(f0 - width, f0 + width + step, step)
    best = float(grid[int(np.argmax([power(f) for f in grid]))])
    res = minimize_scalar(lambda f: -power(f), bounds=(best - step, best + step), method="bounded",
                          options={"xatol": 1e-7})
    return float(res.x)


def _prominent(freq, specs, f, lobe_hz, prominence=None) -> tuple[bool, float]:
    """Whether a line near `f` (within its main lobe, ±`lobe_hz`) stands `prominence`
    (:data:`LINE_PROMINENCE`) x above the median of its neighbourhood (±:data:`_NEIGHBOURHOOD_HZ` beyond the
    lobe) on every channel."""
    d = np.abs(freq - f)
    near = (d > lobe_hz) & (d <= lobe_hz + _NEIGHBOURHOOD_HZ)
    at = d <= 0.5 * lobe_hz
    if not near.any() or not at.any():
        return False, 0.0
    ratios = [float(s[at].max() / max(np.median(s[near]), 1e-300)) for s in specs]
    return min(ratios) >= (prominence or LINE_PROMINENCE), min(ratios)


def _engine_lines(t, channels, fs, cutoff_hz, keep, single=False) -> list[dict]:
    """The engine's lines found on every channel: [{"frequency_hz", "order", "amplitude_m_s2": [...]}]
    (with `single`, also one line without orders).

    Lines are detected on spectra of the samples `keep` (away from the impacts, whose broadband
    content would otherwise hide a weak line and leak into every line's fit) and fitted there.
    """
    hi = min(ENGINE_BAND_HZ[1], 0.45 * fs)
    lo = ENGINE_BAND_HZ[0]
    if hi <= lo + 2 * _NEIGHBOURHOOD_HZ or t[-1] - t[0] < 0.5:
        return []
    freq, specs, n_window = _quiet_spectra(channels, keep, fs)
    lobe = 2.0 * fs / n_window          # the Hann window's main lobe, Hz
    band = (freq >= lo) & (freq <= hi)
    # the fundamental: the strongest line of the channels' product spectrum (a line common to all of them)
    common = np.exp(np.mean([np.log(np.maximum(s, 1e-300)) for s in specs], axis=0))
    lines: list[dict] = []
    f1 = float(freq[band][np.argmax(common[band])])
    ok, _ = _prominent(freq, specs, f1, lobe)
    if not ok:
        return []
    # fit on the channels high-passed below the band (zero-phase, so a line keeps its phase and loses only
    # the known gain): the tires' ringing, cut off at the masked impacts, would leak into the lines
    from scipy import signal

    sos = signal.butter(4, 0.5 * lo, btype="highpass", fs=fs, output="sos")
    t, channels = t[keep], signal.sosfiltfilt(sos, channels, axis=1)[:, keep]

    def gain(f):
        return float(np.abs(signal.sosfreqz(sos, worN=[f], fs=fs)[1][0]) ** 2)

    f1 = refine_line(t, channels, f1, lobe)
    # a lower line whose orders this one is (a 2nd or 3rd order stronger than the first)
    for div in (3, 2):
        fd = f1 / div
        if fd >= lo and _prominent(freq, specs, fd, lobe)[0]:
            f1 = refine_line(t, channels, fd, lobe / div)
            break
    orders = [m for m in range(1, MAX_ORDERS + 1) if m * f1 <= 0.45 * fs - lobe - _NEIGHBOURHOOD_HZ
              and (m == 1 or _prominent(freq, specs, m * f1, lobe, ORDER_PROMINENCE)[0])]
    if len(orders) < 2 and not single:
        return []     # one steady line alone: a road or lug excitation as likely as an engine (the diagnosis
    #                   names it periodic_disturbance); an engine shows its orders
    # the fundamental refined on all its orders together (the higher ones carry its phase faster), then
    # every order's sinusoid fitted jointly
    f1 = refine_line(t, channels, f1, 0.25 / (t[-1] - t[0]) + lobe / 50, orders)
    coefs, _ = line_fit(t, channels, f1, orders)
    for m, coef in zip(orders, coefs):
        coef = coef / gain(m * f1)
        lines.append({"frequency_hz": m * f1, "order": m, "coef": coef,
                      "amplitude_m_s2": [float(np.hypot(*c)) for c in coef]})
    return lines


def _first_excursion(x: np.ndarray, fs: float, sigma: float, start: int = 0) -> tuple[int, float, int]:
    """(onset index, sign of the first excursion, index of the rise) of the first burst of the filtered
    channel `x` from sample `start` on.

    The burst's rise is the first sample where |x| reaches :data:`_RISE_FRACTION` of its largest value
    from `start` on (a later burst may be larger: a hub landing after a lift-off, the middle of an
    enveloped cleat).  The onset is the end of the last quiet stretch (|x| below 5 % of that value,
    3 noise RMS and 1.5 x the record's steady level, for :data:`_QUIET_S`) before the rise; the first
    excursion is where |x| first reaches :data:`_FIRST_FRACTION` of that value from there.  The sign is
    0 (undetermined) when no quiet stretch precedes the rise within :data:`_MAX_RISE_S`.
    """
    from scipy.ndimage import maximum_filter1d

    absx = np.abs(x)
    peak = float(absx[start:].max())
    i_rise = start + int(np.argmax(absx[start:] >= _RISE_FRACTION * peak))
    quiet = max(_ONSET_FRACTION * peak, 3 * sigma)
    w = max(1, int(_QUIET_S * fs))
    trailing = maximum_filter1d(absx, size=w, origin=(w - 1) // 2)   # max over the w samples ending here
    # quiet: below the steady level of the record too (a lug or road vibration that never stops)
    quiet = max(quiet, _STEADY_FACTOR * float(np.median(trailing)))
    lo = max(start, i_rise - int(_MAX_RISE_S * fs))
    calm = np.flatnonzero(trailing[lo:i_rise + 1] < quiet)
    if not calm.size or peak < _MIN_SNR * sigma or calm[-1] >= i_rise - lo:
        return (lo if not calm.size else i_rise), 0.0, i_rise     # no burst out of a quiet stretch
    onset = lo + int(calm[-1]) + 1
    first = onset + int(np.argmax(absx[onset:i_rise + 1] >= _FIRST_FRACTION * peak))
    return onset, float(np.sign(x[first])), i_rise


def _own_impacts(rec: Recording, filt: np.ndarray, sigma: np.ndarray) -> dict[str, tuple[int, float, int]]:
    """Per channel (onset index, sign of the first excursion, index of the rise) of its own impact.

    A front channel's own impact is its first burst; a rear channel's is its first burst from
    :data:`_REAR_SEARCH` x the sidecar's front/rear delay after the front axle's onset (before that, the
    front impact shows in the rear hubs through the body, sometimes larger than their own).
    """
    t, fs = rec.time_s, rec.sample_rate_hz
    names = list(rec.tires)
    out: dict[str, tuple[int, float, int]] = {}
    for i, c in enumerate(names):
        if c in FRONT_TIRES:
            out[c] = _first_excursion(filt[i], fs, sigma[i])
    fronts = [out[c][0] for c in out]
    start = 0
    if fronts:
        start = int(np.searchsorted(t, t[min(fronts)] + _REAR_SEARCH * rec.rear_axle_delay_s()))
    for i, c in enumerate(names):
        if c not in FRONT_TIRES:
            if start >= t.size - 2:
                out[c] = (t.size - 1, 0.0, t.size - 1)
                continue
            out[c] = _first_excursion(filt[i], fs, sigma[i], start)
    return out


def condition(rec: Recording, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ, announce: bool = True,
              single_line: bool = False) -> Recording:
    """`rec` with offsets, drifts, engine lines and flipped signs removed, and its speed checked.

    Parameters
    ----------
    rec : Recording
    cutoff_hz : float
        Low-pass cut-off of the analysis, Hz.
    announce : bool
        Print each warning on stderr (``cleatfmu: warning: ...``).
    single_line : bool
        Also remove one steady line without orders (``steady_line``): an engine's or the lugs', it hides
        the free decay the per-tire identification reads.  The diagnosis keeps it and models it
        (``periodic_disturbance``).

    Returns
    -------
    Recording
        A new recording whose ``conditioning`` says what was done (holding `rec`'s own arrays when
        nothing was changed); a recording already conditioned is returned unchanged.
    """
    if rec.conditioning is not None:
        return rec
    t = np.asarray(rec.time_s, dtype=float)
    fs = rec.sample_rate_hz
    names = list(rec.tires)
    x = np.array([np.asarray(rec.accel_m_s2[c], dtype=float) for c in names])
    doc: dict = {}
    warnings: list[str] = []
    band = min(cutoff_hz, 0.45 * fs)

    def low(rows):
        return np.array([lowpass(row, sample_rate_hz=fs, cutoff_hz=band, source=rec.source) for row in rows])

    tc = t - t.mean()
    # 1. engine lines, fitted (with a constant and a drift) away from every channel's impact: its rise and
    #    its largest burst, found on the channels less their least-squares line
    rough = low(x - x.mean(axis=1, keepdims=True) - np.outer(x @ tc / (tc @ tc), tc))
    impacts = _own_impacts(rec, rough, np.array([_raw_noise(row) for row in rough]))
    keep = np.ones(t.size, dtype=bool)
    for i, (_, _, i_rise) in enumerate(impacts[c] for c in names):
        for j in (i_rise, int(np.argmax(np.abs(rough[i])))):
            keep &= (t < t[j] - _IMPACT_SPAN_S[0]) | (t > t[j] + _IMPACT_SPAN_S[1])
    lines = _engine_lines(t, x, fs, cutoff_hz, keep if keep.sum() > 0.25 * t.size else np.ones(t.size, bool),
                          single_line)
    for line in lines:
        arg = 2 * np.pi * line["frequency_hz"] * t
        x -= line["coef"][:, :1] * np.cos(arg)[None, :] + line["coef"][:, 1:] * np.sin(arg)[None, :]
    if len(lines) == 1:     # single_line: no orders, so an engine or the lugs
        doc["steady_line"] = {"frequency_hz": lines[0]["frequency_hz"],
                              "amplitude_m_s2": dict(zip(names, lines[0]["amplitude_m_s2"]))}
        warnings.append(f"steady {lines[0]['frequency_hz']:.2f} Hz line without orders on every channel (an "
                        f"engine or the lugs; largest {max(lines[0]['amplitude_m_s2']):.3g} m/s^2) removed for "
                        f"the identification of the free decay; diagnose models it instead")
    elif lines:
        doc["engine"] = [{"frequency_hz": ln["frequency_hz"], "order": ln["order"],
                          "amplitude_m_s2": dict(zip(names, ln["amplitude_m_s2"]))} for ln in lines]
        f1 = lines[0]["frequency_hz"]
        warnings.append(f"steady vibration at {f1:.2f} Hz and {len(lines) - 1} of its orders on every channel "
                        f"(engine; largest {max(max(ln['amplitude_m_s2']) for ln in lines):.3g} m/s^2) removed "
                        f"before the analysis")
    # 2. offset and drift, measured where the record is quiet: before the first impact (its onset found on
    #    the engine-free channels less their least-squares line) and at its end
    if lines:
        rough = low(x - x.mean(axis=1, keepdims=True) - np.outer(x @ tc / (tc @ tc), tc))
        impacts = _own_impacts(rec, rough, np.array([_raw_noise(row) for row in rough]))
    first = min(t[onset] for onset, _, _ in impacts.values())
    before, tail = _quiet_segments(t, first)
    removed = {}
    for i, c in enumerate(names):
        off, drift, largest, threshold = _offset_drift(t, x[i], before, tail, min(1.0, 2 * band / fs))
        if largest > threshold:
            x[i] -= off + drift * (t - t[0])
            removed[c] = {"offset_m_s2": off, "drift_m_s2_per_s": drift}
    if removed:
        doc["offset_drift"] = removed
    # 3. flipped channels, from the low-passed, cleaned signals
    sigma = np.array([_raw_noise(row) for row in x]) * np.sqrt(min(1.0, 2 * band / fs))  # in the filter's band
    filt = low(x)
    onsets, flipped = {}, []
    impacts = _own_impacts(rec, filt, sigma)
    ambiguous, carried = [], []
    span = int(_EXCURSION_S * fs)
    for left, right in (("FL", "FR"), ("RL", "RR")):
        if left in impacts and right in impacts:
            (o1, s1, r1), (o2, s2, r2) = impacts[left], impacts[right]
            if s1 * s2 < 0 and min(abs(t[r1] - t[r2]), abs(t[o1] - t[o2])) < _COINCIDENT_S:
                # one event on both sides: each first excursion's size tells an own impact (comparable on
                # the two sides) from one the body carried across (a quarter of it, opposite in sign)
                m = {c: float(np.max(impacts[c][1] * filt[names.index(c)][impacts[c][0]:impacts[c][0] + span]))
                     for c in (left, right)}
                small, large = sorted((left, right), key=m.get)
                if m[small] < _CARRIED_RATIO * m[large]:
                    carried.append(small)           # its sign says nothing; the larger one's does
                elif left[0] == "F":
                    ambiguous += [left, right]      # a pivoting front axle carries the whole impact across
    undetermined = []
    for i, c in enumerate(names):
        onset, sign, _ = impacts[c]
        if sign != 0:
            onsets[c] = float(t[onset])
        else:
            undetermined.append(c)
        if sign < 0 and c not in ambiguous and c not in carried:
            flipped.append(c)
            x[i] = -x[i]
    if ambiguous:
        pairs = " and ".join(f"{a}/{b}" for a, b in zip(ambiguous[::2], ambiguous[1::2]))
        warnings.append(f"channels {pairs} start their impacts at the same time with opposite signs: one "
                        f"sensor may read upside down, or a pivoting axle carried one wheel's impact to the "
                        f"other; left to the whole-tractor diagnosis (check the sensors' mounting)")
        doc["flip_ambiguous"] = ambiguous
    if undetermined:                        # no quiet stretch before the impact: the diagnosis decides
        doc["sign_undetermined"] = undetermined
    if flipped:
        doc["flipped"] = flipped
        warnings.append(f"channel{'s' if len(flipped) > 1 else ''} {', '.join(flipped)}: the impact's first "
                        f"excursion is negative (a cleat pushes the hub up): the sensor reads upside down; "
                        f"sign corrected")
    # 4. speed from the front/rear delay of each side
    delays = [onsets[r] - onsets[f] for f, r in (("FL", "RL"), ("FR", "RR")) if f in onsets and r in onsets]
    if delays and all(d > 0 for d in delays):
        v_delay = rec.wheelbase_m / float(np.mean(delays))
        agree = len(delays) < 2 or abs(delays[0] / delays[1] - 1) < SIDES_AGREE
        doc["speed"] = {"sidecar_m_s": rec.speed_m_s, "from_delay_m_s": v_delay,
                        "delays_s": [float(d) for d in delays], "sides_agree": bool(agree)}
        if agree and abs(v_delay / rec.speed_m_s - 1) > SPEED_TOLERANCE:
            warnings.append(f"the sidecar's speed {rec.speed_kmh:.3g} km/h and the front/rear impact onsets' "
                            f"{v_delay * 3.6:.3g} km/h (wheelbase {rec.wheelbase_m:g} m / "
                            f"{np.mean(delays) * 1e3:.1f} ms) differ by {100 * (v_delay / rec.speed_m_s - 1):+.1f} % "
                            f"(the footprints shift the onsets by up to a few %; diagnose fits the delay and "
                            f"refits at its speed)")
    doc["warnings"] = warnings
    if announce:
        for w in warnings:
            print(f"cleatfmu: warning: {rec.source}: {w}", file=sys.stderr)
    changed = removed or lines or flipped
    return replace(rec, accel_m_s2={c: x[i] for i, c in enumerate(names)} if changed else rec.accel_m_s2,
                   conditioning=doc)


def conditioning_json(rec: Recording) -> dict | None:
    """What conditioning found and did (JSON-ready), or None when it changed nothing and warned of nothing.

    The speeds (sidecar, front/rear onsets) come with it; the diagnosis reports them always.
    """
    doc = rec.conditioning
    if not doc:
        return None
    keys = ("offset_drift", "engine", "steady_line", "flipped", "flip_ambiguous", "warnings")
    out = {k: doc[k] for k in keys if doc.get(k)}
    if out and "speed" in doc:
        out["speed"] = doc["speed"]
    return out or None

