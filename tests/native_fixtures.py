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


@pytest.fixture(scope="session")
def c_host(tmp_path_factory) -> Path:
    """The C host ``tests/native_host.c`` compiled with gcc (skips where gcc is missing)."""
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc is not installed")
    exe = tmp_path_factory.mktemp("host") / "native_host"
    subprocess.run([gcc, "-std=c99", "-O2", "-I", str(_fmpy_headers()), "-o", str(exe),
                    str(Path(__file__).with_name("native_host.c")), "-ldl"], check=True)
    return exe


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
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc is not installed")
    exe = tmp_path_factory.mktemp("host3") / "native_host3"
    subprocess.run([gcc, "-std=c99", "-O2", "-Wall", "-Werror", "-I", str(_fmpy_headers()), "-o", str(exe),
                    str(Path(__file__).with_name("native_host3.c")), "-ldl"], check=True)
    return exe


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
    """force_z of the Python law (:mod:`identification.tire_law`) of FMU `kind` for the values `s`."""
    from identification import tire_law

    if kind == "point_contact":
        return tire_law.point_contact(s["hub_z"], s["hub_vz"], s["road_z"], s["road_vz"], s["stiffness"],
                                      s["damping"], s["unloaded_radius"])[0]
    p = {n: s[n] for n in tire_law.EXTENDED_DEFAULTS}
    return tire_law.extended_tire(s["hub_z"], s["hub_vz"], s["hub_x"], s["hub_vx"], s["road_z"], s["road_vz"], p)[0]
