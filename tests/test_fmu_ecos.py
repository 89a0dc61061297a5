"""The native FMI 2.0 tire FMUs in Ecos (the ``ecospy`` wheel): its C library through Python and its ``ecos``
command line, against the Python law."""

from __future__ import annotations

import csv
import os
import shutil
import stat
import subprocess
from pathlib import Path

import pytest
from native_fixtures import law_force, native_fmus, start_values  # noqa: F401

try:  # ecospy loads its C library (which needs libtbb.so.12) when imported
    import ecospy
    from ecospy import EcosSimulation, EcosSimulationStructure
except ImportError as error:
    pytest.skip(f"ecospy is not installed ({error}); pip install ecospy", allow_module_level=True)
except OSError as error:
    pytest.skip(f"ecospy's native library does not load ({error}); on Debian: apt-get install libtbb12 (CI: .ci/setup-debian)",
                allow_module_level=True)

KINDS = ("point_contact", "extended_tire")
G = 9.80665


def _simulation(fmu, step_size: float, parameters: dict | None = None):
    """An Ecos simulation of one instance ``tire`` of `fmu`, with the optional parameter set ``p``."""
    structure = EcosSimulationStructure()
    structure.add_model("tire", str(fmu))
    if parameters:
        assert structure.add_parameter_set("p", {f"tire::{n}": v for n, v in parameters.items()})
    return EcosSimulation(structure=structure, step_size=step_size)


@pytest.mark.parametrize("kind", KINDS)
def test_ecos_holds_the_static_equilibrium_of_the_python_law(native_fmus, kind):
    fmu = native_fmus[kind]
    starts, _ = start_values(fmu)
    with _simulation(fmu, 1e-3) as sim:
        assert sim.init()
        forces = [sim.get_real("tire::force_z")]
        sim.step(100)
        forces.append(sim.get_real("tire::force_z"))
        assert sim.get_time() == pytest.approx(0.1, abs=1e-12)
        assert sim.get_bool("tire::in_contact")
        sim.terminate()
    want = law_force(kind, starts)
    assert want == pytest.approx(15000.0, rel=1e-12)  # the default wheel load
    for got in forces:
        assert abs(got - want) <= 1e-12 * want, (got, want)


def test_ecos_parameter_set_gives_the_python_laws_force(native_fmus):
    fmu = native_fmus["extended_tire"]
    starts, _ = start_values(fmu)
    changes = {"stiffness": 5e5, "hub_z": 0.7, "unilateral": True, "stiffness_exponent": 1.4,
               "static_load": 15000.0}
    with _simulation(fmu, 1e-3, changes) as sim:
        assert sim.init(parameter_set="p")
        sim.step(10)
        got = sim.get_real("tire::force_z")
        sim.terminate()
    want = law_force("extended_tire", {**starts, **changes})
    assert abs(got - want) <= 1e-12 * want, (got, want)
    assert abs(want - law_force("extended_tire", starts)) > 1000.0  # the set changed the force


def test_ecos_quarter_car_step_response_matches_the_python_law(native_fmus):
    """A quarter car stepped through Ecos (inputs set before each step, force read after it) and the same
    master with the Python law agree to round-off; the hub settles the road step higher."""
    fmu = native_fmus["point_contact"]
    k, c, r0, load, h, n, height = 400e3, 20e3, 0.75, 15000.0, 1e-3, 3000, 0.01
    mass = load / G
    z, v, t = r0 - load / k, 0.0, 0.0
    ez, ev = z, v
    with _simulation(fmu, h, {"damping": c}) as sim:
        assert sim.init(parameter_set="p")
        for i in range(n):
            road = height if t >= 0.1 else 0.0
            for name, value in (("hub_z", ez), ("hub_vz", ev), ("road_z", road)):
                sim.set_real(f"tire::{name}", value)
            sim.step(1)
            f_ecos = sim.get_real("tire::force_z")
            ev += h * (f_ecos / mass - G)
            ez += h * ev
            f = law_force("point_contact", {"hub_z": z, "hub_vz": v, "road_z": road, "road_vz": 0.0,
                                            "stiffness": k, "damping": c, "unloaded_radius": r0})
            v += h * (f / mass - G)
            z += h * v
            t = (i + 1) * h
            assert abs(f_ecos - f) <= 1e-9 * load, (i, f_ecos, f)
            assert abs(ez - z) <= 1e-12, i
        sim.terminate()
    assert ez - (r0 - load / k) == pytest.approx(height, rel=1e-4)


def _ecos_command(folder: Path) -> Path:
    """The wheel's ``ecos`` program (copied into `folder` with the execute bit where the wheel lacks it)."""
    exe = Path(ecospy.__file__).parent / "binaries" / "ecos"
    if not exe.is_file():
        pytest.skip(f"ecospy has no ecos program at {exe}")
    if not os.access(exe, os.X_OK):  # ecospy's wheel ships it with mode 0644
        exe = Path(shutil.copy2(exe, folder / "ecos"))
        exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    return exe


@pytest.mark.parametrize("kind", KINDS)
def test_ecos_command_line_simulates_the_static_equilibrium(native_fmus, kind, tmp_path):
    fmu = native_fmus[kind]
    starts, _ = start_values(fmu)
    done = subprocess.run([str(_ecos_command(tmp_path)), "simulate", "--path", str(fmu), "--stopTime", "0.05",
                           "--stepSize", "0.001", "--noParallel", "--logLevel", "warn"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    with (tmp_path / f"{Path(fmu).stem}.csv").open() as f:
        rows = [{key.strip(): value.strip() for key, value in row.items()} for row in csv.DictReader(f)]
    assert len(rows) >= 50
    assert float(rows[-1]["time"]) >= 0.049 - 1e-9  # 50 steps of 1 ms (Ecos writes a row per step)
    want = law_force(kind, starts)
    for row in rows:  # the CSV has six decimals
        assert abs(float(row["instance::force_z[REAL]"]) - want) <= 1e-6
        assert row["instance::in_contact[BOOL]"] == "1"
