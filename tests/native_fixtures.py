"""Fixtures and helpers of the native (C) FMU tests: FMUs built once per session, a C host without Python."""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

from build_scripts import build_fmu
from build_scripts.native import _fmpy_headers

#: A folder name with characters that must be percent-encoded in a file URI.
AWKWARD_DIR = "tire ä#% 100%"


@pytest.fixture(scope="session")
def native_fmus(tmp_path_factory) -> dict:
    """``{kind: FMU}``: native FMI 2.0 FMUs of both kinds, every platform, default start values."""
    out = tmp_path_factory.mktemp("native")
    return {kind: build_fmu(kind, out / f"{kind}.fmu", backend="native")
            for kind in ("point_contact", "extended_tire")}


def _compile_host(tmp_path_factory, source: str) -> Path:
    """Compile the C host `source` (in tests/) with gcc, warnings as errors; skips where gcc is missing."""
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc is not installed")
    exe = tmp_path_factory.mktemp("host") / Path(source).stem
    subprocess.run([gcc, "-std=c99", "-O2", "-Wall", "-Werror", "-I", str(_fmpy_headers()), "-o", str(exe),
                    str(Path(__file__).with_name(source)), "-ldl"], check=True)
    return exe


@pytest.fixture(scope="session")
def c_host(tmp_path_factory) -> Path:
    """The C host ``tests/native_host.c`` compiled with gcc (skips where gcc is missing)."""
    return _compile_host(tmp_path_factory, "native_host.c")


def assert_step_response(rows, *, k: float, c: float, r0: float, load: float, height: float, h: float,
                         columns=(1, 2, 3)) -> None:
    """A quarter car (mass load/g) on the point-contact tire, road stepping by `height` at 0.1 s, stepped
    by a host: equal to the same master in Python with the Python law to round-off, settling `height`
    higher, with the damped oscillator's overshoot.  `rows[i, columns]` are (z, vz, force) after step i."""
    import math

    import numpy as np

    from identification.model import tire_law

    g = 9.80665
    mass = load / g
    z, v, t = r0 - load / k, 0.0, 0.0
    for i in range(rows.shape[0]):
        f = tire_law.point_contact(z, v, height if t >= 0.1 else 0.0, 0.0, k, c, r0)[0]
        v += h * (f / mass - g)
        z += h * v
        t = (i + 1) * h
        if i % 1000 == 999 or i == rows.shape[0] - 1:
            np.testing.assert_allclose(rows[i, list(columns)], [z, v, f], rtol=1e-12, atol=1e-12)
    z0 = r0 - load / k
    hub = rows[:, columns[0]]
    assert hub[-1] - z0 == pytest.approx(height, rel=1e-4)
    zeta = c / (2.0 * math.sqrt(k * mass))
    overshoot = (hub.max() - z0 - height) / height
    assert overshoot == pytest.approx(math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2)), rel=0.03)


def extract(fmu, folder: Path) -> Path:
    """Extract `fmu` into `folder` (created); returns it."""
    folder.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


def guid(fmu) -> str:
    """The GUID of `fmu`'s model description."""
    from fmpy import read_model_description

    return read_model_description(str(fmu), validate=False).guid


def run_host(host: Path, unzipped: Path, uri: str, fmu_guid: str, *args) -> str:
    """Run the C host on the linux binary of an extracted point-contact FMU; returns its stdout."""
    lib = unzipped / "binaries" / "linux64" / "CleatfmuPointContact.so"
    done = subprocess.run([str(host), str(lib), uri, fmu_guid, *map(str, args)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.fixture(scope="session")
def native_fmus3(tmp_path_factory) -> dict:
    """``{kind: FMU}``: native FMI 3.0 FMUs of both kinds, every platform, default start values."""
    out = tmp_path_factory.mktemp("native3")
    return {kind: build_fmu(kind, out / f"{kind}.fmu", backend="native", fmi_version=3)
            for kind in ("point_contact", "extended_tire")}


@pytest.fixture(scope="session")
def c_host3(tmp_path_factory) -> Path:
    """The FMI 3.0 C host ``tests/native_host3.c`` compiled with gcc (skips where gcc is missing)."""
    return _compile_host(tmp_path_factory, "native_host3.c")


def run_host3(host: Path, unzipped: Path, resource_path: str, token: str, *args) -> str:
    """Run the FMI 3.0 C host on the x86_64-linux binary of an extracted FMU; returns its stdout."""
    (lib,) = (unzipped / "binaries" / "x86_64-linux").glob("*.so")
    done = subprocess.run([str(host), str(lib), resource_path, token, *map(str, args)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, (done.returncode, done.stderr)
    return done.stdout


def start_values(fmu) -> tuple[dict, dict]:
    """``{name: start}`` of the inputs and parameters in `fmu`'s model description (FMI 2.0 or 3.0), and
    ``{name: value reference}`` of every variable."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu), validate=False)
    starts = {v.name: (v.start == "true" if v.type == "Boolean" else float(v.start))
              for v in md.modelVariables if v.causality in ("input", "parameter")}
    return starts, {v.name: v.valueReference for v in md.modelVariables}


def law_force(kind: str, s: dict) -> float:
    """force_z of the Python law (:mod:`identification.model.tire_law`) of FMU `kind` for the values `s`."""
    from identification.model import tire_law

    if kind == "point_contact":
        return tire_law.point_contact(s["hub_z"], s["hub_vz"], s["road_z"], s["road_vz"], s["stiffness"],
                                      s["damping"], s["unloaded_radius"])[0]
    p = {n: s[n] for n in tire_law.EXTENDED_DEFAULTS}
    return tire_law.extended_tire(s["hub_z"], s["hub_vz"], s["hub_x"], s["hub_vx"], s["road_z"], s["road_vz"], p)[0]
