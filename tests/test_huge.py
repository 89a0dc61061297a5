"""Long recordings: read in bounded chunks, analysed on the window of the cleat impacts, and said so.

The long recordings here are a short rig run placed inside a minute of the
rig's own sensor noise (white, the run's noise RMS): the results on the long
recording must be those on the short one, and the window must bracket the
rig's true arrivals.  The 2 M-row case, with time and memory, is
``benchmarks/bench_huge.py``.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from identification.recording import read_recording
from identification.rig import run_rig, write_run
from identification.recording.window import LEAD_S, LONG_RECORD_S, MAX_DECAY_S

RATE_HZ = 500.0
NOISE = 0.05
BEFORE_S, AFTER_S = 30.0, 25.0


@functools.lru_cache(maxsize=1)
def _short_run():
    """A four-wheel rig run of 8 s (the free decay ends inside it) and its truth."""
    return run_rig(("enveloping", "axle_coupling"), {"sensor.rate_hz": RATE_HZ, "sensor.noise_m_s2": NOISE,
                                                     "duration_s": 8.0, "cleat.stagger_m": 0.03}, seed=3)


def _write_pair(folder: Path) -> tuple[Path, Path, dict]:
    """``short.csv`` and ``long.csv`` (the short run at BEFORE_S in a record of BEFORE_S + 8 s + AFTER_S)."""
    run = _short_run()
    short, _ = write_run(run, folder / "short")
    rec = read_recording(short)
    n_before, n_after = int(BEFORE_S * RATE_HZ), int(AFTER_S * RATE_HZ)
    n = n_before + rec.time_s.size + n_after
    rng = np.random.default_rng(5)
    cols = [np.arange(n) / RATE_HZ]
    for tire in rec.tires:
        x = np.round(NOISE * rng.standard_normal(n), 4)
        x[n_before:n_before + rec.time_s.size] = rec.accel_m_s2[tire]
        cols.append(x)
    long_csv = folder / "long.csv"
    with open(long_csv, "w", encoding="utf-8") as f:
        f.write("time," + ",".join(rec.tires) + "\n")
        np.savetxt(f, np.column_stack(cols), fmt=["%.6f"] + ["%.4f"] * len(rec.tires), delimiter=",")
    long_csv.with_suffix(".json").write_text(short.with_suffix(".json").read_text())
    return short, long_csv, run.truth


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    return _write_pair(tmp_path_factory.mktemp("long"))


def test_identify_on_a_long_recording_equals_the_short_one_and_names_the_window(pair, cli):
    short, long_csv, truth = pair
    assert read_recording(long_csv).time_s[-1] > LONG_RECORD_S
    for method in ("paper", "waveform"):
        a, b = cli("identify", short, "--json", "--method", method), cli("identify", long_csv, "--json",
                                                                          "--method", method)
        assert a.code == b.code == 0
        warnings = [ln.replace(str(short), "REC") for ln in a.err.splitlines()]
        assert all(ln.startswith("cleatfmu: warning: ") for ln in warnings), a.err
        notes = [ln for ln in b.err.splitlines() if not ln.startswith("cleatfmu: warning: ")]
        assert [ln.replace(str(long_csv), "REC") for ln in b.err.splitlines() if ln not in notes] == warnings
        assert len(notes) == 1 and notes[0].startswith(f"cleatfmu: note: {long_csv}: ") and "analysed" in notes[0]
        da, db = json.loads(a.out), json.loads(b.out)
        for tire, entry in da["tires"].items():
            other = db["tires"][tire]
            assert "analysed_s" not in entry
            # the paper's peaks come from the same samples; the waveform fit's window ends with the record
            tol = 1e-9 if method == "paper" else 2e-3
            assert other["k"] == pytest.approx(entry["k"], rel=tol) and other["c"] == pytest.approx(entry["c"], rel=tol)
            lo, hi = other["analysed_s"]
            assert other["record_s"] == [0.0, pytest.approx((BEFORE_S + 8.0 + AFTER_S) - 1 / RATE_HZ)]
            assert hi - lo < 20.0
    # the window starts LEAD_S before the first wheel's true arrival (less the footprint's lead, within a block),
    # and holds every wheel's arrival and the free decay that follows
    arrivals = [BEFORE_S + t["arrival_s"] for t in truth["tires"].values()]
    first_touch = BEFORE_S + min(t["excitation_s"][0] for t in truth["tires"].values())
    assert lo == pytest.approx(first_touch - LEAD_S, abs=0.05)
    assert max(arrivals) + 3.0 < hi < max(arrivals) + MAX_DECAY_S


def test_simulate_on_a_long_recording_equals_the_short_one_and_names_the_window(pair, cli, tmp_path):
    short, long_csv, _ = pair
    params = tmp_path / "p.json"
    params.write_text(cli("identify", short, "--json", "--tire", "FL").out)
    assert cli("export", params, "--tire", "FL", "-o", tmp_path / "FL.fmu", "--platforms", "linux64").code == 0
    a = cli("simulate", tmp_path / "FL.fmu", short, "--tire", "FL", "--json")
    b = cli("simulate", tmp_path / "FL.fmu", long_csv, "--tire", "FL", "--json")
    assert a.code == b.code == 0 and a.err == "" and "analysed" in b.err
    da, db = json.loads(a.out), json.loads(b.out)
    assert db["nrmse"] == pytest.approx(da["nrmse"], rel=1e-6)
    assert db["k_reidentified"] == pytest.approx(da["k_reidentified"], rel=1e-6)
    assert "analysis_window" not in da and db["analysis_window"]["record_s"][0] == 0.0


def test_a_long_recording_without_an_impact_is_refused_in_one_line(tmp_path, cli):
    n = int(40 * RATE_HZ)
    rng = np.random.default_rng(2)
    path = tmp_path / "quiet.csv"
    np.savetxt(path, np.column_stack([np.arange(n) / RATE_HZ, NOISE * rng.standard_normal(n)]), fmt="%.5f",
               delimiter=",", header="time,FL", comments="")
    path.with_suffix(".json").write_text(json.dumps({"format": "cleat-recording/1", "speed_kmh": 7.0,
                                                     "cleat_height_mm": 40, "cleat_width_mm": 100,
                                                     "wheelbase_m": 2.77, "wheel_load_kN": {"FL": 11.46}}))
    res = cli("identify", path)
    assert res.code == 2 and res.err.count("\n") == 1 and "channel FL: no detectable cleat impact" in res.err


def _reference_rows(text: str) -> list[list[float]]:
    """The data rows of a CSV by Python's csv module (blank rows skipped)."""
    rows = list(csv.reader(io.StringIO(text)))[1:]
    return [[float(c) for c in row] for row in rows if any(c.strip() for c in row)]


