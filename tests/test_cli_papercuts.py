"""Command-line papercuts: --example wherever a recording is read, output folders created as needed, ``rig``
without -o, a closed pipe, tire names in any letter case, defaults in every --help, -v for timings.

The heavy computations (diagnosis, co-simulation) are replaced by stand-ins where a test is about the
command line around them.
"""

from __future__ import annotations

import argparse
import io
import json
import shlex
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from identification.cli import command_line as cli
from identification.cli.identify import tire_list
from identification.cli.util import OutputFolders, check_output, choose_tire, make_folders
from identification.errors import InputError

TIRES = ("FL", "FR", "RL", "RR")


def _one_line_error(res, *needles):
    assert res.code == 2 and res.out == "", (res.code, res.out, res.err)
    assert len(res.err.strip().splitlines()) == 1 and res.err.startswith("cleatfmu: error: "), res.err
    for needle in needles:
        assert needle in res.err, res.err


def _errors(stderr: str) -> list[str]:
    """The lines of stderr that are not warnings (the embedded day's channels warn that their free decay is
    not one damped mode)."""
    return [ln for ln in stderr.splitlines() if not ln.startswith("cleatfmu: warning: ")]


def _subparsers(parser=None) -> dict:
    parser = parser or cli.build_parser()
    (action,) = [a for a in parser._actions if a.dest == "command"]
    return dict(action.choices)


# ----------------------------------------------------------------------------- 1. --example

def test_every_command_reading_a_recording_takes_example():
    for name, sub in _subparsers().items():
        positionals = [a for a in sub._actions if not a.option_strings and a.metavar == "REC.csv"]
        if positionals:
            assert positionals[0].nargs == "?", name
            assert any("--example" in a.option_strings for a in sub._actions), name


@pytest.mark.parametrize("command", [("identify",), ("diagnose",), ("simulate", "FL.fmu"), ("ride",)])
def test_recording_or_example_exactly_one(cli, tmp_path, command):
    neither = cli(*command) if command[0] != "simulate" else cli(*command, "--tire", "FL")
    _one_line_error(neither, "recording")
    both = cli(*command, tmp_path / "rec.csv", "--example", "7kmh")
    _one_line_error(both, "--example: give either a recording or --example, not both")


@pytest.mark.parametrize("command", [("diagnose",), ("simulate", "FL.fmu")])
def test_example_is_read(cli, command):
    """The embedded recording is read: its channels are what --tire is checked against (before any work)."""
    _one_line_error(cli(*command, "--example", "10kmh", "--tire", "xx"), "testday_10kmh.csv",
                    "tire XX is not in the recording (channels: FL, FR, RL, RR)")
    _one_line_error(cli(*command, "--example", "20kmh"), "--example: unknown example '20kmh'")


def test_simulate_recording_is_the_last_path_even_after_options(cli, tmp_path):
    _one_line_error(cli("simulate", "FL.fmu", "--tire", "FL", tmp_path / "late.csv"), "late.csv: no such file")
    _one_line_error(cli("simulate", "FL.fmu", "--tire", "FL"), "give the FMU(s) and then the recording")


def test_identify_example_with_lower_case_tires(cli):
    res = cli("identify", "--example", "7kmh", "--tire", "rr,fl", "--json")
    assert res.code == 0, res.err
    assert list(json.loads(res.out)["tires"]) == ["RR", "FL"]


# ----------------------------------------------------------------------------- 2. output folders

def test_check_output_creates_the_folder_and_a_failed_block_removes_it(tmp_path):
    target = tmp_path / "a" / "b" / "x.png"
    with pytest.raises(RuntimeError):
        with OutputFolders():
            check_output(target, ".png", "plot")
            assert target.parent.is_dir()
            raise RuntimeError("the run fails")
    assert list(tmp_path.iterdir()) == []
    with OutputFolders():
        check_output(target, ".png", "plot")
    assert target.parent.is_dir()
    check_output(tmp_path / "c" / "y.png", ".png", "plot", create=False)
    assert not (tmp_path / "c").exists()
    (tmp_path / "file").write_text("")
    for path, needle in ((tmp_path / "file" / "x.png", "is not a directory"), (tmp_path / "x.jpg", "must end with"),
                         (tmp_path / "a", "must end with")):
        with pytest.raises(InputError, match=needle):
            check_output(path, ".png", "plot")
    (tmp_path / "d.png").mkdir()
    with pytest.raises(InputError, match="is a directory"):
        check_output(tmp_path / "d.png", ".png", "plot")


