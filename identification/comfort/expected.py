"""Expected ride ratings: the scatter over road realisations, and the mean a_w from the road's PSD.

One ride on one random road is one sample: over 60 s a single ride's a_w scatters by several per cent
from road to road.  :func:`realisation_seeds` derives N road seeds from one, :func:`summarise` turns the
N values of a rating into its expected value with two intervals:

* the **interval of the mean** (confidence level ``level``, default 95 %): mean ± t s / √N, Student's t
  with N − 1 degrees of freedom, s the sample standard deviation over the N rides (the ratings of
  independent roads are independent; their mean is close to normal);
* the **single-ride interval**: where one further ride on a new road falls with probability ``level``, a
  prediction interval exp(m ± t s_log √(1 + 1/N)) on the logarithms of the values (m, s_log their mean and
  standard deviation): ratings are positive and right-skewed (MTVV is a maximum), and a normal model of
  their logarithm covers them better than one of the values.

:func:`psd_rating` is the independent check of the mean: the body with linear tires is a linear system,
so the expected mean square of a weighted seat acceleration is

    a_w² = ∫ |W(f)|² Σ_ij H_i(f) S_ij(f) H_j*(f) df,

with H_i the seat acceleration per unit road height under tire i (from the model's mass, stiffness and
damping matrices, :func:`seat_transfer`), the rear tires delayed by the wheelbase, and S_ij the tracks'
cross-spectra as :mod:`~identification.comfort.road` synthesises them: S(f) = Gd(f / v) / v on each
track, the coherence γ²(n) of the road's model (uniform exp(−a n B) or by class) between the left and right
ones.  This is E[a_w²] over roads (a long ride's limit); the Monte-Carlo counterpart is √(mean a_w²) over
the realisations.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..model.tractor import LEFT_TIRES, Body
from ..recording import FRONT_TIRES

__all__ = ["DEFAULT_REALISATIONS", "MAX_REALISATIONS", "LEVEL", "realisation_seeds", "summarise", "seat_transfer",
           "psd_rating", "PSD_POINTS", "rating_values", "expected_set"]

#: Road realisations of ``cleatfmu ride`` by default (each 60 s ride takes about 0.1 s).
DEFAULT_REALISATIONS = 10
#: Most realisations accepted.
MAX_REALISATIONS = 1000
#: Confidence level of the intervals.
LEVEL = 0.95
#: Frequency points of the PSD integral (log-spaced over the road's band seen at the speed).
PSD_POINTS = 4000


def realisation_seeds(seed: int, n: int) -> list[int]:
    """The road seeds of `n` realisations derived from `seed`: `seed` itself first (the single ride of that
    seed stays the first realisation), then ``SeedSequence((seed, i)).generate_state(1)[0]`` for i = 1 .. n − 1
    (independent streams, no overlap with the neighbouring seeds' roads)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError("--seed", f"must be an integer >= 0, got {seed!r}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_REALISATIONS:
        raise InputError("--realisations", f"1 .. {MAX_REALISATIONS} expected, got {n!r}")
    return [int(seed)] + [int(np.random.SeedSequence((int(seed), i)).generate_state(1)[0]) for i in range(1, n)]


def summarise(values, level: float = LEVEL) -> dict:
    """A rating over N realisations: its expected value and scatter (see the module docstring).

    Parameters
    ----------
    values : array_like
        The rating of each ride (finite; positive for the single-ride interval).
    level : float
        Confidence level of both intervals, 0 < level < 1.

    Returns
    -------
    dict
        ``n``, ``mean``, ``std`` (sample standard deviation, N − 1), ``cv`` (std / mean), ``min``, ``max``,
        ``level``, ``mean_interval`` [low, high] and ``single_ride_interval`` [low, high] (None for N < 2).
    """
    from scipy.stats import t as student

    x = np.asarray(values, dtype=float)
    if x.ndim != 1 or x.size < 1 or not np.all(np.isfinite(x)):
        raise ValueError("values must be a non-empty 1-D array of finite numbers")
    n = x.size
    mean = float(x.mean())
    doc = {"n": n, "mean": mean, "std": None, "cv": None, "min": float(x.min()), "max": float(x.max()),
           "level": level, "mean_interval": None, "single_ride_interval": None}
    if n < 2:
        return doc
    s = float(x.std(ddof=1))
    q = float(student.ppf(0.5 + level / 2.0, n - 1))
    doc.update(std=s, cv=s / mean if mean > 0 else None,
               mean_interval=[mean - q * s / math.sqrt(n), mean + q * s / math.sqrt(n)])
    if np.all(x > 0):
        logs = np.log(x)
        m, sl = float(logs.mean()), float(logs.std(ddof=1))
        half = q * sl * math.sqrt(1.0 + 1.0 / n)
        doc["single_ride_interval"] = [math.exp(m - half), math.exp(m + half)]
    return doc


def seat_transfer(body: Body, k: dict, c: dict, row, frequency_hz) -> np.ndarray:
    """Acceleration of a body point per unit road height under each tire, from the model's matrices.

    The linear tractor M q̈ + Jᵀ C J q̇ + Jᵀ K J q = Jᵀ (K r + C ṙ) (J, M of ``body.matrices()``, K and C the
    tires' diagonal stiffness and damping) gives Q = (−ω² M + jω JᵀCJ + JᵀKJ)⁻¹ Jᵀ (K + jω C) R; the
    point's acceleration is −ω² row · Q.

    Parameters
    ----------
    body : Body
        The tractor.
    k, c : dict
        Tire -> stiffness (N/m) and damping (N s/m).
    row : array_like
        The point's displacement per generalized coordinate (e.g. :func:`identification.model.ride.seat_row`).
    frequency_hz : array_like
        Frequencies, Hz (1-D).

    Returns
    -------
    ndarray of complex, shape (frequencies, tires)
        H_i(f), (m/s²) per m, no delays (every tire's own road).
    """
    J, mass, _ = body.matrices()
    K = np.diag([float(k[t]) for t in body.tires])
    C = np.diag([float(c[t]) for t in body.tires])
    row = np.asarray(row, dtype=float)
    f = np.atleast_1d(np.asarray(frequency_hz, dtype=float))
    out = np.empty((f.size, len(body.tires)), dtype=complex)
    kk, cc = J.T @ K @ J, J.T @ C @ J
    for m, fm in enumerate(f):
        w = 2.0 * math.pi * fm
        q = np.linalg.solve(-w * w * np.diag(mass) + 1j * w * cc + kk, J.T @ (K + 1j * w * C))
        out[m] = -w * w * (row @ q)
    return out


def psd_rating(body: Body, k: dict, c: dict, row, *, road, speed_m_s: float, weighting: str = "Wk",
               points: int = PSD_POINTS, transfer=None, footprints_m: dict | None = None) -> float:
    """Expected weighted RMS acceleration of a body point on a road class, from the PSD (module docstring).

    Parameters
    ----------
    body, k, c, row
        As for :func:`seat_transfer`.
    road : RoadProfile
        Gives the band, the PSD and the tracks' coherence (:meth:`RoadProfile.psd`, :meth:`RoadProfile.coherence`;
        not the heights).
    speed_m_s : float
    weighting : str
        ISO 2631-1 weighting of the point's axis.
    points : int
        Log-spaced frequencies of the integral over the road's band seen at the speed.
    transfer : callable, optional
        A further linear stage from the point to the rated acceleration, ``transfer(frequency_hz)`` -> complex
        (e.g. a suspended seat's :meth:`~identification.comfort.seat.SeatModel.transmissibility`).
    footprints_m : dict, optional
        Tire -> footprint length, m (parabolic pressure): that tire's road is its footprint average, whose
        response (:func:`identification.model.ride.footprint_response`) multiplies its column of H.

    Returns
    -------
    float
        √E[a_w²], m/s².
    """
    from .iso2631 import weighting_response

    lo, hi = road.band_cpm
    f = np.geomspace(lo * speed_m_s, hi * speed_m_s, int(points))
    n = f / speed_m_s
    s = road.psd(n) / speed_m_s                   # m²/Hz on each track (NaN for a road from a file)
    gamma = np.sqrt(road.coherence(n))            # the road's coherence model (uniform or by class)
    delay = np.array([0.0 if t in FRONT_TIRES else body.wheelbase_m / speed_m_s for t in body.tires])
    left = np.array([t in LEFT_TIRES for t in body.tires])
    h = seat_transfer(body, k, c, row, f) * np.exp(-2j * math.pi * f[:, None] * delay[None, :])
    if transfer is not None:
        h = h * np.asarray(transfer(f))[:, None]
    if footprints_m:
        from ..model.ride import footprint_response
        h = h * np.column_stack([footprint_response(n, float(footprints_m.get(t, 0.0))) for t in body.tires])
    hl, hr = h[:, left], h[:, ~left]
    # Σ_ij H_i S_ij H_j*: S_ij = S on the same track, γ S across the tracks
    total = (np.abs(hl.sum(axis=1)) ** 2 + np.abs(hr.sum(axis=1)) ** 2
             + 2.0 * gamma * np.real(hl.sum(axis=1) * np.conj(hr.sum(axis=1))))
    integrand = np.abs(weighting_response(f, weighting)) ** 2 * total * s
    return float(math.sqrt(np.trapezoid(integrand, f)))


def rating_values(result) -> dict:
    """The ratings of one ride's :class:`~identification.comfort.iso2631.ComfortResult` as a flat dict:
    ``a_w``, ``vdv``, ``mtvv`` and, with a daily exposure, ``a8`` and ``daily_vdv`` (SI units)."""
    out = {"a_w": result.a_w, "vdv": result.vdv, "mtvv": result.mtvv}
    if result.exposure is not None:
        out.update(a8=result.exposure.a8, daily_vdv=result.exposure.vdv)
    return out


def expected_set(per_ride: list, *, body: Body, k: dict, c: dict, row, road, speed_m_s: float,
                 seeds: list, level: float = LEVEL, rows: dict | None = None, seat=None,
                 footprints_m: dict | None = None) -> dict:
    """One parameter set's expected ratings over its rides on the realisations (JSON-ready, SI units).

    Parameters
    ----------
    per_ride : list of dict
        Each realisation's :func:`rating_values` (same keys), in the order of `seeds`.
    body, k, c, row, road, speed_m_s
        As for :func:`psd_rating` (the seat's vertical row, Wk).
    seeds : list of int
        The realisations' road seeds.
    rows : dict, optional
        The seat's ``x`` and ``y`` rows (:func:`identification.comfort.seat_axes.axis_rows`): their a_w from the
        PSD (Wd) as well.
    footprints_m : dict, optional
        The set's tires' footprints (:func:`psd_rating`).
    seat : SeatModel, optional
        A suspended seat rated on the z axis: the a_w from the PSD is the linear seat's (no end-stop
        contact), with the floor's (``psd.floor_a_w``) and their ratio (``psd.seat_factor_linear``).

    Returns
    -------
    dict
        ``realisations``, ``seeds``, one :func:`summarise` per rating, and ``psd``: the a_w from the road
        PSD, the realisations' √(mean a_w²) and their ratio.
    """
    doc = {"realisations": len(per_ride), "seeds": list(seeds)}
    for key in per_ride[0]:
        doc[key] = summarise([r[key] for r in per_ride], level)
    predicted = psd_rating(body, k, c, row, road=road, speed_m_s=speed_m_s, weighting="Wk",
                           transfer=None if seat is None else seat.transmissibility, footprints_m=footprints_m)
    rms = float(math.sqrt(np.mean([r["a_w"] ** 2 for r in per_ride])))
    doc["psd"] = {"a_w": predicted, "monte_carlo_rms_a_w": rms, "ratio": rms / predicted if predicted > 0 else None}
    if seat is not None:
        floor = psd_rating(body, k, c, row, road=road, speed_m_s=speed_m_s, weighting="Wk",
                           footprints_m=footprints_m)
        doc["psd"].update(floor_a_w=floor, seat_factor_linear=predicted / floor if floor > 0 else None)
    for axis in ("x", "y") if rows is not None else ():
        doc["psd"][f"{axis}_a_w"] = psd_rating(body, k, c, rows[axis], road=road, speed_m_s=speed_m_s,
                                               weighting="Wd", footprints_m=footprints_m)
        if f"{axis}_a_w" in per_ride[0]:
            doc["psd"][f"{axis}_monte_carlo_rms_a_w"] = float(math.sqrt(np.mean([r[f"{axis}_a_w"] ** 2
                                                                                 for r in per_ride])))
    return doc
