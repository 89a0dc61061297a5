"""Helpers shared by the FMU tests: instances, model descriptions, packaged modules, robustness, leaks.

Every helper works for any FMU kind of ``fmu_src``; the tests of a kind pass
its FMU, its variable names and the values they expect.
"""

from __future__ import annotations

import contextlib
import gc
import os
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

import build_scripts
from build_scripts import build_fmu
from build_scripts.reference import read_reference
from build_scripts.runners import open_fmpy_slave, run_fmpy_loop, run_libcosim_apart, simulate_fmpy, variable_refs

#: Largest RSS growth, in bytes, a leak test accepts over its cycles.
LEAK_LIMIT = 1024 * 1024


# -- instances ----------------------------------------------------------------------------------

def value_refs(fmu) -> dict[str, int]:
    """``{name: value reference}`` of every variable of `fmu`."""
    return {name: ref for name, (ref, _type) in variable_refs(fmu).items()}


def kind_fixtures(kind: str, scope: str = "module"):
    """The fixtures ``fmu``, ``vr`` and ``slave`` of a test module of FMU kind `kind`.

    Bind them at module level: ``fmu, vr, slave = kind_fixtures("point_contact")``.

    Parameters
    ----------
    kind : str
        The FMU kind.
    scope : str
        Scope of ``fmu`` and ``vr``.

    Returns
    -------
    tuple of pytest fixtures
        ``fmu``: the kind's FMU with its default start values, built once per
        scope; ``vr``: its value references by name; ``slave``: an initialised
        instance with a logger, ``(slave, messages)`` as :func:`logged_slave`.
    """
    @pytest.fixture(scope=scope)
    def fmu(tmp_path_factory) -> Path:
        return build_fmu(kind, tmp_path_factory.mktemp(kind) / f"{kind}.fmu")

    @pytest.fixture(scope=scope)
    def vr(fmu) -> dict:
        return value_refs(fmu)

    @pytest.fixture
    def slave(fmu):
        with logged_slave(fmu) as pair:
            yield pair

    return fmu, vr, slave


@contextlib.contextmanager
def logged_slave(fmu):
    """An initialised fmpy instance of `fmu` that records its log messages.

    Yields
    ------
    slave : fmpy.fmi2.FMU2Slave
        Terminated and freed on exit.
    messages : list of (int, str)
        ``(status, message)`` of every message the FMU logged.
    """
    messages = []
    s = open_fmpy_slave(fmu, logger=lambda status, category, message: messages.append((status, message)))
    try:
        yield s, messages
    finally:
        s.terminate()
        s.freeInstance()


def reinitialise_and_step(s) -> None:
    """Set up, initialise and step `s` once (after a reset)."""
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 1e-3)


def run_steps(s, vr, input_names, inputs, read) -> list:
    """Set each row of `inputs`, step, and collect ``read(s)``; row i is the step from i ms."""
    out = []
    for i, u in enumerate(inputs):
        s.setReal([vr[n] for n in input_names], u)
        s.doStep(i * 1e-3, 1e-3)
        out.append(read(s))
    return out


def assert_state_round_trip(fmu, prepare, run, check_restored=None, check_copied=None) -> list:
    """A state restored in its instance, or serialized into another one, reproduces a run bit for bit.

    Parameters
    ----------
    fmu : path-like
        The FMU; two instances are opened and freed.
    prepare : callable
        ``prepare(s)`` sets the values of the first instance before its state is taken.
    run : callable
        ``run(s)`` returns the outputs of a run from the current state.
    check_restored, check_copied : callable, optional
        Called with the first instance after it restored the state, and with
        the second one after it set the deserialized copy.

    Returns
    -------
    list
        The outputs of the first run.
    """
    s, t = open_fmpy_slave(fmu), open_fmpy_slave(fmu, instance_name="copy")
    try:
        prepare(s)
        state = s.getFMUstate()
        first = run(s)
        s.setFMUstate(state)
        if check_restored:
            check_restored(s)
        assert run(s) == first
        blob = s.serializeFMUstate(state)
        s.freeFMUstate(state)
        copy = t.deSerializeFMUstate(blob)
        t.setFMUstate(copy)
        t.freeFMUstate(copy)
        if check_copied:
            check_copied(t)
        assert run(t) == first
    finally:
        s.freeInstance()
        t.freeInstance()
    return first


# -- the FMU file -------------------------------------------------------------------------------

def model_description(fmu) -> ET.Element:
    """The parsed modelDescription.xml of `fmu`."""
    return ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))