def test_inner_block_hands_its_folders_to_the_outer_one(tmp_path):
    with pytest.raises(RuntimeError):
        with OutputFolders():
            with OutputFolders():
                assert make_folders(tmp_path / "p" / "q") == [tmp_path / "p", tmp_path / "p" / "q"]
            raise RuntimeError
    assert list(tmp_path.iterdir()) == []


def test_rig_output_folder_created(cli, tmp_path):
    res = cli("rig", "--param", "duration_s=2", "-o", tmp_path / "runs" / "day1" / "a")
    assert res.code == 0, res.err
    assert sorted(p.name for p in (tmp_path / "runs" / "day1").iterdir()) == ["a.csv", "a.json", "a.truth.json"]


def test_rig_output_under_a_file_refused_before_the_run(cli, tmp_path, monkeypatch):
    from identification.rig import generate

    monkeypatch.setattr(generate, "run_rig", None)   # never reached
    (tmp_path / "afile").write_text("")
    _one_line_error(cli("rig", "-o", tmp_path / "afile" / "sub" / "a"), "afile: is not a directory")
    assert [p.name for p in tmp_path.iterdir()] == ["afile"]


def test_rig_failing_after_the_folder_was_made_leaves_nothing(cli, tmp_path, monkeypatch):
    from identification.rig import generate

    def refuse(*args, **kwargs):
        raise InputError("rig", "cannot write (stand-in)")
    monkeypatch.setattr(generate, "write_run", refuse)
    _one_line_error(cli("rig", "--param", "duration_s=2", "-o", tmp_path / "runs" / "a"), "stand-in")
    assert list(tmp_path.iterdir()) == []


def _params(tmp_path) -> Path:
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"recording": "r.csv", "speed_kmh": 7.0,
                                "tires": {"FL": {"k": 4.1e5, "c": 2.3e3}, "FR": {"k": 4.2e5, "c": 2.4e3}}}))
    return path


def test_export_output_folder_created_and_tire_in_any_case(cli, tmp_path):
    out = tmp_path / "new" / "dir" / "x.fmu"
    res = cli("export", _params(tmp_path), "--tire", "fr", "--backend", "pythonfmu", "-o", out)
    assert res.code == 0, res.err
    assert "tire FR" in res.out and out.is_file()


def test_export_failing_build_removes_the_folder_it_made(cli, tmp_path, monkeypatch):
    import build_scripts

    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(build_scripts, "build_fmu", fail)
    res = cli("export", _params(tmp_path), "--tire", "FL", "--backend", "pythonfmu", "-o", tmp_path / "new" / "x.fmu")
    _one_line_error(res, "cannot write: No space left on device")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.json"]


def test_ride_plot_folder_removed_when_the_run_fails(cli, tmp_path):
    """``ride`` creates the --plot folder when it checks it; the run then fails: the folder goes again."""
    _one_line_error(cli("ride", tmp_path / "missing.csv", "--plot", tmp_path / "new" / "ride.png"),
                    "missing.csv: no such file")
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def fake_simulation(monkeypatch):
    """``simulate`` with a stand-in co-simulation and plot (the command line around them is real)."""
    from identification.report import plots
    from identification.fmu import validation

    def simulate_recording(fmu, rec, tire, **kwargs):
        if str(fmu).endswith("bad.fmu"):
            raise InputError(fmu, "not an FMU (stand-in)")
        return SimpleNamespace(to_json=lambda: {"tire": tire, "fmu": str(fmu)})
    monkeypatch.setattr(validation, "simulate_recording", simulate_recording)
    monkeypatch.setattr(plots, "plot_comparison", lambda cmp: "figure")
    monkeypatch.setattr(plots, "png_bytes", lambda fig, dpi=110: b"\x89PNG stand-in")


def test_simulate_plot_folder_created(cli, tmp_path, fake_simulation):
    plot = tmp_path / "some" / "new" / "x.png"
    res = cli("simulate", "FL.fmu", "--example", "7kmh", "--tire", "rl", "--json", "--plot", plot)
    assert res.code == 0, res.err
    assert json.loads(res.out)["tire"] == "RL" and plot.read_bytes() == b"\x89PNG stand-in"
    _one_line_error(cli("simulate", "bad.fmu", "--example", "7kmh", "--tire", "FL", "--plot",
                        tmp_path / "other" / "x.png"), "stand-in")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["some"]


