"""The truth of a tire: its equivalent linear k and c, from a separate experiment in the same engine.

The wheel alone, a mass m = W/g on its tire on flat ground (standing: no lugs pass, no friction
- friction is a truth of its own), is released in Exudyn from ``amplitude_m`` above its static
equilibrium and rings down for ``duration_s``.  Its hub height is fitted (least squares) with
z(t) = e^{-σt}(A cos ω_d t + B sin ω_d t) + D; then k = m (ω_d² + σ²) and c = 2 m σ: the spring and
damper under m that ring exactly so.  For a progressive tire this is the tangent at the static load
(the amplitude is small); for a bed tire the footprint is the static one.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy.optimize import brentq, least_squares

import exudyn as exu
from exudyn.itemInterface import (LoadForceVector, MarkerBodyPosition, MarkerNodePosition, NodePoint,
                                  ObjectConnectorCartesianSpringDamper, ObjectGround, ObjectMassPoint, SensorNode)

from .tires import TireSpec, pack, tire_force
from .vehicle import GRAVITY

__all__ = ["free_decay_truth", "static_height"]

_FLAT = (np.array([0.0, 1e-3, 2e-3]), np.array([0.0, 0.0, 0.0]))


def static_height(spec: TireSpec, load_N: float) -> float:
    """Hub height over flat ground at which the standing tire carries ``load_N``."""
    par, xs = pack(spec)

    def excess(z):
        return tire_force(par, xs, -10.0, z, 0.0, 0.0, 0.0, 0.0, *_FLAT)[0] - load_N
    r = spec.radius_m
    return brentq(excess, r - 0.3, r, xtol=1e-12)


def free_decay_truth(spec: TireSpec, load_N: float, *, amplitude_m: float = 1e-3, duration_s: float = 1.5,
                     step_s: float = 1e-4) -> dict:
    """k, c (and the fit's details) of ``spec`` under ``load_N``: the free-decay experiment."""
    spec = replace(spec, lug_amplitude_m=0.0, friction_N=0.0)
    m = load_N / GRAVITY
    z_eq = static_height(spec, load_N)
    par, xs = pack(spec)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    m_ground = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    node = mbs.AddNode(NodePoint(referenceCoordinates=[0.0, 0.0, z_eq], initialCoordinates=[0.0, 0.0, amplitude_m]))
    mbs.AddObject(ObjectMassPoint(mass=m, nodeNumber=node))
    marker = mbs.AddMarker(MarkerNodePosition(nodeNumber=node))
    mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=[0.0, 0.0, -load_N]))

    def law(mbs_, t, item, u, v, k, d, off):
        return [0.0, 0.0, -tire_force(par, xs, -10.0, u[2], 0.0, v[2], 0.0, 0.0, *_FLAT)[0]]
    mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[m_ground, marker], springForceUserFunction=law))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=exu.OutputVariableType.Position,
                                      storeInternal=True))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = int(round(duration_s / step_s))
    ss.timeIntegration.endTime = duration_s
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = step_s
    mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.RK44)
    data = mbs.GetSensorStoredData(sensor)
    t, z = data[:, 0], data[:, 3] - z_eq
    return _fit(t, z, m) | {"static_height_m": z_eq, "amplitude_m": amplitude_m}


def _fit(t, z, m):
    # start: frequency from zero crossings, decay from the envelope
    zc = np.where(np.diff(np.signbit(z)))[0]
    wd0 = math.pi / np.mean(np.diff(t[zc])) if len(zc) > 2 else 20.0
    peaks = [np.abs(z[zc[i]:zc[i + 1]]).max() for i in range(min(len(zc) - 1, 6))]
    sigma0 = math.log(peaks[0] / peaks[-1]) / (len(peaks) - 1) / (math.pi / wd0) if len(peaks) > 2 else 1.0

    def model(p):
        s, w, a, b, d = p
        return np.exp(-s * t) * (a * np.cos(w * t) + b * np.sin(w * t)) + d

    res = least_squares(lambda p: model(p) - z, [sigma0, wd0, z[0], 0.0, 0.0], x_scale="jac",
                        xtol=1e-14, ftol=1e-14, gtol=1e-14)
    s, w = res.x[:2]
    rms = float(np.sqrt(np.mean(res.fun ** 2)))
    return {"k": m * (w * w + s * s), "c": 2 * m * s, "mass_kg": m, "omega_d": w, "sigma": s,
            "fit_rms_rel": rms / float(np.abs(z).max())}