def output_dependencies(root: ET.Element) -> dict[str, tuple[set, list]]:
    """``{output: (names of the variables it depends on, dependency kinds)}`` from ModelStructure/Outputs."""
    name = {i: sv.get("name") for i, sv in enumerate(root.iter("ScalarVariable"), start=1)}
    return {name[int(u.get("index"))]: ({name[int(i)] for i in u.get("dependencies", "").split()},
                                        u.get("dependenciesKind", "").split())
            for u in root.find("ModelStructure/Outputs")}


def initial_unknowns(root: ET.Element) -> set:
    """Names of the variables listed in ModelStructure/InitialUnknowns."""
    name = {i: sv.get("name") for i, sv in enumerate(root.iter("ScalarVariable"), start=1)}
    return {name[int(u.get("index"))] for u in root.find("ModelStructure/InitialUnknowns")}


def rewrite_fmu(fmu, dest, member: str, edit) -> Path:
    """Copy `fmu` to `dest` with the bytes of archive member `member` replaced by ``edit(bytes)``."""
    with zipfile.ZipFile(fmu) as zin, zipfile.ZipFile(dest, "w") as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename == member:
                data = edit(data)
            zout.writestr(info, data)
    return Path(dest)


def packaged_modules(fmu) -> tuple[str, dict[str, bytes]]:
    """The entry module named in slavemodule.txt and ``{name: source}`` of the FMU's top-level modules."""
    with zipfile.ZipFile(fmu) as z:
        entry = z.read("resources/slavemodule.txt").decode().strip()
        modules = {Path(n).stem: z.read(n) for n in z.namelist() if n.count("/") == 1 and n.endswith(".py")}
    return entry, modules


# -- importers ----------------------------------------------------------------------------------

def assert_fmpy_matches_the_reference(fmu, kind, inputs, outputs, real_outputs, start_values=None) -> None:
    """``fmpy.simulate_fmu`` of `fmu` on the reference's inputs reproduces the kind's reference.

    Parameters
    ----------
    fmu : path-like
        FMU of the kind built with its default start values.
    kind : build_scripts.FmuKind
        The kind (its reference file and tolerances).
    inputs, outputs, real_outputs : list of str
        Input names; every output compared (Boolean ones exactly); the Real ones among them.
    start_values : dict, optional
        Values set before initialization (the reference's start values).
    """
    ref = read_reference(kind.name)
    sim = simulate_fmpy(fmu, {n: ref[n] for n in ["time", *inputs]}, outputs, start_values=start_values)
    for name in ["time", *real_outputs]:
        np.testing.assert_allclose(sim[name], ref[name], rtol=kind.reference_rtol, atol=kind.reference_atol)
    for name in outputs:
        if name not in real_outputs:
            assert np.array_equal(sim[name], ref[name]), name


def assert_libcosim_matches_fmpy(fmu, kind_name, inputs, outputs, start_values=None) -> None:
    """libcosimpy and the bare fmpy loop agree bit for bit, and with the reference one row later."""
    ref = read_reference(kind_name)
    signals = {n: ref[n] for n in ["time", *inputs]}
    fmpy_out = run_fmpy_loop(fmu, signals, outputs, start_values=start_values)
    cosim_out = run_libcosim_apart(fmu, signals, outputs, start_values=start_values)  # (its own process)
    for name in outputs:
        assert np.array_equal(cosim_out[name], fmpy_out[name]), name
        assert np.array_equal(cosim_out[name], ref[name][1:]), name  # = fmpy.simulate_fmu, one row later


# -- robustness ---------------------------------------------------------------------------------

def assert_value_rejected(s, messages, vr, watched, name, value, reason) -> None:
    """Setting Real `name` to `value` fails with status >= error, logs `reason`, stores nothing."""
    from fmpy.fmi1 import FMICallException

    before = s.getReal([vr[n] for n in watched])
    with pytest.raises(FMICallException) as info:
        s.setReal([vr[name]], [value])
    assert info.value.status >= 3  # fmi2Error or fmi2Fatal (pythonfmu 0.7 reports every failure as fatal)
    assert any(status == 3 and reason in message for status, message in messages), messages
    assert s.getReal([vr[n] for n in watched]) == before  # nothing was stored
    s.doStep(0.0, 1e-3)


