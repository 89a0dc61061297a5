"""Quarter-tractor co-simulation: the tire FMU under a corner mass, driven over the cleat with fmpy.

The master owns the body - a corner mass m = W / g under gravity - and the
road; the tire FMU (FMI 2.0 co-simulation) is the force element between them.
Per communication step h the master makes exactly one ``doStep``, one
``setReal`` and one ``getReal`` call.

Coupling scheme (no one-step delay)
-----------------------------------
The tire's force output has direct feedthrough, so the master reads the force
*for the state it has just set*, not the previous step's.  With
a_n = F_n / m − g:

1. position  z_{n+1} = z_n + h v_n + h²/2 a_n;
2. predicted velocity  v* = v_n + h a_n;
3. ``doStep(t_n, h)``; set hub (z_{n+1}, v*) and road (r_{n+1}, ṙ_{n+1});
   read F_{n+1};
4. velocity  v_{n+1} = v_n + h/2 (a_n + a_{n+1}).

Every force is evaluated at the current time with current inputs, so there is
no coupling delay and hence no artificial negative damping k·τ; the only
error is the scheme's truncation error, second order in h: the position is
exact to O(h³) per step, the predicted velocity to O(h²), which enters the
force through c and is corrected by the trapezoidal velocity update.  For the
linear tire the scheme is the trapezoidal rule with an explicit velocity
predictor; it is stable for ω_n h < 2 and its relative decay-rate error is
O((ω_n h)²) (checked against python-control in the tests).

The road under the contact point is the cleat of the recording, height H on
[t₁, t₁ + w/v).  The communication grid is laid so that both edges are grid
points (origin at t₁, step = (w/v) / an integer no larger than the requested
step); at an edge the road takes the mean of its two sides, H/2, and its rate
±H/h, so that the trapezoidal velocity update integrates the spring's step and
the damper's impulse c·H centred on the edge.  (With the edges between grid
points the scheme would fall back to first order in h.)  At the two edge
points the master also reads the force with zero road rate: the difference is
the damper's impulsive force, whose velocity increment J = h ΔF / m is then
(i) kept out of the predicted velocity of the next step (v* = v_n + h a_n −
J/2) and (ii) restored as a true jump at the edge when the hub velocity is
reconstructed between grid points (:meth:`CosimResult.velocity_at`), so that
the sampled acceleration carries the impulse in the right sample interval.

Before the first step the master finds the static equilibrium itself (secant
iterations on F(z) = m g at rest), as an importer whose body includes gravity
must.
"""

from __future__ import annotations

import math
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import InputError
from .recording import STANDARD_GRAVITY

__all__ = ["TireFmu", "CosimResult", "cleat_grid", "cleat_road", "run_quarter_tractor"]

#: Names of the tire FMU's interface (inputs, parameters, output).
INPUTS = ("hub_z", "hub_vz", "road_z", "road_vz")
PARAMETERS = ("stiffness", "damping", "unloaded_radius")
FORCE = "force_z"


class TireFmu:
    """An instantiated tire FMU (fmpy ``FMU2Slave``), usable as a context manager.

    Parameters
    ----------
    path : path-like
        The ``.fmu`` file.
    start_values : dict, optional
        Parameter values to set before initialization (name -> value).
    instance_name : str
    """

    def __init__(self, path, *, start_values: dict | None = None, instance_name: str = "tire"):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        path = Path(path)
        if not path.is_file():
            raise InputError(path, "no such file")
        try:
            self.md = read_model_description(str(path))
        except Exception as exc:  # fmpy raises several types for a bad archive
            raise InputError(path, f"not a readable FMU ({exc.__class__.__name__}: {exc})") from None
        if self.md.coSimulation is None:
            raise InputError(path, "the FMU does not support co-simulation")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        missing = [n for n in INPUTS + PARAMETERS + (FORCE,) if n not in self.vr]
        if missing:
            raise InputError(path, f"not a cleatfmu tire FMU: missing variable(s) {', '.join(missing)}")
        self.path = path
        self._dir = tempfile.mkdtemp(prefix="cleatfmu_fmu_")
        extract(str(path), self._dir)
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self._dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance_name)
        self.slave.instantiate()
        self._start_values = dict(start_values or {})
        self.input_vrs = [self.vr[n] for n in INPUTS]
        self.force_vr = [self.vr[FORCE]]

    def initialize(self, t0: float) -> None:
        s = self.slave
        s.setupExperiment(startTime=t0)
        if self._start_values:
            names = list(self._start_values)
            s.setReal([self.vr[n] for n in names], [float(self._start_values[n]) for n in names])
        s.enterInitializationMode()
        s.exitInitializationMode()

    def parameters(self) -> dict[str, float]:
        return dict(zip(PARAMETERS, self.slave.getReal([self.vr[n] for n in PARAMETERS])))

    def force(self, hub_z, hub_vz, road_z, road_vz) -> float:
        self.slave.setReal(self.input_vrs, [hub_z, hub_vz, road_z, road_vz])
        return self.slave.getReal(self.force_vr)[0]

    def close(self) -> None:
        if self.slave is not None:
            try:
                self.slave.terminate()
            finally:
                self.slave.freeInstance()
                self.slave = None
                shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


