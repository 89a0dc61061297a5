"""Faults the command fuzz (``tests/test_fuzz_commands.py``) found, each pinned by the smallest case that
showed it (the fuzz draws them again only by chance)."""

from __future__ import annotations

import json
import os

import pytest

pytest.importorskip("hypothesis")
from test_fuzz import Case, _Raw, check_case, dumps_raw  # noqa: E402
from test_fuzz_commands import _files, command_files  # noqa: E402


def test_ride_plot_of_one_road():
    """``ride --realisations 1 --plot`` was a TypeError traceback (the plot took the interval of the mean over
    the roads, which one road does not have); now the plot shows that road's a_w."""
    args = ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=final,static=5e5", "--workers=1",
            "--duration-s=10", "--realisations=1", "--plot={dir}/out/r.png"]
    assert check_case(Case("ride", _files("run.csv", "run.json", "diag.json"), args)) == "valid"


@pytest.mark.parametrize("command", ["comfort", "ride"])
def test_a_plot_that_cannot_be_written_names_the_plot(command, tmp_path, monkeypatch):
    """On a full disk ``comfort --plot`` and ``ride --plot`` said ``stdout: cannot write: File too large``:
    the plot's write error reached the handler of stdout's; the message now names the plot."""
    import errno

    from identification import _files as files_module
    from identification.report import plots

    def full(files):
        raise OSError(errno.EFBIG, os.strerror(errno.EFBIG))

    folder = tmp_path / "case"
    folder.mkdir()
    # the inputs first (the first test of a process makes them with the commands, which write files too)
    for name, data in _files("run.csv", "run.json", "diag.json").items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(data)
    monkeypatch.setattr(plots, "atomic_write_bytes", full)
    monkeypatch.setattr(files_module, "atomic_write_bytes", full)
    plot = folder / "out" / "p.png"
    argv = {"comfort": ["comfort", folder / "run.csv"],
            "ride": ["ride", folder / "run.csv", f"--body={folder}/diag.json", "--compare=final", "--workers=1",
                     "--duration-s=10", "--realisations=1"]}[command] + [f"--plot={plot}"]
    from test_fuzz import _run

    status, stdout, stderr, tb = _run([str(a) for a in argv])
    assert tb is None and status == 2, (status, stderr, tb)
    assert stderr == f"cleatfmu: error: {plot}: cannot write: File too large\n"
    assert not plot.exists()


def test_an_fmu_that_cannot_be_extracted_says_why(tmp_path, monkeypatch):
    """A full temporary folder while an input FMU was extracted said only ``cannot instantiate the FMU here
    (OSError)``; the message now gives the system's reason."""
    import errno

    import fmpy

    from identification.errors import InputError
    from identification.fmu import cosim

    fmu = tmp_path / "run_FL.fmu"
    fmu.write_bytes(command_files()["fmus/run_FL.fmu"])

    def full(*args, **kwargs):
        raise OSError(errno.EFBIG, os.strerror(errno.EFBIG))

    monkeypatch.setattr(fmpy, "extract", full)
    with pytest.raises(InputError) as info:
        cosim.TireFmu(fmu)
    assert str(fmu) in str(info.value) and "File too large" in str(info.value)


def test_warnings_of_an_in_process_case_reach_its_stderr(monkeypatch):
    """Under pytest (which records warnings itself) a case's warnings went to pytest's list, not to the case's
    stderr, so a case that warned passed; :func:`test_fuzz._run` now shows them as a process would."""
    import warnings

    import identification.cli
    from test_fuzz import _run

    def warns(argv):
        warnings.warn("a warning of the command", RuntimeWarning)
        return 0

    monkeypatch.setattr(identification.cli, "main", warns)
    status, stdout, stderr, tb = _run(["identify"])
    assert status == 0 and "RuntimeWarning: a warning of the command" in stderr


