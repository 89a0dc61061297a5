"""The whole-tractor diagnosis problem and its fitting models: all channels of a recording, one body.

A model is the four-corner baseline plus a set of effects.  Tire-side effects
(:data:`TIRE_EFFECTS`) act on every tire, with parameters per axle where the
rig or a real tractor differ front to rear (footprint, lug frequency and
amplitude); body effects change the body (:class:`identification.model.Body`):

``axle_coupling``
    front/rear interference through pitch (half-tractors per side; with
    ``roll_coupling`` the rigid tractor), parameter ``pitch_index``;
``roll_coupling``
    left/right interference through roll (axle pairs; with
    ``axle_coupling`` the rigid tractor), parameter ``roll_index``;
``front_axle_pivot``
    the front axle rolls about a longitudinal pivot and carries no roll
    moment to the body (needs both couplings), parameter ``pivot_index``.

Every model fits each recorded tire's k and c and the arrivals: ``arrival``
(the left front wheel's, s), ``stagger`` (right after left, s; when both sides
are recorded) and ``delay`` (rear after front, s; when both axles are
recorded - the speed it implies is wheelbase / delay).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from . import Body, Cleat, TractorModel
from .kernels import run_model
from .sensing import sensed_lowpassed, sensed_lowpassed_reference
from ..recording.preprocess import DEFAULT_CUTOFF_HZ, broadband_noise, noise_rms, preprocess
from ..recording import FRONT_TIRES, TIRES, Recording
from . import tire_law

__all__ = ["EFFECTS", "TIRE_EFFECTS", "BODY_EFFECTS", "TractorProblem", "TractorFitModel", "parameter_unit", "UNEXPLAINED_RATIO", "residual_test",
           "axle_of"]

TIRE_EFFECTS = ("enveloping", "lift_off", "nonlinear_stiffness", "friction_damping", "periodic_disturbance")
BODY_EFFECTS = ("axle_coupling", "roll_coupling", "front_axle_pivot")
EFFECTS = ("enveloping", "lift_off", "axle_coupling", "nonlinear_stiffness", "friction_damping",
           "periodic_disturbance", "roll_coupling", "front_axle_pivot")

_UNITS = {"k": ("N/m", "tire stiffness (tangent at the static load)"), "c": ("N s/m", "tire viscous damping"),
          "arrival": ("s", "left front wheel reaches its cleat"), "stagger": ("s", "right wheels after the left"),
          "delay": ("s", "rear axle after the front axle"), "pitch_index": ("-", "pitch inertia / (M a b)"),
          "roll_index": ("-", "roll inertia / (M (track/2)^2)"),
          "pivot_index": ("-", "front-axle roll inertia / (m_front (track/2)^2)"),
          "footprint": ("m", "footprint length (uniform contact pressure)"),
          "exponent": ("-", "exponent n of the progressive elastic law"), "friction": ("N", "Coulomb friction"),
          "lug_amplitude": ("m", "road-equivalent amplitude of the periodic excitation"),
          "lug_frequency": ("Hz", "frequency of the periodic excitation"),
          "lug_phase": ("rad", "phase of the periodic excitation")}
#: Signed parameters (the others are positive and fitted as logarithms).
SIGNED = ("arrival", "stagger", "lug_amplitude", "lug_phase")
LEAD_S = 0.05
#: A channel whose residual RMS exceeds this multiple of its noise RMS holds unexplained signal.
UNEXPLAINED_RATIO = 1.5
#: ... and so does one whose residual RMS over some stretch of LOCAL_SPAN_S exceeds LOCAL_RATIO times its
#: noise RMS (:func:`residual_test`): a model wrong only in the impacts leaves a residual there that the
#: quiet rest of the window dilutes below UNEXPLAINED_RATIO (seen on the independent tuning seeds: 1.3x the
#: noise over the window, 4.3x over the worst 0.1 s, c 14 % off).  Noise alone, with n = 2 f_c LOCAL_SPAN_S
#: independent samples per stretch (16 at the default cut-off of a 200 Hz recording, 4 at a 20 Hz cut-off),
#: exceeds it with a chance P(chi2_n > 9 n) under 1e-6.
LOCAL_SPAN_S = 0.1
LOCAL_RATIO = 3.0
#: Margin before the first detected onset of the samples that give the noise floor, s (the robust RMS
#: ignores the few samples of an enveloping impact that rises before its onset is detected).
QUIET_MARGIN_S = 0.05
#: A quiet stretch whose steady lines hold more than this share of its energy is not noise alone.
STEADY_LINE_SHARE = 0.5
PRE_S = 0.3
DEFAULT_STEP_S = 1e-3
#: Velocity scale of the friction damper's tanh law, m/s.
FRICTION_VELOCITY_M_S = 0.01
#: Unloaded radius of every fitting model's tire, m (the vertical law does not depend on it).
_UNLOADED_RADIUS_M = 0.75
#: Largest phase 2π f_aa h of the grid step at the anti-alias cut-off for models with point-contact edges.
EDGE_PHASE_RAD = 0.4


def parameter_unit(name: str) -> tuple[str, str]:
    """(unit, description) of a fitted parameter, e.g. ``k_FL`` or ``footprint_front``."""
    return _UNITS[name if name in _UNITS else name.rsplit("_", 1)[0]]


def axle_of(tire: str) -> str:
    """The axle ('front' or 'rear') of a tire channel: the suffix of its axle's parameters (``lug_frequency_front``)."""
    return "front" if tire in FRONT_TIRES else "rear"


