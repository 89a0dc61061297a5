"""Memory growth of tire FMU instances over instantiate/free cycles, with and without a failing call.

For each FMU — the native (C) FMU for FMI 2.0 and FMI 3.0, and the pythonfmu
FMU (FMI 2.0), all of the same kind — and each scenario, a fresh Python
process loads the FMU's shared library once with ctypes (it stays loaded:
fmpy's ``freeInstance`` would unload it), runs 200 warm-up cycles, then
measures over ``--cycles`` (default 10,000) cycles:

* ``lifecycle``: instantiate, set up, enter and exit initialization mode,
  terminate, free;
* ``get invalid vr``: instantiate, initialize, read a Real at a value
  reference that is no variable (the call fails), free;
* ``set rejected value``: instantiate, initialize, set the stiffness to
  -1 N/m (the FMU rejects it: the call fails), free;
* ``negative step``: instantiate, initialize, step by -1 ms (the native FMU
  refuses it), free.

Instances of failing cycles are instantiated with logging on (the error is
formatted and delivered to a logger that discards it).  Per cycle type it
prints, each per 10,000 cycles, the growth of the resident set size
(``/proc/self/statm``), of the bytes malloc has handed out (glibc
``mallinfo2``; the C code's allocations) and of the blocks Python's
allocator has handed out (``sys.getallocatedblocks``; Python objects kept
alive), the status the failing call returned, and whether the RSS growth
meets the target of <= 1 MB per 10,000 cycles.  For FMI 2.0 it also counts
the blocks the FMU took from the importer's ``allocateMemory`` and had not
given back through ``freeMemory`` at the end (0: every instance freed).

The pythonfmu FMU's growth is Python objects that the FMI wrapper of
pythonfmu 0.7 (its C++ binary, shipped in the FMU) never releases: per
instantiation, its class finder's copy of the slave class's MRO, UTF-8
copies of the reprs and of the class name, and the resources path it inserts
into ``sys.path``; per failing call, the message and category strings of the
logged error (``clearLogBuffer`` does not release the attributes it reads).
Its ``doStep`` accepts a negative step.

Prints the figures; it is not a test.  Linux only (``/proc``, glibc).
Usage::

    python benchmarks/bench_fmu_lifecycle.py [--cycles 10000] [--kind point_contact] [--jobs 2]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

#: Scenario -> the failing call (None: the full lifecycle, nothing fails).
SCENARIOS = {"lifecycle": None, "get invalid vr": "get", "set rejected value": "set", "negative step": "step"}
#: A value reference that is no variable of any tire FMU.
INVALID_VR = 999
LIMIT_KB = 1024
WARMUP = 200


# -- child process: one scenario on one library -----------------------------------------------

def _rss_bytes() -> int:
    """Resident set size of this process, bytes (``/proc/self/statm``)."""
    import os

    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _malloc_in_use():
    """A function returning the bytes glibc's malloc has handed out (``mallinfo2``; None without it)."""
    import ctypes

    class MallInfo2(ctypes.Structure):
        _fields_ = [(name, ctypes.c_size_t) for name in ("arena", "ordblks", "smblks", "hblks", "hblkhd",
                                                          "usmblks", "fsmblks", "uordblks", "fordblks",
                                                          "keepcost")]

    try:
        mallinfo2 = ctypes.CDLL(None).mallinfo2
    except AttributeError:
        return lambda: None
    mallinfo2.restype = MallInfo2

    def in_use():
        info = mallinfo2()
        return info.uordblks + info.hblkhd
    return in_use


