"""``cleatfmu simulate`` with four tire FMUs: the whole tractor under the diagnosed body against every channel."""

import contextlib
import io
import json
import shutil

import pytest

from identification.cli import main
from identification.recording import Recording, read_recording, write_recording
from identification.rig import run_rig, write_run

TIRES = ("FL", "FR", "RL", "RR")


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory):
    """One whole-tractor diagnosis (``diagnose --json --fmu-dir``): (csv, DIAG.json, FMU directory, document)."""
    base = tmp_path_factory.mktemp("simulate_tractor")
    run = run_rig(("enveloping",), {"speed_kmh": 10.0}, seed=8)
    csv_path, truth_path = write_run(run, base / "rec")
    truth_path.unlink()
    fmus = base / "fmus"
    fmus.mkdir()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main([str(a) for a in ("diagnose", csv_path, "--json", "--fmu-dir", fmus, "--workers", "1")])
    assert code == 0
    doc = json.loads(out.getvalue())
    body = base / "diag.json"
    body.write_text(out.getvalue())
    return csv_path, body, fmus, doc


def _check(res, doc):
    assert res.code == 0, res.err
    out = json.loads(res.out)
    assert set(out) == {"recording", "fmus", "body", "tires"}
    assert set(out["tires"]) == set(TIRES)
    assert {t: p.rsplit("/", 1)[-1] for t, p in out["fmus"].items()} == {t: f"rec_{t}.fmu" for t in TIRES}
    assert out["body"]["front_axle"] == doc["body"]["front_axle"]
    for tire, t in out["tires"].items():
        assert set(t) == {"nrmse", "noise_nrmse", "residual_to_noise", "residual_test"}
        assert t["residual_to_noise"] < 1.5, (tire, t)
        # the rig's model is the fitter's: no stretch of the residual above the noise either
        test = t["residual_test"]
        assert test["at_noise"] and test["worst_span_to_noise"] < 3.0, (tire, test)
        assert test["residual_to_noise"] == pytest.approx(t["residual_to_noise"], rel=1e-9)
        assert t["residual_to_noise"] == pytest.approx(t["nrmse"] / t["noise_nrmse"], rel=1e-12)
        # the same FMU co-simulation as the diagnosis' gain check
        assert t["nrmse"] == pytest.approx(doc["tires"][tire]["nrmse_after"], rel=1e-6)
        assert t["noise_nrmse"] == pytest.approx(doc["tires"][tire]["noise_nrmse"], rel=1e-9)


def test_diagnose_json_names_the_pivot_index(diagnosed):
    doc = diagnosed[3]
    assert "pivot_index" in doc["body"]
    assert (doc["body"]["pivot_index"] is None) == (doc["body"]["front_axle"] == "rigid")


