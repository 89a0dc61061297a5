"""One rule per input form, for every reader: repeated JSON keys, number cells, time columns.

Each case failed before its rule was made common (a sidecar's repeated key silently took the last value;
``static`` took ``4_35e-2`` and Arabic-Indic digits; a time column written to 5 decimals at 2048 Hz was
refused as not uniformly sampled).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import analytic_recording
from identification.recording import write_recording
from identification.recording.csv_reader import time_resolution


def _one_line(res, *needles):
    assert res.code == 2, res
    assert res.out == ""
    lines = res.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cleatfmu: error: "), res.err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


def test_a_sidecar_key_given_twice_is_refused_not_the_last_one_taken(cli, good_recording):
    sidecar = good_recording.with_suffix(".json")
    text = sidecar.read_text()
    load = json.loads(text)["wheel_load_kN"]
    sidecar.write_text(text.replace('"wheel_load_kN": {', '"wheel_load_kN": {"FL": 1.0}, "wheel_load_kN": {', 1))
    assert isinstance(load, dict)
    _one_line(cli("identify", good_recording), "run.json", "'wheel_load_kN' appears twice")


def test_a_params_key_given_twice_is_refused(cli, tmp_path):
    entry = {"k": 550e3, "c": 2500.0, "mass": 1716.2}
    body = json.dumps({"recording": "r.csv", "speed_kmh": 7.0, "tires": {"FL": entry}})
    params = tmp_path / "p.json"
    params.write_text(body.replace('"k": 550000.0', '"k": 550000.0, "k": 55000.0'))
    _one_line(cli("export", params, "--tire", "FL", "-o", tmp_path / "fl.fmu"), "p.json", "'k' appears twice")
    assert not (tmp_path / "fl.fmu").exists()


@pytest.mark.parametrize("cell", ["4_35e-2", "\u0664\u0663"])      # digit separator; Arabic-Indic "43"
def test_static_takes_numbers_as_every_table_reader_does(cli, tmp_path, cell):
    rows = ["deformation_m,force_N", "0,0", f"{cell},1000"] + [f"{0.01 * i},{1000.0 * i}" for i in range(2, 8)]
    path = tmp_path / "c.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    _one_line(cli("static", path), "c.csv", "line 3", "is not a number")


def test_time_written_to_5_decimals_at_2048_hz_is_uniform_for_every_reader(cli, tmp_path):
    """1/2048 s written to 5 decimals is up to 1.02 % of a step off the grid: the time column's own resolution,
    not a clock that jitters."""
    rec = analytic_recording(fs=2048.0, duration=4.0, tires=("FL",), noise=0.01)
    csv = write_recording(rec, tmp_path / "r")
    lines = csv.read_text().splitlines()
    t = np.array([float(ln.split(",", 1)[0]) for ln in lines[1:]])
    rounded = np.round(t, 5)
    assert np.max(np.abs(rounded - (t[0] + np.arange(t.size) / 2048.0))) > 0.01 / 2048.0   # beyond 1 % of a step
    assert time_resolution(rounded) == pytest.approx(1e-5)
    lines[1:] = [f"{r:.5f}," + ln.split(",", 1)[1] for r, ln in zip(rounded, lines[1:])]
    csv.write_text("\n".join(lines) + "\n")
    res = cli("identify", csv, "--json")
    assert res.code == 0, res.err
    assert json.loads(res.out)["tires"]["FL"]["k"] > 0
    record = tmp_path / "acc.csv"
    record.write_text("time_s,acc_m_s2\n" + "\n".join(f"{r:.5f},{np.sin(40 * r):.6f}" for r in rounded) + "\n")
    res = cli("comfort", record, "--json")
    assert res.code == 0, res.err
    assert json.loads(res.out)["sample_rate_hz"] == pytest.approx(2048.0, rel=1e-6)


def test_a_clock_that_jitters_beyond_a_tenth_of_the_resolution_rule_is_still_refused(cli, tmp_path):
    """Written to 7 decimals, a time 3 % of a step off the grid is jitter, refused by both readers."""
    t = np.arange(3000) / 2048.0
    t[1500] += 0.03 / 2048.0
    record = tmp_path / "acc.csv"
    record.write_text("time_s,acc_m_s2\n" + "\n".join(f"{v:.9f},{np.sin(40 * v):.6f}" for v in t) + "\n")
    _one_line(cli("comfort", record), "acc.csv", "not uniformly sampled", "line 1502")
    rec = analytic_recording(fs=2048.0, duration=4.0, tires=("FL",))
    csv = write_recording(rec, tmp_path / "r")
    lines = csv.read_text().splitlines()
    tt, rest = lines[1501].split(",", 1)
    lines[1501] = f"{float(tt) + 0.03 / 2048.0:.9f},{rest}"
    csv.write_text("\n".join(lines) + "\n")
    _one_line(cli("identify", csv), "r.csv", "not uniformly sampled", "line 1502")
