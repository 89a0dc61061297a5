"""A suspended operator seat on the tractor's floor, and its SEAT factor (ISO 10326-1).

The seat is one mass on a linear spring and damper between the floor and the occupant, with end stops:
in the seat's travel z (occupant relative to the floor, + up, 0 at the ride height the seat's weight
adjustment sets), with the floor's vertical acceleration a_f(t) as base excitation,

    m z̈ + c ż + k z + F_stop(z) = −m a_f(t),      F_stop(z) = k_stop (|z| − d) sign z  for |z| > d, else 0,

and the occupant's acceleration is a_f + z̈ = −(c ż + k z + F_stop(z)) / m.  Without end-stop contact the
seat is linear, with the transmissibility H(s) = (c s + k) / (m s² + c s + k) from floor to occupant
(:meth:`SeatModel.transmissibility`).  :func:`seat_response` steps the equation with the classical
Runge-Kutta scheme (4th order) on the record's uniform grid, the floor's acceleration linear between its
samples (sub-steps where the end stops are stiff for the grid), and counts the end-stop contacts.

The **SEAT factor** (seat effective amplitude transmissibility, ISO 10326-1, used by ISO 5007 and
ISO 7096) is the ratio of the Wk-weighted RMS accelerations a_w(seat) / a_w(floor) (ISO 2631-1,
:func:`identification.comfort.iso2631.comfort`): below 1 the seat isolates.  :func:`seat_ride` gives it
on a floor record (a ride's), :func:`class_seat_factor` on the input spectral classes of agricultural
wheeled tractors, in the time domain (the seat on a random floor record of the class's PSD, end stops
included) and in the frequency domain for the linear seat (:func:`spectral_seat_factor`),

    SEAT² = ∫ |Wk(f) H(f)|² S(f) df / ∫ |Wk(f)|² S(f) df.

**Input spectra.**  ISO 5007:2003 defines three input spectral classes for agricultural wheeled tractors
with unsprung rear axles and no low-frequency cab isolation, by unladen mass: class I up to 3 600 kg,
class II 3 600 kg to 6 500 kg, class III over 6 500 kg (the standard's public scope).  The standard's
text is not public; the PSDs used here are those of the HVLab HRV Toolbox for MATLAB (ISVR, University
of Southampton; ``hvtestspectrum.m``, issue 1.1 of 4 Dec 2009 by C. Lewis, citing BS ISO 5007:2003 for its
test signals ``ag1``, ``ag2``, ``ag3``): an 8-pole Butterworth high-pass at f_h times an 8-pole
Butterworth low-pass at f_l, scaled by G,

    S(f) = G (f/f_h)¹⁶ / (1 + (f/f_h)¹⁶) · 1 / (1 + (f/f_l)¹⁶)      (m/s²)²/Hz,

with (f_h, f_l, G) = (3.0 Hz, 3.5 Hz, 9.25), (2.1 Hz, 2.6 Hz, 7.22), (1.95 Hz, 2.45 Hz, 5.85) for classes
I, II, III (:data:`ISO5007_CLASSES`).  Their RMS values, 2.26, 1.94 and 1.74 m/s², are the unweighted
RMS targets of the same toolbox's test signals (``hvtestsignal.m``): the two statements agree.  They are
this toolbox's reading of the standard, not checked against its text; the tolerances of the standard
(and of its test rigs) are not modelled.

**Seat defaults** (:data:`DEFAULT_SEAT`), a passive mechanical suspension seat of a mid-size tractor.
They are engineering choices within the ranges commonly quoted for such seats, not a measured seat:
suspended mass 90 kg (about three quarters of a 95 kg operator rests on the seat pan, the rest on the
floor through the legs, plus about 20 kg of the seat's suspended upper part); natural frequency 1.6 Hz
and damping ratio 0.3 (k 9.1 kN/m, c 540 N s/m; the quoted ranges are about 1.5-2 Hz and 0.2-0.4; such a
seat isolates above √2 × 1.6 = 2.3 Hz, where ISO 5007's inputs peak, 2.2-3.2 Hz); ±50 mm free travel (a
100 mm stroke); rubber end stops of 200 kN/m (22 times the spring, a 7.5 Hz bounce of the suspended mass
on them).  A measured seat's values belong in a seat file (:func:`read_seat`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

import numpy as np

from ..errors import InputError
from ._checks import positive

__all__ = ["SeatModel", "DEFAULT_SEAT", "read_seat", "SeatResponse", "seat_response", "SeatRide", "seat_ride",
           "InputClass", "ISO5007_CLASSES", "ISO5007_SOURCE", "class_psd", "class_record", "spectral_seat_factor",
           "class_seat_factor", "class_of_mass", "CLASS_SAMPLE_RATE_HZ", "CLASS_DURATION_S"]

#: Plausible ranges of a seat's values (the file's keys): (low, high), inclusive.
_RANGES = {"mass_kg": (10.0, 300.0), "stiffness_N_per_m": (100.0, 1e7), "damping_N_s_per_m": (0.0, 1e6),
           "travel_m": (1e-3, 0.5), "end_stop_stiffness_N_per_m": (1e3, 1e9)}


@dataclass(frozen=True)
class SeatModel:
    """A passive suspension seat with end stops (module docstring; defaults: :data:`DEFAULT_SEAT`).

    Attributes
    ----------
    mass_kg : float
        Suspended mass: the occupant's share resting on the seat pan and the seat's suspended part, kg.
    stiffness_N_per_m : float
        Suspension spring, N/m.
    damping_N_s_per_m : float
        Suspension damper (linear), N s/m.
    travel_m : float
        Free travel each way from the ride height before the end stops, m.
    end_stop_stiffness_N_per_m : float
        Stiffness of each end stop beyond the free travel, N/m.
    """

    mass_kg: float = 90.0
    stiffness_N_per_m: float = 9.1e3
    damping_N_s_per_m: float = 540.0
    travel_m: float = 0.05
    end_stop_stiffness_N_per_m: float = 2e5

    def __post_init__(self):
        for f in fields(self):
            _check_value(f.name, getattr(self, f.name), "seat")

    @property
    def natural_frequency_hz(self) -> float:
        """Undamped natural frequency √(k/m) / 2π, Hz."""
        return math.sqrt(self.stiffness_N_per_m / self.mass_kg) / (2.0 * math.pi)

    @property
    def damping_ratio(self) -> float:
        """c / (2 √(k m))."""
        return self.damping_N_s_per_m / (2.0 * math.sqrt(self.stiffness_N_per_m * self.mass_kg))

    def transmissibility(self, frequency_hz) -> np.ndarray:
        """Complex acceleration transmissibility floor -> occupant of the linear seat (no end-stop contact),
        H(j 2π f) = (c s + k) / (m s² + c s + k)."""
        s = 2j * np.pi * np.asarray(frequency_hz, dtype=float)
        k, c, m = self.stiffness_N_per_m, self.damping_N_s_per_m, self.mass_kg
        return (c * s + k) / (m * s * s + c * s + k)

    @classmethod
    def from_json(cls, path) -> "SeatModel":
        """The seat of a PARAMS JSON file (:func:`read_seat`)."""
        return read_seat(path)

    def to_json(self) -> dict:
        """The seat's values (the file's keys) with its natural frequency and damping ratio (SI units)."""
        return {**asdict(self), "natural_frequency_hz": self.natural_frequency_hz,
                "damping_ratio": self.damping_ratio}


def _check_value(key: str, value, source) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(source, f"{key} must be a number, got {value!r}")
    lo, hi = _RANGES[key]
    try:
        v = float(value)
    except OverflowError:                # an integer beyond the float range
        raise InputError(source, f"{key}: a number far beyond a seat's {lo:g} .. {hi:g}") from None
    if not (math.isfinite(v) and lo <= v <= hi):
        raise InputError(source, f"{key} = {value!r}: a seat's is {lo:g} .. {hi:g}")
    return v


#: The default seat (module docstring).
DEFAULT_SEAT = SeatModel()


def read_seat(path) -> SeatModel:
    """The seat of a PARAMS JSON file: an object with any of the keys ``mass_kg``, ``stiffness_N_per_m``,
    ``damping_N_s_per_m``, ``travel_m``, ``end_stop_stiffness_N_per_m`` (SI numbers; a key left out takes
    :data:`DEFAULT_SEAT`'s value) and optionally ``comment`` (text).  Any other key, a value that is no
    number or outside a seat's range raises :class:`~identification.errors.InputError` naming the file."""
    from .._inputs import read_json_file

    doc = read_json_file(path)
    if not isinstance(doc, dict):
        raise InputError(path, "a seat file is a JSON object, e.g. {\"mass_kg\": 90, \"stiffness_N_per_m\": 9100}")
    keys = [f.name for f in fields(SeatModel)]
    unknown = [k for k in doc if k not in keys and k != "comment"]
    if unknown:
        raise InputError(path, f"unknown key {unknown[0]!r} (keys: {', '.join(keys)}, comment)")
    if "comment" in doc and not isinstance(doc["comment"], str):
        raise InputError(path, "comment must be text")
    return SeatModel(**{k: _check_value(k, doc[k], path) for k in keys if k in doc})


@dataclass(frozen=True, eq=False)
class SeatResponse:
    """The seat on a floor record: the occupant's acceleration `seat_m_s2` (m/s²) and the travel `travel_m`
    (occupant relative to the floor, m) on the record's grid, and the end stops' contacts (over the samples
    rated: `end_stop_hits` contacts begun, `end_stop_share` of the time in contact, `max_travel_m`)."""

    seat_m_s2: np.ndarray
    travel_m: np.ndarray
    end_stop_hits: int
    end_stop_share: float
    max_travel_m: float

    def end_stops(self) -> dict:
        """The end-stop statistics, JSON-ready."""
        return {"hits": self.end_stop_hits, "share": self.end_stop_share, "max_travel_m": self.max_travel_m}


def _contacts(travel: np.ndarray, d: float) -> tuple:
    hit = np.abs(travel) > d
    starts = int(np.count_nonzero(hit[1:] & ~hit[:-1]) + (1 if hit.size and hit[0] else 0))
    return starts, float(hit.mean()) if hit.size else 0.0


def seat_response(seat: SeatModel, floor_m_s2, sample_rate_hz: float, *, keep=None) -> SeatResponse:
    """Step the seat on the floor's vertical acceleration (module docstring), from rest at ride height.

    Parameters
    ----------
    seat : SeatModel
    floor_m_s2 : array_like
        The floor's vertical acceleration under the seat, m/s², uniformly sampled (1-D, finite).
    sample_rate_hz : float
    keep : slice or array of bool or int, optional
        The samples the returned arrays and end-stop statistics cover (default all; e.g. a ride's samples
        after its fade-in: the seat is stepped over the whole record all the same).

    Returns
    -------
    SeatResponse
    """
    fs = positive("sample_rate_hz", sample_rate_hz)
    a = np.asarray(floor_m_s2, dtype=float)
    if a.ndim != 1 or a.size < 2 or not np.all(np.isfinite(a)):
        raise InputError("floor_m_s2", "must be a 1-D array of at least 2 finite accelerations")
    m, k, c = seat.mass_kg, seat.stiffness_N_per_m, seat.damping_N_s_per_m
    d, ks = seat.travel_m, seat.end_stop_stiffness_N_per_m
    # sub-steps: the stiffest mode (on an end stop) resolved at ≤ 0.25 rad per step, well inside RK4's accuracy
    sub = max(1, math.ceil(math.sqrt((k + ks) / m) / fs / 0.25))
    h = 1.0 / (fs * sub)

    def accel(z, v, af):
        f = c * v + k * z
        if z > d:
            f += ks * (z - d)
        elif z < -d:
            f += ks * (z + d)
        return -f / m - af               # z̈ = −(c ż + k z + F_stop) / m − a_f

    n = a.size
    z = np.zeros(n)
    zdd = np.zeros(n)
    zi = vi = 0.0
    zdd[0] = accel(0.0, 0.0, a[0])
    for i in range(n - 1):
        a0, da = a[i], (a[i + 1] - a[i]) / sub
        for j in range(sub):
            af0, af1 = a0 + j * da, a0 + (j + 1) * da
            afm = 0.5 * (af0 + af1)
            k1v = accel(zi, vi, af0)
            k2z, k2v = vi + 0.5 * h * k1v, accel(zi + 0.5 * h * vi, vi + 0.5 * h * k1v, afm)
            k3z, k3v = vi + 0.5 * h * k2v, accel(zi + 0.5 * h * k2z, vi + 0.5 * h * k2v, afm)
            k4z, k4v = vi + h * k3v, accel(zi + h * k3z, vi + h * k3v, af1)
            zi, vi = (zi + h / 6.0 * (vi + 2.0 * k2z + 2.0 * k3z + k4z),
                      vi + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v))
        z[i + 1] = zi
        zdd[i + 1] = accel(zi, vi, a[i + 1])
    sel = slice(None) if keep is None else keep
    z, acc = z[sel], (a + zdd)[sel]
    hits, share = _contacts(z, d)
    return SeatResponse(acc, z, hits, share, float(np.max(np.abs(z))) if z.size else 0.0)