@pytest.fixture
def fake_diagnosis(monkeypatch):
    """``diagnose`` with a stand-in diagnosis writing four FMU files (the command line around it is real)."""
    from identification.report import plots
    from identification.cli import diagnose as command
    from identification.diagnose.wording import effects_sentence

    calls = []

    def run_tractor_diagnosis(rec, *, cutoff_hz, fmu_dir=None, workers=1, progress=None):
        calls.append(fmu_dir)
        paths = []
        if fmu_dir is not None:
            for tire in TIRES:
                paths.append(Path(fmu_dir) / f"{Path(rec.source).stem}_{tire}.fmu")
                paths[-1].write_bytes(tire.encode())
        if cutoff_hz == 33.0:
            raise InputError(rec.source, "no fit (stand-in)")
        doc = {"effects": [], "body": {"pitch_index": None, "roll_index": None, "front_axle": "rigid",
                                       "speed_m_s": {"sidecar": 7 / 3.6, "from_delay": None}},
               "tires": {}, "intervals": "stand-in"}
        doc["summary"] = effects_sentence(doc)      # as the diagnosis' JSON carries it
        diag = SimpleNamespace(problem=SimpleNamespace(rec=rec), effects=[], extra={}, evidence={}, seconds=4.25,
                               to_json=lambda **kw: doc, tire_json=lambda tire, **kw: {"tire": tire})
        gain = SimpleNamespace(nrmse_before={}, nrmse_after={}, agreement=1e-9, fmu_paths=paths, seconds=1.5,
                               note=None, final_note=None)
        return diag, gain
    monkeypatch.setattr(command, "run_tractor_diagnosis", run_tractor_diagnosis)
    monkeypatch.setattr(plots, "plot_tractor_diagnosis", lambda diag, **kw: "figure")
    monkeypatch.setattr(plots, "png_bytes", lambda fig, dpi=110: b"\x89PNG stand-in")
    return calls


def test_diagnose_output_folders_created_all_outputs_together(cli, tmp_path, fake_diagnosis):
    new = tmp_path / "new"
    res = cli("diagnose", "--example", "--tire", "rr", "--json", "--fmu", new / "one" / "RR_ext.fmu",
              "--fmu-dir", new / "all", "--plot", new / "plots" / "d.png")
    assert res.code == 0, res.err
    assert json.loads(res.out) == {"tire": "RR"}
    assert (new / "one" / "RR_ext.fmu").read_bytes() == b"RR"
    assert sorted(p.name for p in (new / "all").iterdir()) == [f"testday_7kmh_{t}.fmu" for t in TIRES]
    assert (new / "plots" / "d.png").read_bytes() == b"\x89PNG stand-in"


def test_diagnose_failure_writes_nothing(cli, tmp_path, fake_diagnosis):
    res = cli("diagnose", "--example", "--fmu-dir", tmp_path / "fmus", "--plot", tmp_path / "p" / "d.png",
              "--cutoff-hz", "33")
    _one_line_error(res, "no fit (stand-in)")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "afile").write_text("")
    _one_line_error(cli("diagnose", "--example", "--fmu-dir", tmp_path / "afile" / "fmus"), "is not a directory")
    assert len(fake_diagnosis) == 1   # the bad --fmu-dir is refused before any work


# ----------------------------------------------------------------------------- 3. rig without -o