def _noise_floor(rec: Recording, channels, filtered: dict, quiet: np.ndarray, fallback: dict) -> dict:
    """Noise RMS of each low-passed channel, from the samples before the first impact of any tire.

    A channel's own onset may come after another tire's impact, so every
    channel uses the span before the first one.  The low-passed span holds
    few independent samples (its bandwidth is narrow), so its robust RMS
    scatters by tens of percent from channel to channel; the raw span holds
    many.  Each channel's floor is therefore its raw robust RMS times the share
    of the noise the low-pass keeps, that share pooled over the channels (the
    median ratio), which needs no assumption on the noise's spectrum.  Under
    0.1 s of quiet samples: `fallback`.

    A channel whose quiet stretch holds a steady line (over :data:`STEADY_LINE_SHARE` of its energy: lugs,
    a road or engine line) gets the broadband part as its floor
    (:func:`identification.recording.preprocess.broadband_noise`): a model that leaves the line in its residual is
    then not "at the noise floor".  Returns (floors, {channel: {"share", "frequency_hz", "quiet_rms"}}).
    """
    if quiet.sum() / rec.sample_rate_hz < 0.1:
        return dict(fallback), {}
    raw, low, lines = {}, {}, {}
    for c in channels:
        x, y = rec.accel_m_s2[c][quiet], filtered[c][quiet]
        rms, share, hz = broadband_noise(x, sample_rate_hz=rec.sample_rate_hz)
        if share > STEADY_LINE_SHARE:   # a steady line is signal, not noise: the floor is the broadband part
            raw[c] = rms
            low[c] = broadband_noise(y, sample_rate_hz=rec.sample_rate_hz)[0]
            lines[c] = {"share": share, "frequency_hz": hz, "quiet_rms": float(np.sqrt(np.mean((x - x.mean()) ** 2)))}
        else:
            raw[c], low[c] = noise_rms(x), noise_rms(y)
    ratios = [low[c] / raw[c] for c in channels if raw[c] > 0]
    if not ratios:
        return dict(fallback), lines
    kept = float(np.median(ratios))
    return {c: raw[c] * kept if raw[c] > 0 else fallback[c] for c in channels}, lines


