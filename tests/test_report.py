"""``cleatfmu demo`` and ``cleatfmu report``: the whole chain into a self-contained HTML report."""

import base64
import io
import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from conftest import chromium as _chromium
from identification.rig import run_rig, write_run

SECTIONS = ("recommended", "howto", "speed", "summary", "table4", "waveform", "diagnoses", "tires", "fmus",
            "timings")


def test_demo_creates_its_folders_and_says_what_it_wrote_and_how_to_open_it(demo_run):
    code, out, stdout = demo_run
    assert code == 0 and (out / "report.html").is_file()
    lines = stdout.splitlines()
    # said at once what it is about to do, at the end what it wrote and how to open the report
    assert lines[0] == f"cleatfmu demo: 2 recording(s) into {out}{os.sep} on up to 2 local process(es)"
    wrote = {line.split(" (")[0].removeprefix("wrote ") for line in lines if line.startswith("wrote ")}
    assert wrote == {str(out / "report.html"), str(out / "summary.json"), f"{out / 'tables'}{os.sep}",
                     f"{out / 'fmu'}{os.sep}", f"{out / 'params'}{os.sep}"}
    assert f"{out / 'fmu'}{os.sep} (8 recommended tire FMUs <recording>_<TIRE>.fmu; 8 point-contact ones of the " \
           f"same k, c in point_contact{os.sep}; 8 not recommended in not_recommended{os.sep})" in stdout
    assert f"{out / 'tables'}{os.sep} (5 CSV tables)" in stdout
    assert f"{out / 'params'}{os.sep} (2 recommended parameter files <recording>.json; 8 not recommended in " \
           f"not_recommended{os.sep})" in stdout
    assert lines[-1] == f"open the report in a web browser: {(out / 'report.html').resolve().as_uri()}"


def _png(data: bytes):
    import matplotlib.image as mpimg
    return mpimg.imread(io.BytesIO(data), format="png")


def test_demo_report_sections_tables_images(demo, cli):
    code, out = demo
    assert code == 0
    html = (out / "report.html").read_text()
    for section in SECTIONS:
        assert f'<section id="{section}">' in html, section
    for rec in ("testday_7kmh", "testday_10kmh"):
        assert f'id="diagnosis-{rec}"' in html
        for tire in ("FL", "FR", "RL", "RR"):
            assert f'id="tire-{rec}-{tire}"' in html
    # the Table-4 rows hold what `cleatfmu identify --json` says for the same recordings
    table = html[html.index('<section id="table4">'):html.index('<section id="waveform">')]
    rows = re.findall(r"<tr><td>([\d.]+)</td><td class=\"l\">(\w+)</td><td class=\"l\">(\w\w)</td>"
                      r"<td>([\d.]+)</td><td>([\d.]+)</td><td>([\d.]+)</td><td>([\d.]+)</td><td>([\d.]+)</td>"
                      r"<td>([\d.]+)</td><td>([\d.]+)</td><td>(\d+)</td></tr>", table)
    assert len(rows) == 8
    for name in ("7kmh", "10kmh"):
        doc = json.loads(cli("identify", "--example", name, "--json").out)
        for tire, entry in doc["tires"].items():
            row = next(r for r in rows if r[1] == f"testday_{name}" and r[2] == tire)
            assert float(row[7]) == pytest.approx(entry["k"] / 1e3, abs=0.006)
            assert float(row[8]) == pytest.approx(entry["c"] / 1e3, abs=0.006)
            assert float(row[3]) == pytest.approx(entry["T"], abs=6e-4)
    # every embedded image is a PNG that decodes to a real picture
    images = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
    assert len(images) == 8 * 2 + 2 * 3 + 1   # per tire: decay, co-simulation; per recording: diagnosis, impacts,
    #                                           ride; k, c against speed
    for data in images:
        pixels = _png(base64.b64decode(data))
        assert pixels.ndim == 3 and pixels.shape[0] > 200 and pixels.shape[1] > 400
        assert float(pixels[..., :3].std()) > 0.05
    assert "src=\"http" not in html and "<script" not in html   # self-contained, static
    # the verdict first; at most 1 MB; no absolute paths of the machine it ran on
    assert html.index('<section id="recommended">') < html.index('<section id="summary">')
    assert (out / "report.html").stat().st_size <= 1_000_000
    assert str(out) not in html and "identification/data" not in html


