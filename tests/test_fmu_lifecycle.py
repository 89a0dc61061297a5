"""Instances that saw a failing call are freed, and the library goes on serving new instances.

Each FMU's shared library is loaded once (fmpy's ``FMU2Slave``/``FMU3Slave``;
instances are freed with ``fmi2FreeInstance``/``fmi3FreeInstance`` so that the
library stays loaded).  A cycle instantiates, takes the instance to one of the
modes it goes through (instantiated, initialization, step, terminated), makes
one call fail there and frees the instance.  For FMI 2.0 the blocks the FMU
takes from the importer's ``allocateMemory`` must all come back through
``freeMemory`` after each free: every instance is freed, failing calls
included.  Memory growth over many cycles is measured by
``benchmarks/bench_fmu_lifecycle.py``, not here.
"""

from __future__ import annotations

import math
import zipfile

import pytest
from native_fixtures import native_fmus, native_fmus3  # noqa: F401

from build_scripts import build_fmu

CYCLES = 500
#: A value reference that is no variable of the FMU.
INVALID_VR = 999
MODES = ("instantiated", "initialization", "step", "terminated")


@pytest.fixture(scope="module")
def pythonfmu_fmu(tmp_path_factory):
    """The pythonfmu point-contact FMU with its default start values."""
    return build_fmu("point_contact", tmp_path_factory.mktemp("pythonfmu") / "point_contact.fmu")