@dataclass(frozen=True, eq=False)
class TractorProblem:
    """The data of a whole-tractor diagnosis: every channel, filtered, with its noise and the fit window."""

    rec: Recording
    channels: tuple
    measured: dict            # channel -> low-passed acceleration, m/s² (whole record)
    noise: dict               # channel -> noise RMS of the low-passed signal, m/s²
    onsets: dict              # channel -> impact onset, s
    dominant_hz: dict
    window: np.ndarray        # bool mask over the samples
    cutoff_hz: float
    step_s: float
    first_impact_s: float
    steady_lines: dict = field(default_factory=dict)   # channel -> the steady line in its quiet stretch

    @classmethod
    def from_recording(cls, rec: Recording, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
                       step_s: float = DEFAULT_STEP_S, channels=None) -> "TractorProblem":
        channels = tuple(t for t in TIRES if t in (channels or rec.tires))
        sigs = preprocess(rec, list(channels), cutoff_hz=cutoff_hz, min_peaks=0)
        first = min(s.impact_s - (0.0 if s.tire in FRONT_TIRES else rec.rear_axle_delay_s())
                    for s in sigs.values())
        first = min(first, min(s.impact_s for s in sigs.values()))
        t = rec.time_s
        window = t >= max(t[0], first - LEAD_S)
        if window.sum() < 20:
            raise InputError(rec.source, "too few samples after the first impact to fit a model")
        noise, lines = _noise_floor(rec, channels, {c: sigs[c].filtered_m_s2 for c in channels},
                                    t < first - QUIET_MARGIN_S, {c: sigs[c].noise_m_s2 for c in channels})
        return cls(rec=rec, channels=channels, measured={c: sigs[c].filtered_m_s2 for c in channels},
                   noise={c: max(noise[c], 1e-6) for c in channels},
                   onsets={c: sigs[c].impact_s for c in channels},
                   dominant_hz={c: sigs[c].dominant_hz for c in channels}, window=window, cutoff_hz=cutoff_hz,
                   step_s=step_s, first_impact_s=first, steady_lines=lines)

    @property
    def both_sides(self) -> bool:
        return any(t in ("FL", "RL") for t in self.channels) and any(t in ("FR", "RR") for t in self.channels)

    @property
    def both_axles(self) -> bool:
        return any(t in FRONT_TIRES for t in self.channels) and any(t not in FRONT_TIRES for t in self.channels)

    def axles(self) -> tuple:
        return tuple(a for a in ("front", "rear") if any(axle_of(t) == a for t in self.channels))

    def residual_test(self, prediction, channel: str) -> dict:
        """`prediction` of `channel` (whole record, low-passed) against its noise floor over the window and its
        worst stretch (:func:`residual_test`, the stretch in s as ``worst_span_s``)."""
        test = residual_test((prediction - self.measured[channel])[self.window], self.noise[channel],
                             self.rec.sample_rate_hz, self.rec.time_s[self.window])
        del test["worst_span"]
        return test

    def available(self, effect: str, effects=()) -> bool:
        """Whether `effect` can be added to a model with `effects` for these channels."""
        chosen = set(effects)
        if effect == "axle_coupling":
            return self.both_axles and ("roll_coupling" not in chosen or len(self.channels) == 4)
        if effect == "roll_coupling":
            return self.both_sides and ("axle_coupling" not in chosen or len(self.channels) == 4)
        if effect == "front_axle_pivot":
            return len(self.channels) == 4 and {"axle_coupling", "roll_coupling"} <= chosen
        return True


