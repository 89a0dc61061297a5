"""The co-simulation master's stepping scheme for any body, in plain Python: the reference.

Per step h, with generalized coordinates q (diagonal masses M), hub
displacements J q and tire forces F from callbacks (an FMU's ``getReal``, or
the tire law itself):

1. q_{n+1} = q_n + h q̇_n + h²/2 q̈_n;  predicted q̇* = q̇_n + h q̈_n − ½ j_n;
2. (``before_step``: every FMU's ``doStep``); hubs at z_eq + J q_{n+1},
   J q̇*; each tire's force for exactly that state (direct feedthrough);
3. q̈_{n+1} = M⁻¹ Jᵀ (F − W);  q̇_{n+1} = q̇_n + h/2 (q̈_n + q̈_{n+1}).

At a grid point carrying a point-contact edge the force is also read with
the road rate set to zero; the difference is the damper's impulse, which
makes the hub velocity jump (j = h M⁻¹ Jᵀ ΔF, half of which the trapezoidal
update has already spread into the step) and is recorded so that the
trajectory's velocity jumps at the edge time itself.  A corner and a half-tractor
(:func:`identification.model.scheme.corner_body`, :func:`~identification.model.scheme.half_tractor_body`) are bodies of
one and two coordinates; :func:`identification.fmu.master.step_body_fmus` is this scheme with the FMI calls inline.

:mod:`identification.model.kernels` runs the same operations, in the same
order, compiled; the two agree to round-off (tested ≤ 1e-12).
"""

from __future__ import annotations

import numpy as np

from .scheme import Trajectory
from .tractor import Inputs, TractorModel

__all__ = ["run_body", "run_model_python", "edge_jumps", "step_lists", "trajectory_from_arrays"]


def run_body(forces, *, J, mass, static_z, loads_n, inputs: Inputs, start_s: float, step_s: float,
             q0=None, dq0=None, before_step=None) -> Trajectory:
    """Step the body on its tires; returns the :class:`~identification.model.scheme.Trajectory` (tires in J's rows).

    Parameters
    ----------
    forces : sequence of callable
        ``force(hub_z, hub_vz, hub_x, hub_vx, road_z, road_vz) -> N`` per tire.
    J : ndarray (tires × q)
    mass : ndarray (q,)
        Generalized masses (kg, or kg m² for rotations).
    static_z : ndarray (tires,)
        Hub heights at which each tire carries its static load, m.
    loads_n : ndarray (tires,)
    inputs : Inputs
    start_s, step_s : float
    q0, dq0 : ndarray, optional
        Initial coordinates and rates (default: rest at static equilibrium).
    before_step : callable, optional
        ``before_step(t_n, h)`` before each step.
    """
    nt, nq, Jl, minv, zs, W, (rz, rv, hx, hv, em), n, h, hh, hh2 = step_lists(J, mass, static_z, loads_n,
                                                                                inputs, step_s)
    q = [0.0] * nq if q0 is None else [float(v) for v in q0]
    dq = [0.0] * nq if dq0 is None else [float(v) for v in dq0]
    Z = np.empty((nt, n))
    V = np.empty((nt, n))
    F = np.empty((nt, n))
    A = np.empty((nt, n))
    points = inputs.edge_points.tolist()
    jumps = np.zeros((len(points), nt, nt))
    f = [0.0] * nt
    fs = [0.0] * nt
    for t in range(nt):
        zt = zs[t]
        vt = 0.0
        for j in range(nq):
            zt += Jl[t][j] * q[j]
            vt += Jl[t][j] * dq[j]
        f[t] = forces[t](zt, vt, hx[t][0], hv[t][0], rz[t][0], rv[t][0])
        Z[t, 0], V[t, 0], F[t, 0] = zt, vt, f[t]
    ddq = [0.0] * nq
    for j in range(nq):
        s = 0.0
        for t in range(nt):
            s += Jl[t][j] * (f[t] - W[t])
        ddq[j] = minv[j] * s
    for t in range(nt):
        s = 0.0
        for j in range(nq):
            s += Jl[t][j] * ddq[j]
        A[t, 0] = s
    jq = no_jump = [0.0] * nq
    q1 = [0.0] * nq
    dqp = [0.0] * nq
    ddq1 = [0.0] * nq
    edge = 0
    for i in range(1, n):
        for j in range(nq):
            q1[j] = q[j] + h * dq[j] + hh2 * ddq[j]
            dqp[j] = dq[j] + h * ddq[j] - 0.5 * jq[j]
        if before_step is not None:
            before_step(start_s + (i - 1) * h, h)
        any_edge = False
        for t in range(nt):
            zt = zs[t]
            vt = 0.0
            for j in range(nq):
                zt += Jl[t][j] * q1[j]
                vt += Jl[t][j] * dqp[j]
            if em[t][i]:
                any_edge = True
                fs[t] = forces[t](zt, vt, hx[t][i], hv[t][i], rz[t][i], 0.0)
                f[t] = forces[t](zt, vt, hx[t][i], hv[t][i], rz[t][i], rv[t][i])
            else:
                f[t] = forces[t](zt, vt, hx[t][i], hv[t][i], rz[t][i], rv[t][i])
                fs[t] = f[t]
            Z[t, i] = zt
        jq = no_jump
        if any_edge:
            jq = edge_jumps(Jl, minv, f, fs, h, jumps[edge])
            edge += 1
        for j in range(nq):
            s = 0.0
            for t in range(nt):
                s += Jl[t][j] * (f[t] - W[t])
            ddq1[j] = minv[j] * s
            dq[j] = dq[j] + hh * (ddq[j] + ddq1[j])
            q[j] = q1[j]
            ddq[j] = ddq1[j]
        for t in range(nt):
            vt = 0.0
            at = 0.0
            for j in range(nq):
                vt += Jl[t][j] * dq[j]
                at += Jl[t][j] * ddq[j]
            V[t, i], F[t, i], A[t, i] = vt, f[t], at
    return trajectory_from_arrays(Z, V, F, A, jumps, inputs=inputs, start_s=start_s, step_s=h, static_z=static_z)