def test_demo_tables_are_downloadable_and_say_what_the_report_says(demo, cli):
    import csv
    code, out = demo
    html = (out / "report.html").read_text()
    summary = json.loads((out / "summary.json").read_text())
    for name in ("verdict", "campaign", "table4", "methods", "ride"):
        assert f'href="tables/{name}.csv"' in html
    rows = list(csv.DictReader((out / "tables" / "verdict.csv").open()))
    assert len(rows) == 8
    for row in rows:
        r = next(r for r in summary["recordings"] if os.path.basename(r["source"]) == row["recording"] + ".csv")
        rec = r["tires"][row["tire"]]["recommended"]
        assert float(row["k_N_m"]) == pytest.approx(rec["k"], rel=1e-12)
        assert float(row["c_ci_low"]) == pytest.approx(rec["c_ci"][0], rel=1e-12)
        assert (out / row["fmu"]).is_file() and f'href="{row["fmu"]}"' in html
        # the rig truth beside the estimates (display only), from the truth file next to the recording
        assert float(row["k_truth_N_m"]) == pytest.approx(float(row["k_N_m"]), rel=0.03)
    ride = list(csv.DictReader((out / "tables" / "ride.csv").open()))
    assert {r["set"] for r in ride} == {"paper", "final", "static"} and len(ride) == 6
    # the static set comes from the demo's compression test, named in the table; its k is what `static` says
    from identification.recording.examples import compression_path
    static_k = json.loads(cli("static", compression_path(), "--json").out)["k_static_N_per_m"]
    for row in ride:
        assert (row["static_source"] == "testday_compression.csv") == (row["set"] == "static")
        if row["set"] == "static":
            assert float(row["k_FL_N_m"]) == pytest.approx(static_k, rel=1e-12)
        # expected values over 30 roads: the interval of the mean holds the mean, one ride's is wider
        lo, hi = float(row["a_w_mean_lo"]), float(row["a_w_mean_hi"])
        assert int(row["realisations"]) == 30 and lo < float(row["a_w_mean_m_s2"]) < hi
        assert float(row["a_w_one_ride_lo"]) < lo and hi < float(row["a_w_one_ride_hi"])
        # the PSD's a_w (the model's frequency response on the road spectrum) agrees with the mean of 30 rides
        assert float(row["a_w_psd_m_s2"]) == pytest.approx(float(row["a_w_mean_m_s2"]), rel=0.05)


def test_demo_fmus_are_valid_and_listed(demo):
    from fmpy.validation import validate_fmu
    code, out = demo
    fmus = sorted((out / "fmu").rglob("*.fmu"))
    # per tire: the recommended extended FMU, a point-contact one of the same k, c, and the one-corner fit's
    # (not recommended): the joint diagnosis builds no partner duplicates
    assert len(fmus) == 24
    assert sorted(p.relative_to(out / "fmu").parent.as_posix() for p in fmus) == \
        ["."] * 8 + ["not_recommended/waveform"] * 8 + ["point_contact"] * 8
    summary = json.loads((out / "summary.json").read_text())
    listed = [f["file"] for r in summary["recordings"]
              for f in r["diagnosis_fmus"] + [g for t in r["tires"].values() for g in t["fmus"]]]
    assert sorted(listed) == sorted(p.relative_to(out).as_posix() for p in fmus)
    recommended = {f["file"] for r in summary["recordings"] for f in r["diagnosis_fmus"] if f["recommended"]}
    assert recommended == {p.relative_to(out).as_posix() for p in fmus if "not_recommended" not in p.parts}
    for path in fmus:
        assert validate_fmu(str(path)) == [], path.name
        assert "binaries/win64/" in "".join(__import__("zipfile").ZipFile(path).namelist()), path.name