class TractorFitModel:
    """The baseline corners plus a set of effects over all channels, with its parameter vector."""

    def __init__(self, effects, problem: TractorProblem, *, resolve_edges: bool = False, ring: bool = False):
        self.effects = frozenset(effects)
        #: with ``enveloping``: the footprint's cleat seen through a rigid ring over an elastic bed (the tire
        #: law's ``ring_envelope``) instead of a parabolic contact pressure
        self.ring = bool(ring) and "enveloping" in self.effects
        self.resolve_edges = resolve_edges
        unknown = self.effects - set(EFFECTS)
        if unknown:
            raise ValueError(f"unknown effects {sorted(unknown)}")
        self.problem = pb = problem
        names = []
        for t in pb.channels:
            names += [f"k_{t}", f"c_{t}"]
        names.append("arrival")
        if pb.both_sides:
            names.append("stagger")
        if pb.both_axles:
            names.append("delay")
        if "axle_coupling" in self.effects:
            names.append("pitch_index")
        if "roll_coupling" in self.effects:
            names.append("roll_index")
        if "front_axle_pivot" in self.effects:
            names.append("pivot_index")
        if "enveloping" in self.effects:
            names += [f"footprint_{a}" for a in pb.axles()]
        if "nonlinear_stiffness" in self.effects:
            names.append("exponent")
        if "friction_damping" in self.effects:
            names.append("friction")
        if "periodic_disturbance" in self.effects:
            names += [f"lug_frequency_{a}" for a in pb.axles()]
            for t in pb.channels:
                names += [f"lug_amplitude_{t}", f"lug_phase_{t}"]
        self.names = tuple(names)

    @property
    def label(self) -> str:
        return "+".join(e for e in EFFECTS if e in self.effects) or "baseline"

    def arrivals(self, theta: dict) -> dict:
        """Each channel's cleat arrival, s."""
        out = {}
        for t in self.problem.channels:
            a = theta["arrival"]
            if t in ("FR", "RR"):
                a += theta.get("stagger", 0.0)
            if t not in FRONT_TIRES:
                a += theta.get("delay", 0.0)
            out[t] = a
        return out

    def law(self, theta: dict, tire: str) -> dict:
        """The extended tire-law parameters of one tire."""
        axle = axle_of(tire)
        return tire_law_parameters(
            self.problem.rec, tire, self.effects, k=theta[f"k_{tire}"], c=theta[f"c_{tire}"],
            footprint=theta.get(f"footprint_{axle}"), exponent=theta.get("exponent"), friction=theta.get("friction"),
            lug=(theta[f"lug_amplitude_{tire}"], theta[f"lug_frequency_{axle}"], theta[f"lug_phase_{tire}"])
            if "periodic_disturbance" in self.effects else None, ring=self.ring)

    def body(self, theta: dict) -> Body:
        pb, rec = self.problem, self.problem.rec
        return Body(tires=pb.channels, loads_n=tuple(rec.wheel_load_N[t] for t in pb.channels),
                    wheelbase_m=rec.wheelbase_m, pitch="axle_coupling" in self.effects,
                    roll="roll_coupling" in self.effects, pivot="front_axle_pivot" in self.effects,
                    pitch_index=theta.get("pitch_index", 1.0), roll_index=theta.get("roll_index", 1.0),
                    pivot_index=theta.get("pivot_index", 0.05))

    def record(self, theta: dict) -> TractorModel:
        """The model record (body, tires, cleat, arrivals) for parameters `theta`."""
        rec = self.problem.rec
        arrivals = self.arrivals(theta)
        return TractorModel(body=self.body(theta), laws=tuple(self.law(theta, t) for t in self.problem.channels),
                            cleat=Cleat.of(rec),
                            arrivals_s=tuple(arrivals[t] for t in self.problem.channels))

    @property
    def has_sharp_edges(self) -> bool:
        """Point-contact cleat edges seen through an anti-alias filter."""
        aa = self.problem.rec.acquisition
        return aa is not None and bool(aa.anti_alias_order) and "enveloping" not in self.effects

    def default_step_s(self) -> float:
        """The grid step: the problem's, or with `resolve_edges` finer where the model has sharp edges.

        The scheme spreads a cleat edge over one step; seen through an
        anti-alias filter at f_aa that is an O(h) error until 2π f_aa h is
        small (0.4 rad: 0.25 ms at 250 Hz), enough to bias k and c by ~1e-4
        and move them out of their own narrow intervals.  A footprint has no edges.
        """
        pb, aa = self.problem, self.problem.rec.acquisition
        if not (self.resolve_edges and self.has_sharp_edges):
            return pb.step_s
        return min(pb.step_s, EDGE_PHASE_RAD / (2 * math.pi * aa.anti_alias_cutoff_hz))

    def grid(self, record: TractorModel, step_s: float | None = None):
        pb, rec = self.problem, self.problem.rec
        return record.grid(pb.first_impact_s - PRE_S, rec.time_s[-1] + 0.01, step_s or self.default_step_s(),
                           1.0 / rec.sample_rate_hz)

    def simulate(self, theta: dict, *, step_s: float | None = None):
        record = self.record(theta)
        return run_model(record, *self.grid(record, step_s))

    def predict(self, theta: dict, *, step_s: float | None = None, trajectory=None) -> dict:
        """Low-passed predicted acceleration per channel on the recording's time base, m/s²."""
        pb, rec = self.problem, self.problem.rec
        traj = trajectory if trajectory is not None else self.simulate(theta, step_s=step_s)
        y = sensed_lowpassed(traj, rec.time_s, rec.sample_rate_hz, rec.acquisition, cutoff_hz=pb.cutoff_hz,
                             tires=len(pb.channels))
        return dict(zip(pb.channels, y))

    def predict_reference(self, theta: dict, *, step_s: float | None = None, trajectory=None) -> dict:
        """:meth:`predict` channel by channel with the public functions ``sensed_acceleration`` and ``lowpass``
        (the reference of its compiled all-channel pass, :mod:`identification.model.sensing`)."""
        pb, rec = self.problem, self.problem.rec
        traj = trajectory if trajectory is not None else self.simulate(theta, step_s=step_s)
        y = sensed_lowpassed_reference(traj, rec.time_s, rec.sample_rate_hz, rec.acquisition,
                                       cutoff_hz=pb.cutoff_hz, tires=len(pb.channels))
        return dict(zip(pb.channels, y))

    def bounds(self, start: dict) -> tuple[dict, dict]:
        """Physical bounds (lower, upper) around the starting values."""
        rec = self.problem.rec
        lo, hi = {}, {}
        for name in self.names:
            base = name.rsplit("_", 1)[0] if name not in _UNITS else name
            s = start[name]
            if base == "k":
                lo[name], hi[name] = 0.2 * s, 5.0 * s
            elif base == "c":   # a damping 1000x under the waveform fit's is a collapse, not a tire
                lo[name], hi[name] = 1e-3 * s, 5.0 * s + 2000.0
            elif base in ("arrival", "stagger"):
                lo[name], hi[name] = s - 0.2, s + 0.2
            elif base == "delay":
                lo[name], hi[name] = 0.7 * s, 1.3 * s
            elif base in ("pitch_index", "roll_index"):
                lo[name], hi[name] = 0.05, 5.0
            elif base == "pivot_index":
                lo[name], hi[name] = 1e-3, 3.0
            elif base == "footprint":
                lo[name], hi[name] = 0.01, 1.5
            elif base == "exponent":
                lo[name], hi[name] = 0.3, 4.0
            elif base == "friction":
                lo[name], hi[name] = 0.0, 0.5 * min(rec.wheel_load_N.values())
            elif base == "lug_amplitude":
                lo[name], hi[name] = -0.05, 0.05
            elif base == "lug_frequency":
                lo[name], hi[name] = 0.9 * s, 1.1 * s
            else:   # lug_phase: wrapped, not bounded
                lo[name], hi[name] = -math.inf, math.inf
        return lo, hi