def assert_host_survives_errors(fmu, failing_calls, recover: str, iterations: int) -> None:
    """Fail calls over and over, recovering each time, in three instances; in a child process.

    The child process makes a crash show as a failed test, not a dead test
    session.  In the child, ``vr`` maps names to value references, ``s`` is the
    instance and ``i`` the iteration.

    Parameters
    ----------
    fmu : path-like
        The FMU.
    failing_calls : list of str
        Source of functions of ``s`` (e.g. ``"lambda s: s.setReal(...)"``);
        iteration i makes call ``i % len(failing_calls)``, which must fail.
    recover : str
        Statements run after every failed call (they may assert).
    iterations : int
        Failed calls per instance.
    """
    script = textwrap.dedent(f"""
        import gc, math
        from fmpy.fmi1 import FMICallException
        from build_scripts.runners import open_fmpy_slave, variable_refs
        vr = {{n: r for n, (r, _) in variable_refs({str(fmu)!r}).items()}}
        calls = [{", ".join(failing_calls)}]
        for round in range(3):
            s = open_fmpy_slave({str(fmu)!r}, instance_name=f"r{{round}}")
            for i in range({iterations}):
                try:
                    calls[i % len(calls)](s)
                except FMICallException:
                    pass
                else:
                    raise SystemExit(f"call {{i % len(calls)}} did not fail")
                gc.collect()
    """) + textwrap.indent(textwrap.dedent(recover).strip(), " " * 8) + textwrap.dedent("""
            s.reset()
            s.freeInstance()
            gc.collect()
        print("survived")
    """)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(build_scripts.__file__).parent.parent), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr[-2000:] + done.stdout[-2000:]
    assert done.stdout.strip().endswith("survived")


# -- leaks --------------------------------------------------------------------------------------

def rss_bytes() -> int:
    """Resident set size of this process, bytes."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS")


def rss_growth(cycle, *, warmup: int, cycles: int = 1000, collect_every: int | None = None) -> int:
    """RSS growth, bytes, over `cycles` calls of `cycle` after `warmup` calls.

    With `collect_every`, the cyclic garbage collector runs after every that
    many cycles (fmpy's FMU2Slave objects are freed by it: collect, not count,
    them); it always runs before both measurements.
    """
    for _ in range(warmup):
        cycle()
    gc.collect()
    before = rss_bytes()
    for i in range(cycles):
        cycle()
        if collect_every and i % collect_every == collect_every - 1:
            gc.collect()
    gc.collect()
    return rss_bytes() - before


def fresh_cycle(fmu, unzipped):
    """A function that instantiates and frees `fmu` (extracted in `unzipped`) with a new FMU2Slave each call.

    ``freeInstance`` also unloads the library.
    """
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu), validate=False)

    def cycle():
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="leak")
        s.instantiate()
        s.freeInstance()
    return cycle


def assert_instantiate_free_cycles_leak_at_most_1_mb_and_keep_sys_path(fmu, unzipped) -> None:
    """1000 instantiate/free cycles, each on a freshly loaded library, after 300 warm-up cycles."""
    cycle = fresh_cycle(fmu, unzipped)
    for _ in range(300):  # warm-up: fmpy's and ctypes' own first-use allocations
        cycle()
    gc.collect()
    path_before = list(sys.path)
    growth = rss_growth(cycle, warmup=0, collect_every=100)
    assert sys.path == path_before
    assert growth <= LEAK_LIMIT, f"RSS grew by {growth / 1024:.0f} kB over 1000 instantiate/free cycles"


def assert_runs_match_the_law(runs: dict, signals, outputs, law: dict, closed: dict, kind) -> None:
    """Each FMU run of `runs` ({label: (fmu, start values or None)}) stepped by fmpy over `signals` gives
    the Python law's outputs `law` (bit for bit in a pythonfmu FMU, which runs the very law code; to
    1e-12 in a native one) and the independent closed form's `closed` (to the kind's reference tolerance)."""
    for label, (fmu, start_values) in runs.items():
        sim = simulate_fmpy(fmu, signals, outputs, start_values=start_values)
        for name in outputs:
            if name == "in_contact":
                assert np.array_equal(sim[name], law[name]) and np.array_equal(sim[name], closed[name]), label
                continue
            if label.startswith("pythonfmu"):
                assert np.array_equal(sim[name], law[name]), (label, name)
            else:
                np.testing.assert_allclose(sim[name], law[name], rtol=1e-12, atol=0.0, err_msg=f"{label}: {name}")
            np.testing.assert_allclose(sim[name], closed[name], rtol=kind.reference_rtol, atol=kind.reference_atol,
                                       err_msg=f"{label}: {name} (closed form)")