@dataclass(frozen=True, eq=False)
class CosimResult:
    """A quarter-tractor run (arrays on the communication grid, SI units).

    Attributes
    ----------
    time_s : ndarray
    hub_accel_m_s2 : ndarray
        Hub kinematic acceleration F/m - g (gravity excluded, as recorded), m/s².
    hub_z_m, hub_vz_m_s : ndarray
        Absolute hub height (m) and velocity (m/s).
    force_n, road_z_m : ndarray
        Tire force (N, compressive positive) and road height (m).
    step_s : float
    parameters : dict
        The FMU's parameter values (stiffness N/m, damping N·s/m, unloaded_radius m).
    static_hub_z_m : float
        Hub height of the static equilibrium found by the master, m.
    wall_s : float
        Wall time of the stepping loop, s.
    """

    time_s: np.ndarray
    hub_accel_m_s2: np.ndarray
    hub_z_m: np.ndarray
    hub_vz_m_s: np.ndarray
    force_n: np.ndarray
    road_z_m: np.ndarray
    step_s: float
    parameters: dict = field(default_factory=dict)
    static_hub_z_m: float = math.nan
    wall_s: float = math.nan
    impulses: tuple = ()   # (time s, hub velocity jump m/s) at the cleat edges

    def velocity_at(self, time_s) -> np.ndarray:
        """Hub velocity at any times, m/s: linear between grid points, jumping at the cleat edges."""
        t = np.asarray(time_s, dtype=float)
        smooth = self.hub_vz_m_s.copy()
        jumps = np.zeros_like(t)
        for t_edge, jump in self.impulses:
            after = self.time_s - t_edge
            smooth -= jump * np.where(np.abs(after) < 0.5 * self.step_s, 0.5, after > 0)
            jumps += jump * (t >= t_edge)
        return np.interp(t, self.time_s, smooth) + jumps

    def mean_acceleration(self, time_s, interval_s: float) -> np.ndarray:
        """Mean hub acceleration over [t − interval/2, t + interval/2] for each t, m/s²."""
        t = np.asarray(time_s, dtype=float)
        return (self.velocity_at(t + interval_s / 2) - self.velocity_at(t - interval_s / 2)) / interval_s


def cleat_grid(*, t0_s: float, duration_s: float, arrival_s: float, cleat_time_s: float,
               max_step_s: float) -> tuple[float, float, int]:
    """Communication grid with both cleat edges on grid points.

    Returns
    -------
    start_s : float
        First grid point (at or before `t0_s`).
    step_s : float
        (cleat_time_s) / ceil(cleat_time_s / max_step_s).
    n_nodes : int
        Enough points to reach t0_s + duration_s.
    """
    h = cleat_time_s / math.ceil(cleat_time_s / max_step_s - 1e-9)
    start = arrival_s - math.ceil((arrival_s - t0_s) / h - 1e-9) * h
    n = int(math.ceil((t0_s + duration_s - start) / h - 1e-9)) + 1
    return start, h, n


