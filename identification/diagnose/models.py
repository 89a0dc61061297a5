"""Fitting models of the diagnosis: the point-contact corner and its physical extensions.

Every model is the co-simulation master's discrete scheme
(:mod:`identification.scheme`) driven by the tire law itself
(:func:`identification.tire_law.extended_force_fn`), so that a fitted model and
the FMU built from its parameters compute the same numbers.  A model is the
baseline plus a set of effects:

``enveloping``
    the built-in cleat averaged over a footprint of length ℓ under a parabolic
    contact pressure
    (parameter ``footprint``, m), instead of a step under the contact point;
``lift_off``
    unilateral contact: the tire never pulls (no parameter; its evidence is
    the contact-loss intervals);
``axle_coupling``
    a half-tractor in heave and pitch carries this tire and the other axle's
    tire on the same side, fitted jointly on both channels (parameters
    ``k_other``, ``c_other`` and the pitch ``dynamic_index`` = I / (M a b));
``nonlinear_stiffness``
    progressive elastic force W (δ/δ_W)ⁿ, tangent k at the static load W
    (parameter ``exponent``);
``friction_damping``
    a Coulomb-like friction force F_c tanh(δ̇ / 0.01 m/s) beside the damper
    (parameter ``friction``, N);
``periodic_disturbance``
    road-equivalent lug passing A sin(2π f t + φ) in steady state
    (``lug_amplitude`` m, ``lug_frequency`` Hz, ``lug_phase`` rad).

Every model also fits k, c and the tire's ``arrival`` at the cleat (s).
Predictions are the mean hub acceleration over each sample interval of the
recording, low-passed like the measurement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import tire_law
from ..errors import InputError
from ..preprocess import DEFAULT_CUTOFF_HZ, TireSignal, lowpass, preprocess
from ..recording import FRONT_TIRES, Recording
from ..scheme import cleat_grid, lug_steady_state, run_corner, run_half_tractor, tire_inputs

__all__ = ["EFFECTS", "PARAMETERS", "FRICTION_VELOCITY_M_S", "Problem", "Model", "other_axle_tire"]

EFFECTS = ("enveloping", "lift_off", "axle_coupling", "nonlinear_stiffness", "friction_damping",
           "periodic_disturbance")

#: name -> (unit, description) of every fitted parameter.
PARAMETERS = {
    "k": ("N/m", "tire stiffness (tangent at the static load)"),
    "c": ("N s/m", "tire viscous damping"),
    "arrival": ("s", "time the contact point reaches the cleat's leading edge"),
    "footprint": ("m", "footprint length (parabolic contact pressure)"),
    "exponent": ("-", "exponent n of the progressive elastic law"),
    "friction": ("N", "Coulomb friction force"),
    "lug_amplitude": ("m", "road-equivalent amplitude of the periodic excitation"),
    "lug_frequency": ("Hz", "frequency of the periodic excitation"),
    "lug_phase": ("rad", "phase of the periodic excitation at the cleat"),
    "k_other": ("N/m", "other axle's tire stiffness (same side)"),
    "c_other": ("N s/m", "other axle's tire damping"),
    "footprint_other": ("m", "other axle's tire footprint length"),
    "dynamic_index": ("-", "pitch inertia / (M a b) of the half-tractor"),
}

#: Velocity scale of the regularised Coulomb friction, m/s.
FRICTION_VELOCITY_M_S = 0.01
#: Largest step of the fitting model and of the co-simulations that check it, s.
DEFAULT_STEP_S = 1e-3
_UNLOADED_RADIUS_M = 0.75
_LEAD_S = 0.05
_PRE_S = 0.3


def other_axle_tire(tire: str) -> str:
    """The tire on the same side of the other axle (FL <-> RL, FR <-> RR)."""
    return ("R" if tire[0] == "F" else "F") + tire[1]


@dataclass(frozen=True, eq=False)
class Problem:
    """The data of one diagnosis: a tire's channel (and the other axle's, if recorded)."""

    rec: Recording
    tire: str
    sig: TireSignal
    other: str | None
    other_sig: TireSignal | None
    window: np.ndarray          # bool mask over the recording's samples
    cutoff_hz: float
    step_s: float
    first_impact_s: float

    @classmethod
    def from_recording(cls, rec: Recording, tire: str, *, cutoff_hz: float = DEFAULT_CUTOFF_HZ,
                       step_s: float = DEFAULT_STEP_S) -> "Problem":
        """Preprocess the channel(s); the fit window runs from 50 ms before the tractor's first impact to the end."""
        other = other_axle_tire(tire)
        sigs = preprocess(rec, [tire], cutoff_hz=cutoff_hz, min_peaks=0)
        if other in rec.accel_m_s2:
            try:
                sigs.update(preprocess(rec, [other], cutoff_hz=cutoff_hz, min_peaks=0))
            except InputError:
                pass  # no impact in the other axle's channel: axle_coupling cannot be tried
        sig = sigs[tire]
        first = sig.impact_s - (0.0 if tire in FRONT_TIRES else rec.rear_axle_delay_s())
        t = rec.time_s
        window = (t >= max(t[0], first - _LEAD_S)) & (t <= t[-1])
        return cls(rec=rec, tire=tire, sig=sig, other=other if other in sigs else None,
                   other_sig=sigs.get(other), window=window, cutoff_hz=cutoff_hz, step_s=step_s,
                   first_impact_s=first)

    @property
    def front(self) -> bool:
        return self.tire in FRONT_TIRES

    @property
    def measured(self) -> np.ndarray:
        """Low-passed measured acceleration of the tire, m/s² (whole record)."""
        return self.sig.filtered_m_s2

    @property
    def noise(self) -> float:
        return max(self.sig.noise_m_s2, 1e-6)


