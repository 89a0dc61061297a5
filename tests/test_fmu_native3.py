"""The native (C) tire FMUs as FMI 3.0 co-simulation FMUs: compliance, reference, state, platforms."""

from __future__ import annotations

import math
import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest
from native_fixtures import AWKWARD_DIR, extract, native_fmus, native_fmus3  # noqa: F401

from build_scripts import build_fmu, load_kind
from build_scripts.binary_exports import exported_names, fmi_function_names
from build_scripts.compliance import compliance_problems
from build_scripts.native import _fmpy_headers
from build_scripts.reference import read_reference
from build_scripts.runners import simulate_fmpy
from build_scripts.runners3 import fmi3_state_round_trip_problems, open_fmi3_slave, run_fmi3_loop

KINDS = ("point_contact", "extended_tire")
#: FMI 3.0 platform folder -> (executable format, machine): ELF e_machine, PE machine, Mach-O cputype.
MACHINES = {"x86_64-linux": ("elf", 62), "aarch64-linux": ("elf", 183), "x86_64-windows": ("pe", 0x8664),
            "x86_64-darwin": ("macho", 0x01000007), "aarch64-darwin": ("macho", 0x0100000C)}


def machine(data: bytes) -> tuple[str, int]:
    """Executable format and target machine of a shared library."""
    if data[:4] == b"\x7fELF":
        return "elf", struct.unpack_from("<H", data, 18)[0]
    if data[:2] == b"MZ":
        return "pe", struct.unpack_from("<H", data, struct.unpack_from("<I", data, 0x3C)[0] + 4)[0]
    return "macho", struct.unpack_from("<I", data, 4)[0]


def macos_minimum(data: bytes) -> tuple[int, int]:
    """The oldest macOS release a Mach-O binary declares it runs on: (major, minor), from its
    LC_BUILD_VERSION (minos) or LC_VERSION_MIN_MACOSX load command."""
    ncmds = struct.unpack_from("<I", data, 16)[0]
    offset = 32                                   # a 64-bit Mach-O header
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, offset)
        if cmd in (0x32, 0x24):                   # LC_BUILD_VERSION: platform, minos; LC_VERSION_MIN_MACOSX: version
            version = struct.unpack_from("<I", data, offset + (12 if cmd == 0x32 else 8))[0]
            return version >> 16, (version >> 8) & 0xFF
        offset += size
    raise AssertionError("no minimum macOS version in the binary")


def test_macos_binaries_run_on_macos_10_13_intel_and_11_apple_silicon(native_fmus, native_fmus3):
    """The cross-compiler's default minimum is its newest SDK's (macOS 15), which every older Mac refuses."""
    oldest = {"darwin64": (10, 13), "x86_64-darwin": (10, 13), "aarch64-darwin": (11, 0)}
    seen = []
    for fmus in (native_fmus, native_fmus3):
        for kind in KINDS:
            with zipfile.ZipFile(fmus[kind]) as z:
                for name in z.namelist():
                    parts = name.split("/")
                    if parts[0] == "binaries" and parts[1] in oldest and name.endswith(".dylib"):
                        assert macos_minimum(z.read(name)) <= oldest[parts[1]], (kind, name, macos_minimum(z.read(name)))
                        seen.append(parts[1])
    assert sorted(set(seen)) == sorted(oldest)


@pytest.mark.parametrize("kind", KINDS)
def test_fmi3_fmu_is_compliant_and_reproduces_the_python_reference(native_fmus3, kind):
    fmu, k = native_fmus3[kind], load_kind(kind)
    assert compliance_problems(fmu) == []  # includes fmpy's validate_fmu, buildDescription.xml too
    inputs, outputs = k.names("input"), k.names("output")
    ref = read_reference(kind)
    signals = {n: ref[n] for n in ["time", *inputs]}
    sim = simulate_fmpy(fmu, signals, outputs, start_values=k.reference_start_values)
    loop = run_fmi3_loop(fmu, signals, outputs, start_values=k.reference_start_values)
    for name in outputs:
        np.testing.assert_allclose(sim[name], ref[name], rtol=k.reference_rtol, atol=k.reference_atol)
        np.testing.assert_allclose(loop[name], ref[name][1:], rtol=k.reference_rtol, atol=k.reference_atol)
    assert fmi3_state_round_trip_problems(fmu, signals, outputs, k.reference_start_values) == []


@pytest.mark.parametrize("kind", KINDS)
def test_fmi3_default_experiment_shows_the_static_equilibrium(native_fmus3, kind):
    from fmpy import simulate_fmu

    res = simulate_fmu(str(native_fmus3[kind]), output=["force_z", "in_contact"])
    assert float(res["time"][-1]) > 0.0
    np.testing.assert_allclose(res["force_z"], 15000.0, rtol=1e-12)
    assert res["in_contact"].all()