@dataclass(frozen=True, eq=False)
class SeatRide:
    """A floor record rated on the seat: the :class:`SeatResponse`, the floor's acceleration rated
    (`floor_m_s2`, m/s²), the ISO 2631-1 Wk ratings of the occupant (`seat`) and of the floor (`floor`), and the
    SEAT factor a_w(seat) / a_w(floor)."""

    response: SeatResponse
    floor_m_s2: np.ndarray
    seat: object                 # ComfortResult
    floor: object                # ComfortResult
    seat_factor: float

    def values(self) -> dict:
        """Flat values for expected values over realisations (SI units)."""
        return {"seat_factor": self.seat_factor, "floor_a_w": self.floor.a_w,
                "end_stop_hits": float(self.response.end_stop_hits), "end_stop_share": self.response.end_stop_share}

    def to_json(self) -> dict:
        """JSON-ready (SI units): the SEAT factor, the seat's and the floor's ratings, the end stops."""
        return {"seat_factor": self.seat_factor, "seat": self.seat.to_json(), "floor": self.floor.to_json(),
                "end_stops": self.response.end_stops()}


def seat_ride(seat: SeatModel, floor_m_s2, sample_rate_hz: float, *, keep=None,
              exposure_h: float | None = None) -> SeatRide:
    """The seat on a floor record, the occupant and the floor rated by ISO 2631-1 (Wk) over `keep`.

    Parameters
    ----------
    seat : SeatModel
    floor_m_s2 : array_like
        The floor's vertical acceleration, m/s² (see :func:`seat_response`).
    sample_rate_hz : float
    keep : slice or array of bool or int, optional
        The samples rated (default all).
    exposure_h : float, optional
        Daily exposure for A(8) and the daily VDV.

    Returns
    -------
    SeatRide
    """
    from .iso2631 import comfort

    response = seat_response(seat, floor_m_s2, sample_rate_hz, keep=keep)
    floor = np.asarray(floor_m_s2, dtype=float)[slice(None) if keep is None else keep]
    on_seat = comfort(response.seat_m_s2, sample_rate_hz, "Wk", exposure_h=exposure_h)
    on_floor = comfort(floor, sample_rate_hz, "Wk", exposure_h=exposure_h)
    ratio = on_seat.a_w / on_floor.a_w if on_floor.a_w > 0 else math.nan
    return SeatRide(response, floor, on_seat, on_floor, ratio)