def test_rig_without_output_writes_a_generated_name_in_the_current_directory(cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    first = cli("rig", "--param", "duration_s=2")
    assert first.code == 0, first.err
    assert first.out.split() == [f"rig_baseline_7kmh_seed0{s}" for s in (".csv", ".json", ".truth.json")]
    again = cli("rig", "--param", "duration_s=2")   # never overwrites
    assert again.out.split() == [f"rig_baseline_7kmh_seed0_2{s}" for s in (".csv", ".json", ".truth.json")]
    (tmp_path / "runs").mkdir()
    into = cli("rig", "--param", "duration_s=2", "--seed", "4", "--speed", "10", "-o", "runs")
    assert into.out.split()[0] == str(Path("runs") / "rig_baseline_10kmh_seed4.csv")
    assert "rig_EFFECTS_SPEEDkmh_seedSEED" in _subparsers()["rig"].format_help()


def test_rig_tire_names_in_any_case(cli, tmp_path):
    _one_line_error(cli("rig", "--param", "tire.fl.k_N_m=-5", "-o", tmp_path / "x"), "tire.FL.k_N_m must be > 0")
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- 4. closed pipe

def _closed_pipe(*args) -> tuple[int, str]:
    """Run ``python -m identification.cli ARGS`` with stdout a pipe whose reader is gone before it writes."""
    proc = subprocess.Popen([sys.executable, "-m", "identification.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    proc.stdout.close()
    err = proc.stderr.read()
    return proc.wait(timeout=120), err


def test_closed_pipe_is_silent():
    code, err = _closed_pipe("identify", "--example", "7kmh")
    assert code == cli.EXIT_CLOSED_PIPE == 141 and _errors(err) == []
    code, err = _closed_pipe("--help")   # argparse drops help it cannot write (status 0); else cleatfmu: 141
    assert code in (0, cli.EXIT_CLOSED_PIPE) and err == ""


def test_head_closing_the_pipe_early_no_traceback():
    done = subprocess.run(f"{shlex.quote(sys.executable)} -m identification.cli identify --example 7kmh | head -c1",
                          shell=True, capture_output=True, text=True, timeout=120)
    assert "Traceback" not in done.stderr and _errors(done.stderr) == [] and len(done.stdout) == 1


def test_broken_stdout_in_process(monkeypatch, capsys):
    class Closed(io.StringIO):
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(sys, "stdout", Closed())
    assert cli.main(["rig", "--list-params"]) == 141


# ----------------------------------------------------------------------------- 5. tire names

def test_choose_tire_any_case():
    rec = SimpleNamespace(source="r.csv", tires=("FL", "RR"), accel_m_s2={"FL": 0, "RR": 0})
    assert choose_tire(rec, "fl") == "FL" and choose_tire(rec, " Rr ") == "RR"
    with pytest.raises(InputError, match="tire FR is not in the recording"):
        choose_tire(rec, "fr")
    assert tire_list(["fl,Rr", "FL"]) == ["FL", "RR"]
    with pytest.raises(InputError, match="unknown tire 'XX'"):
        tire_list(["xx"])


# ----------------------------------------------------------------------------- 6. defaults in --help

def test_every_default_is_in_the_help():
    for name, sub in _subparsers().items():
        formatter = sub._get_formatter()
        for action in sub._actions:
            if action.default in (None, False, argparse.SUPPRESS) or action.help in (None, argparse.SUPPRESS):
                continue
            assert "default" in formatter._expand_help(action).lower(), (name, action.dest)
        assert "default: None" not in sub.format_help() and "default: False" not in sub.format_help(), name


# ----------------------------------------------------------------------------- 7. -v for timings

def test_diagnose_timings_only_with_verbose(cli, fake_diagnosis):
    quiet = cli("diagnose", "--example", "7kmh")
    loud = cli("diagnose", "--example", "7kmh", "-v")
    assert quiet.code == loud.code == 0, (quiet.err, loud.err)
    assert "s diagnosis" not in quiet.out and "4.2 s diagnosis, 1.5 s FMU gain check" in loud.out


def test_tractor_text_says_not_determined_instead_of_printing_huge_bounds():
    from identification.cli.diagnose import _interval

    assert _interval(480e3, (470e3, 490e3), 1e3, ".1f") == "(470.0-490.0)"
    assert _interval(480e3, (1e-3, 1e300), 1e3, ".1f") == "(not determined by the data)"
    assert _interval(480e3, (0.0, float("inf")), 1e3, ".1f") == "(not determined by the data)"
    assert _interval(2e3, (0.5e3, 4.2e3), 1e3, ".3f") == "(not determined by the data)"   # half-width 1.85 > 1
    assert _interval(2e3, (1.2e3, 2.9e3), 1e3, ".3f") == "(1.200-2.900)"                  # half-width 0.85


def test_json_output_is_strict_json_with_null_for_unbounded_values():
    """An unbounded interval end is null, never ``Infinity``: strict parsers (jq, JavaScript) refuse those."""
    import math

    import numpy as np

    from identification._files import json_text

    doc = {"k_ci": (5e5, math.inf), "c_ci": [np.float64(-np.inf), np.float32(2.0)], "nan": float("nan"),
           "arr": np.array([1.0, np.inf]), "n": np.int64(3), "ok": True, "none": None}

    def refuse(constant):
        raise ValueError(f"non-standard JSON constant {constant}")

    back = json.loads(json_text(doc), parse_constant=refuse)
    assert back == {"k_ci": [5e5, None], "c_ci": [None, 2.0], "nan": None, "arr": [1.0, None], "n": 3,
                    "ok": True, "none": None}


def test_every_json_document_is_written_through_the_strict_writer():
    """No module writes a JSON document with ``json.dumps`` itself (that would write ``Infinity``); only
    one-value quotes in error messages (no ``indent``) may."""
    import ast

    offenders = []
    for path in Path(__file__).resolve().parents[1].joinpath("identification").rglob("*.py"):
        if path.name == "_files.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in ("dumps", "dump") \
                    and getattr(node.func.value, "id", "") == "json" and any(k.arg == "indent" for k in node.keywords):
                offenders.append(f"{path.name}:{node.lineno}")
    assert offenders == []


@pytest.mark.parametrize("command,kind", [(c, k) for c in ("export", "static", "simulate-body", "sidecar")
                                          for k in ("deep", "fifo", "device") if (c, k) != ("static", "deep")])
def test_json_nested_too_deep_a_fifo_or_a_device_is_refused_in_one_line(cli, tmp_path, good_recording, command,
                                                                         kind):
    """JSON nested 20,000 deep was a RecursionError traceback; a FIFO hung and /dev/zero behind a symlink
    filled memory, in export, static, simulate --body and a recording's sidecar."""
    import os

    bad = tmp_path / ("bad.json" if command != "static" else "bad.csv")
    if kind == "deep":                                   # (a CSV has no nesting: not for static)
        bad.write_text("[" * 20000 + "]" * 20000)
    elif kind == "fifo":
        os.mkfifo(bad)
    else:
        bad.symlink_to("/dev/zero")
    if command == "export":
        res = cli("export", bad, "-o", tmp_path / "x.fmu")
    elif command == "static":
        res = cli("static", bad)
    elif command == "simulate-body":                      # the reader of simulate --body, ssp --body
        from identification.errors import InputError
        from identification.fmu.simulate_inputs import read_body_document
        with pytest.raises(InputError) as info:
            read_body_document(bad)
        assert str(bad) in str(info.value) and ("nested too deeply" in str(info.value)
                                                 or "not a regular file" in str(info.value))
        return
    else:
        sidecar = good_recording.with_suffix(".json")
        sidecar.unlink()
        if kind == "deep":
            sidecar.write_text(bad.read_text())
        elif kind == "fifo":
            os.mkfifo(sidecar)
        else:
            sidecar.symlink_to("/dev/zero")
        res = cli("identify", good_recording)
    assert res.code == 2, (res.code, res.err)
    assert len(res.err.strip().splitlines()) == 1 and "Traceback" not in res.err
    assert any(word in res.err for word in ("nested too deeply", "not a regular file", "sidecar run.json not found")), \
        res.err


def test_an_output_name_too_long_is_one_line(cli, tmp_path):
    """A 300-character output name was an ENAMETOOLONG traceback (``Path.is_dir``)."""
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"tires": {"FL": {"k": 5e5, "c": 4e3}}}))
    res = cli("export", params, "-o", tmp_path / ("a" * 300 + ".fmu"))
    assert res.code == 2 and res.out == "" and "File name too long" in res.err
    assert len(res.err.strip().splitlines()) == 1 and list(tmp_path.iterdir()) == [params]