def _open(fmu, folder, fmi_version):
    """Extract `fmu` into `folder` and load its library; returns the fmpy slave (no instance yet) and
    ``{name: (value reference, start)}``."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu), validate=False)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    if fmi_version == 2:
        from fmpy.fmi2 import FMU2Slave as Slave
    else:
        from fmpy.fmi3 import FMU3Slave as Slave
    slave = Slave(guid=md.guid, unzipDirectory=str(folder), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="lifecycle")
    return slave, {v.name: (v.valueReference, v.start) for v in md.modelVariables}


def _counting_callbacks(messages: list):
    """FMI 2.0 callbacks: a logger appending ``(status, message)`` to `messages`, and calloc/free counting the
    blocks handed out and not yet given back (``callbacks.live[0]``)."""
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)

    live = [0]

    def allocate(n, size):
        p = calloc(n, size)
        if p:
            live[0] += 1
        return p

    def release(p):
        if p:
            live[0] -= 1
            free(p)

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda _env, _name, status, _category, message:
                                              messages.append((status, message)))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(allocate)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(release)
    return callbacks, live


def _to_mode(s, mode: str, fmi_version: int) -> None:
    """Take a fresh instance of slave `s` to `mode` (a name in MODES)."""
    if MODES.index(mode) >= 1:
        if fmi_version == 2:
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
        else:
            s.enterInitializationMode(startTime=0.0)
    if MODES.index(mode) >= 2:
        s.exitInitializationMode()
    if mode == "terminated":
        s.terminate()


def _failing_calls(s, refs, fmi_version: int, negative_step: bool) -> dict:
    """``{name: call}``: calls of slave `s` that must fail in every mode."""
    get, set_ = (s.getReal, s.setReal) if fmi_version == 2 else (s.getFloat64, s.setFloat64)
    calls = {"get invalid vr": lambda: get([INVALID_VR]),
             "set rejected value": lambda: set_([refs["stiffness"][0]], [-1.0])}
    if negative_step:
        calls["negative step"] = lambda: s.doStep(0.0, -1e-3)
    return calls


def _assert_a_clean_instance_works(s, refs, fmi_version: int, **instantiate) -> None:
    """A new instance of the loaded library goes through its whole life with its start values."""
    s.instantiate(**instantiate)
    _to_mode(s, "step", fmi_version)
    get = s.getReal if fmi_version == 2 else s.getFloat64
    assert get([refs["stiffness"][0]]) == [float(refs["stiffness"][1])]
    s.doStep(0.0, 1e-3)
    assert math.isfinite(get([refs["force_z"][0]])[0])
    s.terminate()
    (s.fmi2FreeInstance if fmi_version == 2 else s.fmi3FreeInstance)(s.component)


def _cycle_with_failures(s, refs, fmi_version, *, status, negative_step, instantiate, after_free=None):
    """CYCLES cycles: instantiate, go to a mode, one failing call (returning `status`), free."""
    from fmpy.fmi1 import FMICallException

    calls = _failing_calls(s, refs, fmi_version, negative_step)
    free = s.fmi2FreeInstance if fmi_version == 2 else s.fmi3FreeInstance
    for i in range(CYCLES):
        mode, name = MODES[i % len(MODES)], list(calls)[i % len(calls)]
        s.instantiate(**instantiate)
        _to_mode(s, mode, fmi_version)
        with pytest.raises(FMICallException) as info:
            calls[name]()
        assert info.value.status == status, (mode, name)
        free(s.component)
        if after_free is not None:
            after_free(mode, name)


@pytest.mark.parametrize("backend", ["native", "pythonfmu"])
def test_fmi2_instances_that_saw_a_failing_call_are_freed_and_the_library_serves_new_ones(
        backend, native_fmus, pythonfmu_fmu, tmp_path):  # noqa: F811
    fmu = native_fmus["point_contact"] if backend == "native" else pythonfmu_fmu
    s, refs = _open(fmu, tmp_path / "unzipped", 2)
    messages = []
    callbacks, live = _counting_callbacks(messages)

    def every_block_back(mode, name):
        assert live[0] == 0, f"{live[0]} blocks not freed after a failing {name} in {mode} mode"

    try:
        _assert_a_clean_instance_works(s, refs, 2, callbacks=callbacks, loggingOn=True)
        assert live[0] == 0
        # pythonfmu reports fmi2Fatal for every failing call, and its doStep takes a negative step
        _cycle_with_failures(s, refs, 2, status=3 if backend == "native" else 4, negative_step=backend == "native",
                             instantiate=dict(callbacks=callbacks, loggingOn=True), after_free=every_block_back)
        assert sum(status >= 3 for status, _ in messages) >= CYCLES  # each failure reached the logger
        _assert_a_clean_instance_works(s, refs, 2, callbacks=callbacks, loggingOn=True)
        assert live[0] == 0
    finally:
        s.freeLibrary()


def test_fmi3_instances_that_saw_a_failing_call_are_freed_and_the_library_serves_new_ones(native_fmus3,  # noqa: F811
                                                                                          tmp_path):
    s, refs = _open(native_fmus3["point_contact"], tmp_path / "unzipped", 3)
    messages = []

    def logger(_env, status, _category, message):
        messages.append((status, message))

    try:
        _assert_a_clean_instance_works(s, refs, 3, loggingOn=True, logMessage=logger)
        _cycle_with_failures(s, refs, 3, status=3, negative_step=True,
                             instantiate=dict(loggingOn=True, logMessage=logger))
        assert sum(status >= 3 for status, _ in messages) >= CYCLES
        _assert_a_clean_instance_works(s, refs, 3, loggingOn=True, logMessage=logger)
    finally:
        s.freeLibrary()


def _rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_fmu_states_the_importer_never_freed_go_with_their_instance(native_fmus, native_fmus3,  # noqa: F811
                                                                    tmp_path, fmi_version):
    """FMI: freeing an instance frees all the memory its functions allocated, the FMU states included.
    10,000 instances each take 20 states (two also serialized and deserialized) and are freed without
    freeing a state: the process grows by far less than the states' size (tens of MB if they leaked)."""
    fmu = (native_fmus if fmi_version == 2 else native_fmus3)["extended_tire"]
    s, refs = _open(fmu, tmp_path / "unzipped", fmi_version)
    free = s.fmi2FreeInstance if fmi_version == 2 else s.fmi3FreeInstance
    get_state = s.getFMUstate if fmi_version == 2 else s.getFMUState
    n_values = len(refs)
    try:
        def cycle():
            s.instantiate()
            _to_mode(s, "step", fmi_version)
            for _ in range(20):
                get_state()
            state = get_state()
            s.deSerializeFMUstate(s.serializeFMUstate(state)) if fmi_version == 2 else \
                s.deserializeFMUState(s.serializeFMUState(state))
            free(s.component)

        for _ in range(200):   # warm-up: allocator pools, ctypes caches
            cycle()
        before = _rss_bytes()
        for _ in range(10_000):
            cycle()
        grown = _rss_bytes() - before
    finally:
        s.freeLibrary()
    leaked_if_kept = 10_000 * 22 * 8 * n_values
    assert leaked_if_kept > 15e6
    assert grown < leaked_if_kept / 10, f"grew {grown / 1e6:.1f} MB over 10,000 instances (states: " \
                                        f"{leaked_if_kept / 1e6:.0f} MB if none were freed)"