class _Fmi2:
    """The FMI 2.0 functions of a loaded library, with counting memory callbacks and a discarding logger."""

    def __init__(self, spec):
        import ctypes as C

        lib = C.CDLL(spec["lib"])
        self.lib, self.spec = lib, spec
        libc = C.CDLL(None)
        libc.calloc.restype, libc.calloc.argtypes = C.c_void_p, [C.c_size_t, C.c_size_t]
        libc.free.restype, libc.free.argtypes = None, [C.c_void_p]
        self.live = 0

        def allocate(n, size):
            p = libc.calloc(n, size)
            if p:
                self.live += 1
            return p

        def release(p):
            if p:
                self.live -= 1
                libc.free(p)

        logger_type = C.CFUNCTYPE(None, C.c_void_p, C.c_char_p, C.c_int, C.c_char_p, C.c_char_p)

        class Callbacks(C.Structure):
            _fields_ = [("logger", logger_type), ("allocateMemory", C.CFUNCTYPE(C.c_void_p, C.c_size_t, C.c_size_t)),
                        ("freeMemory", C.CFUNCTYPE(None, C.c_void_p)), ("stepFinished", C.c_void_p),
                        ("componentEnvironment", C.c_void_p)]

        self.callbacks = Callbacks(logger_type(lambda *args: None), Callbacks._fields_[1][1](allocate),
                                   Callbacks._fields_[2][1](release), None, None)
        status, comp = C.c_int, C.c_void_p
        for name, args in (("fmi2Instantiate", [C.c_char_p, C.c_int, C.c_char_p, C.c_char_p, C.c_void_p, C.c_int,
                                                C.c_int]),
                           ("fmi2FreeInstance", [comp]),
                           ("fmi2SetupExperiment", [comp, C.c_int, C.c_double, C.c_double, C.c_int, C.c_double]),
                           ("fmi2EnterInitializationMode", [comp]), ("fmi2ExitInitializationMode", [comp]),
                           ("fmi2Terminate", [comp]),
                           ("fmi2GetReal", [comp, C.c_void_p, C.c_size_t, C.c_void_p]),
                           ("fmi2SetReal", [comp, C.c_void_p, C.c_size_t, C.c_void_p]),
                           ("fmi2DoStep", [comp, C.c_double, C.c_double, C.c_int])):
            f = getattr(lib, name)
            f.argtypes = args
            f.restype = comp if name == "fmi2Instantiate" else None if name == "fmi2FreeInstance" else status
        self.name, self.guid = b"lifecycle", spec["guid"].encode()
        self.resources = spec["resources"].encode()
        self.callbacks_ref = C.byref(self.callbacks)
        self.invalid = (C.c_uint * 1)(INVALID_VR)
        self.stiffness = (C.c_uint * 1)(spec["stiffness_vr"])
        self.minus_one = (C.c_double * 1)(-1.0)
        self.out = (C.c_double * 1)()

    def start(self, logging):
        lib = self.lib
        c = lib.fmi2Instantiate(self.name, 1, self.guid, self.resources, self.callbacks_ref, 0, 1 if logging else 0)
        if not c:
            raise SystemExit("fmi2Instantiate failed")
        if (lib.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) or lib.fmi2EnterInitializationMode(c)
                or lib.fmi2ExitInitializationMode(c)):
            raise SystemExit("initialization failed")
        return c

    def terminate(self, c):
        return self.lib.fmi2Terminate(c)

    def fail(self, c, call):
        lib = self.lib
        if call == "get":
            return lib.fmi2GetReal(c, self.invalid, 1, self.out)
        if call == "set":
            return lib.fmi2SetReal(c, self.stiffness, 1, self.minus_one)
        return lib.fmi2DoStep(c, 0.0, -1e-3, 1)

    def free(self, c):
        self.lib.fmi2FreeInstance(c)


class _Fmi3:
    """The FMI 3.0 co-simulation functions of a loaded library, with a discarding logger."""

    def __init__(self, spec):
        import ctypes as C

        lib = C.CDLL(spec["lib"])
        self.lib, self.live = lib, None
        self.logger = C.CFUNCTYPE(None, C.c_void_p, C.c_int, C.c_char_p, C.c_char_p)(lambda *args: None)
        status, inst, flag = C.c_int, C.c_void_p, C.c_bool
        for name, args in (("fmi3InstantiateCoSimulation", [C.c_char_p, C.c_char_p, C.c_char_p, flag, flag, flag,
                                                             flag, C.c_void_p, C.c_size_t, C.c_void_p, C.c_void_p,
                                                             C.c_void_p]),
                           ("fmi3FreeInstance", [inst]),
                           ("fmi3EnterInitializationMode", [inst, flag, C.c_double, C.c_double, flag, C.c_double]),
                           ("fmi3ExitInitializationMode", [inst]), ("fmi3Terminate", [inst]),
                           ("fmi3GetFloat64", [inst, C.c_void_p, C.c_size_t, C.c_void_p, C.c_size_t]),
                           ("fmi3SetFloat64", [inst, C.c_void_p, C.c_size_t, C.c_void_p, C.c_size_t]),
                           ("fmi3DoStep", [inst, C.c_double, C.c_double, flag, C.c_void_p, C.c_void_p, C.c_void_p,
                                           C.c_void_p])):
            f = getattr(lib, name)
            f.argtypes = args
            f.restype = inst if name == "fmi3InstantiateCoSimulation" else None if name == "fmi3FreeInstance" \
                else status
        self.name, self.token = b"lifecycle", spec["guid"].encode()
        self.resources = spec["resources"].encode()
        self.logger_pointer = C.cast(self.logger, C.c_void_p)
        self.invalid = (C.c_uint32 * 1)(INVALID_VR)
        self.stiffness = (C.c_uint32 * 1)(spec["stiffness_vr"])
        self.minus_one = (C.c_double * 1)(-1.0)
        self.out = (C.c_double * 1)()
        self.flags = [C.byref(C.c_bool()) for _ in range(3)]
        self.last = C.byref(C.c_double())

    def start(self, logging):
        lib = self.lib
        c = lib.fmi3InstantiateCoSimulation(self.name, self.token, self.resources, False, logging, False, False,
                                            None, 0, None, self.logger_pointer, None)
        if not c:
            raise SystemExit("fmi3InstantiateCoSimulation failed")
        if lib.fmi3EnterInitializationMode(c, False, 0.0, 0.0, False, 0.0) or lib.fmi3ExitInitializationMode(c):
            raise SystemExit("initialization failed")
        return c

    def terminate(self, c):
        return self.lib.fmi3Terminate(c)

    def fail(self, c, call):
        lib = self.lib
        if call == "get":
            return lib.fmi3GetFloat64(c, self.invalid, 1, self.out, 1)
        if call == "set":
            return lib.fmi3SetFloat64(c, self.stiffness, 1, self.minus_one, 1)
        return lib.fmi3DoStep(c, 0.0, -1e-3, True, *self.flags, self.last)

    def free(self, c):
        self.lib.fmi3FreeInstance(c)