def step_lists(J, mass, static_z, loads_n, inputs: Inputs, step_s: float):
    """The stepping's operands as Python lists and floats (a plain-Python loop is fastest on those):
    (tires, coordinates, J rows, 1/mass, static heights, loads, (road z, road vz, hub x, hub vx, edge mask),
    steps, h, h/2, h²/2)."""
    J = np.asarray(J, dtype=float)
    nt, nq = J.shape
    road = tuple(a.tolist() for a in (inputs.road_z, inputs.road_vz, inputs.hub_x, inputs.hub_vx,
                                      inputs.edge_mask))
    h = float(step_s)
    return (nt, nq, J.tolist(), (1.0 / np.asarray(mass, dtype=float)).tolist(), [float(v) for v in static_z],
            [float(v) for v in loads_n], road, len(road[0][0]), h, 0.5 * h, 0.5 * h * h)


def edge_jumps(Jl, minv, f, fs, h: float, jumps_row) -> list:
    """A step holding cleat edges: the jump of the generalized velocities, h M⁻¹ Jᵀ (f − f_smooth), returned,
    and each edge tire's share of every hub's velocity jump written into ``jumps_row[src, hub]``."""
    nt, nq = len(Jl), len(minv)
    jq = [0.0] * nq
    for j in range(nq):
        s = 0.0
        for t in range(nt):
            s += Jl[t][j] * (f[t] - fs[t])
        jq[j] = h * minv[j] * s
    for src in range(nt):
        for hub in range(nt):
            s = 0.0
            for j in range(nq):
                s += Jl[hub][j] * (h * minv[j] * (Jl[src][j] * (f[src] - fs[src])))
            jumps_row[src, hub] = s
    return jq


def trajectory_from_arrays(Z, V, F, A, jumps, *, inputs: Inputs, start_s, step_s, static_z) -> Trajectory:
    """The :class:`~identification.model.scheme.Trajectory` of a stepped run, its impulses at the true edge times."""
    points = inputs.edge_points.tolist()
    nt = Z.shape[0]
    impulses = [[] for _ in range(nt)]
    for i, src, t_edge in inputs.edges:
        e = points.index(i)
        for hub in range(nt):
            if jumps[e, src, hub] != 0.0:
                impulses[hub].append((float(t_edge), float(jumps[e, src, hub])))
    return Trajectory(time_s=start_s + step_s * np.arange(Z.shape[1]), hub_z_m=Z, hub_vz_m_s=V, hub_accel_m_s2=A,
                      force_n=F, step_s=step_s, static_hub_z_m=np.asarray(static_z, dtype=float),
                      impulses=tuple(tuple(sorted(imp)) for imp in impulses))


def prepared(model: TractorModel, start_s: float, step_s: float, n: int):
    """Everything a stepping run needs from the model record: (J, mass, static_z, loads, inputs, q0, dq0)."""
    J, mass, _ = model.body.matrices()
    inputs = model.inputs(start_s, step_s, n)
    static_z = model.static_hub_z(inputs.hub_x[:, 0])
    q0, dq0 = model.initial_state(start_s, inputs.hub_x[:, 0], inputs.hub_vx[:, 0])
    loads = np.array([p["static_load"] for p in model.laws], dtype=float)
    return J, mass, static_z, loads, inputs, q0, dq0


def run_model_python(model: TractorModel, start_s: float, step_s: float, n: int) -> Trajectory:
    """The model record stepped with the tire law in plain Python (the reference of the compiled kernel)."""
    from . import tire_law

    J, mass, static_z, loads, inputs, q0, dq0 = prepared(model, start_s, step_s, n)
    forces = []
    for p in model.laws:
        vec = tire_law.law_vector(p)
        forces.append(lambda z, vz, x, vx, r, rv, vec=vec: tire_law.tire_force(z, vz, x, vx, r, rv, vec))
    return run_body(forces, J=J, mass=mass, static_z=static_z, loads_n=loads, inputs=inputs, start_s=start_s,
                    step_s=step_s, q0=q0, dq0=dq0)
