"""The native FMI 3.0 tire FMUs in a C host without Python (``tests/native_host3.c``): equilibrium, a step
response against the Python law, resource paths and instantiate/free leaks."""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest
from native_fixtures import (AWKWARD_DIR, assert_step_response, c_host3, extract, guid, law_force,  # noqa: F401
                             native_fmus3, run_host3, start_values)

from build_scripts import build_fmu
from identification.model import tire_law

G = 9.80665


@pytest.mark.parametrize("kind", ["point_contact", "extended_tire"])
def test_fmi3_c_host_equilibrium_is_the_python_laws_and_the_static_load(native_fmus3, c_host3, tmp_path, kind):
    fmu = native_fmus3[kind]
    starts, refs = start_values(fmu)
    unzipped = extract(fmu, tmp_path / AWKWARD_DIR)
    got = float(run_host3(c_host3, unzipped, f"{unzipped / 'resources'}/", guid(fmu), "equilibrium",
                          refs["force_z"]))
    assert abs(got - law_force(kind, starts)) <= 1e-12 * abs(got)
    assert got == pytest.approx(15000.0, rel=1e-12)  # the default wheel load: k (r0 - hub_z) at equilibrium


def test_fmi3_c_host_resource_path_forms_refusal_and_no_leak(native_fmus3, c_host3, tmp_path):
    fmu = native_fmus3["point_contact"]
    unzipped = extract(fmu, tmp_path / AWKWARD_DIR)
    resources = unzipped / "resources"
    assert "ä#% 100%" in str(resources)
    # FMI 3.0: an absolute path with a trailing separator; also tolerated: none, and a file URI.
    for form in (f"{resources}/", str(resources), resources.as_uri() + "/"):
        assert float(run_host3(c_host3, unzipped, form, guid(fmu), "equilibrium")) == pytest.approx(15000.0,
                                                                                                    rel=1e-12)
    lib = next((unzipped / "binaries" / "x86_64-linux").glob("*.so"))
    for path, token, reason in ((f"{tmp_path}/nowhere/", guid(fmu), "cannot open"),
                                (f"{resources}/", "{00000000-0000-0000-0000-000000000000}", "does not match")):
        done = subprocess.run([str(c_host3), str(lib), path, token, "equilibrium"], capture_output=True, text=True,
                              timeout=60)
        assert done.returncode == 4 and reason in done.stderr and "logStatusError" in done.stderr, done.stderr
    growth = int(run_host3(c_host3, unzipped, f"{resources}/", guid(fmu), "leak", 10000))
    assert growth <= 1024 * 1024, f"RSS grew by {growth} bytes over 10000 instantiate/free cycles"


def test_fmi3_c_host_step_response_matches_the_python_law_and_the_damped_oscillator(c_host3, tmp_path):
    k, c, r0, load = 400e3, 20e3, 0.75, 15000.0
    mass = load / G
    fmu = build_fmu("point_contact", tmp_path / "pc.fmu", start_values={"damping": c}, backend="native",
                    fmi_version=3, platforms=["x86_64-linux"])
    unzipped = extract(fmu, tmp_path / AWKWARD_DIR)
    h, n, height = 1e-4, 30000, 0.01
    rows = np.array([[float(x) for x in line.split()] for line in
                     run_host3(c_host3, unzipped, f"{unzipped / 'resources'}/", guid(fmu), "step", mass, height, n,
                               h).splitlines()])
    assert rows.shape == (n, 5)
    np.testing.assert_allclose(rows[:, 4], rows[:, 0], rtol=1e-12, atol=0.0)  # the FMU's time variable
    assert_step_response(rows, k=k, c=c, r0=r0, load=load, height=height, h=h)
