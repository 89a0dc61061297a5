"""Run times apart from compilation: a report's stage times and its diagnosis time leave out what the first
run after an install spends compiling (issue: a first report said "diagnosis 85.7 s")."""

import time

import numba
import numpy as np

from identification._compile import compile_seconds
from identification.report.batch import _timed


def _fresh():
    """A new function each call, so numba compiles it (no cache)."""
    def f(x):
        s = 0.0
        for i in range(x.size):
            s += np.sin(x[i]) * np.cos(x[i] ** 2) / (1.0 + x[i] ** 2)
        return s
    return numba.njit(f)


def test_compile_seconds_counts_compilation_once_and_nothing_else():
    f, x = _fresh(), np.linspace(0.0, 1.0, 1000)
    t0 = time.perf_counter()
    with compile_seconds() as first:
        f(x)
    wall = time.perf_counter() - t0
    assert 0.05 < first.seconds <= wall
    with compile_seconds() as again:       # compiled already: running it is not compiling
        f(x)
        time.sleep(0.05)
    assert again.seconds == 0.0


def test_a_stage_time_leaves_out_compilation():
    timings = {}
    f, x = _fresh(), np.linspace(0.0, 1.0, 1000)
    t0 = time.perf_counter()
    with _timed(timings, "diagnose"):
        f(x)
        time.sleep(0.2)
    wall = time.perf_counter() - t0
    assert timings["compile"] > 0.05
    assert timings["diagnose"] + timings["compile"] <= wall + 1e-6
    assert 0.2 <= timings["diagnose"] < wall - 0.05