def tire_law_parameters(rec: Recording, tire: str, effects, *, k: float, c: float, footprint=None, exponent=None,
                        friction=None, lug=None, ring: bool = False) -> dict:
    """The extended tire-law parameters of one tire of a fitting model.

    `lug` is (amplitude m, frequency Hz, phase rad); every tire-side effect in
    `effects` takes its parameter from the keyword of the same meaning; with `ring` an enveloping
    tire sees the cleat through the rigid ring (``ring_envelope``).
    """
    p = dict(tire_law.EXTENDED_DEFAULTS)
    p.update(stiffness=k, damping=c, unloaded_radius=_UNLOADED_RADIUS_M, static_load=rec.wheel_load_N[tire],
             unilateral="lift_off" in effects)
    if "enveloping" in effects:
        p.update(footprint_length=footprint, parabolic_pressure=True, ring_envelope=ring, cleat_x=0.0,
                 cleat_height=rec.cleat_height_m,
                 cleat_width=rec.cleat_width_m,
                 cleat_bevel=0.0 if rec.cleat_profile is None else rec.cleat_profile.builtin_bevel_m)
    if "nonlinear_stiffness" in effects:
        p.update(stiffness_exponent=exponent)
    if "friction_damping" in effects:
        p.update(friction_force=friction, friction_velocity=FRICTION_VELOCITY_M_S)
    if "periodic_disturbance" in effects:
        amplitude, frequency, phase = lug
        p.update(lug_amplitude=amplitude, lug_pitch=rec.speed_m_s / frequency, lug_phase=phase)
    return p


def residual_test(residual, noise_rms: float, sample_rate_hz: float, time_s=None) -> dict:
    """Whether a residual is at its noise floor, over the whole window and over its worst stretch.

    Parameters
    ----------
    residual : array_like
        Prediction minus measurement (both low-passed) over the window, m/s².
    noise_rms : float
        The channel's noise RMS after the same low-pass, m/s².
    sample_rate_hz : float
        Sampling rate of `residual`, Hz.
    time_s : array_like, optional
        The residual's times, s: the worst stretch is then also given in s (``worst_span_s``, first and last
        sample).

    Returns
    -------
    dict
        ``residual_to_noise`` (RMS over the window / noise RMS), ``worst_span_to_noise`` (the same over the
        worst of the consecutive stretches of :data:`LOCAL_SPAN_S`), ``worst_span`` ([first, last) sample of
        that stretch) and ``at_noise``: both ratios within :data:`UNEXPLAINED_RATIO` and :data:`LOCAL_RATIO`.
    """
    r = np.asarray(residual, dtype=float)
    if not (noise_rms > 0) or not (sample_rate_hz > 0):
        raise ValueError(f"residual_test: noise_rms and sample_rate_hz must be positive, got {noise_rms!r}, "
                         f"{sample_rate_hz!r}")
    whole = float(np.sqrt(np.mean(r ** 2))) / noise_rms if r.size else 0.0
    m = max(1, min(r.size, int(round(LOCAL_SPAN_S * sample_rate_hz))))
    spans = r.size // m
    if spans:
        energy = np.mean(r[:spans * m].reshape(spans, m) ** 2, axis=1)
        worst = int(np.argmax(energy))
        local, span = float(np.sqrt(energy[worst])) / noise_rms, [worst * m, (worst + 1) * m]
    else:
        local, span = whole, [0, r.size]
    out = {"residual_to_noise": whole, "worst_span_to_noise": local, "worst_span": span,
           "at_noise": bool(whole <= UNEXPLAINED_RATIO and local <= LOCAL_RATIO)}
    if time_s is not None and r.size:
        t = np.asarray(time_s, dtype=float)
        out["worst_span_s"] = [float(t[span[0]]), float(t[max(span[0], span[1] - 1)])]
    return out