def cleat_road(n_nodes: int, start_s: float, step_s: float, *, arrival_s: float, cleat_time_s: float,
               height_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Rectangular cleat on a grid whose points include both edges: height (m) and rate (m/s).

    At an edge the height is the mean of both sides and the rate carries the
    whole step over one grid step.
    """
    n1 = int(round((arrival_s - start_s) / step_s))
    n2 = int(round((arrival_s + cleat_time_s - start_s) / step_s))
    r = np.zeros(n_nodes)
    rd = np.zeros(n_nodes)
    for edge, sign in ((n1, 1.0), (n2, -1.0)):
        if 0 <= edge < n_nodes:
            rd[edge] = sign * height_m / step_s
    r[max(n1, 0):max(min(n2, n_nodes), 0)] = height_m
    for edge in (n1, n2):
        if 0 <= edge < n_nodes:
            r[edge] = 0.5 * height_m
    return r, rd


def _static_equilibrium(tire: TireFmu, weight_n: float, r0: float, k_guess: float) -> float:
    """Hub height where the tire carries the weight at rest on a flat road (secant iterations)."""
    z_a, z_b = r0, r0 - weight_n / k_guess
    f_a, f_b = tire.force(z_a, 0.0, 0.0, 0.0) - weight_n, tire.force(z_b, 0.0, 0.0, 0.0) - weight_n
    for _ in range(50):
        if abs(f_b) <= 1e-12 * weight_n or f_b == f_a:
            break
        z_a, z_b, f_a = z_b, z_b - f_b * (z_b - z_a) / (f_b - f_a), f_b
        f_b = tire.force(z_b, 0.0, 0.0, 0.0) - weight_n
    if not abs(f_b) <= 1e-6 * weight_n:
        raise InputError(tire.path, f"no static equilibrium found under a load of {weight_n:.1f} N")
    return z_b


def run_quarter_tractor(fmu_path, *, mass_kg: float, speed_m_s: float, cleat_height_m: float,
                        cleat_width_m: float, arrival_s: float, t0_s: float, duration_s: float,
                        max_step_s: float, start_values: dict | None = None) -> CosimResult:
    """Drive a corner mass on the tire FMU over the cleat.

    Parameters
    ----------
    fmu_path : path-like
        Tire FMU (inputs hub_z, hub_vz, road_z, road_vz; output force_z).
    mass_kg : float
        Corner mass m = W / g, kg.
    speed_m_s, cleat_height_m, cleat_width_m : float
        Driving speed (m/s) and cleat cross-section (m).
    arrival_s : float
        Time the contact point reaches the cleat, s.
    t0_s, duration_s : float
        The run covers [t0_s, t0_s + duration_s], s.
    max_step_s : float
        Largest communication step, s; the step used is the cleat's duration
        divided by an integer (see :func:`cleat_grid`).
    start_values : dict, optional
        FMU parameters to override (e.g. ``{"stiffness": 5e5}``).

    Returns
    -------
    CosimResult
        On the communication grid; use :meth:`CosimResult.accel_at` for other times.
    """
    if not (max_step_s > 0 and duration_s > max_step_s and mass_kg > 0 and speed_m_s > 0):
        raise ValueError("step, duration, mass and speed must be positive (duration > step)")
    cleat_time = cleat_width_m / speed_m_s
    start, h, n = cleat_grid(t0_s=t0_s, duration_s=duration_s, arrival_s=arrival_s, cleat_time_s=cleat_time,
                             max_step_s=max_step_s)
    g = STANDARD_GRAVITY
    weight = mass_kg * g
    road, road_rate = cleat_road(n, start, h, arrival_s=arrival_s, cleat_time_s=cleat_time,
                                 height_m=cleat_height_m)
    road_l, rate_l = road.tolist(), road_rate.tolist()
    z = np.empty(n)
    v = np.empty(n)
    f = np.empty(n)
    with TireFmu(fmu_path, start_values=start_values) as tire:
        tire.initialize(start)
        params = tire.parameters()
        z_eq = _static_equilibrium(tire, weight, params["unloaded_radius"], params["stiffness"])
        slave, in_vrs, f_vrs = tire.slave, tire.input_vrs, tire.force_vr
        set_real, get_real, do_step = slave.setReal, slave.getReal, slave.doStep
        zn, vn = z_eq, 0.0
        fn = tire.force(zn, vn, road_l[0], rate_l[0])
        an = fn / mass_kg - g
        z[0], v[0], f[0] = zn, vn, fn
        inv_m, half_h, half_h2 = 1.0 / mass_kg, 0.5 * h, 0.5 * h * h
        tn = start
        jump = 0.0          # impulsive velocity increment at the previous grid point (a cleat edge)
        impulses = []
        wall = time.perf_counter()
        for i in range(1, n):
            zn1 = zn + h * vn + half_h2 * an
            vp = vn + h * an - 0.5 * jump
            do_step(tn, h)
            jump = 0.0
            if rate_l[i]:     # a cleat edge: measure the damper's impulsive force
                set_real(in_vrs, [zn1, vp, road_l[i], 0.0])
                f_smooth = get_real(f_vrs)[0]
            set_real(in_vrs, [zn1, vp, road_l[i], rate_l[i]])
            fn1 = get_real(f_vrs)[0]
            if rate_l[i]:
                jump = h * (fn1 - f_smooth) * inv_m
                impulses.append((start + i * h, jump))
            an1 = fn1 * inv_m - g
            vn = vn + half_h * (an + an1)
            zn, an = zn1, an1
            tn = start + i * h
            z[i], v[i], f[i] = zn, vn, fn1
        wall = time.perf_counter() - wall
    if not np.all(np.isfinite(f)):
        raise InputError(fmu_path, "the co-simulation diverged (non-finite tire force)")
    return CosimResult(time_s=start + h * np.arange(n), hub_accel_m_s2=f / mass_kg - g, hub_z_m=z, hub_vz_m_s=v,
                       force_n=f, road_z_m=road, step_s=h, parameters=params, static_hub_z_m=z_eq, wall_s=wall,
                       impulses=tuple(impulses))
