"""Random road profiles of the ISO 8608 classes, two tracks, and the cleat on the same grid.

ISO 8608 describes a road's vertical displacement by its one-sided power
spectral density over the spatial frequency n (cycles/m)::

    Gd(n) = Gd(n0) · (n / n0)^(−w),   n0 = 0.1 cycles/m,   w = 2,

with Gd(n0) the class's geometric mean (:data:`ISO8608_GD_N0_M3`: A 16e-6 m³,
each next class four times the previous one, up to H) and the spectrum
defined over the band 0.011–2.83 cycles/m (:data:`ISO8608_BAND_CPM`).

The left and right tracks share the spectrum Gd(n); their magnitude-squared
coherence γ²(n) follows one of the models of
:mod:`~identification.comfort.coherence`: by default the uniform exponential
γ²(n) = exp(−a · n · B) (:func:`track_coherence`, B the track width, m, a the
dimensionless :data:`DEFAULT_COHERENCE_DECAY`), or, with ``coherence="class"``,
the class-dependent coherence measured on roads of classes A to E (Project
Chrono's RandomSurfaceTerrain; lower on rough roads).  Either way the tracks
are fully coherent at long wavelengths and become independent once the
wavelength is short against the track width; ISO 8608 itself does not specify
the coherence between tracks.

:func:`road_profile` synthesises both tracks as sums of harmonics with the
class's amplitudes and random phases (inverse FFT): the left track is
L(n) = A(n) e^{iφ}, the right track R(n) = γ(n) L(n) + √(1 − γ²(n)) A(n) e^{iψ}
with φ and ψ independent and uniform.  In expectation over the phases both
tracks then have the PSD Gd(n) exactly at every harmonic, and the coherence
between them is γ²(n).  A seed makes the profile reproducible.

Heights are in metres, positions in metres along the road, spatial
frequencies in cycles/m and PSDs in m³ (m² per cycle/m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ._checks import positive
from .coherence import COHERENCE_MODELS, DEFAULT_COHERENCE_DECAY, track_coherence
from .coherence import coherence as model_coherence

__all__ = ["ISO8608_N0_CPM", "ISO8608_WAVINESS", "ISO8608_BAND_CPM", "ISO8608_GD_N0_M3", "CLEAT_HEIGHT_M",
           "DEFAULT_TRACK_WIDTH_M", "DEFAULT_COHERENCE_DECAY", "COHERENCE_MODELS", "FILE_CLASS", "RoadProfile",
           "iso8608_psd", "track_coherence", "MAX_POINTS", "road_profile", "profile_height", "cleat_profile"]

#: Reference spatial frequency n0 of ISO 8608, cycles/m.
ISO8608_N0_CPM = 0.1
#: Waviness w of ISO 8608 (the PSD falls as n^-w).
ISO8608_WAVINESS = 2.0
#: Spatial-frequency band over which ISO 8608 defines the classes, cycles/m.
ISO8608_BAND_CPM = (0.011, 2.83)
#: Gd(n0) of each ISO 8608 class: the geometric mean of the class's range, m³.
ISO8608_GD_N0_M3 = {"A": 16e-6, "B": 64e-6, "C": 256e-6, "D": 1024e-6, "E": 4096e-6, "F": 16384e-6,
                    "G": 65536e-6, "H": 262144e-6}
#: Height of the cleat of the cleat test (the paper's 40 mm cleat), m.
CLEAT_HEIGHT_M = 0.04
#: Default distance between the left and right tracks, m (a mid-size tractor's track width).
DEFAULT_TRACK_WIDTH_M = 1.8
#: The class of a road read from a file (:mod:`~identification.comfort.road_files`): its spectrum and
#: coherence are those of its heights, not of a model.
FILE_CLASS = "file"
#: Largest number of grid points a profile may have.
MAX_POINTS = 20_000_000
#: The synthesis period holds at least this many cycles of the band's lowest frequency, so that the
#: lowest octave of the band has several harmonics even for a short profile.
_MIN_CYCLES_LOWEST = 8.0


def _class(road_class) -> str:
    name = str(road_class).strip().upper()
    if name not in ISO8608_GD_N0_M3:
        raise InputError("road class", f"unknown ISO 8608 class {road_class!r} "
                                       f"(allowed: {', '.join(ISO8608_GD_N0_M3)})")
    return name


def _positive(value, what: str) -> float:
    return positive(what, value)


def _band(band_cpm) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in band_cpm)
    except (TypeError, ValueError):
        raise InputError("band", f"must be two spatial frequencies (low, high) in cycles/m, got {band_cpm!r}") \
            from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise InputError("band", f"needs 0 < low < high (cycles/m), got {band_cpm!r}")
    return lo, hi


def iso8608_psd(n_cpm, road_class: str = "A", *, band_cpm=ISO8608_BAND_CPM) -> np.ndarray:
    """The ISO 8608 displacement PSD of a class, Gd(n) = Gd(n0) (n / n0)^-2.

    Parameters
    ----------
    n_cpm : array_like
        Spatial frequencies, cycles/m.
    road_class : str
        ISO 8608 class, ``"A"`` to ``"H"``.
    band_cpm : tuple of float, optional
        The band (low, high) in cycles/m; the PSD is zero outside it (default: ISO 8608's
        0.011–2.83 cycles/m).  None: no band limit (n must then be > 0).

    Returns
    -------
    ndarray
        Gd(n), m³, the shape of `n_cpm`.

    Raises
    ------
    InputError
        An unknown class or a bad band.
    """
    gd0 = ISO8608_GD_N0_M3[_class(road_class)]
    n = np.asarray(n_cpm, dtype=float)
    with np.errstate(divide="ignore"):
        psd = gd0 * (np.abs(n) / ISO8608_N0_CPM) ** (-ISO8608_WAVINESS)
    if band_cpm is None:
        return np.where(n > 0, psd, 0.0)
    lo, hi = _band(band_cpm)
    return np.where((n >= lo) & (n <= hi), psd, 0.0)


@dataclass(frozen=True, eq=False)
class RoadProfile:
    """A two-track road profile on a regular grid.

    Attributes
    ----------
    x_m : ndarray
        Positions along the road, m (0, s, 2 s, ...).
    left_m, right_m : ndarray
        Heights of the left and right tracks, m.
    road_class : str
        ISO 8608 class, or :data:`FILE_CLASS` for a road read from a file.
    gd_n0_m3 : float
        The class's Gd(n0), m³ (NaN for a road from a file).
    band_cpm : tuple of float
        Band of the synthesised spectrum, cycles/m.
    track_width_m : float
        Distance between the tracks, m.
    coherence_decay : float
        Decay a of the uniform coherence model γ²(n) = exp(−a n B).
    seed : int
        Seed of the random phases (-1 for a road from a file).
    period_m : float
        Period of the synthesis (the profile repeats after it; ≥ the profile's length), m.
    coherence_model : str
        ``"uniform"`` or ``"class"`` (:data:`COHERENCE_MODELS`), the model of the tracks' coherence.
    """

    x_m: np.ndarray
    left_m: np.ndarray
    right_m: np.ndarray
    road_class: str
    gd_n0_m3: float
    band_cpm: tuple
    track_width_m: float
    coherence_decay: float
    seed: int
    period_m: float = 0.0
    coherence_model: str = "uniform"

    @property
    def spacing_m(self) -> float:
        """Grid spacing, m."""
        return float(self.x_m[1] - self.x_m[0])

    @property
    def length_m(self) -> float:
        """Length of the profile, m (last position)."""
        return float(self.x_m[-1])

    @property
    def metadata(self) -> dict:
        """What describes the profile (JSON-ready, SI units; the heights excluded)."""
        return {"standard": "ISO 8608", "road_class": self.road_class, "gd_n0_m3": self.gd_n0_m3,
                "n0_cpm": ISO8608_N0_CPM, "waviness": ISO8608_WAVINESS, "band_cpm": list(self.band_cpm),
                "length_m": self.length_m, "spacing_m": self.spacing_m, "n_points": int(self.x_m.size),
                "coherence": self.coherence_model, "coherence_decay": self.coherence_decay,
                "coherence_model": {"uniform": "exp(-a n B)", "class": "[1 + (2 pi n B / Omega_p)^2]^(-p)"}.get(
                    self.coherence_model, "none"),
                "track_width_m": self.track_width_m, "seed": self.seed, "period_m": self.period_m,
                "rms_left_m": float(np.std(self.left_m)), "rms_right_m": float(np.std(self.right_m))}

    def psd(self, n_cpm) -> np.ndarray:
        """The one-track displacement PSD Gd(n) the road was synthesised with, m³ (NaN for a road from a file)."""
        if self.road_class == FILE_CLASS:
            return np.full(np.shape(n_cpm), np.nan)
        return iso8608_psd(n_cpm, self.road_class, band_cpm=None)

    def coherence(self, n_cpm) -> np.ndarray:
        """The tracks' magnitude-squared coherence γ²(n) the road was synthesised with (NaN for a file's road)."""
        if self.road_class == FILE_CLASS:
            return np.full(np.shape(n_cpm), np.nan)
        return model_coherence(n_cpm, self.track_width_m, model=self.coherence_model, road_class=self.road_class,
                               decay=self.coherence_decay)

    def height(self, x_m, track: str = "left", *, fill: float | None = None) -> np.ndarray:
        """Height of a track at arbitrary positions (see :func:`profile_height`)."""
        return profile_height(self, x_m, track, fill=fill)


def _fast_length(n: int) -> int:
    """The smallest 2^a 3^b 5^c ≥ n (a fast FFT length)."""
    best = 1 << max(0, (n - 1).bit_length())
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            m = p35
            while m < n:
                m *= 2
            best = min(best, m)
            p35 *= 3
        p5 *= 5
    return best


def road_profile(road_class: str, length_m: float, spacing_m: float, seed: int, *,
                 track_width_m: float = DEFAULT_TRACK_WIDTH_M, coherence_decay: float = DEFAULT_COHERENCE_DECAY,
                 band_cpm=ISO8608_BAND_CPM, coherence: str = "uniform") -> RoadProfile:
    """A random two-track road of an ISO 8608 class, reproducible from its seed.

    Both tracks have the class's PSD Gd(n) over `band_cpm` (zero outside) in expectation, and
    the magnitude-squared coherence γ²(n) of the `coherence` model between them (see the module
    docstring for the synthesis).  Each track has zero mean over the synthesis period.

    Parameters
    ----------
    road_class : str
        ISO 8608 class, ``"A"`` (best) to ``"H"``.
    length_m : float
        Length of the profile, m (> 0).
    spacing_m : float
        Grid spacing, m; at most 1 / (2 n_high), so that the grid resolves the band's highest
        frequency (0.1767 m for ISO 8608's band).
    seed : int
        Seed of the random phases (same seed, same profile).
    track_width_m : float, optional
        Distance B between the tracks, m (default :data:`DEFAULT_TRACK_WIDTH_M`).
    coherence_decay : float, optional
        Decay a ≥ 0 of the coherence model (default :data:`DEFAULT_COHERENCE_DECAY`; 0: identical
        tracks).
    band_cpm : tuple of float, optional
        Band (low, high) of the spectrum, cycles/m (default ISO 8608's 0.011–2.83).
    coherence : {"uniform", "class"}, optional
        The tracks' coherence model (:mod:`~identification.comfort.coherence`): ``"uniform"``
        (default) exp(−a n B) with a = `coherence_decay`; ``"class"`` the class-dependent measured
        coherence (classes A to E; `coherence_decay` is then not used).  The left track is the
        same for both models and a seed.

    Returns
    -------
    RoadProfile
        Positions 0, s, 2 s, ... up to round(length / s) s, and both tracks' heights.

    Raises
    ------
    InputError
        Unknown class, non-positive length or spacing, a spacing too coarse for the band,
        a synthesis of more than :data:`MAX_POINTS` points, a bad seed, width or decay.
    """
    name = _class(road_class)
    length = _positive(length_m, "length")
    dx = _positive(spacing_m, "spacing")
    lo, hi = _band(band_cpm)
    track_coherence(0.0, track_width_m, decay=coherence_decay)      # checks the width and the decay
    if coherence not in COHERENCE_MODELS:
        raise InputError("coherence", f"unknown coherence model {coherence!r} (allowed: {', '.join(COHERENCE_MODELS)})")
    model_coherence(0.0, track_width_m, model=coherence, road_class=name)    # checks the class has the model
    if dx > 1.0 / (2.0 * hi) * (1 + 1e-12):
        raise InputError("spacing", f"{dx:g} m is too coarse for the band up to {hi:g} cycles/m "
                                    f"(at most 1/(2 n_high) = {1.0 / (2.0 * hi):.4g} m)")
    if dx > length:
        raise InputError("spacing", f"{dx:g} m is longer than the profile ({length:g} m)")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError("seed", f"must be an integer >= 0, got {seed!r}")
    n_points = int(round(length / dx)) + 1
    wanted = max(n_points, int(math.ceil(_MIN_CYCLES_LOWEST / (lo * dx))))
    if wanted > MAX_POINTS:
        raise InputError("spacing", f"the synthesis needs {wanted} points, more than {MAX_POINTS} (length "
                                    f"{length:g} m, spacing {dx:g} m, lowest frequency {lo:g} cycles/m)")
    m = _fast_length(wanted)
    period = m * dx
    n = np.arange(m // 2 + 1) / period
    inside = (n >= lo) & (n <= hi) & (np.arange(n.size) > 0)
    if m % 2 == 0:
        inside[-1] = False                        # the Nyquist bin carries no phase
    gd = ISO8608_GD_N0_M3[name] * (n[inside] / ISO8608_N0_CPM) ** (-ISO8608_WAVINESS)
    amplitude = np.sqrt(2.0 * gd / period)        # A_k of A_k cos(2 pi n_k x + phi_k); variance sum Gd dn
    gamma = np.sqrt(model_coherence(n[inside], track_width_m, model=coherence, road_class=name, decay=coherence_decay))
    rng = np.random.default_rng(int(seed))
    phase_left = np.exp(2j * np.pi * rng.random(amplitude.size))
    phase_own = np.exp(2j * np.pi * rng.random(amplitude.size))
    spec_left = np.zeros(n.size, dtype=complex)
    spec_right = np.zeros(n.size, dtype=complex)
    spec_left[inside] = amplitude * phase_left
    spec_right[inside] = amplitude * (gamma * phase_left + np.sqrt(1.0 - gamma ** 2) * phase_own)
    scale = m / 2.0                               # irfft: x_j = (2/m) sum_k Re(X_k e^{2 pi i k j / m})
    left = np.fft.irfft(spec_left * scale, m)[:n_points]
    right = np.fft.irfft(spec_right * scale, m)[:n_points]
    x = dx * np.arange(n_points)
    return RoadProfile(x_m=x, left_m=left, right_m=right, road_class=name, gd_n0_m3=ISO8608_GD_N0_M3[name],
                       band_cpm=(lo, hi), track_width_m=float(track_width_m), coherence_decay=float(coherence_decay),
                       seed=int(seed), period_m=float(period), coherence_model=coherence)


def profile_height(profile: RoadProfile, x_m, track: str = "left", *, fill: float | None = None) -> np.ndarray:
    """Height of a profile's track at arbitrary positions, by linear interpolation.

    Parameters
    ----------
    profile : RoadProfile
        The road.
    x_m : array_like
        Positions along the road, m.
    track : {"left", "right"}
        The track.
    fill : float, optional
        Height returned outside the profile's positions; None (default): positions outside
        raise InputError.

    Returns
    -------
    ndarray
        Heights, m, the shape of `x_m`.
    """
    if track not in ("left", "right"):
        raise InputError("track", f"must be 'left' or 'right', got {track!r}")
    heights = profile.left_m if track == "left" else profile.right_m
    x = np.asarray(x_m, dtype=float)
    if not np.all(np.isfinite(x)):
        raise InputError("position", "positions must be finite numbers")
    x0, x1 = float(profile.x_m[0]), float(profile.x_m[-1])
    if fill is None:
        if x.size and (x.min() < x0 or x.max() > x1):
            raise InputError("position", f"positions {x.min():g}..{x.max():g} m leave the profile "
                                         f"({x0:g}..{x1:g} m); give fill= for a height outside")
        return np.interp(x, profile.x_m, heights)
    return np.interp(x, profile.x_m, heights, left=float(fill), right=float(fill))


def cleat_profile(x_m, position_m: float, width_m: float, height_m: float = CLEAT_HEIGHT_M) -> np.ndarray:
    """The cleat of the cleat test as a height profile on a grid.

    The cleat is a rectangular block of height H and width w whose leading edge (the edge a
    tire meets first) is at `position_m`: the height is H for position ≤ x < position + w and
    zero elsewhere, as the point-contact road of :mod:`identification.rig.road`.  Interpolated
    linearly between grid points, its edges become ramps one grid spacing long.

    Parameters
    ----------
    x_m : array_like
        Increasing positions along the road, m (e.g. a :class:`RoadProfile`'s ``x_m``).
    position_m : float
        Position of the leading edge, m.
    width_m : float
        Width of the cleat along the road, m (> 0, at least the largest grid spacing).
    height_m : float, optional
        Height of the cleat, m (default 0.04 m, the paper's cleat).

    Returns
    -------
    ndarray
        Heights, m, the shape of `x_m`.

    Raises
    ------
    InputError
        Non-increasing positions, a non-positive width or height, a width smaller than the grid
        spacing (the cleat could fall between two points), or a cleat off the grid.
    """
    x = np.asarray(x_m, dtype=float)
    if x.ndim != 1 or x.size < 2 or not np.all(np.isfinite(x)) or np.any(np.diff(x) <= 0):
        raise InputError("positions", "the grid must be at least two increasing finite positions")
    w = _positive(width_m, "cleat width")
    h = _positive(height_m, "cleat height")
    try:
        p = float(position_m)
    except (TypeError, ValueError):
        raise InputError("cleat position", f"must be a number, got {position_m!r}") from None
    if not math.isfinite(p):
        raise InputError("cleat position", f"must be finite, got {position_m!r}")
    step = float(np.max(np.diff(x)))
    if w < step:
        raise InputError("cleat width", f"{w:g} m is narrower than the grid spacing ({step:g} m)")
    if p < x[0] or p + w > x[-1]:
        raise InputError("cleat position", f"the cleat {p:g}..{p + w:g} m is not inside the grid "
                                           f"({x[0]:g}..{x[-1]:g} m)")
    return np.where((x >= p) & (x < p + w), h, 0.0)
