"""Run an FMU on sampled input signals: fmpy (``simulate_fmu`` and a bare loop) and libcosimpy.

Signals are dicts ``{name: 1-D array}`` on a uniform time grid ``t_k = start
+ k h`` (k = 0..N), key ``"time"`` included.  Semantics of the results:

* :func:`simulate_fmpy` — ``fmpy.simulate_fmu`` with the inputs as an input
  table: row 0 holds the outputs after initialisation (inputs of row 0);
  row k ≥ 1 the outputs recorded at t_k after the step from t_{k-1}, during
  which fmpy held the inputs of row k-1 (its co-simulation master applies
  inputs at the start of each communication step).
* :func:`run_fmpy_loop` and :func:`run_libcosim` (:func:`run_libcosim_apart`: the
  same in a child process) — for k = 0..N-1: set the
  inputs of row k, step from t_k to t_{k+1}, read the outputs; so their
  row k equals row k+1 of :func:`simulate_fmpy`.

``start_values`` (``{name: value}``, floats for Real and bools for Boolean
variables) are set before initialization in every runner, overriding the
FMU's own start values.
"""

from __future__ import annotations

import math
import os
import pickle
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["simulate_fmpy", "run_fmpy_loop", "run_libcosim", "run_libcosim_apart", "open_fmpy_slave", "set_values",
           "variable_refs", "python_apart", "ending", "publish"]


