"""The independent simulator's vehicles, built and integrated by Exudyn.

Axes: x forward, y left, z up; the tractor stands (the tires push only vertically) and the road runs under it at the driving speed.  Layouts:

``corners``
    Four independent masses W/g, each on its own tire (x and z free).
``rigid``
    One rigid body (all six coordinates free, Lie-group rotation vector) carrying the four hubs
    at its centre-of-gravity height: heave, pitch and roll.
``pivot``
    The rigid body, and a front axle of its own that rolls about a longitudinal pivot at the track
    centre: a second rigid body held to the first by a stiff six-axis spring-damper whose roll
    stiffness is zero.

Each hub is a body point on a tire (:mod:`.tires`) through a Cartesian spring-damper connector
whose force is the tire law.  The vehicle first settles on flat ground (extra dampers on), then
rolls towards the cleats; the hub's vertical acceleration, position and velocity are stored at
every step of Exudyn's explicit Runge-Kutta (RK44) integrator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

import exudyn as exu
import exudyn.utilities as eu
from exudyn.itemInterface import (LoadForceVector, MarkerBodyMass, MarkerBodyPosition, MarkerBodyRigid,
                                  MarkerNodePosition, NodePoint, ObjectMassPoint, NodeRigidBodyRotVecLG,
                                  ObjectConnectorCartesianSpringDamper, ObjectConnectorRigidBodySpringDamper,
                                  ObjectGround, ObjectRigidBody, SensorBody, SensorNode, LoadMassProportional)

from .tires import TireSpec, pack, tire_force

__all__ = ["Vehicle", "Crossing", "cross_cleat", "GRAVITY"]

GRAVITY = 9.81
WHEELS = ("FL", "FR", "RL", "RR")


@dataclass
class Vehicle:
    """The tractor of one scenario (SI units)."""

    layout: str                               # corners | rigid | pivot
    tires: dict                               # wheel -> TireSpec
    corner_mass_kg: dict = field(default_factory=dict)   # corners: wheel -> mass
    mass_kg: float = 5500.0                   # rigid/pivot: body mass (with the front axle's)
    cg_from_front_m: float = 1.6              # a: centre of gravity behind the front axle
    cg_left_m: float = 0.0                    # lateral offset of the centre of gravity (left +)
    pitch_index: float = 0.8                  # I_yy / (M a b)
    roll_gyration_m: float = 0.65             # I_xx = M r^2
    wheelbase_m: float = 2.77
    track_m: float = 1.9
    axle_mass_kg: float = 350.0               # pivot: front axle mass (part of mass_kg)
    axle_roll_inertia_kg_m2: float = 150.0    # pivot: front axle's roll inertia about the pivot

    def hub_xy(self, wheel: str) -> tuple[float, float]:
        """Hub position relative to the front axle's centre: (x, y), m."""
        x = 0.0 if wheel[0] == "F" else -self.wheelbase_m
        y = self.track_m / 2 if wheel[1] == "L" else -self.track_m / 2
        return x, y


@dataclass
class Crossing:
    """What Exudyn computed: per wheel, at the step times ``time_s``."""

    time_s: np.ndarray
    accel_z: dict           # hub vertical acceleration, m/s²
    hub_z: dict             # hub height over the flat ground, m
    hub_vz: dict            # hub vertical velocity, m/s
    hub_x: dict             # hub x (road frame: relative to its cleat's leading edge), m
    force_z: dict           # vertical tire force, N
    static_force_z: dict    # the settled wheel loads, N


def _settings(step_s: float, end_s: float) -> exu.SimulationSettings:
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.numberOfSteps = int(round(end_s / step_s))
    ti.endTime = end_s
    ti.verboseMode = 0
    ti.explicit.computeEndOfStepAccelerations = True
    ti.explicit.useLieGroupIntegration = True
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = step_s
    return ss