def test_fmi3_binaries_for_five_platforms_export_every_fmi3_function(native_fmus3):
    required = fmi_function_names((_fmpy_headers() / "fmi3Functions.h").read_text())
    assert len(required) >= 70
    with zipfile.ZipFile(native_fmus3["extended_tire"]) as z:
        binaries = {n.split("/")[1]: z.read(n) for n in z.namelist() if n.startswith("binaries/")}
        assert "sources/buildDescription.xml" in z.namelist()
    assert sorted(binaries) == sorted(MACHINES)
    for platform, data in binaries.items():
        assert machine(data) == MACHINES[platform], platform
        assert b"python" not in data.lower(), platform
        if MACHINES[platform][0] != "elf":
            assert required <= exported_names(data), platform


def test_fmi3_refused_value_is_fmi3Error_and_the_time_variable_reads_the_time(native_fmus3):
    from fmpy.fmi1 import FMICallException

    fmu = native_fmus3["point_contact"]
    messages = []
    s = open_fmi3_slave(fmu, log_message=lambda env, status, category, message: messages.append(
        (status, category.decode(), message.decode())))
    try:
        with pytest.raises(FMICallException) as info:
            s.setFloat64([4], [-1.0])  # stiffness
        assert info.value.status == 3  # fmi3Error
        assert any("stiffness must be > 0" in m for _, _, m in messages), messages
        with pytest.raises(FMICallException):
            s.setFloat64([0], [math.nan])  # hub_z
        s.doStep(0.0, 0.25)
        s.doStep(0.25, 0.25)
        assert s.getFloat64([11]) == [0.5]  # the independent variable
        assert s.getFloat64([4]) == [400e3]
        s.terminate()
    finally:
        s.freeInstance()


@pytest.mark.parametrize("kind", KINDS)
def test_fmi3_a_step_that_ends_beyond_the_largest_double_is_refused(native_fmus3, kind):
    """fmi3DoStep(1e308, 1e308) would put the clock at inf: fmi3Error, and the time stays where it was."""
    from fmpy.fmi1 import FMICallException

    from fmpy import read_model_description

    time_vr = next(v.valueReference for v in read_model_description(str(native_fmus3[kind])).modelVariables
                   if v.causality == "independent")
    messages = []
    s = open_fmi3_slave(native_fmus3[kind], log_message=lambda env, status, category, message: messages.append(
        message.decode()))
    try:
        s.doStep(0.0, 0.25)
        with pytest.raises(FMICallException) as info:
            s.doStep(1e308, 1e308)
        assert info.value.status == 3  # fmi3Error
        assert any("must end at a finite time" in m for m in messages), messages
        assert s.getFloat64([time_vr]) == [0.25]
    finally:
        s.freeInstance()


def test_fmi3_fmu_under_an_awkward_path_and_byte_identical_re_export(native_fmus3, tmp_path):
    from fmpy import simulate_fmu

    unzipped = extract(native_fmus3["point_contact"], tmp_path / AWKWARD_DIR)
    np.testing.assert_allclose(simulate_fmu(str(unzipped), output=["force_z"])["force_z"], 15000.0, rtol=1e-12)
    again = build_fmu("point_contact", tmp_path / "again.fmu", backend="native", fmi_version=3)
    assert again.read_bytes() == native_fmus3["point_contact"].read_bytes()


def _listing(folder):
    return sorted(p.name for p in Path(folder).iterdir())


def test_simulate_refuses_an_fmi3_fmu_and_one_without_this_machines_binary_leaving_nothing(
        native_fmus, native_fmus3, tmp_path, cli, monkeypatch):
    """Before: 'Cannot find shared library …/linux64/' for an FMI 3.0 FMU, and the extracted FMU stayed in
    $TMPDIR."""
    import tempfile
    import zipfile

    from identification.recording import write_recording
    from conftest import analytic_recording

    rec = write_recording(analytic_recording(tires=("FL",), noise=0.01), tmp_path / "r")
    stage = tmp_path / "tmp"
    stage.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(stage))
    foreign = tmp_path / "foreign.fmu"
    with zipfile.ZipFile(native_fmus["point_contact"]) as zin, zipfile.ZipFile(foreign, "w") as zout:
        for info in zin.infolist():
            if not info.filename.startswith("binaries/linux64/"):
                zout.writestr(info, zin.read(info))
    for fmu, needle in ((native_fmus3["point_contact"], "an FMI 3.0 FMU"),
                        (foreign, "has no binary for this machine (binaries/linux64/CleatfmuPointContact.so)")):
        res = cli("simulate", fmu, rec, "--tire", "FL")
        assert res.code == 2 and res.out == ""
        lines = res.err.strip().splitlines()
        assert len(lines) == 1 and needle in lines[0] and str(fmu) in lines[0], res.err
        assert _listing(stage) == []
