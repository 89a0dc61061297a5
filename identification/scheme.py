"""The co-simulation master's discrete scheme: one source for FMU runs and for the fitting models.

A body (a corner mass, or a half-tractor in heave and pitch) rides on tires
whose forces come from callbacks - an FMU's ``getReal`` in a co-simulation,
the tire law itself in a fitting model - so both compute the same numbers.

Per step h, with generalized coordinates q, mass matrix M (diagonal), hub
Jacobian J (hub heights z = z_eq + J q) and a = M⁻¹ (Jᵀ F + G):

1. q_{n+1} = q_n + h q̇_n + h²/2 q̈_n;
2. predicted q̇* = q̇_n + h q̈_n − J_imp/2 (J_imp: the impulsive part of the
   previous step, see below);
3. tire forces for hub (z, ż) = (z_eq + J q_{n+1}, J q̇*) and the road at
   t_{n+1}: direct feedthrough, no one-step delay;
4. q̇_{n+1} = q̇_n + h/2 (q̈_n + q̈_{n+1}).

Point-contact cleat edges are grid points (see :func:`cleat_grid`): there the
road is the mean of its two sides and its rate ±H/h, and the force is also
read with zero road rate; the difference is the damper's impulse, whose
velocity increment is kept out of the next prediction and reported, so the
hub velocity can be reconstructed with a true jump at the edge.

Hub longitudinal position x = v (t − t_arrival) (the contact point reaches
the cleat's leading edge at x = 0) and ẋ = v are passed to the tires for a
built-in cleat and lugs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from .recording import STANDARD_GRAVITY

__all__ = ["cleat_grid", "TireInputs", "tire_inputs", "Trajectory", "run_corner", "run_half_tractor",
           "half_tractor_geometry", "lug_steady_state"]

#: force(hub_z m, hub_vz m/s, hub_x m, hub_vx m/s, road_z m, road_vz m/s) -> force N
ForceFn = Callable[[float, float, float, float, float, float], float]


def cleat_grid(*, t0_s: float, duration_s: float, arrival_s: float, cleat_time_s: float,
               max_step_s: float, other_axle_delay_s: float | None = None,
               vertex_fractions=()) -> tuple[float, float, int]:
    """Grid with the cleat's edges (arrival, arrival + w/v) on grid points.

    Parameters
    ----------
    other_axle_delay_s : float, optional
        L / v: the step is then chosen (among cleat_time / N for N up to 1.5
        times the smallest) to put the other axle's edges as close to grid
        points as possible.
    vertex_fractions : sequence of float
        Where a cleat profile's vertices lie, as fractions of the cleat's
        width: the step is then chosen (as above) to put them as close to
        grid points as possible (a bevel's kinks on grid points).

    Returns
    -------
    start_s : float
        First grid point (at or before `t0_s`).
    step_s : float
        cleat_time_s / N, no larger than `max_step_s`.
    n_nodes : int
        Enough points to reach t0_s + duration_s.
    """
    n_min = math.ceil(cleat_time_s / max_step_s - 1e-9)
    n_cells = n_min
    fractions = list(vertex_fractions)
    if other_axle_delay_s is not None:
        fractions.append(other_axle_delay_s / cleat_time_s)
    if fractions:
        def off_grid(n_c):
            return max(abs(f * n_c - round(f * n_c)) for f in fractions)
        n_cells = min(range(n_min, int(1.5 * n_min) + 2), key=off_grid)
    h = cleat_time_s / n_cells
    start = arrival_s - math.ceil((arrival_s - t0_s) / h - 1e-9) * h
    n = int(math.ceil((t0_s + duration_s - start) / h - 1e-9)) + 1
    return start, h, n


@dataclass(frozen=True)
class TireInputs:
    """Per-grid-point inputs of one tire (lists of floats, for the stepping loop)."""

    road_z: list
    road_vz: list
    hub_x: list
    hub_vx: list
    edge: list | None = None      # True where a grid point holds a vertical edge (None: wherever the rate is not 0)

    @property
    def edges(self) -> list:
        """Per grid point: whether it holds a vertical edge of the road (its rate then applied as an impulse)."""
        return self.edge if self.edge is not None else [r != 0.0 for r in self.road_vz]


def tire_inputs(n: int, start_s: float, step_s: float, *, arrival_s: float, speed_m_s: float,
                cleat_height_m: float, cleat_width_m: float, external_cleat: bool = True,
                x_offset_m: float = 0.0, profile=None) -> TireInputs:
    """Road and longitudinal inputs of one tire on the grid start + i h.

    With `external_cleat` the rectangular cleat is passed as the road under
    the contact point (edges must be grid points: mean height and rate ±H/h
    there); otherwise the road input is flat and the tire, knowing the cleat,
    uses the longitudinal position x = v (t − t_arrival) + `x_offset_m` (the
    position of its cleat's leading edge).  An external cleat `profile`
    (:class:`identification.cleat.CleatProfile`, not rectangular) is the road
    itself: height z(v (t − t_arrival)) and rate v dz/dx on its slopes; its
    vertical edges, if any, on the nearest grid points as above.
    """
    t = start_s + step_s * np.arange(n)
    road = np.zeros(n)
    rate = np.zeros(n)
    if external_cleat and profile is not None and not profile.is_rectangular:
        road, rate, edges = profile.on_grid(t, arrival_s=arrival_s, speed_m_s=speed_m_s, step_s=step_s)
        edge = [False] * n
        for i, _ in edges:
            edge[i] = True
        x = speed_m_s * (t - arrival_s) + x_offset_m
        return TireInputs(road.tolist(), rate.tolist(), x.tolist(), [float(speed_m_s)] * n, edge)
    if external_cleat and cleat_height_m:
        n1 = int(round((arrival_s - start_s) / step_s))
        n2 = int(round((arrival_s + cleat_width_m / speed_m_s - start_s) / step_s))
        road[max(n1, 0):max(min(n2, n), 0)] = cleat_height_m
        for edge, sign in ((n1, 1.0), (n2, -1.0)):
            if 0 <= edge < n:
                road[edge] = 0.5 * cleat_height_m
                rate[edge] = sign * cleat_height_m / step_s
    x = speed_m_s * (t - arrival_s) + x_offset_m
    return TireInputs(road.tolist(), rate.tolist(), x.tolist(), [float(speed_m_s)] * n)


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Hub motion and tire forces on the grid (arrays shaped (tires, n), SI units)."""

    time_s: np.ndarray
    hub_z_m: np.ndarray
    hub_vz_m_s: np.ndarray
    hub_accel_m_s2: np.ndarray
    force_n: np.ndarray
    step_s: float
    static_hub_z_m: np.ndarray
    impulses: tuple          # per tire: ((time s, hub velocity jump m/s), ...)

    def velocity_at(self, tire: int, time_s) -> np.ndarray:
        """Hub velocity of a tire at any times, m/s: linear between grid points, jumping at impulses."""
        t = np.asarray(time_s, dtype=float)
        smooth = self.hub_vz_m_s[tire].copy()
        jumps = np.zeros_like(t)
        for t_edge, jump in self.impulses[tire]:
            after = self.time_s - t_edge
            smooth -= jump * np.where(np.abs(after) < 0.5 * self.step_s, 0.5, after > 0)
            jumps += jump * (t >= t_edge)
        return np.interp(t, self.time_s, smooth) + jumps

    def mean_acceleration(self, tire: int, time_s, interval_s: float) -> np.ndarray:
        """Mean hub acceleration over [t − interval/2, t + interval/2] for each t, m/s²."""
        t = np.asarray(time_s, dtype=float)
        return (self.velocity_at(tire, t + interval_s / 2) - self.velocity_at(tire, t - interval_s / 2)) \
            / interval_s


def _equilibrium_corner(force: Callable[[float], float], weight: float, z_guess: float, dz: float) -> float:
    """Hub height where force(z) = weight: a bracket from the unloaded height downwards, then Brent's method.

    The tire force falls as the hub rises; the bracket [z_lo, z_hi] has
    force(z_lo) > weight >= force(z_hi).
    """
    from scipy.optimize import brentq

    z_hi = z_guess
    f_hi = force(z_hi) - weight
    step = max(abs(dz), 1e-4)
    while f_hi > 0:              # already loaded at the guess: go up
        z_hi += step
        step *= 2
        f_hi = force(z_hi) - weight
        if step > 10.0:
            raise ValueError(f"no static equilibrium under {weight:.1f} N")
    z_lo, step = z_hi - max(abs(dz), 1e-4), max(abs(dz), 1e-4)
    f_lo = force(z_lo) - weight
    while f_lo <= 0:
        z_lo -= step
        step *= 2
        f_lo = force(z_lo) - weight
        if step > 10.0:
            raise ValueError(f"no static equilibrium under {weight:.1f} N")
    return brentq(lambda z: force(z) - weight, z_lo, z_hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)


def run_corner(force: ForceFn, *, mass_kg: float, start_s: float, step_s: float, n: int, inputs: TireInputs,
               unloaded_radius_m: float, stiffness_guess_n_m: float, before_step=None,
               initial_offset=(0.0, 0.0)) -> Trajectory:
    """A corner mass m under gravity on one tire, from static equilibrium.

    Parameters
    ----------
    force : callable
        Tire force for hub and road motion (see :data:`ForceFn`).
    mass_kg : float
    start_s, step_s, n : float, float, int
        The grid (see :func:`cleat_grid`).
    inputs : TireInputs
    unloaded_radius_m, stiffness_guess_n_m : float
        Start of the equilibrium search.
    before_step : callable, optional
        ``before_step(t_n, h)``, called before each step (an FMU's ``doStep``).
    initial_offset : (float, float)
        Hub height (m) and velocity (m/s) added to the static equilibrium at
        the start (a periodic steady state, see :func:`lug_steady_state`).
    """
    g = STANDARD_GRAVITY
    h = step_s
    rz, rv, hx, hv, ed = inputs.road_z, inputs.road_vz, inputs.hub_x, inputs.hub_vx, inputs.edges
    z_eq = _equilibrium_corner(lambda z: force(z, 0.0, hx[0], 0.0, 0.0, 0.0), mass_kg * g, unloaded_radius_m,
                               mass_kg * g / stiffness_guess_n_m)
    z = np.empty(n)
    v = np.empty(n)
    f = np.empty(n)
    zn, vn = z_eq + initial_offset[0], float(initial_offset[1])
    fn = force(zn, vn, hx[0], hv[0], rz[0], rv[0])
    inv_m = 1.0 / mass_kg
    an = fn * inv_m - g
    z[0], v[0], f[0] = zn, vn, fn
    half_h, half_h2 = 0.5 * h, 0.5 * h * h
    jump = 0.0
    impulses = []
    for i in range(1, n):
        zn1 = zn + h * vn + half_h2 * an
        vp = vn + h * an - 0.5 * jump
        if before_step is not None:
            before_step(start_s + (i - 1) * h, h)
        jump = 0.0
        if ed[i]:
            f_smooth = force(zn1, vp, hx[i], hv[i], rz[i], 0.0)
        fn1 = force(zn1, vp, hx[i], hv[i], rz[i], rv[i])
        if ed[i]:
            jump = h * (fn1 - f_smooth) * inv_m
            impulses.append((start_s + i * h, jump))
        an1 = fn1 * inv_m - g
        vn = vn + half_h * (an + an1)
        zn, an = zn1, an1
        z[i], v[i], f[i] = zn, vn, fn1
    return Trajectory(time_s=start_s + h * np.arange(n), hub_z_m=z[None], hub_vz_m_s=v[None],
                      hub_accel_m_s2=(f * inv_m - g)[None], force_n=f[None], step_s=h,
                      static_hub_z_m=np.array([z_eq]), impulses=(tuple(impulses),))


def half_tractor_geometry(load_front_n: float, load_rear_n: float, wheelbase_m: float, dynamic_index: float):
    """Mass (kg), pitch inertia (kg m²) and distances CG-front axle a, CG-rear axle b (m).

    The centre of gravity follows from the static loads (W_f a = W_r b); the
    pitch inertia is dynamic_index · M · a · b.
    """
    mass = (load_front_n + load_rear_n) / STANDARD_GRAVITY
    a = wheelbase_m * load_rear_n / (load_front_n + load_rear_n)
    b = wheelbase_m - a
    return mass, dynamic_index * mass * a * b, a, b


def run_half_tractor(forces: Sequence[ForceFn], *, loads_n: Sequence[float], wheelbase_m: float,
                     dynamic_index: float, start_s: float, step_s: float, n: int, inputs: Sequence[TireInputs],
                     unloaded_radii_m: Sequence[float], stiffness_guesses_n_m: Sequence[float],
                     before_step=None, initial_offset=((0.0, 0.0), (0.0, 0.0))) -> Trajectory:
    """A half-tractor (heave z and pitch θ, nose-up) on a front and a rear tire, from static equilibrium.

    Hub heights: front z + a θ, rear z − b θ (relative to their static heights).
    `initial_offset` gives ((front hub m, m/s), (rear hub m, m/s)) added at the start.
    """
    g = STANDARD_GRAVITY
    h = step_s
    mass, inertia, a, b = half_tractor_geometry(loads_n[0], loads_n[1], wheelbase_m, dynamic_index)
    arm = (a, -b)
    ff, fr = forces
    inf, inr = inputs
    # static equilibrium: each tire carries its load (the CG makes the moments balance)
    z_eq = [_equilibrium_corner(lambda z, fn=fn, x=inp.hub_x[0]: fn(z, 0.0, x, 0.0, 0.0, 0.0), w, r0, w / k)
            for fn, inp, w, r0, k in zip(forces, inputs, loads_n, unloaded_radii_m, stiffness_guesses_n_m)]
    zs = np.empty((2, n))
    vs = np.empty((2, n))
    fs = np.empty((2, n))
    (zf0, vf0), (zr0, vr0) = initial_offset
    q, th = (b * zf0 + a * zr0) / (a + b), (zf0 - zr0) / (a + b)
    dq, dth = (b * vf0 + a * vr0) / (a + b), (vf0 - vr0) / (a + b)
    inv_m, inv_i = 1.0 / mass, 1.0 / inertia

    def accelerations(f_front, f_rear):  # generalized accelerations, gravity excluded
        return (f_front + f_rear) * inv_m, (a * f_front - b * f_rear) * inv_i

    f0 = ff(z_eq[0] + q + a * th, dq + a * dth, inf.hub_x[0], inf.hub_vx[0], inf.road_z[0], inf.road_vz[0])
    f1 = fr(z_eq[1] + q - b * th, dq - b * dth, inr.hub_x[0], inr.hub_vx[0], inr.road_z[0], inr.road_vz[0])
    ddq, ddth = accelerations(f0, f1)
    ddq -= g
    zs[:, 0] = z_eq[0] + q + a * th, z_eq[1] + q - b * th
    vs[:, 0] = dq + a * dth, dq - b * dth
    fs[:, 0] = f0, f1
    half_h, half_h2 = 0.5 * h, 0.5 * h * h
    jq = jth = 0.0
    impulses = ([], [])
    for i in range(1, n):
        q1 = q + h * dq + half_h2 * ddq
        th1 = th + h * dth + half_h2 * ddth
        dqp = dq + h * ddq - 0.5 * jq
        dthp = dth + h * ddth - 0.5 * jth
        if before_step is not None:
            before_step(start_s + (i - 1) * h, h)
        zf, zr = z_eq[0] + q1 + a * th1, z_eq[1] + q1 - b * th1
        vf, vr = dqp + a * dthp, dqp - b * dthp
        jq = jth = 0.0
        fsm = [0.0, 0.0]
        if inf.road_vz[i]:
            fsm[0] = ff(zf, vf, inf.hub_x[i], inf.hub_vx[i], inf.road_z[i], 0.0)
        if inr.road_vz[i]:
            fsm[1] = fr(zr, vr, inr.hub_x[i], inr.hub_vx[i], inr.road_z[i], 0.0)
        f0 = ff(zf, vf, inf.hub_x[i], inf.hub_vx[i], inf.road_z[i], inf.road_vz[i])
        f1 = fr(zr, vr, inr.hub_x[i], inr.hub_vx[i], inr.road_z[i], inr.road_vz[i])
        if inf.road_vz[i] or inr.road_vz[i]:
            dfront = f0 - fsm[0] if inf.road_vz[i] else 0.0
            drear = f1 - fsm[1] if inr.road_vz[i] else 0.0
            jq, jth = accelerations(dfront, drear)
            jq, jth = h * jq, h * jth
            t_i = start_s + i * h
            for k_tire, arm_k in enumerate(arm):
                impulses[k_tire].append((t_i, jq + arm_k * jth))
        ddq1, ddth1 = accelerations(f0, f1)
        ddq1 -= g
        dq = dq + half_h * (ddq + ddq1)
        dth = dth + half_h * (ddth + ddth1)
        q, th, ddq, ddth = q1, th1, ddq1, ddth1
        zs[:, i] = z_eq[0] + q + a * th, z_eq[1] + q - b * th
        vs[:, i] = dq + a * dth, dq - b * dth
        fs[:, i] = f0, f1
    acc_q = (fs[0] + fs[1]) * inv_m - g
    acc_th = (a * fs[0] - b * fs[1]) * inv_i
    acc = np.vstack([acc_q + a * acc_th, acc_q - b * acc_th])
    return Trajectory(time_s=start_s + h * np.arange(n), hub_z_m=zs, hub_vz_m_s=vs, hub_accel_m_s2=acc,
                      force_n=fs, step_s=h, static_hub_z_m=np.array(z_eq),
                      impulses=(tuple(impulses[0]), tuple(impulses[1])))


def lug_steady_state(*, masses_kg, stiffness_n_m, damping_n_s_m, lug_amplitude_m, lug_pitch_m, lug_phase_rad,
                     speed_m_s: float, arrival_s, t0_s: float, wheelbase_m: float | None = None,
                     dynamic_index: float | None = None, loads_n=None):
    """Offsets from static equilibrium of each hub at t0 in periodic steady state under lug passing.

    The tires are linearized (tangent k, viscous c); the lug road under tire i
    is A_i sin(2π x_i / p_i + φ_i) with x_i = v (t − arrival_i).  One tire: a
    corner of mass m; two tires with `wheelbase_m`: the half-tractor.  The
    static equilibrium already holds the lug height at t0 (it is found with the
    tire at rest on the road there), which is subtracted.

    Returns
    -------
    list of (float, float)
        Hub height (m) and velocity (m/s) offsets per tire.
    """
    n_t = len(stiffness_n_m)
    k = np.asarray(stiffness_n_m, dtype=float)
    c = np.asarray(damping_n_s_m, dtype=float)
    amp = np.asarray(lug_amplitude_m, dtype=float)
    pitch = np.asarray(lug_pitch_m, dtype=float)
    phase = np.asarray(lug_phase_rad, dtype=float) - 2 * np.pi * speed_m_s * np.asarray(arrival_s) / pitch
    omega = 2 * np.pi * speed_m_s / pitch
    if n_t == 1:
        J = np.eye(1)
        M = np.diag([float(np.asarray(masses_kg).ravel()[0])])
    else:
        mass, inertia, a, b = half_tractor_geometry(loads_n[0], loads_n[1], wheelbase_m, dynamic_index)
        J = np.array([[1.0, a], [1.0, -b]])
        M = np.diag([mass, inertia])
    z = np.zeros(n_t)
    v = np.zeros(n_t)
    for w in np.unique(omega):
        sel = (omega == w) & (amp != 0)
        if not sel.any():
            continue
        R = np.where(sel, amp * np.exp(1j * phase), 0.0)          # road phasors (sin convention)
        Kd = J.T @ (k[:, None] * J)
        Cd = J.T @ (c[:, None] * J)
        Q = np.linalg.solve(Kd - w * w * M + 1j * w * Cd, J.T @ ((k + 1j * w * c) * R))
        X = J @ Q
        e = np.exp(1j * w * t0_s)
        z += np.imag(X * e)
        v += np.imag(1j * w * X * e)
    lug_now = np.where(amp != 0, amp * np.sin(omega * t0_s + phase), 0.0)
    return [(float(z[i] - lug_now[i]), float(v[i])) for i in range(n_t)]
