"""Run an SSP 1.0 system of FMUs: with fmpy, in libcosim (Open Simulation Platform), and the project's master.

Two exchange schemes, both once per communication step h:

``"sequential"`` (Gauss-Seidel)
    the components step in the order of the SSD's elements, each with its
    inputs read from its sources' outputs just before its ``doStep``.  With the
    body first, the tires' forces are those of the body's latest hub motion -
    the scheme of the project's master (:func:`identification.model.stepping.run_body`).
``"parallel"`` (Jacobi)
    every component steps on the values of the last exchange, then all
    outputs are exchanged: what fixed-step masters such as libcosim do.  The
    tire forces are then one step old (a coupling delay, which acts as a
    negative damper of about k h).

Both start from consistent initial values: in initialization mode the
connections are applied as many times as there are components (as libcosim
does), so the tires' first forces are those of the body's initial hub motion.

:func:`master_reference` runs the same system in the project's master (the
stepping of the model record with the tire law, in plain Python) with either
exchange, for comparison.
"""

from __future__ import annotations

import math
import shutil
import tempfile
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from .ssp import _NS, BODY, SSD_NAME
from .._files import temp_prefix

__all__ = ["EXCHANGES", "read_system", "ssd_step", "run_ssp_fmpy", "run_ssp_libcosim", "master_reference", "BODY_OUTPUTS",
           "AGREEMENT", "relative_deviation", "check_ssp"]

EXCHANGES = ("sequential", "parallel")
#: Body outputs recorded by the runners (the tires' order FL, FR, RL, RR).
BODY_OUTPUTS = tuple(f"{q}_{t}" for q in ("hub_z", "hub_vz", "hub_az") for t in ("FL", "FR", "RL", "RR")) + (
    "seat_z", "seat_az")


def _check_exchange(exchange: str) -> None:
    if exchange not in EXCHANGES:
        raise ValueError(f"exchange must be one of {', '.join(EXCHANGES)}, got {exchange!r}")


def read_system(ssp_path):
    """(components [(name, source)], connections [(start element, start connector, end element, end
    connector)], default experiment (start, stop)) of an SSP, read with fmpy's SSD reader (schema-validated)."""
    from fmpy.ssp.ssd import get_connections, read_ssd

    ssd = read_ssd(str(ssp_path))
    components = [(c.name, c.source) for c in ssd.system.elements]
    connections = [(a.parent.name, a.name, b.parent.name, b.name) for a, b in get_connections(ssd.system)]
    with zipfile.ZipFile(ssp_path) as z:   # (fmpy's reader skips the default experiment)
        root = ET.fromstring(z.read(SSD_NAME))
    de = root.find("ssd:DefaultExperiment", _NS)
    if de is None:
        raise ValueError(f"{ssp_path}: the SSD has no DefaultExperiment")
    return components, connections, (float(de.get("startTime", 0.0)), float(de.get("stopTime")))