def test_a_ride_too_short_for_its_speed_is_an_error_of_the_duration():
    """``ride --speed-kmh 1 --duration-s 10`` was a ValueError traceback: at 1 km/h the axles' fade-in takes
    longer than the ride; the allowed range of --duration-s (10 .. 3600 s) does not depend on the speed."""
    details = {}
    args = ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=final", "--workers=1", "--duration-s=10",
            "--realisations=1", "--speed-kmh=1"]
    assert check_case(Case("ride", _files("run.csv", "run.json", "diag.json"), args), details) == "error"
    assert details["message"].startswith("cleatfmu: error: --duration-s: must exceed twice the fade-in"), details


@pytest.mark.parametrize("cell", ["-4e298", "1e200", "2e11"])
def test_a_compression_test_beyond_any_tire_is_refused(cell):
    """A deformation of -4e298 mm overflowed the fit's squares: a RuntimeWarning on stderr and "slope 0 N/m";
    such a cell is now refused by line and column."""
    lines = command_files()["comp.csv"].decode().splitlines()
    cells = lines[3].split(",")
    cells[1] = cell
    lines[3] = ",".join(cells)
    details = {}
    case = Case("static", _files(**{"comp.csv": "\n".join(lines).encode() + b"\n"}), ["{dir}/comp.csv"])
    assert check_case(case, details) == "error"
    assert details["message"] == (f"cleatfmu: error: {{dir}}/comp.csv: line 4, column deformation_mm: {cell} is "
                                  "beyond any compression test (|deformation| <= 100 m, |force| <= 1e+09 N)")


@pytest.mark.parametrize("key", ["speed_m_s", "k_ci"])
def test_a_summary_number_beyond_the_float_range_is_refused(key):
    """An integer of 400 digits as a run's speed or interval in summary.json was an OverflowError traceback
    (``math.isfinite`` of an int beyond the float range) in ``map``."""
    doc = json.loads(command_files()["summary.json"])
    run = doc["recordings"][0]
    if key == "speed_m_s":
        run["conditions"]["speed_m_s"] = _Raw("1" * 400)
    else:
        run["tires"]["FL"]["recommended"]["k_ci"] = [_Raw("1" * 400), 1.0]
    details = {}
    case = Case("map", _files(**{"summary.json": dumps_raw(doc)}), ["{dir}/summary.json", "-o", "{dir}/map",
                                                                   "--no-fmu"])
    assert check_case(case, details) == "error"
    assert "must be finite numbers" in details["message"], details


def test_ssp_of_one_fmu_names_it():
    """``ssp run_FL.fmu REC.csv ...`` said ``cleatfmu: error: give one tire FMU, four ...``: no file named."""
    details = {}
    args = ["{dir}/fmus/run_FL.fmu", "{dir}/run.csv", "--body={dir}/diag.json", "-o", "{dir}/out/x.ssp"]
    assert check_case(Case("ssp", _files("run.csv", "run.json", "diag.json", "fmus"), args), details) == "error"
    assert details["message"].startswith("cleatfmu: error: {dir}/fmus/run_FL.fmu: give one tire FMU, four"), details


def test_comfort_axes_with_a_plot_is_refused():
    """``comfort --axes X,Y,Z --plot OUT.png`` exited 0 without writing OUT.png (the three-axis rating has no
    plot); the option is now refused, as --column is."""
    details = {}
    case = Case("comfort", _files("run.csv"), ["{dir}/run.csv", "--axes=FL,FR,RL", "--plot={dir}/out/p.png"])
    assert check_case(case, details) == "error"
    assert details["message"] == "cleatfmu: error: --plot: does not apply with --axes", details


@pytest.mark.parametrize("command", ["seat", "ride"])
def test_a_seat_number_beyond_the_float_range_is_refused(command):
    """A seat file whose mass is an integer of 400 digits was an OverflowError traceback (``seat``,
    ``ride --seat``)."""
    doc = json.loads(command_files()["seat.json"])
    doc["mass_kg"] = _Raw("9" * 400)
    files = _files("run.csv", "run.json", "diag.json", **{"seat.json": dumps_raw(doc)})
    args = {"seat": ["{dir}/seat.json", "--duration-s=10", "--class=I"],
            "ride": ["{dir}/run.csv", "--body={dir}/diag.json", "--seat={dir}/seat.json", "--compare=final",
                     "--duration-s=10", "--realisations=1", "--workers=1"]}[command]
    details = {}
    assert check_case(Case(command, files, args), details) == "error"
    assert details["message"].startswith("cleatfmu: error: {dir}/seat.json: mass_kg: a number far beyond"), details


