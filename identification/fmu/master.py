"""The one co-simulation master over tire FMUs: any body (a corner, a half-tractor, the tractor) on one
tire FMU per wheel, stepped by :func:`identification.model.stepping.run_body`'s scheme with the FMI calls
inline.

:func:`identification.fmu.cosim.run_quarter_tractor` (a corner),
:func:`identification.fmu.cosim.run_half_tractor_fmus` (heave and pitch) and
:func:`identification.fmu.tractor_cosim.run_tractor_fmus` (the model record's body) all step here; the SSP
check (:mod:`identification.fmu.ssp_run`) compares hosts with ``run_body`` itself on the tire law.
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..model.stepping import edge_jumps, step_lists, trajectory_from_arrays
from ..model.scheme import Trajectory

__all__ = ["step_body_fmus", "step_fn", "fmi_error"]

#: fmi2Warning: a larger status is a failed call (as fmpy's wrappers judge it).
_WARNING = 1


def step_fn(tires):
    """``do_steps(t_n, h)``: one ``fmi2DoStep(t_n, h)`` of each tire, in order (the ``before_step`` callback)."""
    calls = [(t._raw.do_step, t._raw.component) for t in tires]
    t_now, size, true = ctypes.c_double(), ctypes.c_double(), ctypes.c_int(1)

    def do_steps(t_n, h):
        t_now.value = t_n
        size.value = h
        for do_step, c in calls:
            status = do_step(c, t_now, size, true)
            if status > _WARNING:
                raise fmi_error("fmi2DoStep", status)
    return do_steps


#: fmi2Warning: a larger status is a failed call (as fmpy's wrappers judge it).
_WARNING = 1
def fmi_error(function: str, status: int) -> Exception:
    """fmpy's error for a failed FMI call (status above fmi2Warning)."""
    from fmpy.fmi1 import FMICallException

    return FMICallException(function=function, status=status)


def step_body_fmus(tires, *, J, mass, static_z, loads_n, inputs, start_s: float, step_s: float, q0,
                   dq0) -> Trajectory:
    """:func:`identification.model.stepping.run_body` on open, initialized tire FMUs, the FMI calls inline.

    The same operations in the same order, so the same trajectory (tested
    against ``run_body`` with the FMUs' force callbacks); per step one
    ``fmi2DoStep`` of every FMU, then one ``fmi2SetReal`` of the inputs and one
    ``fmi2GetReal`` of the force of each tire (two at a point-contact edge).
    Faster: the products with J's zero entries, exact zeros, are skipped (a
    body of independent corners has one non-zero entry per row), the steps'
    values are kept in lists, and each tire's FMI arguments are allocated once.
    """
    nt, nq, Jl, minv, zs, W, (rz, rv, hx, hv, em), n, h, hh, hh2 = step_lists(J, mass, static_z, loads_n,
                                                                                inputs, step_s)
    rows = [[(j, Jl[t][j]) for j in range(nq) if Jl[t][j] != 0.0] for t in range(nt)]
    cols = [[(t, Jl[t][j]) for t in range(nt) if Jl[t][j] != 0.0] for j in range(nq)]
    q = [float(v) for v in q0]
    dq = [float(v) for v in dq0]
    Z, V, F, A = ([[0.0] * n for _ in range(nt)] for _ in range(4))
    points = inputs.edge_points.tolist()
    jumps = np.zeros((len(points), nt, nt))
    forces = [tire.force_fn() for tire in tires]
    do_steps = step_fn(tires)
    f = [0.0] * nt
    fs = [0.0] * nt
    for t in range(nt):
        zt, vt = zs[t], 0.0
        for j, Jtj in rows[t]:
            zt += Jtj * q[j]
            vt += Jtj * dq[j]
        f[t] = forces[t](zt, vt, hx[t][0], hv[t][0], rz[t][0], rv[t][0])
        Z[t][0], V[t][0], F[t][0] = zt, vt, f[t]
    ddq = [0.0] * nq
    for j in range(nq):
        s = 0.0
        for t, Jtj in cols[j]:
            s += Jtj * (f[t] - W[t])
        ddq[j] = minv[j] * s
    for t in range(nt):
        s = 0.0
        for j, Jtj in rows[t]:
            s += Jtj * ddq[j]
        A[t][0] = s
    # per tire: its index, static height, row of J, inputs, FMI exchange (see TireFmu.force_fn) and outputs
    per_tire = [(t, zs[t], rows[t], rz[t], rv[t], em[t], hx[t], hv[t], *tire.exchange_args(), Z[t])
                for t, tire in enumerate(tires)]
    columns = list(zip(range(nq), cols, minv))
    jq = no_jump = (0.0,) * nq
    q1 = [0.0] * nq
    dqp = [0.0] * nq
    edge = 0
    for i in range(1, n):
        for j in range(nq):
            q1[j] = q[j] + h * dq[j] + hh2 * ddq[j]
            dqp[j] = dq[j] + h * ddq[j] - 0.5 * jq[j]
        do_steps(start_s + (i - 1) * h, h)
        any_edge = False
        for t, zt, row, rz_t, rv_t, em_t, hx_t, hv_t, set_real, get_real, c, vrs, n_in, values, f_vr, one, out, \
                Z_t in per_tire:
            vt = 0.0
            for j, Jtj in row:
                zt += Jtj * q1[j]
                vt += Jtj * dqp[j]
            if em_t[i]:
                any_edge = True
                fs[t] = forces[t](zt, vt, hx_t[i], hv_t[i], rz_t[i], 0.0)
                f[t] = forces[t](zt, vt, hx_t[i], hv_t[i], rz_t[i], rv_t[i])
            else:
                values[:] = (zt, vt, rz_t[i], rv_t[i], hx_t[i], hv_t[i])
                status = set_real(c, vrs, n_in, values)
                if status > 1:  # above fmi2Warning: failed
                    raise fmi_error("fmi2SetReal", status)
                status = get_real(c, f_vr, one, out)
                if status > 1:
                    raise fmi_error("fmi2GetReal", status)
                f[t] = fs[t] = out[0]
            Z_t[i] = zt
        jq = no_jump
        if any_edge:
            jq = edge_jumps(Jl, minv, f, fs, h, jumps[edge])
            edge += 1
        for j, col, minv_j in columns:
            s = 0.0
            for t, Jtj in col:
                s += Jtj * (f[t] - W[t])
            ddq1 = minv_j * s
            dq[j] = dq[j] + hh * (ddq[j] + ddq1)
            q[j] = q1[j]
            ddq[j] = ddq1
        for t, row in enumerate(rows):
            vt = 0.0
            at = 0.0
            for j, Jtj in row:
                vt += Jtj * dq[j]
                at += Jtj * ddq[j]
            V[t][i], F[t][i], A[t][i] = vt, f[t], at
    return trajectory_from_arrays(*(np.array(X) for X in (Z, V, F, A)), jumps, inputs=inputs, start_s=start_s,
                                  step_s=h, static_z=static_z)