def run_ssp_fmpy(ssp_path, *, step_s: float, stop_s: float | None = None, exchange: str = "sequential",
                 outputs=BODY_OUTPUTS) -> dict:
    """Run the system with fmpy's FMI 2.0 slaves; returns ``{"time": ..., output: array}`` of the body.

    Row 0 holds the outputs after initialization, row i those after the i-th step.
    """
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    _check_exchange(exchange)
    components, connections, (start, stop) = read_system(ssp_path)
    stop = stop if stop_s is None else float(stop_s)
    n = int(round((stop - start) / step_s))
    tmp = Path(tempfile.mkdtemp(prefix=temp_prefix("ssprun")))
    slaves, refs = {}, {}
    try:
        with zipfile.ZipFile(ssp_path) as z:
            z.extractall(tmp)
        for name, source in components:
            fmu = tmp / source
            unzip = tmp / f"{name}.unzipped"
            with zipfile.ZipFile(fmu) as z:
                z.extractall(unzip)
            md = read_model_description(str(fmu))
            refs[name] = {v.name: v.valueReference for v in md.modelVariables}
            slave = FMU2Slave(guid=md.guid, unzipDirectory=str(unzip),
                              modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
            slave.instantiate()
            slaves[name] = slave
        order = [name for name, _ in components]
        # per end component: [(its vr, source slave, source vr)]
        feeds = {name: [] for name in order}
        for a, ca, b, cb in connections:
            feeds[b].append((refs[b][cb], slaves[a], refs[a][ca]))

        def apply(name, values=None):
            if feeds[name]:
                vals = values[name] if values is not None else [s.getReal([vr])[0] for _, s, vr in feeds[name]]
                slaves[name].setReal([vr for vr, _, _ in feeds[name]], list(vals))

        def snapshot():
            return {name: [s.getReal([vr])[0] for _, s, vr in feeds[name]] for name in order}

        for s in slaves.values():
            s.setupExperiment(startTime=start)
            s.enterInitializationMode()
        for _ in range(len(order)):
            for name in order:
                apply(name)
        for s in slaves.values():
            s.exitInitializationMode()
        body, body_refs = slaves[BODY], [refs[BODY][o] for o in outputs]
        rows = np.empty((n + 1, len(outputs)))
        rows[0] = body.getReal(body_refs)
        for i in range(n):
            t = start + i * step_s
            if exchange == "sequential":
                for name in order:
                    apply(name)
                    slaves[name].doStep(currentCommunicationPoint=t, communicationStepSize=step_s)
                apply(BODY)      # the forces of the new hub motion (the next step starts from them)
                rows[i + 1] = body.getReal(body_refs)
            else:
                values = snapshot()
                for name in order:
                    apply(name, values)
                    slaves[name].doStep(currentCommunicationPoint=t, communicationStepSize=step_s)
                rows[i + 1] = body.getReal(body_refs)
        for s in slaves.values():
            s.terminate()
    finally:
        for s in slaves.values():
            s.freeInstance()
        shutil.rmtree(tmp, ignore_errors=True)
    out = {"time": start + step_s * np.arange(n + 1)}
    out.update({o: rows[:, j] for j, o in enumerate(outputs)})
    return out


def ssd_step(ssp_path) -> float:
    """The communication step (s) the SSP's default experiment gives its hosts (the Open Simulation
    Platform's ``osp:FixedStepAlgorithm`` annotation)."""
    with zipfile.ZipFile(ssp_path) as z:
        root = ET.fromstring(z.read(SSD_NAME))
    algorithm = root.find("ssd:DefaultExperiment/ssd:Annotations/ssc:Annotation/osp:Algorithm/"
                          "osp:FixedStepAlgorithm", _NS)
    if algorithm is None:
        raise ValueError(f"{ssp_path}: the SSD gives its hosts no step (no osp:FixedStepAlgorithm)")
    return float(algorithm.get("baseStepSize"))


def run_ssp_libcosim(ssp_path, *, step_s: float | None, stop_s: float | None = None, outputs=BODY_OUTPUTS) -> dict:
    """Run the system in libcosim's fixed-step algorithm (libcosimpy); returns the body's outputs.

    libcosim reads the SSP itself (its SSP parser) and exchanges once per step
    after every component stepped: the ``"parallel"`` exchange.  Row i ≥ 1 holds
    the outputs after the i-th step; row 0 those after initialization.  With
    ``step_s=None`` libcosim takes the step from the SSP itself (its
    ``osp:FixedStepAlgorithm`` annotation, :func:`ssd_step`), as a user of the
    SSP alone would run it.
    """
    from libcosimpy.CosimEnums import CosimExecutionState
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    _, _, (start, stop) = read_system(ssp_path)
    stop = stop if stop_s is None else float(stop_s)
    own_step = step_s is None
    step_s = ssd_step(ssp_path) if own_step else step_s
    step_ns = round(step_s * 1e9)
    if not math.isclose(step_ns * 1e-9, step_s, rel_tol=1e-12):
        raise ValueError(f"step {step_s} s is not a whole number of nanoseconds")
    n = int(round((stop - start) / step_s))
    log_output_level(CosimLogLevel.WARNING)
    with tempfile.TemporaryDirectory(prefix=temp_prefix("cosim")) as tmp:
        with zipfile.ZipFile(ssp_path) as z:
            z.extractall(tmp)
        execution = CosimExecution.from_ssp_file(str(Path(tmp)), step_size=None if own_step else step_ns)
        index = execution.slave_index_from_instance_name(BODY)
        refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        vrs = [refs[o] for o in outputs]
        observer = CosimObserver.create_last_value()
        execution.add_observer(observer)
        rows = np.empty((n + 1, len(outputs)))
        rows[0] = np.nan
        for i in range(n):
            if not execution.step() or execution.status().state == CosimExecutionState.ERROR.value:
                raise RuntimeError(f"libcosim step {i} failed: {execution.status()}")
            rows[i + 1] = observer.last_real_values(index, vrs)
        del execution
    out = {"time": start + step_s * np.arange(n + 1)}
    out.update({o: rows[:, j] for j, o in enumerate(outputs)})
    return out


def _delayed(force):
    """The force callback of a parallel exchange: each call returns the force of the previous call's
    arguments (the first call its own), as a master that exchanges once per step after all steps."""
    last = []

    def call(*args):
        value = force(*(last[0] if last else args))
        last[:] = [args]
        return value

    return call


def master_reference(record, *, start_s: float, step_s: float, n: int, exchange: str = "sequential",
                     seat_x_m: float, seat_y: float = 0.0) -> dict:
    """The system in the project's master: ``run_body`` on the record with the tire law (plain Python).

    Returns the body outputs of :data:`BODY_OUTPUTS` on the grid start + i h
    (accelerations with the forces the body used at each point).
    """
    from ..model import tire_law
    from ..model.stepping import prepared, run_body
    from .ssp import body_seat_row

    _check_exchange(exchange)
    J, mass, static_z, loads, inputs, q0, dq0 = prepared(record, start_s, step_s, n)
    forces = []
    for p in record.laws:
        vec = tire_law.law_vector(p)
        f = (lambda z, vz, x, vx, r, rv, vec=vec: tire_law.tire_force(z, vz, x, vx, r, rv, vec))
        forces.append(f if exchange == "sequential" else _delayed(f))
    traj = run_body(forces, J=J, mass=mass, static_z=static_z, loads_n=loads, inputs=inputs, start_s=start_s,
                    step_s=step_s, q0=q0, dq0=dq0)
    qdd = np.linalg.lstsq(J, np.asarray(traj.hub_accel_m_s2), rcond=None)[0]
    q = np.linalg.lstsq(J, np.asarray(traj.hub_z_m) - np.asarray(static_z)[:, None], rcond=None)[0]
    row = body_seat_row(record.body, seat_x_m=seat_x_m, seat_y=seat_y)
    out = {"time": traj.time_s}
    for i, t in enumerate(record.tires):
        out[f"hub_z_{t}"] = traj.hub_z_m[i]
        out[f"hub_az_{t}"] = traj.hub_accel_m_s2[i]
    out["seat_z"] = row @ q
    out["seat_az"] = row @ qdd
    return out


#: Largest deviation of a host's run from the project's master accepted by :func:`check_ssp` (relative).
AGREEMENT = 1e-6


def relative_deviation(got: dict, ref: dict, names, rows=slice(None)) -> float:
    """Largest |got − ref| of the outputs `names` over rows `rows`, each over its own range in `ref`."""
    worst = 0.0
    for name in names:
        a, b = np.asarray(got[name])[rows], np.asarray(ref[name])[rows]
        worst = max(worst, float(np.max(np.abs(a - b)) / (float(np.ptp(ref[name])) or 1.0)))
    return worst


def check_ssp(ssp_path, record, *, start_s: float, step_s: float, stop_s: float, seat_x_m: float,
              seat_y: float = 0.0, libcosim: bool = True) -> dict:
    """Run the SSP in fmpy (both exchanges) and in libcosim, each against the project's master with the
    same exchange; returns ``{host: largest relative deviation of the hub heights and the seat}``."""
    n = int(round((stop_s - start_s) / step_s)) + 1
    names = [f"hub_z_{t}" for t in record.tires] + ["seat_z"]
    refs = {ex: master_reference(record, start_s=start_s, step_s=step_s, n=n, exchange=ex, seat_x_m=seat_x_m,
                                 seat_y=seat_y) for ex in EXCHANGES}
    out = {}
    for ex in EXCHANGES:
        out[f"fmpy ({ex} exchange)"] = relative_deviation(run_ssp_fmpy(ssp_path, step_s=step_s, stop_s=stop_s,
                                                                        exchange=ex), refs[ex], names)
    if libcosim:
        got = run_ssp_libcosim(ssp_path, step_s=step_s, stop_s=stop_s)
        out["libcosim (parallel exchange)"] = relative_deviation(got, refs["parallel"], names, rows=slice(1, None))
    out["exchange effect (parallel vs sequential master)"] = relative_deviation(refs["parallel"],
                                                                                 refs["sequential"], names)
    return out