def test_simulate_directory_and_four_paths(cli, diagnosed, tmp_path):
    csv_path, body, fmus, doc = diagnosed
    _check(cli("simulate", fmus, csv_path, "--body", body, "--json"), doc)
    # four paths, shuffled: matched by their _FL .. _RR suffixes
    shuffled = [fmus / f"rec_{t}.fmu" for t in ("RR", "FL", "RL", "FR")]
    _check(cli("simulate", *shuffled, csv_path, "--body", body, "--json"), doc)
    # four paths without suffixes: taken in FL, FR, RL, RR order
    plain = []
    for i, t in enumerate(TIRES):
        plain.append(tmp_path / f"tire{i}.fmu")
        shutil.copy(fmus / f"rec_{t}.fmu", plain[-1])
    res = cli("simulate", *plain, csv_path, "--body", body, "--json", "--plot", tmp_path / "all.png")
    assert res.code == 0, res.err
    assert json.loads(res.out)["tires"]["RR"]["nrmse"] == pytest.approx(doc["tires"]["RR"]["nrmse_after"], rel=1e-6)
    assert (tmp_path / "all.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = cli("simulate", fmus, csv_path, "--body", body)
    assert text.code == 0 and "NRMSE" in text.out and "explains every channel" in text.out
    assert "NOT EXPLAINED" not in text.out


def _one_line_error(res, needle):
    assert res.code == 2, res.out
    assert res.out == ""
    assert len(res.err.strip().splitlines()) == 1 and "Traceback" not in res.err, res.err
    assert needle in res.err, res.err


def test_simulate_tractor_bad_input(cli, diagnosed, tmp_path):
    csv_path, body, fmus, doc = diagnosed
    three = tmp_path / "three"
    three.mkdir()
    for t in ("FL", "FR", "RL"):
        shutil.copy(fmus / f"rec_{t}.fmu", three / f"rec_{t}.fmu")
    _one_line_error(cli("simulate", three, csv_path, "--body", body), "*_RR.fmu")
    assert str(three) in cli("simulate", three, csv_path, "--body", body).err
    _one_line_error(cli("simulate", fmus, csv_path), "--body")
    no_body = tmp_path / "no_body.json"
    no_body.write_text(json.dumps({k: v for k, v in doc.items() if k != "body"}))
    _one_line_error(cli("simulate", fmus, csv_path, "--body", no_body), f"{no_body}: ")
    _one_line_error(cli("simulate", fmus, csv_path, "--body", no_body), "missing key body")
    no_arrival = json.loads(json.dumps(doc))
    del no_arrival["tires"]["RL"]["parameters"]["arrival"]
    (tmp_path / "no_arrival.json").write_text(json.dumps(no_arrival))
    _one_line_error(cli("simulate", fmus, csv_path, "--body", tmp_path / "no_arrival.json"),
                    "tires.RL.parameters.arrival")
    _one_line_error(cli("simulate", *(fmus / f"rec_{t}.fmu" for t in TIRES[:2]), csv_path, "--body", body),
                    "got 2 path(s)")
    rec = read_recording(csv_path)
    three_channels = Recording(time_s=rec.time_s, accel_m_s2={t: rec.accel_m_s2[t] for t in TIRES[:3]},
                               speed_m_s=rec.speed_m_s, cleat_height_m=rec.cleat_height_m,
                               cleat_width_m=rec.cleat_width_m, wheelbase_m=rec.wheelbase_m,
                               wheel_load_N={t: rec.wheel_load_N[t] for t in TIRES[:3]})
    _one_line_error(cli("simulate", fmus, write_recording(three_channels, tmp_path / "three"), "--body", body),
                    "needs all four channels")


def test_simulate_under_a_pivot_body_from_the_document(cli, diagnosed, tmp_path):
    """The couplings and indices come from the document: a pivot tractor is built and reported as used."""
    csv_path, _, fmus, doc = diagnosed
    pivot = json.loads(json.dumps(doc))
    pivot["effects"] += ["axle_coupling", "roll_coupling", "front_axle_pivot"]
    pivot["body"].update(pitch_index={"value": 0.9, "ci": [0.8, 1.0]}, roll_index={"value": 0.6, "ci": [0.5, 0.7]},
                         front_axle="pivot", pivot_index={"value": 0.1, "ci": [0.05, 0.2]})
    path = tmp_path / "pivot.json"
    path.write_text(json.dumps(pivot))
    res = cli("simulate", fmus, csv_path, "--body", path, "--json")
    assert res.code == 0, res.err
    body = json.loads(res.out)["body"]
    assert body["kind"] == "pivot" and body["front_axle"] == "pivot"
    assert (body["pitch_index"], body["roll_index"], body["pivot_index"]) == (0.9, 0.6, 0.1)
    del pivot["body"]["pivot_index"]
    path.write_text(json.dumps(pivot))
    _one_line_error(cli("simulate", fmus, csv_path, "--body", path), "body.pivot_index")


def test_ssp_of_the_diagnosed_tractor_runs_in_fmpy_and_libcosim_like_the_master(cli, diagnosed, tmp_path):
    """``cleatfmu ssp``: the diagnosed tractor as an SSP 1.0 system (native body + four tires), checked."""
    csv_path, body, fmus, doc = diagnosed
    out = tmp_path / "new" / "tractor.ssp"
    res = cli("ssp", fmus, csv_path, "--body", body, "-o", out, "--check", "--json")
    assert res.code == 0, res.err
    result = json.loads(res.out)
    assert out.is_file() and result["body"] == "corners"      # this rig day: independent corners
    hosts = {h: d for h, d in result["check"].items() if not h.startswith("exchange")}
    assert len(hosts) == 3 and all(d < 1e-6 for d in hosts.values()), hosts
    # the fixed-step exchange's delay is visible in the master itself: it is not what the hosts' agreement hides
    assert result["check"]["exchange effect (parallel vs sequential master)"] > 1e-4


def test_ssp_check_without_libcosimpy_checks_in_fmpy_and_says_so(cli, diagnosed, tmp_path, monkeypatch):
    """After the main install (libcosimpy is only in the test extra) --check ran into a traceback; now it
    checks in fmpy, says libcosim was not run and why, and exits 0 when fmpy agrees."""
    from identification.cli import ssp as ssp_cmd

    monkeypatch.setattr(ssp_cmd, "libcosim_available", lambda: False)
    csv_path, body, fmus, doc = diagnosed
    res = cli("ssp", fmus, csv_path, "--body", body, "-o", tmp_path / "t.ssp", "--check", "--json")
    assert res.code == 0, res.err
    assert res.err.strip() == ("cleatfmu: warning: --check: libcosimpy is not installed (pip install 'cleatfmu[libcosim]'): "
                               "the archive is checked in fmpy only")
    hosts = [h for h in json.loads(res.out)["check"] if not h.startswith("exchange")]
    assert hosts == ["fmpy (sequential exchange)", "fmpy (parallel exchange)"]


def test_ssp_refuses_a_body_document_that_is_not_json(cli, diagnosed, tmp_path):
    csv_path, body, fmus, doc = diagnosed
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    res = cli("ssp", fmus, csv_path, "--body", bad, "-o", tmp_path / "t.ssp")
    assert res.code == 2 and len(res.err.strip().splitlines()) == 1 and "bad.json" in res.err
    assert not (tmp_path / "t.ssp").exists()
