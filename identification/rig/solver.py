"""Event-driven integration of the rig's plant.

The time axis is cut at every point where the road input is not smooth (the
cleat's edges, the footprint's kinks).  Between cuts, ``scipy``'s DOP853
(8th-order Runge-Kutta with 7th-order dense output) integrates at a tight
tolerance.  Point-contact road steps are applied as exact impulses between
pieces.  With ``lift_off`` each tire's contact is a discrete mode; a terminal
event on the switching function min(k δ, F) ends a piece exactly where a tire
loses or regains contact, and integration resumes in the new mode, so the
integrator never steps across a discontinuity of the force.

:func:`hub_acceleration_on_grid` evaluates the piecewise solution on a uniform
grid and returns, for every cut, the acceleration on both sides and the hub
velocity jump, which the sensor chain needs to stay exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from .vehicle import Plant

__all__ = ["Piece", "Trajectory", "integrate", "hub_acceleration_on_grid"]


@dataclass(eq=False)
class Piece:
    t_a: float
    t_b: float
    dense: object          # callable t -> y (2n, N)
    contact: np.ndarray    # (4,) bool, fixed on the piece
    t_mid: float           # a time strictly inside the step-free road interval


@dataclass(eq=False)
class Trajectory:
    pieces: list[Piece] = field(default_factory=list)
    jumps: dict = field(default_factory=dict)          # time -> hub velocity jump (4,)
    switches: list = field(default_factory=list)       # (time, tire index, in contact after)
    nfev: int = 0


#: Longest integration step while a tire is airborne, s.  In flight the
#: motion is a parabola, which DOP853 would cross in one step, missing a
#: touch-down followed by a second lift-off inside it.
MAX_STEP_FLIGHT_S = 0.005


def _events(plant: Plant, contact: np.ndarray, t_mid: float, t_start: float, just_switched=()):
    """Terminal contact events; a tire that has just switched starts on its new side of zero."""
    memo = {"key": None, "val": None}

    def switching(t, y):
        key = (t, y.tobytes())
        if memo["key"] != key:
            val = plant.switching(t, y, t_mid)
            if t == t_start:
                for i in just_switched:  # g = 0 here up to round-off: take the new mode's sign
                    val[i] = (abs(val[i]) + 1e-9) * (1.0 if contact[i] else -1.0)
            memo["key"], memo["val"] = key, val
        return memo["val"]

    events = []
    for i in range(4):
        def ev(t, y, i=i):
            return switching(t, y)[i]
        ev.terminal = True
        ev.direction = -1.0 if contact[i] else 1.0
        events.append(ev)
    return events


def integrate(plant: Plant, t_start: float, t_end: float, y0, *, rtol: float = 1e-9) -> Trajectory:
    """Integrate the plant from `t_start` to `t_end` (s) starting at state `y0` (2n,).

    Returns
    -------
    Trajectory
        Pieces with dense output, the impulsive hub velocity jumps at road
        steps, and the contact switches.
    """
    n = plant.n
    scale = np.concatenate([np.full(n, 1e-2), np.full(n, 1e-1)])
    atol = rtol * scale
    steps: dict[float, np.ndarray] = {}
    for t, i, dr in plant.road.steps():
        if t_start < t < t_end:
            steps.setdefault(t, np.zeros(4))[i] += dr
    cuts = sorted({b for b in plant.road.breakpoints() if t_start < b < t_end} | {t_end})
    traj = Trajectory()
    y = np.asarray(y0, dtype=float).copy()
    contact = np.ones(4, dtype=bool)
    if plant.unilateral:
        contact = plant.switching(t_start, y, 0.5 * (t_start + cuts[0])) > 0
    t = t_start
    just_switched: list[int] = []
    for cut in cuts:
        t_mid = 0.5 * (t + cut)
        stalls = 0
        while t < cut:
            mode = contact.copy()

            def rhs(tt, yy, mode=mode, t_mid=t_mid):
                return plant.derivatives(np.atleast_1d(tt), yy.reshape(-1, 1), mode, t_mid)[0][:, 0]

            options = {}
            if plant.unilateral:
                options = {"events": _events(plant, mode, t_mid, t, just_switched)}
                if not mode.all():
                    options["max_step"] = MAX_STEP_FLIGHT_S
            sol = solve_ivp(rhs, (t, cut), y, method="DOP853", rtol=rtol, atol=atol,
                            dense_output=True, **options)
            if sol.status < 0:  # pragma: no cover - integrator failure is a bug
                raise RuntimeError(f"rig integrator failed at t = {t}: {sol.message}")
            traj.nfev += sol.nfev
            t_new = float(sol.t[-1])
            traj.pieces.append(Piece(t, t_new, sol.sol, mode, t_mid))
            y = sol.y[:, -1].copy()
            just_switched = []
            if sol.status == 1:
                just_switched = [i for i in range(4) if sol.t_events[i].size]
                stalls = stalls + 1 if t_new - t < 1e-12 else 0
                if stalls > 8:  # pragma: no cover - chattering guard
                    raise RuntimeError(f"contact chattering at t = {t_new}")
                for i in just_switched:
                    contact[i] = not contact[i]
                    traj.switches.append((t_new, i, bool(contact[i])))
            t = t_new
        just_switched = []
        if cut in steps:
            y_after = plant.step_impulse(cut, y, steps[cut], t_mid)
            traj.jumps[cut] = plant.J @ (y_after[n:] - y[n:])
            y = y_after
        if plant.unilateral and cut < t_end:
            nxt = cuts[cuts.index(cut) + 1]
            new = plant.switching(cut, y, 0.5 * (cut + nxt)) > 0
            just_switched = [int(i) for i in np.flatnonzero(new != contact)]
            for i in just_switched:
                traj.switches.append((cut, i, bool(new[i])))
            contact = new
    return traj


def hub_acceleration_on_grid(plant: Plant, traj: Trajectory, t0: float, h: float, n_nodes: int):
    """Hub acceleration on the grid t0 + j h, j < n_nodes, plus the cut events.

    Returns
    -------
    acc : ndarray (4, n_nodes)
        Hub acceleration, m/s²; at a node that coincides with a cut, the value
        just after it.
    cuts : list of (t, acc_before (4,), acc_after (4,), velocity_jump (4,))
        Every boundary between pieces, in time order.
    """
    acc = np.empty((4, n_nodes))
    pos = [(p.t_a - t0) / h for p in traj.pieces] + [n_nodes]
    first = [int(np.ceil(m - 1e-7)) for m in pos]
    for p, j0, j1 in zip(traj.pieces, first[:-1], first[1:]):
        j0, j1 = max(j0, 0), min(j1, n_nodes)
        if j1 <= j0:
            continue
        tt = t0 + h * np.arange(j0, j1)
        _, acc[:, j0:j1] = plant.derivatives(tt, p.dense(tt), p.contact, p.t_mid)
    cuts = []
    for left, right in zip(traj.pieces[:-1], traj.pieces[1:]):
        tb = right.t_a
        a_l = plant.derivatives(np.array([tb]), left.dense(tb).reshape(-1, 1), left.contact, left.t_mid)[1][:, 0]
        a_r = plant.derivatives(np.array([tb]), right.dense(tb).reshape(-1, 1), right.contact, right.t_mid)[1][:, 0]
        cuts.append((tb, a_l, a_r, traj.jumps.get(tb, np.zeros(4))))
    return acc, cuts