def test_ride_on_a_road_file_with_a_seat_prints_its_table():
    """``ride --road-file ROAD.csv --seat SEAT.json`` (text) was a TypeError traceback: a road file has no PSD,
    so no linear seat factor from it, and the table formatted that None as a number."""
    args = ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=final", "--workers=1", "--duration-s=10",
            "--realisations=1", "--road-file={dir}/road.csv", "--seat={dir}/seat.json"]
    assert check_case(Case("ride", _files("run.csv", "run.json", "diag.json", "road.csv", "seat.json"), args)) \
        == "valid"


def test_a_saved_road_that_cannot_be_written_names_the_file(monkeypatch, tmp_path):
    """On a full disk ``ride --save-road OUT.csv`` said ``stdout: cannot write: File too large``."""
    import errno

    from identification.comfort import road_files
    from identification.errors import InputError

    def full(files):
        raise OSError(errno.EFBIG, os.strerror(errno.EFBIG))

    source = tmp_path / "r.csv"
    source.write_bytes(command_files()["road.csv"])
    road = road_files.read_road(source)
    monkeypatch.setattr(road_files, "atomic_write_texts", full)
    for name in ("out.csv", "out.crg"):
        with pytest.raises(InputError) as info:
            road_files.write_road(road, tmp_path / name)
        assert info.value.one_line() == f"{tmp_path / name}: cannot write: File too large"


def test_a_compression_test_of_no_measurable_deformation_is_refused():
    """Deformations of 1e-290 mm passed every check, then their squares underflowed to 0: a ZeroDivisionError
    traceback in the fit."""
    lines = command_files()["comp.csv"].decode().splitlines()
    for i in range(2, len(lines)):
        cells = lines[i].split(",")
        cells[1] = repr(float(cells[1]) * 1e-288)
        lines[i] = ",".join(cells)
    details = {}
    case = Case("static", _files(**{"comp.csv": "\n".join(lines).encode() + b"\n"}), ["{dir}/comp.csv"])
    assert check_case(case, details) == "error"
    assert "on the loading branch: less than 1e-09 m, no compression test" in details["message"], details


@pytest.mark.parametrize("command", ["simulate", "ride"])
def test_a_body_number_beyond_the_float_range_is_refused(command):
    """An arrival time of 400 digits in a ``diagnose --json`` document was an OverflowError traceback in the
    body reader of ``simulate --body``, ``ssp`` and ``ride --body``."""
    doc = json.loads(command_files()["diag.json"])
    doc["tires"]["RL"]["parameters"]["arrival"]["value"] = _Raw("1" * 400)
    files = _files("run.csv", "run.json", "fmus", **{"diag.json": dumps_raw(doc)})
    args = {"simulate": ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json"],
            "ride": ["{dir}/run.csv", "--body={dir}/diag.json", "--compare=final", "--duration-s=10",
                     "--realisations=1", "--workers=1"]}[command]
    details = {}
    assert check_case(Case(command, files, args), details) == "error"
    assert details["message"] == ("cleatfmu: error: {dir}/diag.json: tires.RL.parameters.arrival.value must be a "
                                  "finite number, got an integer of 400 digits"), details


def test_ssp_to_a_name_in_capitals():
    """``ssp ... -o X.SSP`` (the option takes the suffix in any case) failed with a message blaming the --body
    file and naming a temporary file: the archive was staged under the given name, which its writer refuses."""
    args = ["{dir}/fmus", "{dir}/run.csv", "--body={dir}/diag.json", "--output={dir}/out/X.SSP"]
    assert check_case(Case("ssp", _files("run.csv", "run.json", "diag.json", "fmus"), args)) == "valid"