def test_the_chunked_reader_matches_a_plain_parse_and_names_lines_across_chunks(tmp_path, monkeypatch):
    import identification.recording.csv_reader as rc
    from identification.errors import InputError

    monkeypatch.setattr(rc, "CHUNK_LINES", 7)
    rng = np.random.default_rng(4)
    lines = ["time,FL,RR"] + [f"{i / 200:.4f},{rng.normal():.5f},{rng.normal():.5f}" for i in range(300)]
    for at in (9, 10, 23, 150):   # blank lines, some at chunk boundaries
        lines.insert(at, "" if at % 2 else "  ")
    text = "\n".join(lines) + "\n"
    path = tmp_path / "r.csv"
    path.write_text(text)
    names, data = rc.read_csv(path, ("FL", "FR", "RL", "RR"))
    assert names == ["FL", "RR"]
    np.testing.assert_array_equal(data.T, np.array(_reference_rows(text)))
    bad = list(lines)
    bad[200] = bad[200].split(",")[0] + ",abc," + bad[200].split(",")[2]
    path.write_text("\n".join(bad) + "\n")
    with pytest.raises(InputError, match="line 201, column FL: 'abc' is not a number"):
        rc.read_csv(path, ("FL", "FR", "RL", "RR"))
    bad = list(lines)
    bad[180] = bad[180].replace(bad[180].split(",")[2], "inf")
    path.write_text("\n".join(bad) + "\n")
    with pytest.raises(InputError, match="line 181, column RR: non-finite value inf"):
        rc.read_csv(path, ("FL", "FR", "RL", "RR"))
    bad = list(lines)
    bad[250], bad[251] = bad[251], bad[250]
    path.write_text("\n".join(bad) + "\n")
    t_swapped = float(bad[251].split(",")[0])
    with pytest.raises(InputError, match=f"not strictly increasing at line 252 \\(t = {t_swapped:g} s"):
        rc.read_csv(path, ("FL", "FR", "RL", "RR"))