@pytest.mark.parametrize("redirect,needle", [("> /dev/full", "stdout: cannot write: No space left on device"),
                                             (">&-", "stdout: closed (the result would be lost)")])
def test_stdout_that_cannot_take_the_result_is_an_error_not_a_traceback_or_a_silent_success(redirect, needle):
    """``identify --example > /dev/full`` was an ENOSPC traceback; with stdout closed it exited 0 and the
    result was lost."""
    import os

    if redirect.endswith("/dev/full") and not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full here")
    cmd = f"{shlex.quote(sys.executable)} -m identification.cli identify --example {redirect}"
    done = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, timeout=120,
                          cwd=Path(__file__).resolve().parents[1])
    assert done.returncode == 2, (done.returncode, done.stderr)
    lines = _errors(done.stderr)
    assert len(lines) == 1 and lines[0].startswith(f"cleatfmu: error: {needle}"), done.stderr


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full here")
@pytest.mark.parametrize("args,made", [(["export", "{params}", "--tire", "FL", "-o", "{out}/kept.fmu",
                                         "--platforms", "linux64"], "kept.fmu"),
                                        (["export", "{params}", "--tire", "FL", "--format", "tir", "-o",
                                          "{out}/kept.tir"], "kept.tir"),
                                        (["rig", "-o", "{out}/run.csv"], "run.csv")])