def test_demo_recommends_one_joint_k_c_per_tire_within_the_truth(demo):
    """One joint diagnosis per recording; its k, c per tire judged against the test day's truth files."""
    from identification.recording.examples import truth_path
    code, out = demo
    summary = json.loads((out / "summary.json").read_text())
    html = (out / "report.html").read_text()
    table = html[html.index('<section id="recommended">'):html.index('<section id="diagnoses">')]
    for r in summary["recordings"]:
        name = os.path.basename(r["source"]).removeprefix("testday_").removesuffix(".csv")
        truth = json.loads(truth_path(name).read_text())
        d = r["diagnosis"]
        assert r["diagnosis_errors"] == []
        assert "enveloping" in d["effects"] and {"axle_coupling", "roll_coupling"} <= set(d["effects"])
        # the extended FMUs under the body give what the fitting model gave for the parameters reported
        assert d["agreement"] <= 1e-6, d["agreement"]
        for tire, t in r["tires"].items():
            assert t["errors"] == []
            rec = t["recommended"]
            assert rec["k"] == d["tires"][tire]["k"] and rec["source"] == "joint diagnosis"
            assert rec["k"] == pytest.approx(truth["tires"][tire]["k"], rel=0.03), (name, tire)
            assert rec["c"] == pytest.approx(truth["tires"][tire]["c"], rel=0.10), (name, tire)
            assert rec["k_ci"][0] < rec["k"] < rec["k_ci"][1]
            after, noise = d["tires"][tire]["nrmse_after"], d["tires"][tire]["noise_nrmse"]
            assert after < d["tires"][tire]["nrmse_before"] / 2
            # the report's verdict follows the numbers: at the noise floor only if within 1.5x the noise
            assert (d["tires"][tire]["unexplained"] is None) == (after <= 1.5 * noise) or \
                abs(after / noise - 1.5) < 0.01, (name, tire, after, noise)
            assert f"<b>{rec['k'] / 1e3:.2f}</b>" in table
        # the ride: the final set is the recommended one, rated at the seat beside the paper's and a static one
        ride = r["ride"]
        assert set(ride["sets"]) == {"paper", "final", "static"}
        assert ride["static"]["file"] == "testday_compression.csv" and "testday_compression.csv" in html
        assert ride["sets"]["final"]["k"] == {t: r["tires"][t]["recommended"]["k"] for t in r["tires"]}
        assert all(s["a_w"] > 0 and s["vdv"] > 0 for s in ride["sets"].values())
        # the page quotes the expected a_w with its interval, not one road's ride
        e = ride["sets"]["final"]["expected"]["a_w"]
        assert f'<td>{e["mean"]:.3f}</td><td>{e["mean_interval"][0]:.3f}–{e["mean_interval"][1]:.3f}</td>' in html
        # paired on the same roads, the paper's set against the final one: the ratio's interval is far narrower
        # than the two sets' own intervals, and it holds the ratio the model's frequency response gives on the
        # road PSD (to 1 %: a ratio of expected RMS values, not the expected ratio)
        paired = ride["sets"]["paper"]["expected"]["a_w_ratio_to_final"]
        lo, hi = paired["mean_interval"]
        psd = ride["sets"]["paper"]["expected"]["psd"]["a_w"] / ride["sets"]["final"]["expected"]["psd"]["a_w"]
        assert lo - 0.01 < psd < hi + 0.01, (lo, psd, hi)
        assert hi - lo < 0.5 * (e["mean_interval"][1] - e["mean_interval"][0]) / e["mean"]
        assert f'paper {100 * (paired["mean"] - 1):+.1f} %' in html
        # the compression test's static stiffness is below the dynamic one by the paper's 100-170 kN/m (section 4)
        static_k = ride["sets"]["static"]["k"]["FL"]
        assert 100e3 <= truth["tires"]["FL"]["k"] - static_k <= 170e3


def test_report_renders_in_headless_chromium(demo, tmp_path):
    code, out = demo
    browser = _chromium()
    shot = tmp_path / "shot.png"
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'profile'}", "--hide-scrollbars", "--window-size=1280,3000",
           f"--screenshot={shot}", (out / "report.html").resolve().as_uri()]
    subprocess.run(cmd, capture_output=True, timeout=180)
    assert shot.exists(), "chromium wrote no screenshot"
    pixels = _png(shot.read_bytes())[..., :3]
    ink = (pixels.min(axis=2) < 0.9).mean()          # share of pixels that are not (near) white
    colours = len(np.unique((pixels[::4, ::4] * 255).astype(np.uint8).reshape(-1, 3), axis=0))
    assert ink > 0.03 and colours > 100, (ink, colours)


def test_every_link_of_the_demo_report_resolves(demo):
    code, out = demo
    html = (out / "report.html").read_text()
    ids = set(re.findall(r'id="([^"]+)"', html))
    links = re.findall(r'href="([^"]+)"', html)
    assert len(links) > 30
    for link in links:
        if link.startswith("#"):
            assert link[1:] in ids, link
        else:
            assert not link.startswith(("http:", "https:", "/")), link
            assert (out / link).is_file(), link