def cross_cleat(vehicle: Vehicle, *, speed_m_s: float, cleats: dict, cleat_x_m: dict, step_s: float,
                duration_s: float, settle_s: float = 1.5) -> Crossing:
    """Settle the vehicle on flat ground, then drive it over the cleats.

    Parameters
    ----------
    cleats : dict
        side ('L' or 'R') -> (n, 2) cleat polyline (:func:`.terrain.cleat_polyline`).
    cleat_x_m : dict
        side -> distance the front hub travels from t = 0 to that side's cleat's leading edge, m.
    step_s, duration_s : float
        Integration step and length of the crossing, s.
    """
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    m_ground = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    packed = {w: pack(vehicle.tires[w]) for w in WHEELS}
    radius = {w: vehicle.tires[w].radius_m for w in WHEELS}
    hub_z0 = {w: radius[w] - 0.02 for w in WHEELS}   # near the static heights; the settling finds them
    z0 = float(np.mean(list(hub_z0.values())))
    zf = hub_z0["FL"]
    state = {"rolling": False, "v": speed_m_s}
    segs = {s: (np.ascontiguousarray(c[:, 0]), np.ascontiguousarray(c[:, 1])) for s, c in cleats.items()}
    hub_marker, sensors, body_of = {}, {}, {}

    def make_law(wheel):
        par, theta = packed[wheel]
        sx, sz = segs[wheel[1]]
        x_cleat = cleat_x_m[wheel[1]]
        r_roll = radius[wheel] * 0.97

        def law(mbs_, t, item, u, v, k, d, off):
            if state["rolling"]:
                x_rel = u[0] + state["v"] * t - x_cleat
                phi, phi_dot = (state["v"] * t + u[0]) / r_roll, state["v"] / r_roll
                vx = state["v"] + v[0]
            else:                                          # settling: flat ground, standing
                x_rel, phi, phi_dot, vx = -10.0, 0.0, 0.0, 0.0
            fz, _ = tire_force(par, theta, x_rel, u[2], vx, v[2], phi, phi_dot, sx, sz)
            return [0.0, 0.0, -fz]
        return law

    if vehicle.layout == "corners":
        for w in WHEELS:
            x, y = vehicle.hub_xy(w)
            m = vehicle.corner_mass_kg[w]
            delta = m * GRAVITY / _flat_stiffness(vehicle.tires[w])
            node = mbs.AddNode(NodePoint(referenceCoordinates=[x, y, radius[w] - delta]))
            body = mbs.AddObject(ObjectMassPoint(mass=m, nodeNumber=node))
            hub_marker[w] = mbs.AddMarker(MarkerNodePosition(nodeNumber=node))
            mbs.AddLoad(LoadForceVector(markerNumber=hub_marker[w], loadVector=[0, 0, -m * GRAVITY]))
            body_of[w] = (body, [0.0, 0.0, 0.0])
        bodies = [body_of[w][0] for w in WHEELS]
    else:
        a, L = vehicle.cg_from_front_m, vehicle.wheelbase_m
        b = L - a
        M = vehicle.mass_kg
        pivot = vehicle.layout == "pivot"
        m_body = M - (vehicle.axle_mass_kg if pivot else 0.0)
        cg = np.array([-a, vehicle.cg_left_m, z0])
        i_xx, i_yy = M * vehicle.roll_gyration_m ** 2, vehicle.pitch_index * M * a * b
        if pivot:   # the axle's own share (at the front axle's centre), taken from the body's
            share = vehicle.axle_mass_kg / m_body
            cg = cg + share * (cg - np.array([0.0, 0.0, z0]))
            i_xx -= vehicle.axle_roll_inertia_kg_m2 + m_body * vehicle.cg_left_m ** 2 * share
            i_yy -= vehicle.axle_mass_kg * a ** 2 + m_body * (cg[0] + a) ** 2
        inertia = np.diag([i_xx, i_yy, 0.9 * (i_xx + i_yy)])
        main = _rigid_body(mbs, m_body, inertia, cg)
        bodies = [main]
        axle = None
        if pivot:
            ia = vehicle.axle_roll_inertia_kg_m2
            axle = _rigid_body(mbs, vehicle.axle_mass_kg, np.diag([ia, 0.3 * ia, ia]), np.array([0.0, 0.0, zf]))
            bodies.append(axle)
            m_a = mbs.AddMarker(MarkerBodyRigid(bodyNumber=axle, localPosition=[0.0, 0.0, 0.0]))
            m_b = mbs.AddMarker(MarkerBodyRigid(bodyNumber=main, localPosition=list(np.array([0.0, 0.0, zf]) - cg)))
            # the pivot's bearings: stiff (a 120 Hz axle mode) but for roll, free
            kt, kr = 2e8, 1e7
            ct = 0.6 * math.sqrt(kt * vehicle.axle_mass_kg)
            cr = 0.6 * math.sqrt(kr * 0.3 * ia)
            stiff = np.diag([kt, kt, kt, 0.0, kr, kr])
            damp = np.diag([ct, ct, ct, 0.0, cr, cr])
            mbs.AddObject(ObjectConnectorRigidBodySpringDamper(markerNumbers=[m_b, m_a], stiffness=stiff,
                                                               damping=damp))
        for w in WHEELS:
            x, y = vehicle.hub_xy(w)
            if pivot and w[0] == "F":
                body_of[w] = (axle, [0.0, y, hub_z0[w] - zf])
            else:
                body_of[w] = (main, list(np.array([x, y, hub_z0[w]]) - cg))
            hub_marker[w] = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body_of[w][0], localPosition=body_of[w][1]))
        for body in bodies:
            mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
            mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0.0, 0.0, -GRAVITY]))

    tire_connectors = {}
    for w in WHEELS:
        tire_connectors[w] = mbs.AddObject(ObjectConnectorCartesianSpringDamper(
            markerNumbers=[m_ground, hub_marker[w]], springForceUserFunction=make_law(w)))
    # settling dampers (vertical, at every hub; off for the crossing)
    settle = [mbs.AddObject(ObjectConnectorCartesianSpringDamper(
        markerNumbers=[m_ground, hub_marker[w]], damping=[2e4, 2e4, 6e4])) for w in WHEELS]
    for w in WHEELS:
        body, local = body_of[w]
        sensors[w] = [mbs.AddSensor(SensorBody(bodyNumber=body, localPosition=local, storeInternal=True,
                                               outputVariableType=q))
                      for q in (exu.OutputVariableType.Acceleration, exu.OutputVariableType.Position,
                                exu.OutputVariableType.Velocity)]
    mbs.Assemble()

    # 1. settle on flat ground, standing
    mbs.SolveDynamic(_settings(5e-4, settle_s), solverType=exu.DynamicSolverType.RK44)
    current = mbs.systemData.GetSystemState(exu.ConfigurationType.Current)
    mbs.systemData.SetSystemState(current, exu.ConfigurationType.Initial)
    # zero the settled velocities (the dampers have taken them to round-off)
    for s in settle:
        mbs.SetObjectParameter(s, "activeConnector", False)
    static = {}
    for w in WHEELS:
        pos = mbs.GetSensorValues(sensors[w][1])
        par, theta = packed[w]
        static[w] = tire_force(par, theta, -10.0, pos[2], 0.0, 0.0, 0.0, 0.0, *segs[w[1]])[0]

    # 2. the crossing
    state["rolling"] = True
    mbs.SolveDynamic(_settings(step_s, duration_s), solverType=exu.DynamicSolverType.RK44)
    out = {q: {} for q in ("a", "z", "vz", "x", "f")}
    time_s = None
    for w in WHEELS:
        acc, pos, vel = (mbs.GetSensorStoredData(s) for s in sensors[w])
        time_s = acc[:, 0]
        out["a"][w], out["z"][w], out["vz"][w] = acc[:, 3], pos[:, 3], vel[:, 3]
        x_cleat = cleat_x_m[w[1]]
        out["x"][w] = pos[:, 1] + speed_m_s * time_s - x_cleat
        par, theta = packed[w]
        r_roll = radius[w] * 0.97
        out["f"][w] = np.array([
            tire_force(par, theta, x, z, speed_m_s + vx, vz, (speed_m_s * t + px) / r_roll, speed_m_s / r_roll,
                       *segs[w[1]])[0]
            for t, x, z, vx, vz, px in zip(time_s, out["x"][w], pos[:, 3], vel[:, 1], vel[:, 3], pos[:, 1])])
    return Crossing(time_s=time_s, accel_z=out["a"], hub_z=out["z"], hub_vz=out["vz"], hub_x=out["x"],
                    force_z=out["f"], static_force_z=static)


def _rigid_body(mbs, mass, inertia, position):
    ri = eu.RigidBodyInertia(mass=mass, inertiaTensor=inertia)
    node = mbs.AddNode(NodeRigidBodyRotVecLG(referenceCoordinates=list(position) + [0.0, 0.0, 0.0]))
    return mbs.AddObject(ObjectRigidBody(mass=ri.mass, inertia=ri.GetInertia6D(), nodeNumber=node))


def _flat_stiffness(spec: TireSpec) -> float:
    """A rough flat-ground stiffness, only to place a corner near its equilibrium before settling."""
    if spec.kind == "point":
        return spec.stiffness
    return spec.stiffness * math.pi * math.sqrt(2 * spec.radius_m) / (2 * spec.dx_m) * 0.02 ** (spec.exponent - 0.5)
