"""Shared helpers: analytic cleat recordings and an in-process CLI runner."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from identification.cli import main
from identification.recording import STANDARD_GRAVITY, Recording, write_recording

#: Table 2 of the cleat-test paper: static wheel loads, N.
LOADS_N = {"FL": 11460.0, "FR": 11600.0, "RL": 15650.0, "RR": 15510.0}


def damped_sine(t, t_start, omega_n, zeta, amplitude=15.0):
    """A(t) = A e^{-ζ ω_n τ} sin(ω_d τ) for τ = t - t_start ≥ 0, else 0."""
    tau = t - t_start
    wd = omega_n * np.sqrt(1 - zeta ** 2)
    return np.where(tau >= 0, amplitude * np.exp(-zeta * omega_n * tau) * np.sin(wd * tau), 0.0)


def analytic_recording(*, fs=1000.0, duration=5.0, speed_kmh=7.0, wheelbase=2.77, t0=0.5, noise=0.0,
                       seed=0, modes=None, second_axle_impulse=False, tires=("FL", "FR", "RL", "RR")):
    """Damped sinusoids starting at each axle's arrival (front t0, rear t0 + L/v).

    `modes` maps tire -> (omega_n rad/s, zeta); default: the paper's FL/RL-like values.
    With `second_axle_impulse`, every front channel also gets a decaying burst at
    t0 + L/v, as the rear axle's impact seen through the body.
    """
    modes = modes or {"FL": (21.65, 0.08), "FR": (20.3, 0.09), "RL": (16.0, 0.05), "RR": (16.5, 0.045)}
    v = speed_kmh / 3.6
    t = np.arange(int(round(duration * fs))) / fs
    rng = np.random.default_rng(seed)
    accel = {}
    for name in tires:
        start = t0 if name[0] == "F" else t0 + wheelbase / v
        a = damped_sine(t, start, *modes[name])
        if second_axle_impulse and name[0] == "F":
            a = a + damped_sine(t, t0 + wheelbase / v, 40.0, 0.2, amplitude=12.0)
        accel[name] = a + noise * rng.standard_normal(t.size)
    return Recording(time_s=t, accel_m_s2=accel, speed_m_s=v, cleat_height_m=0.04, cleat_width_m=0.1,
                     wheelbase_m=wheelbase, wheel_load_N={n: LOADS_N[n] for n in tires})


def true_k(tire, modes_value):
    omega_n, _ = modes_value
    return LOADS_N[tire] / STANDARD_GRAVITY * omega_n ** 2


@dataclass
class CliResult:
    code: int
    out: str
    err: str


@pytest.fixture
def cli(capsys):
    """Run ``cleatfmu ARGS`` in-process; returns exit code, stdout and stderr."""
    def run(*args):
        code = main([str(a) for a in args])
        captured = capsys.readouterr()
        return CliResult(code, captured.out, captured.err)
    return run


@pytest.fixture
def good_recording(tmp_path) -> Path:
    """A valid 4-channel analytic recording on disk; returns the CSV path."""
    return write_recording(analytic_recording(noise=0.02), tmp_path / "run")


def rewrite_sidecar(csv_path: Path, **changes) -> None:
    """Modify the sidecar of a recording; a value None deletes the key."""
    meta_path = csv_path.with_suffix(".json")
    meta = json.loads(meta_path.read_text())
    for key, value in changes.items():
        if value is None:
            meta.pop(key, None)
        else:
            meta[key] = value
    meta_path.write_text(json.dumps(meta))


def _run_main(argv):
    """`main(argv)` with stdout and stderr captured: (exit status, stdout, stderr)."""
    import contextlib
    import io

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """``cleatfmu demo`` into a folder whose parents do not exist yet, once per test process: exit status,
    folder, stdout (``tests/test_report.py``, ``tests/test_report_files.py``)."""
    out = tmp_path_factory.mktemp("demo") / "new" / "deeper" / "out"
    code, stdout, _ = _run_main(["demo", "--out", str(out), "--workers", "2"])
    return code, out, stdout


@pytest.fixture(scope="session")
def example_diagnosis_run(tmp_path_factory):
    """``cleatfmu diagnose --example 7kmh --json`` once per test process: the document as a file, and stderr."""
    code, out, err = _run_main(["diagnose", "--example", "7kmh", "--json"])
    assert code == 0
    path = tmp_path_factory.mktemp("diagnosis") / "diag.json"
    path.write_text(out)
    return path, err


@pytest.fixture(scope="session")
def example_diagnosis(example_diagnosis_run):
    """The embedded 7 km/h day's ``diagnose --json`` document as a file: ``ride --body`` takes it, so the rides
    whose subject is not the diagnosis do not diagnose the day again."""
    return example_diagnosis_run[0]


@pytest.fixture(scope="session")
def demo(demo_run):
    """The demo's exit status and folder."""
    return demo_run[:2]


def chromium() -> str:
    """The headless browser, installed by CI's setup (``.ci/setup-debian``), never by a test; else skip."""
    import shutil

    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if not found:
        pytest.skip("chromium is not installed (CI installs Debian's chromium with .ci/setup-debian, as root)")
    return found


# ----------------------------------------------------------------------------- fuzz case count

#: Cases of the fuzz suites run in this session (summed from the test reports, workers' included).
_fuzz_cases = [0]


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item):
    """Attach the number of fuzz cases a test ran (``test_fuzz.CASES``) to its report."""
    import sys

    def count():
        module = sys.modules.get("test_fuzz")
        return module.CASES[0] if module is not None else 0

    before = count()
    yield
    if count() > before:
        item.user_properties.append(("fuzz_cases", count() - before))


def pytest_runtest_logreport(report):
    if report.when == "call":
        _fuzz_cases[0] += sum(value for key, value in report.user_properties if key == "fuzz_cases")


def pytest_terminal_summary(terminalreporter):
    if _fuzz_cases[0]:
        terminalreporter.write_line(f"fuzz cases run: {_fuzz_cases[0]}")


def pytest_sessionfinish(session, exitstatus):
    """``CLEATFMU_FUZZ_MIN_CASES=N``: the session fails unless at least N fuzz cases ran (CI's fuzz step)."""
    import os

    minimum = os.environ.get("CLEATFMU_FUZZ_MIN_CASES")
    if minimum and not hasattr(session.config, "workerinput") and _fuzz_cases[0] < int(minimum):
        session.config.get_terminal_writer().line(
            f"fuzz cases run: {_fuzz_cases[0]}, fewer than CLEATFMU_FUZZ_MIN_CASES={minimum}", red=True)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