def variable_refs(fmu) -> dict[str, tuple[int, str]]:
    """``{name: (value reference, type)}`` of every variable of `fmu`."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu), validate=False)
    return {v.name: (v.valueReference, v.type) for v in md.modelVariables}


def _grid(signals):
    t = np.asarray(signals["time"], dtype=float)
    if t.size < 2:
        raise ValueError("input signals need at least two samples")
    return t, float(t[1] - t[0])


def simulate_fmpy(fmu, signals: dict, outputs: list[str], *, start_values: dict | None = None) -> dict:
    """``fmpy.simulate_fmu`` over the time grid of `signals`; returns ``{name: array}`` incl. time."""
    from fmpy import simulate_fmu

    t, h = _grid(signals)
    names = [n for n in signals if n != "time"]
    table = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = t
    for n in names:
        table[n] = signals[n]
    res = simulate_fmu(str(fmu), start_time=float(t[0]), stop_time=float(t[-1]), step_size=h,
                       output_interval=h, input=table, output=list(outputs),
                       start_values=start_values or {})
    return {name: np.array(res[name]) for name in ["time", *outputs]}


def open_fmpy_slave(fmu, *, instance_name="instance", logger=None, logging_on=False, start_values=None):
    """Extract, instantiate and initialise `fmu` with fmpy's FMU2Slave.

    Parameters
    ----------
    logger : callable, optional
        ``logger(status: int, category: str, message: str)`` receiving the FMU's log messages.
    start_values : dict, optional
        Values set after instantiation, before initialization.

    Returns
    -------
    slave : fmpy.fmi2.FMU2Slave
        Initialised (after exitInitializationMode); call ``terminate`` and ``freeInstance``.
        The extracted FMU is removed when the slave object is garbage-collected.
    """
    import ctypes
    import shutil
    import tempfile

    from identification._files import temp_prefix
    import weakref

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                           fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
    from fmpy import calloc, free

    md = read_model_description(str(fmu), validate=False)
    unzipped = extract(str(fmu), unzipdir=tempfile.mkdtemp(prefix=temp_prefix("fmu")))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=instance_name)
    weakref.finalize(slave, shutil.rmtree, unzipped, ignore_errors=True)
    callbacks = None
    if logger is not None:
        from fmpy.logging import addLoggerProxy

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda _c, _name, status, category, message: logger(
                status, (category or b"").decode("utf-8", "replace"), (message or b"").decode("utf-8", "replace")))
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(ctypes.byref(callbacks))
    slave.instantiate(callbacks=callbacks, loggingOn=logging_on or logger is not None)
    slave.setupExperiment(startTime=0.0)
    if start_values:
        set_values(slave, variable_refs(fmu), start_values)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def set_values(slave, refs: dict, values: dict) -> None:
    """Set Real and Boolean variables of an fmpy slave by name, one call per type.

    Parameters
    ----------
    refs : dict
        :func:`variable_refs` of the FMU.
    values : dict
        ``{name: value}``.
    """
    reals, bools = _split(refs, list(values))
    if reals:
        slave.setReal([refs[n][0] for n in reals], [float(values[n]) for n in reals])
    if bools:
        slave.setBoolean([refs[n][0] for n in bools], [bool(values[n]) for n in bools])


def _split(refs, names):
    reals = [n for n in names if refs[n][1] == "Real"]
    bools = [n for n in names if refs[n][1] == "Boolean"]
    unknown = set(names) - set(reals) - set(bools)
    if unknown:
        raise ValueError(f"only Real and Boolean variables are supported, not {sorted(unknown)}")
    return reals, bools


def run_fmpy_loop(fmu, signals: dict, outputs: list[str], *, start_values: dict | None = None) -> dict:
    """Bare FMU2Slave loop: set inputs of row k, doStep(t_k, h), read outputs (N rows)."""
    t, h = _grid(signals)
    refs = variable_refs(fmu)
    inputs = [n for n in signals if n != "time"]
    in_vrs = [refs[n][0] for n in inputs]
    reals, bools = _split(refs, outputs)
    slave = open_fmpy_slave(fmu, start_values=start_values)
    out = {n: np.empty(t.size - 1, dtype=bool if n in bools else float) for n in outputs}
    try:
        for k in range(t.size - 1):
            slave.setReal(in_vrs, [float(signals[n][k]) for n in inputs])
            slave.doStep(float(t[k]), h)
            for n, v in zip(reals, slave.getReal([refs[n][0] for n in reals])):
                out[n][k] = v
            for n, v in zip(bools, slave.getBoolean([refs[n][0] for n in bools])):
                out[n][k] = bool(v)
        slave.terminate()
    finally:
        slave.freeInstance()
    out["time"] = t[1:]
    return out


def run_libcosim(fmu, signals: dict, outputs: list[str], *, start_values: dict | None = None) -> dict:
    """The loop of :func:`run_fmpy_loop` in the Open Simulation Platform engine (libcosimpy).

    The inputs are applied with an override manipulator before each step and
    the outputs read with a last-value observer after it; `start_values` are
    libcosim initial values.  Sets libcosim's
    (process-wide) log level to warning.

    Raises
    ------
    RuntimeError
        If libcosim fails to load the FMU or a step fails.
    """
    from libcosimpy.CosimEnums import CosimExecutionState
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    t, h = _grid(signals)
    step_ns = round(h * 1e9)
    if not math.isclose(step_ns * 1e-9, h, rel_tol=1e-12):
        raise ValueError(f"step {h} s is not a whole number of nanoseconds")
    refs = variable_refs(fmu)
    inputs = [n for n in signals if n != "time"]
    in_vrs = [refs[n][0] for n in inputs]
    reals, bools = _split(refs, outputs)
    log_output_level(CosimLogLevel.WARNING)  # libcosim's default level prints every FMI call
    execution = CosimExecution.from_step_size(step_ns)
    slave = CosimLocalSlave(fmu_path=str(Path(fmu).resolve()), instance_name="fmu")
    index = execution.add_local_slave(slave)
    if index < 0:
        raise RuntimeError(f"libcosim could not load {fmu}")
    start_values = start_values or {}
    start_reals, start_bools = _split(refs, list(start_values))
    for n in start_reals:
        if not execution.real_initial_value(index, refs[n][0], float(start_values[n])):
            raise RuntimeError(f"libcosim refused the initial value of {n}")
    for n in start_bools:
        if not execution.boolean_initial_value(index, refs[n][0], bool(start_values[n])):
            raise RuntimeError(f"libcosim refused the initial value of {n}")
    observer = CosimObserver.create_last_value()
    manipulator = CosimManipulator.create_override()
    execution.add_observer(observer)
    execution.add_manipulator(manipulator)
    out = {n: np.empty(t.size - 1, dtype=bool if n in bools else float) for n in outputs}
    for k in range(t.size - 1):
        if in_vrs:   # (a kind without inputs: nothing to override)
            manipulator.slave_real_values(index, in_vrs, [float(signals[n][k]) for n in inputs])
        if not execution.step() or execution.status().state == CosimExecutionState.ERROR.value:
            raise RuntimeError(f"libcosim step {k} of {fmu} failed: {execution.status()}")
        for n, v in zip(reals, observer.last_real_values(index, [refs[n][0] for n in reals])):
            out[n][k] = v
        for n, v in zip(bools, observer.last_boolean_values(index, [refs[n][0] for n in bools]) if bools else ()):
            out[n][k] = bool(v)
    out["time"] = t[1:]
    return out


def python_apart(module_args: list[str], **kwargs) -> subprocess.CompletedProcess:
    """``python -P -m <module_args>`` in a child process that imports this very ``build_scripts`` (its folder
    first on PYTHONPATH), output captured as text."""
    path = [str(Path(__file__).resolve().parents[1]), os.environ.get("PYTHONPATH")]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, path))}
    return subprocess.run([sys.executable, "-P", "-m", *module_args], capture_output=True, text=True, env=env,
                          **kwargs)


def publish(path, data: bytes) -> None:
    """Write `data` to `path` whole or not at all (a ``.part`` file renamed): a child's result, which its
    parent takes as written once the file exists."""
    part = Path(path).with_suffix(".part")
    part.write_bytes(data)
    part.replace(path)


def ending(returncode: int) -> str:
    """How a child process ended, in words: "signal SIGABRT", "exit status 1"."""
    if returncode < 0:
        try:
            return f"signal {signal.Signals(-returncode).name}"
        except ValueError:
            return f"signal {-returncode}"
    return f"exit status {returncode}"


def run_libcosim_apart(fmu, signals: dict, outputs: list[str], *, start_values: dict | None = None,
                       log=print) -> dict:
    """:func:`run_libcosim` in a child process, its results returned.

    libcosim's engine, its worker threads and the FMU library it loads (a pythonfmu FMU's C++ calls back into
    the interpreter) are torn down with the child, not in the caller (see :mod:`build_scripts.check` for the
    abort this avoids).  The child writes its outputs before it exits; if it then dies, they stand and `log`
    says how it ended.

    Raises
    ------
    RuntimeError
        If the child ends before writing its outputs (with its last line of error output).
    """
    with tempfile.TemporaryDirectory(prefix="libcosim_") as tmp:
        job, result = Path(tmp) / "job.pkl", Path(tmp) / "out.pkl"
        job.write_bytes(pickle.dumps((str(Path(fmu).resolve()), {k: np.asarray(v) for k, v in signals.items()},
                                      list(outputs), start_values)))
        proc = python_apart(["build_scripts.runners", str(job), str(result)])
        if not result.exists():
            last = (proc.stderr.strip().splitlines() or [ending(proc.returncode)])[-1]
            raise RuntimeError(f"libcosim's process on {Path(fmu).name} ended before its result: {last}")
        out = pickle.loads(result.read_bytes())
    if proc.returncode:
        log(f"{Path(fmu).name}: libcosim's process wrote its result, then ended with {ending(proc.returncode)}")
    return out


def _child(job: str, result: str) -> int:
    fmu, signals, outputs, start_values = pickle.loads(Path(job).read_bytes())
    publish(result, pickle.dumps(run_libcosim(fmu, signals, outputs, start_values=start_values)))
    return 0


if __name__ == "__main__":
    sys.exit(_child(*sys.argv[1:]))