@pytest.mark.parametrize("width", [1400, 800])
def test_report_fits_the_window_in_headless_chromium(demo, tmp_path, width):
    """No horizontal overflow: the page's scrollWidth (read by a script added to a copy) within the viewport."""
    code, out = demo
    browser = _chromium()
    probe = out / f".probe{width}.html"
    probe.write_text((out / "report.html").read_text().replace(
        "</body>", "<script>document.title='W'+document.documentElement.scrollWidth;</script></body>"))
    try:
        dom = subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                              "--disable-background-networking", "--disable-component-update", "--disable-sync",
                              f"--user-data-dir={tmp_path / 'profile'}", "--hide-scrollbars",
                              f"--window-size={width},1000", "--dump-dom", probe.resolve().as_uri()],
                             capture_output=True, text=True, timeout=180).stdout
    finally:
        probe.unlink()
    found = re.search(r"<title>W(\d+)</title>", dom)
    assert found, dom[:300]
    assert int(found.group(1)) <= width, (width, found.group(1))


def test_report_with_a_broken_recording(cli, tmp_path):
    data = tmp_path / "day"
    data.mkdir()
    for name, effects in (("good_a", ()), ("good_b", ("enveloping",))):
        write_run(run_rig(effects, {"sensor.channels": "FL"}, seed=4), data / name)
    lines = (data / "good_a.csv").read_text().splitlines()
    lines[700] = lines[700].split(",")[0] + ",abc"          # one unreadable cell
    (data / "broken.csv").write_text("\n".join(lines) + "\n")
    (data / "broken.json").write_text((data / "good_a.json").read_text())
    out = tmp_path / "new" / "deeper" / "out"            # missing parents are created
    res = cli("report", data, "-o", out, "--workers", "2")
    assert res.code == 2
    assert "broken.csv" in res.err and "not a number" in res.err
    assert res.out.splitlines()[-1] == f"open the report in a web browser: {(out / 'report.html').resolve().as_uri()}"
    summary = json.loads((out / "summary.json").read_text())
    by_name = {os.path.basename(r["source"]): r for r in summary["recordings"]}
    assert by_name["broken.csv"]["ok"] is False and "abc" in by_name["broken.csv"]["error"]
    for good in ("good_a.csv", "good_b.csv"):
        assert by_name[good]["ok"] is True
        assert by_name[good]["diagnosis"] is not None
        assert by_name[good]["tires"]["FL"]["recommended"]["source"] == "joint diagnosis"
    assert by_name["good_b.csv"]["diagnosis"]["effects"] == ["enveloping"]
    html = (out / "report.html").read_text()
    assert "broken.csv" in html and "failed" in html


def test_report_needs_recordings(cli, tmp_path):
    res = cli("report", tmp_path, "-o", tmp_path / "out")
    assert res.code == 2 and "no recording" in res.err
    # a pipe named as a recording is refused as what it is (it was "no such file")
    os.mkfifo(tmp_path / "pipe.csv")
    res = cli("report", tmp_path / "pipe.csv", "-o", tmp_path / "out")
    assert res.code == 2 and res.err == f"cleatfmu: error: {tmp_path / 'pipe.csv'}: is not a regular file (a pipe, " \
                                        "a device or a socket)\n", res.err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("case", ["unreadable", "through a file", "interrupted"])
def test_a_failed_run_into_new_folders_leaves_none_behind(cli, tmp_path, monkeypatch, case):
    """report: nothing readable; demo: a path through a file, or interrupted once its folders exist (in the
    new set beside the output folder).  One line on stderr, exit 2 (130 interrupted), and no folder left
    behind."""
    import identification.report.batch as batch

    (tmp_path / "bad.csv").write_text("x,FL\n0,1\n")
    (tmp_path / "file").write_text("")
    made = []

    def interrupt(job):
        made.extend(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_dir())
        raise KeyboardInterrupt
    monkeypatch.setattr(batch, "_job", interrupt)
    if case == "unreadable":
        res = cli("report", tmp_path / "bad.csv", "-o", tmp_path / "a" / "b" / "c")
        assert res.code == 2 and res.err == f"cleatfmu: error: {tmp_path / 'bad.csv'}: sidecar bad.json not " \
                                           "found (a recording is NAME.csv + NAME.json)\n", res.err
    elif case == "through a file":
        res = cli("demo", "--out", tmp_path / "file" / "b" / "c")
        assert res.code == 2 and res.err == f"cleatfmu: error: {tmp_path / 'file'}: is not a directory\n", res.err
    else:
        res = cli("demo", "--out", tmp_path / "a" / "b" / "c", "--workers", "1")
        assert res.code == 130 and res.err == "cleatfmu: interrupted\n", res.err
        new = f"a/b/c.cleatfmu-new-{os.getpid()}"          # the new set, written beside the folder
        assert {f"{new}/fmu", f"{new}/params", f"{new}/.figures-staging"} <= {str(p) for p in made}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "file"]