# ----------------------------------------------------------------------------- ISO 5007 input classes

@dataclass(frozen=True)
class InputClass:
    """An input spectral class (module docstring): 8-pole Butterworth high-pass `high_pass_hz`, low-pass
    `low_pass_hz`, scale `scale_m2_s4_per_hz` ((m/s²)²/Hz), for tractors of `tractor_mass`."""

    name: str
    tractor_mass: str
    high_pass_hz: float
    low_pass_hz: float
    scale_m2_s4_per_hz: float


#: ISO 5007's input spectral classes of agricultural wheeled tractors, as the HVLab toolbox gives them.
ISO5007_CLASSES = {"I": InputClass("I", "up to 3600 kg", 3.0, 3.5, 9.25),
                   "II": InputClass("II", "3600 to 6500 kg", 2.1, 2.6, 7.22),
                   "III": InputClass("III", "over 6500 kg", 1.95, 2.45, 5.85)}
#: Where the spectra come from.
ISO5007_SOURCE = ("ISO 5007:2003 classes as implemented by the HVLab HRV Toolbox (ISVR, University of "
                  "Southampton), hvtestspectrum.m issue 1.1 (2009): 8-pole Butterworth band, not checked against "
                  "the standard's text")
#: Sampling rate (Hz), length (s) of a class's random floor record by default, and the seat's settling before it, s.
CLASS_SAMPLE_RATE_HZ, CLASS_DURATION_S, _SETTLE_S = 200.0, 120.0, 5.0