def test_a_result_that_cannot_reach_stdout_leaves_the_files_as_they_were(tmp_path, args, made):
    """``export … -o kept.fmu > /dev/full`` failed with status 2 but had written kept.fmu; over an older file it
    now leaves the older file, and with none, nothing."""
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"recording": "r.csv", "speed_kmh": 7.0,
                                  "tires": {"FL": {"k": 550e3, "c": 2500.0, "mass": 1716.2}}}))
    out = tmp_path / "out"
    out.mkdir()
    argv = [a.format(params=params, out=out) for a in args]
    cmd = " ".join(shlex.quote(a) for a in [sys.executable, "-m", "identification.cli", *argv])
    root = Path(__file__).resolve().parents[1]
    for older in (None, b"the older file\n"):
        if older is not None:
            (out / made).write_bytes(older)
        done = subprocess.run(["bash", "-c", cmd + " > /dev/full"], capture_output=True, text=True, timeout=300,
                              cwd=root)
        assert done.returncode == 2, done.stderr
        assert done.stderr.strip().splitlines()[-1].startswith("cleatfmu: error: stdout: cannot write"), done.stderr
        if older is None:
            assert sorted(p.name for p in out.iterdir()) == []
        else:
            assert sorted(p.name for p in out.iterdir()) == [made] and (out / made).read_bytes() == older


def test_a_sidecar_without_acquisition_is_warned_and_one_with_it_is_not(tmp_path, capsys, example_diagnosis_run):
    """The joint fit's models then take an ideal sensor; on the embedded day (a declared chain) that would
    leave the impacts' residual: one warning line from diagnose, none with the chain; identify's free-decay
    methods do not model the chain and say nothing of it."""
    import shutil

    from identification.diagnose.run import NO_ACQUISITION
    from identification.recording.examples import example_path

    csv = Path(example_path("7kmh"))
    doc = json.loads(csv.with_suffix(".json").read_text())
    assert "acquisition" in doc
    doc.pop("acquisition")
    shutil.copy(csv, tmp_path / "day.csv")
    (tmp_path / "day.json").write_text(json.dumps(doc))
    assert cli.main(["diagnose", str(tmp_path / "day.csv"), "--json"]) == 0
    err = capsys.readouterr().err
    assert err.count(NO_ACQUISITION) == 1 and f"cleatfmu: warning: {tmp_path / 'day.csv'}: {NO_ACQUISITION}" in err
    assert "acquisition chain" not in example_diagnosis_run[1]      # the embedded day as it is
    assert cli.main(["identify", str(tmp_path / "day.csv")]) == 0
    assert "acquisition chain" not in capsys.readouterr().err


