"""``cleatfmu export``: identified parameters -> FMU, through the real CLI entry point."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile

import pytest

from identification.cli import command_line as cli
from identification.fmu import export

FL = {"k": 412345.678901234, "c": 2345.6789, "T": 0.41, "delta": 0.9, "zeta": 0.142, "omega_n": 15.5,
      "r2": 0.98, "n_peaks": 5, "mass": 1716.2}
FR = {**FL, "k": 398000.0, "c": 2100.0}


@pytest.fixture(autouse=True)
def export_registered(monkeypatch):
    """Register the export command the way identification.cli does for its command modules."""
    if ".export" not in cli._COMMAND_MODULES:
        monkeypatch.setattr(cli, "_COMMAND_MODULES", [*cli._COMMAND_MODULES, ".export"])


def params_file(tmp_path, doc=None, text=None, name="params.json"):
    path = tmp_path / name
    if text is None:
        doc = doc if doc is not None else {"recording": "cleat_7kmh.csv", "speed_kmh": 7.0,
                                           "tires": {"FL": FL, "FR": FR}}
        text = json.dumps(doc)
    path.write_text(text, encoding="utf-8")
    return path


def starts(fmu) -> dict:
    root = ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))
    return {sv.get("name"): float(sv.find("Real").get("start")) for sv in root.iter("ScalarVariable")
            if sv.find("Real") is not None and sv.find("Real").get("start") is not None}


def test_export_writes_a_native_fmu_starting_at_the_identified_values_and_the_static_equilibrium(tmp_path, capsys):
    from fmpy.validation import validate_fmu

    doc = {"recording": "/home/someone/data/cleat_7kmh.csv", "speed_kmh": 7.0, "tires": {"FL": FL, "FR": FR}}
    params = params_file(tmp_path, doc)
    out = tmp_path / "out" / "FL.fmu"
    out.parent.mkdir()
    assert cli.main(["export", str(params), "--tire", "FL", "-o", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    assert validate_fmu(str(out)) == []
    s = starts(out)
    assert (s["stiffness"], s["damping"]) == (FL["k"], FL["c"])
    assert s["unloaded_radius"] == export.DEFAULT_UNLOADED_RADIUS_M
    # The hub starts where the tire carries the corner's weight m g: deflection m g / k.
    assert s["unloaded_radius"] - s["hub_z"] == pytest.approx(FL["mass"] * 9.80665 / FL["k"], rel=1e-12)
    with zipfile.ZipFile(out) as z:
        names = z.namelist()
        root = ET.fromstring(z.read("modelDescription.xml"))
        provenance = json.loads(z.read("resources/provenance.json"))
        assert b"/home/someone" not in b"".join(z.read(n) for n in names)
    assert {"binaries/linux64/CleatfmuPointContact.so", "binaries/win64/CleatfmuPointContact.dll",
            "binaries/darwin64/CleatfmuPointContact.dylib"} <= set(names)
    assert not any(n.endswith(".py") for n in names)
    description = root.get("description")
    assert "'cleat_7kmh.csv'" in description and "FL" in description and "paper method" in description
    assert "cleatfmu 0.1.0" in description or "cleatfmu unknown" in description
    assert provenance["identified"] == FL and provenance["recording"] == "cleat_7kmh.csv"
    assert provenance["method"] == "paper" and provenance["unloaded_radius_source"] == "default assumption"
    assert sorted(p.name for p in out.parent.iterdir()) == ["FL.fmu"]


def test_export_with_the_pythonfmu_backend(tmp_path):
    from fmpy.validation import validate_fmu

    out = tmp_path / "FL.fmu"
    assert cli.main(["export", str(params_file(tmp_path)), "--tire", "FL", "-o", str(out),
                     "--backend", "pythonfmu"]) == 0
    assert validate_fmu(str(out)) == []
    s = starts(out)
    assert s["unloaded_radius"] == s["hub_z"] == export.DEFAULT_UNLOADED_RADIUS_M
    entry = zipfile.ZipFile(out).read("resources/slavemodule.txt").decode().strip()
    provenance = json.loads(zipfile.ZipFile(out).read(f"resources/{entry}_start.json"))["provenance"]
    assert provenance["identified"] == FL and provenance["recording"] == "cleat_7kmh.csv"


def test_export_for_chosen_platforms_only(tmp_path):
    out = tmp_path / "FL.fmu"
    assert cli.main(["export", str(params_file(tmp_path)), "--tire", "FL", "-o", str(out),
                     "--platforms", "linux64, win64"]) == 0
    binaries = sorted(n for n in zipfile.ZipFile(out).namelist() if n.startswith("binaries/"))
    assert binaries == ["binaries/linux64/CleatfmuPointContact.so", "binaries/win64/CleatfmuPointContact.dll"]


def test_exported_fmu_computes_with_the_identified_stiffness(tmp_path):
    from build_scripts.runners import open_fmpy_slave, variable_refs

    out = tmp_path / "FR.fmu"
    assert cli.main(["export", str(params_file(tmp_path)), "--tire", "FR", "-o", str(out),
                     "--unloaded-radius-m", "0.8"]) == 0
    vr = {n: r for n, (r, _) in variable_refs(out).items()}
    s = open_fmpy_slave(out)
    try:
        s.setReal([vr["hub_z"]], [0.79])
        assert s.getReal([vr["force_z"]])[0] == pytest.approx(FR["k"] * 0.01, rel=1e-12)
    finally:
        s.freeInstance()


def test_default_output_name_and_single_tire_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    params = params_file(tmp_path, {"recording": "r.csv", "speed_kmh": 5.0, "tires": {"RL": FL}})
    assert cli.main(["export", str(params)]) == 0
    assert (tmp_path / "RL.fmu").is_file()


def test_help_documents_the_default_radius_assumption(capsys):
    with pytest.raises(SystemExit):
        cli.main(["export", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"default {export.DEFAULT_UNLOADED_RADIUS_M}, an assumption" in text


BAD_FILES = {
    "missing tire": (dict(doc={"tires": {"FR": FR}}), ["--tire", "FL"], "no tire 'FL'"),
    "k zero": (dict(doc={"tires": {"FL": {**FL, "k": 0.0}}}), [], "stiffness k must be > 0"),
    "k negative": (dict(doc={"tires": {"FL": {**FL, "k": -5.0}}}), [], "stiffness k must be > 0"),
    "c negative": (dict(doc={"tires": {"FL": {**FL, "c": -1.0}}}), [], "damping c must be >= 0"),
    "k NaN": (dict(text='{"tires": {"FL": {"k": NaN, "c": 1.0}}}'), [], "k must be a finite number"),
    "c infinite": (dict(text='{"tires": {"FL": {"k": 1e5, "c": Infinity}}}'), [], "c must be a finite number"),
    "k string": (dict(doc={"tires": {"FL": {**FL, "k": "4e5"}}}), [], "k must be a finite number"),
    "k missing": (dict(doc={"tires": {"FL": {"c": 1.0}}}), [], "missing 'k'"),
    "malformed JSON": (dict(text='{"tires": {"FL": '), [], "malformed JSON"),
    "no tires": (dict(doc={"recording": "x"}), [], "no \"tires\" object"),
    "several tires": (dict(doc={"tires": {"FL": FL, "FR": FR}}), [], "choose one with --tire"),
}


@pytest.mark.parametrize("case", list(BAD_FILES))
def test_bad_params_file_exits_2_with_one_line_naming_the_file(tmp_path, capsys, case):
    spec, extra, fragment = BAD_FILES[case]
    params = params_file(tmp_path, **spec)
    out = tmp_path / "out.fmu"
    before = sorted(tmp_path.iterdir())
    assert cli.main(["export", str(params), "-o", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("cleatfmu: error: ") and str(params) in err
    assert fragment in err
    assert sorted(tmp_path.iterdir()) == before


@pytest.mark.parametrize("args, source, fragment", [
    (["--unloaded-radius-m", "0"], "--unloaded-radius-m", "must be > 0"),
    (["--unloaded-radius-m", "nan"], "--unloaded-radius-m", "must be finite"),
    (["-o", "FL.zip"], "FL.zip", "must end with .fmu"),
    (["-o", "params.json/FL.fmu"], "params.json", "is not a directory"),  # a missing folder is created
    (["--platforms", "linux64,amiga"], "--platforms", "unknown platform 'amiga'"),
    (["--platforms", ","], "--platforms", "no platform given"),
    (["--fmi-version", "1"], "--fmi-version", "FMI 1 is not supported"),
    (["--backend", "java"], "--backend", "unknown backend 'java'"),
    (["--backend", "pythonfmu", "--platforms", "linux64"], "--platforms", "pythonfmu backend"),
])
def test_bad_options_exit_2_and_write_nothing(tmp_path, monkeypatch, capsys, args, source, fragment):
    monkeypatch.chdir(tmp_path)
    params = params_file(tmp_path)
    before = sorted(tmp_path.iterdir())
    assert cli.main(["export", str(params), "--tire", "FL", *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and source in err and fragment in err
    assert sorted(tmp_path.iterdir()) == before


def test_missing_params_file(tmp_path, capsys):
    assert cli.main(["export", str(tmp_path / "nope.json"), "--tire", "FL"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nope.json: no such file" in err


def test_failed_export_keeps_the_previous_fmu(tmp_path, capsys):
    out = tmp_path / "FL.fmu"
    out.write_bytes(b"previous FMU")
    params = params_file(tmp_path, {"tires": {"FL": {**FL, "c": -3.0}}})
    assert cli.main(["export", str(params), "-o", str(out)]) == 2
    assert out.read_bytes() == b"previous FMU"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["FL.fmu", "params.json"]
