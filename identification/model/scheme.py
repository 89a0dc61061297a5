"""The corner and half-tractor bodies of the single-FMU masters, their grid, road inputs and trajectory.

There is one stepping scheme, :func:`identification.model.stepping.run_body`
(reference Python; :mod:`identification.model.kernels` is its compiled twin,
:func:`identification.fmu.master.step_body_fmus` its twin with the FMI calls
inline): :func:`corner_body` (a corner mass, one coordinate) and
:func:`half_tractor_body` (heave and pitch) are bodies for it, J = [1] and
J = [[1, a], [1, −b]], from the static equilibrium each tire's force law
gives.

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

from ..recording import STANDARD_GRAVITY

__all__ = ["cleat_grid", "TireInputs", "tire_inputs", "Trajectory", "corner_body", "half_tractor_body",
           "grid_inputs", "half_tractor_geometry", "lug_steady_state"]

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
    (:class:`identification.recording.cleat.CleatProfile`, not rectangular) is the road
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


def corner_body(force: ForceFn, *, mass_kg: float, inputs: TireInputs, unloaded_radius_m: float,
                stiffness_guess_n_m: float, initial_offset=(0.0, 0.0)) -> dict:
    """A corner mass m on one tire as a body of :func:`identification.model.stepping.run_body`: ``J``,
    ``mass``, ``static_z`` (where the tire's force law carries m g), ``loads_n``, ``q0``, ``dq0``
    (`initial_offset`: hub height m and velocity m/s added to the static equilibrium, e.g. a periodic
    steady state, see :func:`lug_steady_state`)."""
    weight = mass_kg * STANDARD_GRAVITY
    z_eq = _equilibrium_corner(lambda z: force(z, 0.0, inputs.hub_x[0], 0.0, 0.0, 0.0), weight, unloaded_radius_m,
                               weight / stiffness_guess_n_m)
    return {"J": np.ones((1, 1)), "mass": np.array([float(mass_kg)]), "static_z": np.array([z_eq]),
            "loads_n": np.array([weight]), "q0": [float(initial_offset[0])], "dq0": [float(initial_offset[1])]}


def half_tractor_body(forces: Sequence[ForceFn], *, loads_n: Sequence[float], wheelbase_m: float,
                      dynamic_index: float, inputs: Sequence[TireInputs], unloaded_radii_m: Sequence[float],
                      stiffness_guesses_n_m: Sequence[float], initial_offset=((0.0, 0.0), (0.0, 0.0))) -> dict:
    """A half-tractor (heave z and pitch θ, nose-up) on a front and a rear tire as a body of ``run_body``:
    hub heights front z + a θ, rear z − b θ from their static heights (each tire carrying its load: the CG
    makes the moments balance); `initial_offset` ((front hub m, m/s), (rear hub m, m/s))."""
    mass, inertia, a, b = half_tractor_geometry(loads_n[0], loads_n[1], wheelbase_m, dynamic_index)
    z_eq = [_equilibrium_corner(lambda z, fn=fn, x=inp.hub_x[0]: fn(z, 0.0, x, 0.0, 0.0, 0.0), w, r0, w / k)
            for fn, inp, w, r0, k in zip(forces, inputs, loads_n, unloaded_radii_m, stiffness_guesses_n_m)]
    (zf0, vf0), (zr0, vr0) = initial_offset
    return {"J": np.array([[1.0, a], [1.0, -b]]), "mass": np.array([mass, inertia]), "static_z": np.array(z_eq),
            "loads_n": np.asarray(loads_n, dtype=float),
            "q0": [(b * zf0 + a * zr0) / (a + b), (zf0 - zr0) / (a + b)],
            "dq0": [(b * vf0 + a * vr0) / (a + b), (vf0 - vr0) / (a + b)]}


def grid_inputs(inputs: Sequence[TireInputs], start_s: float, step_s: float, n: int):
    """The tires' :class:`TireInputs` as the model's :class:`~identification.model.tractor.Inputs`."""
    from .tractor import Inputs

    edges = tuple((i, t, start_s + i * step_s) for t, inp in enumerate(inputs)
                  for i, edge in enumerate(inp.edges[:n]) if edge)
    return Inputs(*(np.array([getattr(inp, name)[:n] for inp in inputs], dtype=float)
                    for name in ("road_z", "road_vz", "hub_x", "hub_vx")), edges=edges)


def half_tractor_geometry(load_front_n: float, load_rear_n: float, wheelbase_m: float, dynamic_index: float):
    """Mass (kg), pitch inertia (kg m²) and distances CG-front axle a, CG-rear axle b (m).

    The centre of gravity follows from the static loads (W_f a = W_r b); the
    pitch inertia is dynamic_index · M · a · b.
    """
    mass = (load_front_n + load_rear_n) / STANDARD_GRAVITY
    a = wheelbase_m * load_rear_n / (load_front_n + load_rear_n)
    b = wheelbase_m - a
    return mass, dynamic_index * mass * a * b, a, b


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