class _Pipe(io.StringIO):
    def isatty(self):
        return False


def test_diagnose_progress_on_a_long_recording_is_plain_lines_on_a_pipe(monkeypatch):
    from identification.cli import diagnose as command

    err = _Pipe()
    monkeypatch.setattr(sys, "stderr", err)
    tick, closer = command._progress("diagnose tractor", long=True)
    tick("baseline")
    tick("enveloping")
    closer.close()
    lines = err.getvalue().splitlines()
    assert len(lines) == 3 and all(ln.startswith("cleatfmu: diagnose tractor: ") for ln in lines)
    assert lines[0].endswith("step 1: baseline") and lines[1].endswith("step 2: enveloping")
    assert lines[2].endswith("done")
    seconds = [float(ln.split(": ")[2].rstrip(" s")) for ln in lines]
    assert seconds == sorted(seconds) and all(math.isfinite(s) for s in seconds)
    quiet = _Pipe()
    monkeypatch.setattr(sys, "stderr", quiet)
    tick, closer = command._progress("diagnose tractor", long=False)
    tick("baseline")
    closer.close()
    assert quiet.getvalue() == ""


def test_decimation_keeps_the_analysis_band_and_says_so(capsys):
    from identification.model.acquisition import Acquisition
    from identification.recording.preprocess import lowpass
    from identification.recording import Recording
    from identification.recording.window import decimate, window_json

    from conftest import damped_sine

    fs = 10_000.0
    t = np.arange(int(4 * fs)) / fs
    rng = np.random.default_rng(1)
    x = damped_sine(t, 1.0, 2 * np.pi * 9.0, 0.1, amplitude=8.0) + 0.05 * rng.standard_normal(t.size)
    rec = Recording(time_s=t, accel_m_s2={"FL": x}, speed_m_s=2.0, cleat_height_m=0.04, cleat_width_m=0.1,
                    wheelbase_m=2.77, wheel_load_N={"FL": 11460.0}, source="hifi.csv",
                    acquisition=Acquisition(4, 2500.0, 0.05))
    out = decimate(rec, cutoff_hz=100.0)
    assert out.sample_rate_hz == pytest.approx(2000.0) and out.decimated_from_hz == pytest.approx(fs)
    np.testing.assert_array_equal(out.time_s, t[::5])
    # the analysis' 100 Hz low-pass of the decimated samples is that of the original ones, sampled
    a = lowpass(out.accel_m_s2["FL"], sample_rate_hz=out.sample_rate_hz, cutoff_hz=100.0)
    b = lowpass(x, sample_rate_hz=fs, cutoff_hz=100.0)[::5]
    inner = slice(200, -200)   # away from the record's ends, where the two filters' edges differ
    assert np.sqrt(np.mean((a - b)[inner] ** 2)) < 1e-3 * np.sqrt(np.mean(b[inner] ** 2))
    # the anti-alias filter above the new Nyquist frequency leaves the model; the AC coupling stays
    assert out.acquisition == Acquisition(0, 0.0, 0.05)
    err = capsys.readouterr().err
    assert err.startswith("cleatfmu: note: hifi.csv: sampled at 10000 Hz; analysed at 2000 Hz") and \
        "2500 Hz anti-alias filter is left out" in err and err.count("\n") == 1
    assert window_json(out)["decimated_from_hz"] == pytest.approx(fs)
    assert decimate(out, cutoff_hz=100.0) is out and decimate(rec, cutoff_hz=400.0) is rec