def _input_class(name) -> InputClass:
    if isinstance(name, InputClass):
        return name
    key = {"1": "I", "2": "II", "3": "III"}.get(str(name).strip(), str(name).strip().upper())
    if key not in ISO5007_CLASSES:
        raise InputError("--class", f"unknown ISO 5007 input class {name!r} (I, II or III)")
    return ISO5007_CLASSES[key]


def class_of_mass(tractor_mass_kg: float) -> str:
    """The ISO 5007 input class of a tractor of `tractor_mass_kg` (its unladen mass in the standard): ``I`` up
    to 3600 kg, ``II`` up to 6500 kg, ``III`` above."""
    m = positive("tractor_mass_kg", tractor_mass_kg)
    return "I" if m <= 3600.0 else "II" if m <= 6500.0 else "III"


def class_psd(frequency_hz, input_class) -> np.ndarray:
    """The floor's acceleration PSD of an ISO 5007 input class (module docstring), (m/s²)²/Hz."""
    cls = _input_class(input_class)
    f = np.abs(np.asarray(frequency_hz, dtype=float))
    hp = (f / cls.high_pass_hz) ** 16
    return cls.scale_m2_s4_per_hz * hp / (1.0 + hp) / (1.0 + (f / cls.low_pass_hz) ** 16)


