"""``python -m build_scripts.check``: build and check every FMU kind in ``fmu_src``.

For each kind and variant (pythonfmu FMI 2.0, native C FMI 2.0 and 3.0; the
variants of the kind's backends: the tractor body is native only):

1. build the FMU (:func:`build_scripts.build_fmu`) with the kind's default
   start values;
2. compliance: ``validate_fmu(fmu) == []`` and the checks of
   :mod:`build_scripts.compliance` (units, descriptions, default experiment,
   model structure, module names);
3. simulate the default experiment with ``fmpy.simulate_fmu`` on the input
   signals of the kind's reference CSV, with the reference's start values
   (``kind.json``: ``reference.start_values``, set before initialization),
   and compare every output with the reference:
   ``|x - ref| <= atol + rtol |ref|`` with the kind's tolerances (rtol, atol
   in the output's SI unit, from ``kind.json``; booleans exactly);
4. run the same inputs in libcosimpy (Open Simulation Platform) and compare
   with fmpy: the bare fmpy FMU2Slave loop must agree bit for bit (a kind
   with a state or outputs that follow the clock, ``native.state`` or ``native.clock``
   in kind.json: within the reference's tolerance), and both
   with the reference within its tolerance (FMI 3.0: the bare FMU3Slave loop
   with the reference; libcosimpy runs FMI 2.0 only);
5. if the kind declares FMU-state support: get/set and serialize/deserialize
   round trips must reproduce the outputs bit for bit.

For the native backend, the default experiment (no inputs) must also show
the static equilibrium: force_z = the default static wheel load throughout
(a tire), the body at rest on its static loads (the body).

Across kinds, module names and model identifiers must be unique.  Exit status
0 if everything passes, 1 otherwise (problems on stderr).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .build import BACKENDS, build_fmu, resolve_start_values
from .compliance import compliance_problems
from .kinds import kind_names, load_kind, module_name_conflicts
from .reference import read_reference
from .runners import (ending, open_fmpy_slave, publish, python_apart, run_fmpy_loop, run_libcosim, simulate_fmpy,
                      variable_refs)
from identification._files import temp_prefix

__all__ = ["check_kind", "check_variant", "check_variant_apart", "state_round_trip_problems", "compare", "main"]


def compare(label: str, got: dict, ref: dict, names, rtol: float, atol: float, rows=slice(None)) -> list[str]:
    """Problems where ``got[name]`` differs from ``ref[name][rows]`` beyond tolerance."""
    problems = []
    for name in names:
        a, b = np.asarray(got[name]), np.asarray(ref[name])[rows]
        if a.shape != b.shape:
            problems.append(f"{label}: {name}: {a.shape[0]} samples, expected {b.shape[0]}")
        elif a.dtype == bool or b.dtype == bool:
            if not np.array_equal(a.astype(bool), b.astype(bool)):
                problems.append(f"{label}: {name}: {int(np.sum(a != b))} samples differ")
        else:
            err = np.abs(a - b) - (atol + rtol * np.abs(b))
            if not np.all(err <= 0.0):
                i = int(np.argmax(err))
                problems.append(f"{label}: {name}[{i}] = {a[i]!r}, expected {b[i]!r} (rtol {rtol}, atol {atol})")
    return problems


def state_round_trip_problems(fmu, signals: dict, outputs, start_values: dict | None = None) -> list[str]:
    """Get/set and serialize/deserialize the FMU state mid-run; outputs must repeat bit for bit.

    The state is taken from an instance started with `start_values`; the
    deserialized copy goes to an instance started with the FMU's own values,
    so the state must carry the parameters too.
    """
    refs = variable_refs(fmu)
    inputs = [n for n in signals if n != "time"]
    in_vrs = [refs[n][0] for n in inputs]
    reals = [refs[n][0] for n in outputs if refs[n][1] == "Real"]
    bools = [refs[n][0] for n in outputs if refs[n][1] == "Boolean"]
    t = np.asarray(signals["time"])
    h = float(t[1] - t[0])
    half = (t.size - 1) // 2

    def run(slave, ks):
        out = []
        for k in ks:
            slave.setReal(in_vrs, [float(signals[n][k]) for n in inputs])
            slave.doStep(float(t[k]), h)
            out.append((*slave.getReal(reals), *(slave.getBoolean(bools) if bools else ())))
        return out

    problems = []
    slave = open_fmpy_slave(fmu, instance_name="state", start_values=start_values)
    try:
        run(slave, range(half))
        state = slave.getFMUstate()
        first = run(slave, range(half, t.size - 1))
        slave.setFMUstate(state)
        if run(slave, range(half, t.size - 1)) != first:
            problems.append("outputs after fmi2SetFMUstate differ from the first run")
        blob = slave.serializeFMUstate(state)
        slave.freeFMUstate(state)
        other = open_fmpy_slave(fmu, instance_name="state_copy")
        try:
            copy = other.deSerializeFMUstate(blob)
            other.setFMUstate(copy)
            if run(other, range(half, t.size - 1)) != first:
                problems.append("outputs after fmi2DeSerializeFMUstate in a new instance differ from the first run")
            other.freeFMUstate(copy)
            other.terminate()
        finally:
            other.freeInstance()
        slave.terminate()
    finally:
        slave.freeInstance()
    return problems


#: (backend, FMI version) of every FMU the check builds per kind.
VARIANTS = (("pythonfmu", 2), ("native", 2), ("native", 3))


def check_kind(kind: str, workdir: Path, log=print, backend: str = "pythonfmu", fmi_version: int = 2) -> list[str]:
    """All checks of one kind, backend and FMI version (FMU built in `workdir`); returns the problems found."""
    k = load_kind(kind)
    t0 = time.perf_counter()
    fmu = build_fmu(kind, workdir / f"{kind}_{backend}_fmi{fmi_version}.fmu", backend=backend,
                    fmi_version=fmi_version)
    kind = f"{kind} ({backend}, FMI {fmi_version})"
    log(f"{kind}: built {fmu.name} ({time.perf_counter() - t0:.1f} s)")
    problems = [f"compliance: {p}" for p in compliance_problems(fmu)]
    if problems:
        return problems
    log(f"{kind}: validate_fmu == [] and compliance checks pass")

    ref = read_reference(k.name)
    outputs = k.names("output")
    inputs = k.names("input")
    missing = [n for n in ["time", *inputs, *outputs] if n not in ref]
    if missing:
        return [f"reference CSV lacks columns {missing}"]
    from fmpy import read_model_description

    de = read_model_description(str(fmu)).defaultExperiment
    t = ref["time"]
    grid = np.array([float(de.startTime) + i * float(de.stepSize) for i in range(t.size)])
    if t[-1] != float(de.stopTime) or not np.array_equal(t, grid):
        problems.append("reference time grid is not the default experiment's")
    signals = {"time": t, **{n: ref[n] for n in inputs}}
    starts = k.reference_start_values
    resolve_start_values(k, starts)  # known inputs/parameters with values of their types, or ValueError
    sim = simulate_fmpy(fmu, signals, outputs, start_values=starts)
    problems += compare("fmpy.simulate_fmu vs reference", sim, ref, ["time", *outputs],
                        k.reference_rtol, k.reference_atol)
    log(f"{kind}: default experiment simulated with fmpy ({t.size} samples) and compared with the reference")

    if fmi_version == 3:
        return problems + _fmi3_problems(kind, fmu, signals, outputs, starts, ref, k, log)
    loop = run_fmpy_loop(fmu, signals, outputs, start_values=starts)
    cosim = run_libcosim(fmu, signals, outputs, start_values=starts)
    # libcosim's times are whole nanoseconds converted to seconds: a kind with a state or a clock sees steps
    # and times that may differ from fmpy's in the last bit, so it agrees to round-off, the others bit for bit
    exact = (k.reference_rtol, k.reference_atol) if k.native.get("state") or k.native.get("clock") else (0.0, 0.0)
    problems += compare("libcosimpy vs fmpy loop", cosim, loop, outputs, *exact)
    problems += compare("libcosimpy vs reference", cosim, ref, outputs, k.reference_rtol, k.reference_atol,
                        rows=slice(1, None))
    log(f"{kind}: run in libcosimpy and compared with fmpy")

    if k.fmu_state:
        problems += [f"FMU state: {p}" for p in state_round_trip_problems(fmu, signals, outputs, starts)]
        log(f"{kind}: FMU state get/set and serialize/deserialize round trips checked")
    if not problems:
        log(f"{kind}: OK")
    return problems


def _fmi3_problems(kind, fmu, signals, outputs, starts, ref, k, log) -> list[str]:
    """The bare FMU3Slave loop against the reference (one row later) and FMU-state round trips."""
    from .runners3 import fmi3_state_round_trip_problems, run_fmi3_loop

    loop = run_fmi3_loop(fmu, signals, outputs, start_values=starts)
    problems = compare("fmpy FMU3Slave loop vs reference", loop, ref, outputs, k.reference_rtol, k.reference_atol,
                       rows=slice(1, None))
    log(f"{kind}: bare FMU3Slave loop compared with the reference (libcosimpy runs FMI 2.0 only)")
    problems += [f"FMU state: {p}" for p in fmi3_state_round_trip_problems(fmu, signals, outputs, starts)]
    log(f"{kind}: FMU state get/set and serialize/deserialize round trips checked")
    if not problems:
        log(f"{kind}: OK")
    return problems


def native_problems(kind: str, workdir: Path, log=print, fmi_version: int = 2) -> list[str]:
    """Checks of the native FMU beyond the common ones: the default experiment shows the static equilibrium.

    Built with the kind's default start values, simulated without inputs, a
    tire FMU must give force_z = the default static wheel load (N) throughout and be
    in contact (the hub starts at the static equilibrium, off the built-in cleat);
    the body must stay at rest on its static loads (hubs at their static heights,
    no seat acceleration).
    """
    from .native_fmu import DEFAULT_STATIC_LOAD_N
    from fmpy import simulate_fmu

    fmu = workdir / f"{kind}_native_fmi{fmi_version}.fmu"
    if "road_z_FL" in load_kind(kind).names("output"):
        return []          # no equilibrium: the reference experiment is the road itself
    if "force_z" not in load_kind(kind).names("output"):
        return _body_rest_problems(kind, fmu, log, fmi_version)
    res = simulate_fmu(str(fmu), output=["force_z", "in_contact"])
    force = np.asarray(res["force_z"], dtype=float)
    problems = []
    if not np.allclose(force, DEFAULT_STATIC_LOAD_N, rtol=1e-9) or not np.all(res["in_contact"]):
        problems.append(f"default experiment: force_z from {force.min()!r} to {force.max()!r} N, "
                        f"expected the static load {DEFAULT_STATIC_LOAD_N} N throughout")
    else:
        log(f"{kind} (native, FMI {fmi_version}): default experiment shows the static equilibrium "
            f"({DEFAULT_STATIC_LOAD_N} N)")
    return problems


def _body_rest_problems(kind: str, fmu: Path, log, fmi_version: int) -> list[str]:
    from fmpy import simulate_fmu

    k = load_kind(kind)
    tires = ("FL", "FR", "RL", "RR")
    res = simulate_fmu(str(fmu), output=[*(f"hub_z_{t}" for t in tires), "seat_az"])
    static = {t: float(k.variable(f"static_hub_z_{t}").start) for t in tires}
    worst = max(float(np.max(np.abs(np.asarray(res[f"hub_z_{t}"]) - static[t]))) for t in tires)
    if worst > 0.0 or np.any(np.asarray(res["seat_az"]) != 0.0):
        return [f"default experiment: the body moves (hub heights up to {worst!r} m off their static heights, "
                f"seat acceleration up to {float(np.max(np.abs(res['seat_az'])))!r} m/s2); it must rest"]
    log(f"{kind} (native, FMI {fmi_version}): default experiment shows the body at rest on its static loads")
    return []


def check_variant(kind: str, backend: str, fmi_version: int, workdir: Path, log=print) -> list[str]:
    """Every check of one kind, backend and FMI version, in this process; the problems, each with its label."""
    label = f"{kind} ({backend}, FMI {fmi_version})"
    try:
        problems = check_kind(kind, workdir, log=log, backend=backend, fmi_version=fmi_version)
        if backend == "native":
            problems += native_problems(kind, workdir, log=log, fmi_version=fmi_version)
    except Exception as exc:  # a failing kind must not hide the others
        problems = [f"{type(exc).__name__}: {exc}"]
    return [f"{label}: {p}" for p in problems]


def check_variant_apart(kind: str, backend: str, fmi_version: int, workdir: Path) -> list[str]:
    """:func:`check_variant` in a child process (``python -P -m build_scripts.check KIND --backend B
    --fmi-version V --result FILE``), its output relayed.

    Each variant's FMU libraries, fmpy's and libcosim's (its engine, its worker threads; with a pythonfmu FMU,
    C++ that calls back into the interpreter) are loaded and torn down in a process of their own.  With every
    variant in one process the check aborted about once in 70-100 runs *after* its last line, in a library's
    exit handler ("corrupted double-linked list": a 4-byte count at offset 8 of an already freed 128-byte
    block decremented, a C++ shared count released twice in a teardown).

    The child writes its problems before it exits.  If it then dies of a signal, they stand and a line says
    so; if it dies before writing them, that is a problem of the variant.
    """
    label = f"{kind} ({backend}, FMI {fmi_version})"
    result = workdir / f"{kind}_{backend}_fmi{fmi_version}.problems.json"
    proc = python_apart(["build_scripts.check", kind, "--backend", backend, "--fmi-version", str(fmi_version),
                         "--result", str(result), "--workdir", str(workdir)])
    sys.stdout.write(proc.stdout)
    sys.stderr.write(proc.stderr)
    if not result.exists():
        return [f"{label}: its check process ended with {ending(proc.returncode)} before writing its result"]
    problems = json.loads(result.read_text(encoding="utf-8"))
    if proc.returncode and not problems:
        print(f"{label}: its check process wrote its result (every check passed), then ended with "
              f"{ending(proc.returncode)} while the libraries it had loaded were torn down")
    return problems


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m build_scripts.check", description=__doc__.split("\n\n")[0])
    parser.add_argument("kinds", nargs="*", help="kinds to check (default: all in fmu_src)")
    parser.add_argument("--backend", choices=BACKENDS, action="append",
                        help="backend(s) to check (default: all)")
    parser.add_argument("--fmi-version", type=int, choices=(2, 3), action="append",
                        help="FMI version(s) to check (default: all the backend builds)")
    parser.add_argument("--result", type=Path, help=argparse.SUPPRESS)   # a child: one variant, problems to FILE
    parser.add_argument("--workdir", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.result:
        problems = check_variant(args.kinds[0], args.backend[0], args.fmi_version[0], args.workdir)
        publish(args.result, json.dumps(problems).encode("utf-8"))
        sys.stdout.flush()
        return 1 if problems else 0
    variants = [(b, v) for b, v in VARIANTS if (not args.backend or b in args.backend)
                and (not args.fmi_version or v in args.fmi_version)]
    kinds = args.kinds or kind_names()
    if not kinds:
        print("check: no FMU kinds found in fmu_src", file=sys.stderr)
        return 1
    failures = [f"module names: {p}" for p in module_name_conflicts([load_kind(k) for k in kind_names()])]
    with tempfile.TemporaryDirectory(prefix=temp_prefix("check")) as tmp:
        for kind in kinds:
            for backend, version in [(b, v) for b, v in variants if b in load_kind(kind).backends]:
                sys.stdout.flush()
                failures += check_variant_apart(kind, backend, version, Path(tmp))
    for problem in failures:
        print(f"check: FAIL {problem}", file=sys.stderr)
    print(f"check: {len(kinds)} FMU kind(s), {'all passed' if not failures else f'{len(failures)} problem(s)'}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