def tire_law_parameters(rec: Recording, tire: str, effects, *, k: float, c: float, footprint=None, exponent=None,
                        friction=None, lug=None) -> dict:
    """The extended tire-law parameters of one tire of a fitting model (both the single-tire and the joint one).

    `lug` is (amplitude m, frequency Hz, phase rad); every tire-side effect in
    `effects` takes its parameter from the keyword of the same meaning.
    """
    p = dict(tire_law.EXTENDED_DEFAULTS)
    p.update(stiffness=k, damping=c, unloaded_radius=_UNLOADED_RADIUS_M, static_load=rec.wheel_load_N[tire],
             unilateral="lift_off" in effects)
    if "enveloping" in effects:
        p.update(footprint_length=footprint, parabolic_pressure=True, cleat_x=0.0, cleat_height=rec.cleat_height_m,
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


class Model:
    """The baseline corner plus a set of effects, with its parameter vector.

    Parameters
    ----------
    effects : iterable of str
    problem : Problem
    """

    def __init__(self, effects, problem: Problem):
        self.effects = frozenset(effects)
        unknown = self.effects - set(EFFECTS)
        if unknown:
            raise ValueError(f"unknown effects {sorted(unknown)}")
        if "axle_coupling" in self.effects and problem.other is None:
            raise ValueError("axle_coupling needs the other axle's channel on the same side")
        self.problem = problem
        names = ["k", "c", "arrival"]
        if "enveloping" in self.effects:
            names.append("footprint")
        if "nonlinear_stiffness" in self.effects:
            names.append("exponent")
        if "friction_damping" in self.effects:
            names.append("friction")
        if "periodic_disturbance" in self.effects:
            names += ["lug_amplitude", "lug_frequency", "lug_phase"]
        if "axle_coupling" in self.effects:
            names += ["k_other", "c_other", "dynamic_index"]
            if "enveloping" in self.effects:
                names.append("footprint_other")
        self.names = tuple(names)

    @property
    def label(self) -> str:
        return "+".join(e for e in EFFECTS if e in self.effects) or "baseline"

    # ------------------------------------------------------------------ parameters -> tire laws
    def tire_parameters(self, theta: dict, which: str = "tire") -> dict:
        """Extended-tire law parameters (see :data:`identification.tire_law.EXTENDED_DEFAULTS`)."""
        pb = self.problem
        own = which == "tire"
        return tire_law_parameters(
            pb.rec, pb.tire if own else pb.other, self.effects, k=theta["k" if own else "k_other"],
            c=theta["c" if own else "c_other"], footprint=theta.get("footprint" if own else "footprint_other"),
            exponent=theta.get("exponent"), friction=theta.get("friction"),
            lug=(theta["lug_amplitude"], theta["lug_frequency"], theta["lug_phase"])
            if "periodic_disturbance" in self.effects else None)

    # ------------------------------------------------------------------ simulation
    def simulate(self, theta: dict, *, step_s: float | None = None):
        """Run the model; returns the scheme's :class:`~identification.scheme.Trajectory`.

        The first tire of the trajectory is the front one for the half-tractor.
        """
        pb, rec = self.problem, self.problem.rec
        v, w = rec.speed_m_s, rec.cleat_width_m
        t_end = rec.time_s[-1] + 0.01
        t0 = pb.first_impact_s - _PRE_S
        if "axle_coupling" not in self.effects:
            p = self.tire_parameters(theta)
            start, h, n = cleat_grid(t0_s=t0, duration_s=t_end - t0, arrival_s=theta["arrival"],
                                     cleat_time_s=w / v, max_step_s=step_s or pb.step_s)
            inputs = tire_inputs(n, start, h, arrival_s=theta["arrival"], speed_m_s=v,
                                 cleat_height_m=rec.cleat_height_m, cleat_width_m=w,
                                 external_cleat=p["cleat_height"] == 0.0, profile=rec.cleat_profile)
            offset = (0.0, 0.0)
            if p["lug_amplitude"]:
                offset = lug_steady_state(masses_kg=[rec.mass_kg(pb.tire)], stiffness_n_m=[p["stiffness"]],
                                          damping_n_s_m=[p["damping"]], lug_amplitude_m=[p["lug_amplitude"]],
                                          lug_pitch_m=[p["lug_pitch"]], lug_phase_rad=[p["lug_phase"]],
                                          speed_m_s=v, arrival_s=[theta["arrival"]], t0_s=start)[0]
            return run_corner(tire_law.extended_force_fn(p), mass_kg=rec.mass_kg(pb.tire), start_s=start, step_s=h,
                              n=n, inputs=inputs, unloaded_radius_m=_UNLOADED_RADIUS_M,
                              stiffness_guess_n_m=p["stiffness"], initial_offset=offset)
        delay = rec.rear_axle_delay_s()
        front_arrival = theta["arrival"] - (0.0 if pb.front else delay)
        laws = [self.tire_parameters(theta, "tire"), self.tire_parameters(theta, "other")]
        if not pb.front:
            laws.reverse()
        names = (pb.tire, pb.other) if pb.front else (pb.other, pb.tire)
        start, h, n = cleat_grid(t0_s=t0, duration_s=t_end - t0, arrival_s=front_arrival, cleat_time_s=w / v,
                                 max_step_s=step_s or pb.step_s, other_axle_delay_s=delay)
        arrivals = (front_arrival, front_arrival + delay)
        inputs = [tire_inputs(n, start, h, arrival_s=arr, speed_m_s=v, cleat_height_m=rec.cleat_height_m,
                              cleat_width_m=w, external_cleat=p["cleat_height"] == 0.0, profile=rec.cleat_profile)
                  for arr, p in zip(arrivals, laws)]
        loads = [rec.wheel_load_N[nm] for nm in names]
        offset = ((0.0, 0.0), (0.0, 0.0))
        if laws[0]["lug_amplitude"]:
            offset = lug_steady_state(
                masses_kg=None, stiffness_n_m=[p["stiffness"] for p in laws], damping_n_s_m=[p["damping"] for p in laws],
                lug_amplitude_m=[p["lug_amplitude"] for p in laws], lug_pitch_m=[p["lug_pitch"] for p in laws],
                lug_phase_rad=[p["lug_phase"] for p in laws], speed_m_s=v, arrival_s=list(arrivals), t0_s=start,
                wheelbase_m=rec.wheelbase_m, dynamic_index=theta["dynamic_index"], loads_n=loads)
        return run_half_tractor([tire_law.extended_force_fn(p) for p in laws], loads_n=loads,
                                wheelbase_m=rec.wheelbase_m, dynamic_index=theta["dynamic_index"], start_s=start,
                                step_s=h, n=n, inputs=inputs, unloaded_radii_m=[_UNLOADED_RADIUS_M] * 2,
                                stiffness_guesses_n_m=[p["stiffness"] for p in laws], initial_offset=offset)

    def tire_index(self, which: str = "tire") -> int:
        """Index of the tire (or the other one) in this model's trajectory."""
        if "axle_coupling" not in self.effects:
            return 0
        own = 0 if self.problem.front else 1
        return own if which == "tire" else 1 - own

    def predict(self, theta: dict, *, step_s: float | None = None, trajectory=None):
        """Low-passed predicted acceleration on the recording's time base: (tire, other or None), m/s²."""
        pb, rec = self.problem, self.problem.rec
        traj = trajectory if trajectory is not None else self.simulate(theta, step_s=step_s)
        fs = rec.sample_rate_hz

        def channel(which):
            raw = traj.mean_acceleration(self.tire_index(which), rec.time_s, 1.0 / fs)
            return lowpass(raw, sample_rate_hz=fs, cutoff_hz=pb.cutoff_hz)

        other = channel("other") if "axle_coupling" in self.effects else None
        return channel("tire"), other

    # ------------------------------------------------------------------ starting values and bounds
    def bounds(self, start: dict) -> tuple[dict, dict]:
        """Physical bounds (lower, upper) around the starting values."""
        pb, rec = self.problem, self.problem.rec
        lo, hi = {}, {}
        for key in ("k", "k_other"):
            lo[key], hi[key] = 0.2 * start.get(key, 1.0), 5.0 * start.get(key, 1.0)
        for key in ("c", "c_other"):
            lo[key], hi[key] = 0.0, 5.0 * start.get(key, 1.0) + 2000.0
        lo["arrival"], hi["arrival"] = start["arrival"] - 0.2, start["arrival"] + 0.2
        lo["footprint"] = lo["footprint_other"] = 0.01
        hi["footprint"] = hi["footprint_other"] = 1.5
        lo["exponent"], hi["exponent"] = 0.3, 4.0
        lo["friction"], hi["friction"] = 0.0, 0.5 * rec.wheel_load_N[pb.tire]
        lo["lug_amplitude"], hi["lug_amplitude"] = -0.05, 0.05
        f0 = start.get("lug_frequency", 10.0)
        lo["lug_frequency"], hi["lug_frequency"] = 0.9 * f0, 1.1 * f0
        lo["lug_phase"], hi["lug_phase"] = -math.inf, math.inf   # a phase is wrapped, not bounded
        lo["dynamic_index"], hi["dynamic_index"] = 0.2, 3.0
        return {n: lo[n] for n in self.names}, {n: hi[n] for n in self.names}