def class_record(input_class, *, duration_s: float = CLASS_DURATION_S,
                 sample_rate_hz: float = CLASS_SAMPLE_RATE_HZ, seed: int = 1) -> np.ndarray:
    """A random floor acceleration of an input class, m/s²: harmonics at multiples of 1 / `duration_s` with
    the amplitudes √(2 S(f) Δf) of the class's PSD and random phases (seeded), so that the record's mean
    square is ∫ S df up to the Nyquist frequency."""
    fs = positive("sample_rate_hz", sample_rate_hz)
    n = int(round(positive("duration_s", duration_s) * fs))
    if n < 16:
        raise InputError("duration_s", f"a record of at least 16 samples is needed, got {n}")
    f = np.fft.rfftfreq(n, 1.0 / fs)
    amp = np.sqrt(2.0 * class_psd(f, input_class) * fs / n)
    amp[0] = 0.0
    if n % 2 == 0:
        amp[-1] = 0.0
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError("--seed", f"must be an integer >= 0, got {seed!r}")
    phase = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, f.size)
    return np.fft.irfft(0.5 * n * amp * np.exp(1j * phase), n)


def spectral_seat_factor(seat: SeatModel, input_class, *, points: int = 20000) -> float:
    """The linear seat's SEAT factor on an input class, √(∫|Wk H|² S df / ∫|Wk|² S df) (no end-stop
    contact), the integrals on `points` frequencies over 0.1-40 Hz (the class PSDs are negligible outside)."""
    from .iso2631 import weighting_response

    f = np.linspace(0.1, 40.0, int(points))
    wk2s = np.abs(weighting_response(f, "Wk")) ** 2 * class_psd(f, input_class)
    return float(math.sqrt(np.trapezoid(wk2s * np.abs(seat.transmissibility(f)) ** 2, f) / np.trapezoid(wk2s, f)))


def class_seat_factor(seat: SeatModel, input_class, *, duration_s: float = CLASS_DURATION_S,
                      sample_rate_hz: float = CLASS_SAMPLE_RATE_HZ, seed: int = 1) -> dict:
    """The seat's SEAT factor on an ISO 5007 input class, in the time and in the frequency domain.

    The seat is stepped on :func:`class_record` (`duration_s` rated after 5 s of settling on the record's
    periodic continuation) and rated with
    :func:`seat_ride`; :func:`spectral_seat_factor` gives the linear seat's value.

    Returns
    -------
    dict
        ``class``, ``tractor_mass``, ``input_rms`` (√∫S df, m/s²), ``floor_a_w`` (m/s²), ``seat_a_w``,
        ``seat_factor`` (time domain), ``seat_factor_linear`` (frequency domain), ``end_stops``,
        ``duration_s``, ``sample_rate_hz``, ``seed``.
    """
    cls = _input_class(input_class)
    fs = positive("sample_rate_hz", sample_rate_hz)
    skip = int(round(_SETTLE_S * fs))
    floor = class_record(cls, duration_s=positive("duration_s", duration_s), sample_rate_hz=fs, seed=seed)
    # the record is periodic: its last 5 s lead in, and the rated part is one whole period (Parseval's mean square)
    rated = seat_ride(seat, np.concatenate((floor[-skip:], floor)), fs, keep=slice(skip, None))
    f = np.linspace(0.1, 40.0, 20000)
    return {"class": cls.name, "tractor_mass": cls.tractor_mass,
            "input_rms": float(math.sqrt(np.trapezoid(class_psd(f, cls), f))),
            "floor_a_w": rated.floor.a_w, "seat_a_w": rated.seat.a_w, "seat_factor": rated.seat_factor,
            "seat_factor_linear": spectral_seat_factor(seat, cls), "end_stops": rated.response.end_stops(),
            "duration_s": float(duration_s), "sample_rate_hz": fs, "seed": int(seed)}
