"""Property-based fuzzing of the native FMUs' inputs and parameters (FMI 2.0, loaded in this process).

Hypothesis draws a sequence of calls on one instance of each native tire FMU:
real values set on its inputs and parameters (finite, huge, tiny, negative,
infinite, NaN), booleans, steps of any size (negative, zero, NaN, huge), and
reads of every output.  Every call must either succeed or return fmi2Error
with a message at the logger; nothing in between, nothing that ends the
process.  The FMI contract checked per call:

* a set that succeeds is read back exactly; a refused set leaves the previous
  value in place (the instance "keeps its previous values and stays usable");
  values that are valid one by one but not together (a huge hub height makes
  a non-finite force) make reads fail cleanly until they are fixed;
* after a step that succeeds every output reads finite (or fails cleanly, as above);
* after a failing step the instance is freed and every block it took from the
  importer's allocator comes back; a new instance of the same library then
  goes through a clean run.
"""

from __future__ import annotations

import math
import zipfile

import pytest

pytestmark = pytest.mark.fuzz   # its own CI step (pytest -m fuzz), left out of the default run
from native_fixtures import native_fmus  # noqa: F401

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from test_fmu_lifecycle import _counting_callbacks, _open, _to_mode  # noqa: E402
from test_fuzz import CASES, scaled  # noqa: E402

#: Values a careless or hostile importer sends.
SPECIAL = [0.0, -0.0, 1e-320, -1e-320, 1e-300, 1e308, -1e308, math.inf, -math.inf, math.nan, 1.0, -1.0]
VALUES = st.one_of(st.sampled_from(SPECIAL), st.floats(allow_nan=True, allow_infinity=True, width=64),
                   st.floats(-1e7, 1e7))
STEPS = st.one_of(st.sampled_from([0.0, -1e-3, 1e-3, 1e-6, 0.5, 10.0, 1e300, math.nan, math.inf]),
                  st.floats(1e-6, 0.05))
CI = settings(deadline=None, derandomize=True, database=None, print_blob=True, max_examples=scaled(150),
              suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


class _Fmu:
    """One native FMU's library loaded once, its variables and counting callbacks."""

    def __init__(self, fmu, folder):
        from fmpy import read_model_description

        self.slave, self.refs = _open(fmu, folder, 2)
        md = read_model_description(str(fmu), validate=False)
        self.reals = [v.name for v in md.modelVariables if v.type == "Real" and v.causality in ("input", "parameter")
                      and v.variability != "constant"]
        self.flags = [v.name for v in md.modelVariables if v.type == "Boolean" and v.causality == "parameter"]
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
        self.messages: list = []
        self.callbacks, self.live = _counting_callbacks(self.messages)


@pytest.fixture(scope="module")
def loaded(native_fmus, tmp_path_factory):  # noqa: F811
    fmus = {kind: _Fmu(native_fmus[kind], tmp_path_factory.mktemp(kind)) for kind in ("point_contact",
                                                                                     "extended_tire")}
    yield fmus
    for f in fmus.values():
        f.slave.freeLibrary()


def _operations(fmu: _Fmu):
    set_real = st.tuples(st.just("real"), st.sampled_from(fmu.reals), VALUES)
    set_flag = st.tuples(st.just("flag"), st.sampled_from(fmu.flags or ["-"]), st.booleans())
    step = st.tuples(st.just("step"), st.just(""), STEPS)
    return st.lists(st.one_of(set_real, set_real, set_flag, step, step), min_size=1, max_size=12)


def _same(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


def _read(fmu: _Fmu, get, ref):
    """The value at `ref`, or None where the read fails cleanly (status 3 with a message: values that are
    invalid together make every read fail until they are fixed)."""
    from fmpy.fmi1 import FMICallException

    fmu.messages.clear()
    try:
        return get([ref])[0]
    except FMICallException as exc:
        assert exc.status == 3 and fmu.messages and fmu.messages[-1][1], f"a read failed with status {exc.status}"
        return None


def _run(fmu: _Fmu, ops, tally) -> None:
    from fmpy.fmi1 import FMICallException

    s = fmu.slave
    vr = {name: ref for name, (ref, _) in fmu.refs.items()}
    s.instantiate(callbacks=fmu.callbacks, loggingOn=True)
    try:
        _to_mode(s, "step", 2)
        t = 0.0
        for kind, name, value in ops:
            if kind == "flag" and name == "-":
                continue
            fmu.messages.clear()
            if kind == "step":
                try:
                    s.doStep(t, value)
                except FMICallException as exc:
                    assert exc.status == 3, f"doStep({value!r}) returned status {exc.status}"
                    assert fmu.messages and fmu.messages[-1][0] >= 3 and fmu.messages[-1][1], \
                        f"doStep({value!r}) failed without a message"
                    tally["failed steps"] += 1
                    return                                    # the instance is freed below
                t += value
                tally["steps"] += 1
                out = [_read(fmu, s.getReal, vr[n]) for n in fmu.outputs]
                bad = [n for n, x in zip(fmu.outputs, out) if x is not None and not math.isfinite(x)]
                assert not bad, f"a successful doStep({value!r}) left non-finite outputs {bad}"
                continue
            get, put = (s.getReal, s.setReal) if kind == "real" else (s.getBoolean, s.setBoolean)
            before = _read(fmu, get, vr[name])
            fmu.messages.clear()
            try:
                put([vr[name]], [value])
            except FMICallException as exc:
                assert exc.status == 3, f"set {name} = {value!r} returned status {exc.status}"
                assert fmu.messages and fmu.messages[-1][1], f"set {name} = {value!r} failed without a message"
                after = _read(fmu, get, vr[name])
                assert before is None or after is None or _same(after, before), \
                    f"a refused {name} = {value!r} changed it from {before} to {after}"
                tally["refused sets"] += 1
                continue
            tally["sets"] += 1
            after = _read(fmu, get, vr[name])
            assert after is None or _same(after, value) or (kind == "flag" and bool(after) == bool(value)), \
                f"{name} = {value!r} accepted but reads {after!r}"
    finally:
        s.fmi2FreeInstance(s.component)
        assert fmu.live[0] == 0, f"{fmu.live[0]} blocks not given back after freeing the instance"


def _clean_run_works(fmu: _Fmu) -> None:
    s = fmu.slave
    s.instantiate(callbacks=fmu.callbacks, loggingOn=True)
    _to_mode(s, "step", 2)
    s.doStep(0.0, 1e-3)
    assert math.isfinite(s.getReal([fmu.refs["force_z"][0]])[0])
    s.terminate()
    s.fmi2FreeInstance(s.component)
    assert fmu.live[0] == 0


@pytest.mark.parametrize("kind", ["point_contact", "extended_tire"])
def test_any_inputs_and_parameters_succeed_or_fail_cleanly(loaded, kind):
    fmu = loaded[kind]
    assert fmu.reals and fmu.outputs

    tally = dict.fromkeys(("cases", "sets", "refused sets", "steps", "failed steps"), 0)

    @CI
    @given(ops=_operations(fmu))
    def case(ops):
        tally["cases"] += 1
        CASES[0] += 1
        _run(fmu, ops, tally)
        _clean_run_works(fmu)

    case()
    # the cases went both ways: accepted and refused values, steps taken and refused
    assert tally["cases"] >= scaled(150) and min(tally.values()) >= 20, tally