def test_names_xml_forbids_are_escaped_in_the_fmu_and_the_ssp(tmp_path):
    """A recording's name or a tire key with a control character, U+FFFE or a byte not in UTF-8 (a lone
    surrogate): export exits 0 with a modelDescription.xml that parses, names them as escapes and simulates;
    the line it prints does not fail on the surrogate.  Before: the XML did not parse (exit 0) and the print
    ended in a UnicodeEncodeError traceback."""
    import xml.etree.ElementTree as ET
    import zipfile

    from fmpy import simulate_fmu

    from identification.fmu.ssp import ssd_bytes

    entry = {"k": 550e3, "c": 2500.0, "mass": 1716.2}
    (tmp_path / "p.json").write_text(json.dumps({"recording": "c\x01d\ufffe\udcff.csv", "speed_kmh": 7.0,
                                                 "tires": {"F\x02L": entry, "\udcffR": entry}}))
    for key, arg in (("F\x02L", b"F\x02L"), ("\udcffR", b"\xffR")):
        fmu = tmp_path / "t.fmu"
        res = subprocess.run([sys.executable, "-m", "identification.cli", "export", str(tmp_path / "p.json"),
                              "--tire", arg, "-o", str(fmu), "--platforms", "linux64"], capture_output=True)
        assert res.returncode == 0 and b"Traceback" not in res.stderr, res.stderr
        assert res.stdout.startswith(b"wrote ") and b"stiffness 550000 N/m" in res.stdout
        root = ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))
        assert "recording 'c\\x01d\\ufffe\\udcff.csv'" in root.get("description")
        assert ("\\x02" if key == "F\x02L" else "\\udcff") in root.get("description")
        assert simulate_fmu(str(fmu), stop_time=0.05)["time"][-1] == pytest.approx(0.05)
    ssd = ET.fromstring(ssd_bytes("ride", "a ride on c\x01d\udcff.csv", start_s=0.0, stop_s=1.0, step_s=1e-3))
    assert ssd.find("{*}System").get("description") == "a ride on c\\x01d\\udcff.csv"


def test_a_pipe_named_as_a_recording_is_called_what_it_is(tmp_path, capsys):
    import os

    fifo = tmp_path / "rec.csv"
    os.mkfifo(fifo)
    for command in (["identify", str(fifo)], ["diagnose", str(fifo)]):
        assert cli.main(command) == 2
        err = capsys.readouterr().err
        assert err.strip() == f"cleatfmu: error: {fifo}: is not a regular file (a pipe or a device)", err


def test_export_says_so_when_identify_warned_of_the_tire(tmp_path, capsys):
    entry = {"k": 651.7e3, "c": 2500.0, "mass": 1716.2,
             "warning": "its one-mode fit leaves a correlated residual (decay_misfit 14): see diagnose"}
    (tmp_path / "p.json").write_text(json.dumps({"recording": "r.csv", "speed_kmh": 7.0,
                                                 "tires": {"FR": entry, "FL": {**entry, "warning": None}}}))
    assert cli.main(["export", str(tmp_path / "p.json"), "--tire", "FR", "-o", str(tmp_path / "fr.fmu"),
                     "--platforms", "linux64"]) == 0
    err = capsys.readouterr().err
    assert err.strip() == (f"cleatfmu: warning: {tmp_path / 'p.json'}: tire FR: the identification warned: "
                           f"{entry['warning']} (the exported k and c are its values)")
    assert cli.main(["export", str(tmp_path / "p.json"), "--tire", "FL", "-o", str(tmp_path / "fl.fmu"),
                     "--platforms", "linux64"]) == 0
    assert capsys.readouterr().err == ""


def test_a_missing_optional_package_is_one_line_naming_its_extra(tmp_path, capsys, monkeypatch):
    """report --scheduler without dask.distributed: exit 2, one line naming the extra, nothing written."""
    import builtins

    real_import = builtins.__import__

    def no_distributed(name, *args, **kwargs):
        if name == "distributed" or name.startswith("distributed."):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_distributed)
    monkeypatch.delitem(sys.modules, "distributed", raising=False)
    from identification.recording.examples import example_path

    assert cli.main(["report", str(example_path("7kmh")), "-o", str(tmp_path / "out"), "--scheduler",
                     "tcp://127.0.0.1:1"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == ("cleatfmu: error: --scheduler: needs the 'distributed' package "
                           "(pip install 'cleatfmu[cluster]')"), err
    assert not (tmp_path / "out").exists()


def test_comfort_refuses_accelerations_no_vibration_record_holds(tmp_path, capsys):
    """1e300 m/s^2 gave exit 0, numpy overflow warnings and a crest factor of 0."""
    rows = "\n".join(f"{i / 1000:.3f},{1e300 if i % 7 else -1e300}" for i in range(3000))
    (tmp_path / "big.csv").write_text("time_s,z\n" + rows + "\n")
    assert cli.main(["comfort", str(tmp_path / "big.csv"), "--json"]) == 2
    err = capsys.readouterr().err
    assert err.strip().startswith(f"cleatfmu: error: {tmp_path / 'big.csv'}") and "1e+300 m/s^2" in err, err
    assert "Warning" not in err and len(err.strip().splitlines()) == 1