def test_the_progress_bar_shows_from_the_first_second(tmp_path, monkeypatch):
    """On a terminal the bar is drawn at once and its elapsed time moves before the first result arrives."""
    import time
    import identification.report.batch as batch

    class Terminal(io.StringIO):
        def __init__(self):
            super().__init__()
            self.times = []

        def isatty(self):
            return True

        def write(self, text):
            self.times.append(time.monotonic())
            return super().write(text)

    def slow_job(job):                                           # the diagnosis, first, takes 1.8 s
        if job[0] == "recording":
            time.sleep(1.8)
            return batch.DiagnosisReport(recording=job[2])
        return batch.TireReport(recording=job[2], tire=job[3])

    write_run(run_rig((), {"sensor.channels": "FL", "sensor.rate_hz": 500.0}, seed=1), tmp_path / "one")
    monkeypatch.setattr(batch, "_job", slow_job)
    terminal = Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    t0 = time.monotonic()
    batch.run_batch([tmp_path / "one.csv"], tmp_path / "out", workers=1)
    draws = [t - t0 for t in terminal.times]
    assert draws and draws[0] < 1.0, draws                       # drawn within the first second
    assert sum(1 for t in draws if 1.0 < t < 1.8) >= 1, draws    # redrawn while the first job still runs
    assert "0/2" in terminal.getvalue() and "2/2" in terminal.getvalue()


def test_the_summary_shows_what_conditioning_and_diagnosis_warned_of():
    """A recording whose diagnosis warned (a sign settled by the joint fit, an engine line removed): each
    warning is on its summary row, escaped; a recording without warnings shows none."""
    from identification.report.batch import BatchResult, DiagnosisReport, RecordingReport
    from identification.report.html import _summary

    warned = ["steady vibration at 45.00 Hz and 2 of its orders on every channel (engine) removed",
              "the signs of FL/FR tested in the joint fit: FL reads upside down (sign corrected) <by BIC>"]
    recs = [RecordingReport(source=f"/d/{name}.csv", stem=name, ok=True, speed_kmh=7.0, sample_rate_hz=1000.0,
                            diagnosis=DiagnosisReport(recording=name, diagnosis={
                                "effects": [], "tires": {"FL": {"unexplained": None}}, "warnings": w}))
            for name, w in (("a", warned), ("b", []))]
    html = _summary(BatchResult(recordings=recs, out_dir="/d", seconds=1.0, timings={}))
    rows = html.split("<tr>")[2:]
    assert all(f"warning: {w.replace('<', '&lt;').replace('>', '&gt;')}" in rows[0] for w in warned)
    assert "warning" not in rows[1]



def test_report_rides_without_a_static_set_unless_given_a_compression_test(cli, tmp_path):
    """No compression test, no static row (the page says how to add one); a file that is not a compression
    test is refused in one line naming it, before anything is written."""
    import shutil

    from identification.recording.examples import example_path
    day = tmp_path / "day"
    day.mkdir()
    for suffix in (".csv", ".json"):
        shutil.copy(example_path("7kmh").with_suffix(suffix), day)
    bad = tmp_path / "press.csv"
    bad.write_text("deformation_mm,force_kN\n1,2\n")
    res = cli("report", day, "-o", tmp_path / "refused", "--static", bad)
    assert res.code == 2 and res.err.startswith(f"cleatfmu: error: {bad}: ") and res.err.count("\n") == 1, res.err
    assert not (tmp_path / "refused").exists()
    out = tmp_path / "out"
    res = cli("report", day, "-o", out, "--workers", "2")
    assert res.code == 0, res.err
    ride = json.loads((out / "summary.json").read_text())["recordings"][0]["ride"]
    assert set(ride["sets"]) == {"paper", "final"} and "static" not in ride
    assert "No static set: no compression test was given" in (out / "report.html").read_text()