def child(spec: dict) -> dict:
    """Run one scenario on one library (in this fresh process); returns the figures.

    Parameters
    ----------
    spec : dict
        ``api`` ("fmi2" or "fmi3"), ``lib``, ``resources`` (the location the
        FMU's instantiate function expects), ``guid``, ``stiffness_vr``,
        ``scenario`` (a key of :data:`SCENARIOS`), ``cycles`` and ``warmup``.

    Returns
    -------
    dict
        ``rss`` and ``malloc`` (growth in bytes over the measured cycles;
        ``malloc`` None without ``mallinfo2``), ``python_blocks`` (growth of
        the blocks the Python allocator has handed out), ``statuses``
        (``{status: count}`` of the failing call, or of terminate over the
        measured cycles), ``live`` (blocks not given back through
        ``freeMemory`` at the end, warm-up included; FMI 2.0 only, else
        None) and ``seconds``.
    """
    import gc
    import time

    fmu = (_Fmi2 if spec["api"] == "fmi2" else _Fmi3)(spec)
    call = SCENARIOS[spec["scenario"]]
    statuses = {}
    malloc_in_use = _malloc_in_use()

    def cycle():
        c = fmu.start(logging=call is not None)
        status = fmu.terminate(c) if call is None else fmu.fail(c, call)
        statuses[status] = statuses.get(status, 0) + 1
        fmu.free(c)

    for _ in range(spec["warmup"]):
        cycle()
    gc.collect()
    statuses.clear()
    rss, heap, blocks, start = _rss_bytes(), malloc_in_use(), sys.getallocatedblocks(), time.perf_counter()
    for _ in range(spec["cycles"]):
        cycle()
    seconds = time.perf_counter() - start
    gc.collect()
    heap_after, blocks_after = malloc_in_use(), sys.getallocatedblocks()
    return {"rss": _rss_bytes() - rss, "malloc": None if heap is None else heap_after - heap,
            "python_blocks": blocks_after - blocks,
            "statuses": {str(k): v for k, v in statuses.items()},
            "live": fmu.live, "seconds": seconds}


# -- parent: build, extract, one process per FMU and scenario ---------------------------------

#: kind -> a parameter that must be > 0 (the failing call sets it to -1); default ``stiffness``.
_POSITIVE_PARAMETER = {"tractor_body": "wheelbase", "road_profile": "ramp_length"}


