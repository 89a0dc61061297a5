"""Run an FMI 3.0 FMU with fmpy's FMU3Slave: an initialised instance, the bare loop, FMU-state round trips.

Same semantics as :mod:`build_scripts.runners` (which is FMI 2.0 only for the
bare loop and libcosimpy): for k = 0..N-1 set the inputs of row k, step from
t_k to t_{k+1}, read the outputs.
"""

from __future__ import annotations

import shutil
import tempfile
import weakref

import numpy as np
from identification._files import temp_prefix

__all__ = ["open_fmi3_slave", "run_fmi3_loop", "fmi3_state_round_trip_problems"]


def _refs(fmu):
    from fmpy import read_model_description

    md = read_model_description(str(fmu), validate=False)
    return md, {v.name: (v.valueReference, v.type) for v in md.modelVariables}


def open_fmi3_slave(fmu, *, instance_name="instance", start_values=None, log_message=None):
    """Extract, instantiate and initialise an FMI 3.0 co-simulation FMU (fmpy's FMU3Slave).

    Parameters
    ----------
    start_values : dict, optional
        ``{name: value}`` set before initialization (Float64 and Boolean variables).
    log_message : callable, optional
        fmpy's ``logMessage(instanceEnvironment, status, category, message)`` callback.

    Returns
    -------
    fmpy.fmi3.FMU3Slave
        In step mode; call ``terminate`` and ``freeInstance``.
    """
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    md, refs = _refs(fmu)
    unzipped = extract(str(fmu), unzipdir=tempfile.mkdtemp(prefix=temp_prefix("fmu3")))
    slave = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=instance_name)
    weakref.finalize(slave, shutil.rmtree, unzipped, ignore_errors=True)
    slave.instantiate(logMessage=log_message, loggingOn=log_message is not None)
    slave.enterInitializationMode(startTime=0.0)
    for name, value in (start_values or {}).items():
        vr, typ = refs[name]
        if typ == "Boolean":
            slave.setBoolean([vr], [bool(value)])
        else:
            slave.setFloat64([vr], [float(value)])
    slave.exitInitializationMode()
    return slave


def _runner(fmu, signals, outputs):
    _, refs = _refs(fmu)
    inputs = [n for n in signals if n != "time"]
    in_vrs = [refs[n][0] for n in inputs]
    reals = [n for n in outputs if refs[n][1] == "Float64"]
    bools = [n for n in outputs if refs[n][1] == "Boolean"]
    t = np.asarray(signals["time"], dtype=float)
    h = float(t[1] - t[0])

    def run(slave, ks):
        rows = []
        for k in ks:
            slave.setFloat64(in_vrs, [float(signals[n][k]) for n in inputs])
            slave.doStep(float(t[k]), h)
            rows.append((*slave.getFloat64([refs[n][0] for n in reals]),
                         *(slave.getBoolean([refs[n][0] for n in bools]) if bools else ())))
        return rows

    return run, reals, bools, t


def run_fmi3_loop(fmu, signals: dict, outputs: list[str], *, start_values: dict | None = None) -> dict:
    """Bare FMU3Slave loop: set inputs of row k, doStep(t_k, h), read outputs (N rows, time = t[1:])."""
    run, reals, bools, t = _runner(fmu, signals, outputs)
    slave = open_fmi3_slave(fmu, start_values=start_values)
    try:
        rows = run(slave, range(t.size - 1))
        slave.terminate()
    finally:
        slave.freeInstance()
    names = [*reals, *bools]
    out = {n: np.array([r[i] for r in rows], dtype=bool if n in bools else float) for i, n in enumerate(names)}
    out["time"] = t[1:]
    return out


def fmi3_state_round_trip_problems(fmu, signals: dict, outputs, start_values: dict | None = None) -> list[str]:
    """Get/set and serialize/deserialize the FMU state mid-run; the outputs must repeat bit for bit."""
    from fmpy.fmi3 import fmi3FMUState

    run, _, _, t = _runner(fmu, signals, outputs)
    half = (t.size - 1) // 2
    problems = []
    slave = open_fmi3_slave(fmu, instance_name="state", start_values=start_values)
    try:
        run(slave, range(half))
        state = slave.getFMUState()
        first = run(slave, range(half, t.size - 1))
        slave.setFMUState(state)
        if run(slave, range(half, t.size - 1)) != first:
            problems.append("outputs after fmi3SetFMUState differ from the first run")
        blob = slave.serializeFMUState(state)
        slave.freeFMUState(state)
        other = open_fmi3_slave(fmu, instance_name="state_copy")
        try:
            copy = fmi3FMUState()
            other.deserializeFMUState(blob, copy)
            other.setFMUState(copy)
            if run(other, range(half, t.size - 1)) != first:
                problems.append("outputs after fmi3DeserializeFMUState in a new instance differ from the first run")
            other.freeFMUState(copy)
            other.terminate()
        finally:
            other.freeInstance()
        slave.terminate()
    finally:
        slave.freeInstance()
    return problems
