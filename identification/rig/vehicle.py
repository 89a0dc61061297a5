"""Mechanics of the virtual tractor: generalized coordinates, tire force law, impulses.

The plants share one formulation, q̈ = M⁻¹ (Jᵀ F + G):

* **corners** (baseline): four independent masses m_i = W_i / g, q = hub
  displacements from static equilibrium (m), J = I;
* **rigid body** (``axle_coupling``): q = (heave z at the centre of gravity m,
  pitch θ rad nose-up, roll φ rad left-up), hub i at (ξ_i, η_i) from the
  centre of gravity moves by z + ξ_i θ + η_i φ.  The centre of gravity follows
  from the static wheel loads; pitch inertia = dynamic index · M · a · b;
* **pivoting front axle** (``axle_coupling`` with ``front_axle_pivot = 1``):
  q gains ψ rad, the front axle's absolute roll left-up about a longitudinal
  pivot at the track centre (lateral position 0, carried by the body).  Front
  hubs move by z + ξ_f θ − y_cg φ ± (track/2) ψ, rear hubs as for the rigid
  body: the front tires act on the body's roll only through their sum.  The
  body mass M = ΣW/g includes the axle; the axle adds the roll inertia I_axle.

Mass matrix diag(M, I_pitch, I_roll[, I_axle]); generalized gravity
G = −Jᵀ W, so that the static wheel loads W are the equilibrium.  It is
written in closed form, with exact zeros where the centre of gravity makes
a component vanish: (−M g, 0, 0) for the rigid body, and
(−M g, 0, Δ, −Δ) with Δ = (track/2)(W_FL − W_FR) with the pivot.

Tire force (compressive positive, N), with deflection δ = δ₀ + r − x (m) and
rate δ̇ = ṙ − ẋ (m/s):

* elastic  k δ, or W sign(δ) |δ / δ₀|ⁿ with δ₀ = n W / k (``nonlinear_stiffness``,
  k is then the tangent stiffness at the static load);
* viscous  c δ̇;
* friction F_c tanh(δ̇ / v_s) (``friction_damping``);
* ``lift_off``: the sum only while δ > 0 and the sum > 0, zero otherwise.

This module is the rig's own; it shares no code with the models the pipeline
identifies or with the FMUs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .road import RoadInput

__all__ = ["Plant", "build_plant", "STANDARD_GRAVITY"]

STANDARD_GRAVITY = 9.80665
TIRES = ("FL", "FR", "RL", "RR")


@dataclass(eq=False)
class Plant:
    """A tractor model ready for integration (arrays over the tires FL, FR, RL, RR)."""

    J: np.ndarray          # (4, n) hub displacement per generalized coordinate
    minv: np.ndarray       # (n,) inverse generalized masses
    gravity: np.ndarray    # (n,) generalized gravity force
    k: np.ndarray          # N/m
    c: np.ndarray          # N s/m
    load: np.ndarray       # N
    defl0: np.ndarray      # static deflection, m
    exponent: float        # 1: linear elastic law
    friction_N: float
    slip_m_s: float
    unilateral: bool
    road: RoadInput
    mass_kg: float         # total mass
    inertia: dict          # for the truth file

    @property
    def n(self) -> int:
        return self.J.shape[1]

    # ------------------------------------------------------------------ force law
    def force(self, defl, rate, contact=None):
        """Tire forces (4, N) for deflections and rates (4, N); contact (4,) bool masks them."""
        if self.exponent == 1.0:
            f = self.k[:, None] * defl
        else:
            ratio = defl / self.defl0[:, None]
            f = self.load[:, None] * np.sign(ratio) * np.abs(ratio) ** self.exponent
        f = f + self.c[:, None] * rate
        if self.friction_N:
            f = f + self.friction_N * np.tanh(rate / self.slip_m_s)
        if contact is not None and self.unilateral:
            f = np.where(np.asarray(contact)[:, None], f, 0.0)
        return f

    def kinematics(self, t, y, t_mid):
        """Deflection and rate (4, N) for times t (N,) and states y (2n, N)."""
        n = self.n
        r, rd = self.road(t, t_mid)
        return self.defl0[:, None] + r - self.J @ y[:n], rd - self.J @ y[n:]

    def derivatives(self, t, y, contact, t_mid):
        """dy/dt (2n, N) and hub accelerations (4, N)."""
        n = self.n
        defl, rate = self.kinematics(t, y, t_mid)
        qdd = self.minv[:, None] * (self.J.T @ self.force(defl, rate, contact) + self.gravity[:, None])
        return np.vstack([y[n:], qdd]), self.J @ qdd

    def switching(self, t, y, t_mid):
        """Contact switching functions (4,), N: positive while the tire carries load."""
        defl, rate = self.kinematics(np.atleast_1d(t), y.reshape(-1, 1), t_mid)
        return np.minimum(self.k * defl[:, 0], self.force(defl, rate)[:, 0])

    # ------------------------------------------------------------------ impulses
    def step_impulse(self, t, y, dr, t_mid_before):
        """State after road steps dr (4,) at time t: the damper's impulse c·Δr.

        A unilateral tire can only push: only the part of the step that
        increases a positive deflection delivers an impulse.
        """
        n = self.n
        defl, _ = self.kinematics(np.atleast_1d(t), y.reshape(-1, 1), t_mid_before)
        before = defl[:, 0]
        if self.unilateral:
            push = np.maximum(0.0, np.maximum(before + dr, 0.0) - np.maximum(before, 0.0))
        else:
            push = dr
        y = y.copy()
        y[n:] += self.minv * (self.J.T @ (self.c * push))
        return y

    # ------------------------------------------------------------------ periodic steady state
    def linear_steady_state(self, t):
        """State at time t of the linearized plant in steady state under the lug input (2n,)."""
        road = self.road
        y = np.zeros(2 * self.n)
        if not road.lug_a:
            return y
        K = self.J.T @ (self.k[:, None] * self.J)
        C = self.J.T @ (self.c[:, None] * self.J)
        M = np.diag(1.0 / self.minv)
        for w in np.unique(road.lug_w):
            sel = road.lug_w == w
            R = np.where(sel, road.lug_a * np.exp(1j * road.lug_phi), 0.0)
            Q = np.linalg.solve(K - w * w * M + 1j * w * C, self.J.T @ ((self.k + 1j * w * self.c) * R))
            e = np.exp(1j * w * t)
            y[: self.n] += np.real(Q * e)
            y[self.n:] += np.real(1j * w * Q * e)
        return y


def build_plant(values: dict, effects: tuple[str, ...], road: RoadInput) -> Plant:
    """Assemble the plant from resolved rig parameters and the active effects."""
    g = STANDARD_GRAVITY
    load = np.array([values[f"tire.{t}.load_N"] for t in TIRES])
    k = np.array([values[f"tire.{t}.k_N_m"] for t in TIRES])
    c = np.array([values[f"tire.{t}.c_Ns_m"] for t in TIRES])
    exponent = float(values["nonlinear_stiffness.exponent"]) if "nonlinear_stiffness" in effects else 1.0
    defl0 = exponent * load / k
    mass = load.sum() / g
    inertia: dict = {}
    if "axle_coupling" in effects:
        J, minv, gravity, inertia = _rigid_body(values, load, mass)
    else:
        J = np.eye(4)
        minv = g / load
        gravity = -load
    friction = values["friction_damping.force_N"] if "friction_damping" in effects else 0.0
    return Plant(J=J, minv=minv, gravity=gravity, k=k, c=c, load=load, defl0=defl0, exponent=exponent,
                 friction_N=float(friction), slip_m_s=float(values["friction_damping.slip_velocity_m_s"]),
                 unilateral="lift_off" in effects, road=road, mass_kg=mass, inertia=inertia)


def _rigid_body(values: dict, load: np.ndarray, mass: float):
    """J (4, n), inverse generalized masses (n,), gravity (n,) and the truth's "body" (``axle_coupling``)."""
    L, track = values["vehicle.wheelbase_m"], values["vehicle.track_m"]
    half = track / 2
    x = np.array([L, L, 0.0, 0.0])                  # from the rear axle, forward
    yl = np.array([half, -half, half, -half])       # left positive
    x_cg, y_cg = (load * x).sum() / load.sum(), (load * yl).sum() / load.sum()
    a, b = L - x_cg, x_cg
    pitch_index = values["axle_coupling.pitch_dynamic_index"]
    i_pitch = pitch_index * mass * a * b
    i_roll = mass * values["axle_coupling.roll_gyration_m"] ** 2
    body = {"mass_kg": mass, "pitch_inertia_kg_m2": i_pitch, "roll_inertia_kg_m2": i_roll,
            "cg_behind_front_axle_m": a, "cg_ahead_of_rear_axle_m": b, "cg_left_of_centre_m": y_cg,
            "pitch_dynamic_index": pitch_index, "roll_dynamic_index": i_roll / (mass * half ** 2)}
    if not values["axle_coupling.front_axle_pivot"]:
        J = np.column_stack([np.ones(4), x - x_cg, yl - y_cg])
        gravity = np.array([-mass * STANDARD_GRAVITY, 0.0, 0.0])
        return J, 1.0 / np.array([mass, i_pitch, i_roll]), gravity, dict(body, front_axle="rigid")
    i_axle = values["axle_coupling.front_axle_roll_inertia_kg_m2"]
    front = np.array([1.0, 1.0, 0.0, 0.0])
    # the pivot sits at lateral position 0: the body's roll moves both front hubs by -y_cg φ
    J = np.column_stack([np.ones(4), x - x_cg, np.where(front > 0, 0.0, yl) - y_cg, front * yl])
    m_front = (load[0] + load[1]) / STANDARD_GRAVITY
    moment = half * (load[0] - load[1])  # the front loads' roll moment about the pivot, N m
    gravity = np.array([-mass * STANDARD_GRAVITY, 0.0, moment, -moment])
    return J, 1.0 / np.array([mass, i_pitch, i_roll, i_axle]), gravity, dict(
        body, front_axle="pivot", front_axle_roll_inertia_kg_m2=i_axle,
        front_axle_roll_index=i_axle / (m_front * half ** 2))