def _fmus(kind: str, folder: Path) -> dict:
    """``{label: spec}`` of the FMUs measured: built into `folder`, extracted, their libraries located."""
    import zipfile

    from fmpy import read_model_description

    from build_scripts import build_fmu
    from build_scripts.kinds import load_kind

    backends = load_kind(kind).backends
    builds = {"native FMI 2.0": ("fmi2", dict(backend="native", platforms=["linux64"]), "linux64"),
              "native FMI 3.0": ("fmi3", dict(backend="native", fmi_version=3, platforms=["x86_64-linux"]),
                                 "x86_64-linux"),
              "pythonfmu FMI 2.0": ("fmi2", dict(backend="pythonfmu"), "linux64")}
    builds = {label: b for label, b in builds.items() if b[1]["backend"] in backends}
    positive = _POSITIVE_PARAMETER.get(kind, "stiffness")
    specs = {}
    for label, (api, options, platform) in builds.items():
        stem = label.replace(" ", "_").replace(".", "")
        fmu = build_fmu(kind, folder / f"{stem}.fmu", **options)
        unzipped = folder / stem
        zipfile.ZipFile(fmu).extractall(unzipped)
        md = read_model_description(str(fmu), validate=False)
        (lib,) = (unzipped / "binaries" / platform).glob(f"{md.coSimulation.modelIdentifier}.*")
        resources = unzipped / "resources"
        specs[label] = {"api": api, "lib": str(lib), "guid": md.guid,
                        "resources": resources.as_uri() if api == "fmi2" else f"{resources}/",
                        "stiffness_vr": next(v.valueReference for v in md.modelVariables if v.name == positive)}
    return specs


def _run_child(spec: dict) -> dict:
    done = subprocess.run([sys.executable, __file__, "--child", json.dumps(spec)], capture_output=True, text=True,
                          timeout=600)
    if done.returncode != 0:
        lines = (done.stderr.strip() or done.stdout.strip()).splitlines()
        return {"error": lines[-1][-300:] if lines else f"exit status {done.returncode}"}
    return json.loads(done.stdout.strip().splitlines()[-1])


def _per_10000_kb(value: int | None, cycles: int) -> str:
    return "n/a" if value is None else f"{value / 1024 * 10000 / cycles:+.0f}"


def _status_text(statuses: dict, failing: bool) -> str:
    names = {"0": "OK", "1": "Warning", "2": "Discard", "3": "Error", "4": "Fatal", "5": "Pending"}
    text = ", ".join(f"{names.get(k, k)} x{v}" for k, v in sorted(statuses.items()))
    if failing and "0" in statuses:
        text += " (does not fail)"
    return text


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles", type=int, default=10000, help="measured cycles per scenario (default %(default)s)")
    parser.add_argument("--kind", default="point_contact", help="FMU kind (default %(default)s)")
    parser.add_argument("--jobs", type=int, default=2, help="processes run at the same time (default %(default)s)")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        print(json.dumps(child(json.loads(args.child))))
        return 0

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    with tempfile.TemporaryDirectory(prefix="cleatfmu_bench_lifecycle_") as tmp:
        specs = _fmus(args.kind, Path(tmp))
        jobs = [(label, scenario, {**spec, "scenario": scenario, "cycles": args.cycles, "warmup": WARMUP})
                for label, spec in specs.items() for scenario in SCENARIOS]
        with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            results = list(pool.map(lambda job: _run_child(job[2]), jobs))

    print(f"{args.kind} FMUs: growth per 10,000 cycles after {WARMUP} warm-up cycles, measured over "
          f"{args.cycles:,} cycles, one fresh process per row (target: RSS <= {LIMIT_KB} kB)")
    print(f"  {'FMU':<18} {'cycle':<19} {'RSS kB':>8} {'malloc kB':>10} {'Python blocks':>13} {'not freed':>9} "
          f"{'us/cycle':>9}  {'meets':<5}  status of the last call")
    growth = {}  # label -> RSS growth per 10,000 cycles of each cycle type, bytes (None: the run failed)
    for (label, scenario, _), r in zip(jobs, results):
        if "error" in r:
            print(f"  {label:<18} {scenario:<19} failed: {r['error']}")
            growth.setdefault(label, []).append(None)
            continue
        rss = r["rss"] * 10000 / args.cycles
        growth.setdefault(label, []).append(rss)
        print(f"  {label:<18} {scenario:<19} {_per_10000_kb(r['rss'], args.cycles):>8} "
              f"{_per_10000_kb(r['malloc'], args.cycles):>10} {r['python_blocks'] * 10000 // args.cycles:>+13} "
              f"{'n/a' if r['live'] is None else r['live']:>9} "
              f"{1e6 * r['seconds'] / args.cycles:>9.1f}  {'yes' if rss <= LIMIT_KB * 1024 else 'NO':<5}  "
              f"{_status_text(r['statuses'], SCENARIOS[scenario] is not None)}")
    print("summary (largest RSS growth per 10,000 cycles of any cycle type):")
    for label, values in growth.items():
        if None in values:
            print(f"  {label:<18} a run failed")
            continue
        worst = max(values)
        print(f"  {label:<18} {worst / 1024:+.0f} kB: {'meets' if worst <= LIMIT_KB * 1024 else 'misses'} "
              f"the target of <= {LIMIT_KB} kB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
