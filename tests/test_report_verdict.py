"""The report's verdict and files on made-up batches: what the flags say, which FMU a folder gives, which
diagnosis a summary gives (no demo run: ``tests/test_report.py`` checks the same on the demo's report)."""

import json
import re

import pytest

from identification.errors import InputError
from identification.report.batch import BatchResult, DiagnosisReport, RecordingReport, TireReport

TIRES = ("FL", "FR", "RL", "RR")


def _diagnosis(*, warnings=(), unexplained=None, sign_test=None):
    tire = {"k": 5.2e5, "c": 4.3e3, "k_ci": [5.19e5, 5.21e5], "c_ci": [4.29e3, 4.31e3], "nrmse_after": 0.012,
            "noise_nrmse": 0.005, "unexplained": unexplained}
    return {"effects": ["enveloping"], "tires": {t: dict(tire) for t in TIRES}, "warnings": list(warnings),
            **({"sign_test": sign_test} if sign_test else {})}


def _result(diagnosis, *, paper=True) -> BatchResult:
    p = {"T": 0.27, "zeta": 0.09, "delta": 0.55, "omega_n": 23.5, "k": 6.5e5, "c": 5.2e3, "r2": 1.0, "n_peaks": 5}
    rep = RecordingReport(source="/day/run.csv", stem="run", ok=True, speed_kmh=7.0, sample_rate_hz=1000.0,
                          tires=[TireReport(recording="run", tire=t, paper=p if paper else None) for t in TIRES],
                          diagnosis=DiagnosisReport(recording="run", diagnosis=diagnosis,
                                                    fmus=[{"file": f"fmu/run_{t}.fmu", "kind": "extended_tire",
                                                           "recommended": True, "role": "r"} for t in TIRES]))
    return BatchResult(recordings=[rep], out_dir="/out", seconds=1.0, timings={})


def _verdict(result) -> str:
    from identification.report.html import build_tables
    from identification.report.verdict import verdict_section
    return verdict_section(result, build_tables(result, {}))


def test_a_residual_above_the_noise_says_its_ratio_and_a_share_that_is_not_zero():
    """NRMSE 1.2 % against noise 0.5 %: the flag gives the ratio and the excess (1.2² − 0.5²)/100² = 0.012 %
    of the signal energy, not "0.0% of the signal" in red."""
    left = {"share": 0.012 ** 2 - 0.005 ** 2, "window": [0.5, 0.62], "residual_to_noise": 2.4}
    html = _verdict(_result(_diagnosis(unexplained=left)))
    row = html[html.index("<td"):]
    assert "0.0%" not in row and "0.012 %" in row and "2.4× the noise" in row and "NRMSE 1.2% against 0.5%" in row
    assert 'class="bad">unexplained' not in row


@pytest.mark.parametrize("warned", [[], ["steady vibration at 45.00 Hz (engine) removed",
                                         "the signs of FL/FR tested in the joint fit: FR reads upside down"]])
def test_the_verdict_is_green_only_without_warnings_and_shows_each_beside_it(warned):
    html = _verdict(_result(_diagnosis(warnings=warned)))
    intro = html[:html.index("</p>")]
    assert ('class="ok"' in intro) == (not warned)
    for w in warned:
        assert f"warning: {w}" in html
    if warned:
        assert 'class="warn"' in intro and f"warned of {len(warned)} thing(s)" in intro


def test_a_failed_stage_turns_the_verdict_from_green():
    result = _result(_diagnosis())
    result.recordings[0].tires[1].errors.append("export: cannot write")
    html = _verdict(result)
    assert 'class="ok"' not in html[:html.index("</p>")] and "warning: FR: export: cannot write" in html


def test_table4_marks_a_channel_the_joint_fit_found_upside_down():
    from identification.report.tables import table4_table
    table = table4_table(_result(_diagnosis(sign_test={"open": ["FR"], "chosen": "FR", "margin": 40.0})))
    marked = {row[2]: row[-1] for row in table.rows}
    assert marked["FR"].startswith("upside down") and marked["FL"] == "as recorded"
    html = {row[2]: h for row, h in zip(table.rows, table.html_rows)}
    assert "upside down" in html["FR"] and "upside down" not in html["FL"]


def test_the_verdict_links_name_their_recording_and_every_cell_its_column():
    from identification.report.html import build_tables
    table = build_tables(_result(_diagnosis()), {})["verdict"]
    for row, h in zip(table.rows, table.html_rows):
        assert f'>run_{row[2]}.fmu</a>' in h and row[14] == f"fmu/run_{row[2]}.fmu"
        assert h.count("<td") == h.count('data-label="') == 13 - 2     # no truth columns here


@pytest.mark.parametrize("value, lo, hi, text", [
    (0.7998614, 0.7996068, 0.8001162, "0.7999 (0.7996-0.8001)"), (0.468, 0.4677, 0.4683, "0.4680 (0.4677-0.4683)"),
    (0.468, 0.466, 0.470, "0.468 (0.466-0.470)"), (0.5, 0.5, 0.5, "0.500 (0.500-0.500)")])
def test_an_interval_is_printed_with_ends_that_differ(value, lo, hi, text):
    from identification.diagnose.joint_evidence import interval_text
    assert interval_text(value, lo, hi) == text


def test_a_limited_axis_is_not_labelled_like_a_saturated_sensor():
    import numpy as np
    from identification.report.plots import _limit_to, figure
    fig, ax = figure(1, 1)
    ax.set_ylabel("acceleration / (m/s²)")
    ax.plot([0, 1, 2], [0, 50.0, 0])                      # a model spike far beyond the measurement
    _limit_to(ax, np.array([1.0, -2.0, 1.5]))
    _limit_to(ax, np.array([1.0, -2.0, 1.5]))             # a second call adds no second note
    notes = [t.get_text() for t in ax.texts]
    assert notes == ["axis ±1.6× the measured peak; model peaks beyond it"] and ax.get_ylim() == (-3.2, 3.2)
    assert "clipped" not in ax.get_ylabel()


def test_a_limited_axis_of_a_four_channel_figure_keeps_its_label_within_its_panel():
    """The note once made each panel's y label longer than the panel (a 2.3 inch panel, a 3.5 inch label):
    the four labels ran over each other."""
    import numpy as np
    from identification.report.plots import figure, finish_channel_axis
    fig, axes = figure(4, 1, size=(10.0, 2.3 * 4 + 0.8), sharex=True, squeeze=False)
    for ax in axes[:, 0]:
        ax.plot([0, 1, 2], [0, 50.0, 0], label="model")
        finish_channel_axis(ax, np.array([1.0, -2.0, 1.5]))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    boxes = [ax.yaxis.label.get_window_extent(renderer) for ax in axes[:, 0]]
    for ax, box in zip(axes[:, 0], boxes):
        panel = ax.get_window_extent(renderer)
        assert panel.y0 <= box.y0 and box.y1 <= panel.y1
    assert all(a.y1 < b.y0 or b.y1 < a.y0 for i, a in enumerate(boxes) for b in boxes[i + 1:])


def _fmu_folder(tmp_path, stems):
    folder = tmp_path / "fmu"
    folder.mkdir()
    for stem in stems:
        for t in TIRES:
            (folder / f"{stem}_{t}.fmu").write_bytes(b"")
    return folder


def test_a_folder_of_several_recordings_gives_the_recordings_fmus_or_one_line(tmp_path):
    from identification.fmu.simulate_inputs import tractor_fmu_paths
    folder = _fmu_folder(tmp_path, ["day_7kmh", "day_10kmh"])
    assert tractor_fmu_paths(folder, recording="day_7kmh") == {t: folder / f"day_7kmh_{t}.fmu" for t in TIRES}
    for recording in (None, "other"):
        with pytest.raises(InputError) as exc:
            tractor_fmu_paths(folder, recording=recording)
        assert "\n" not in str(exc.value) and "2 recordings (day_10kmh, day_7kmh)" in exc.value.problem


def test_a_report_summary_gives_the_recordings_diagnosis_or_one_line():
    from identification.fmu.simulate_inputs import diagnosis_of
    summary = {"recordings": [{"source": f"/d/{name}.csv", "diagnosis": {"name": name}} for name in ("a", "b")]
               + [{"source": "/d/c.csv", "diagnosis": None}]}
    assert diagnosis_of(summary, "summary.json", "/elsewhere/b.csv") == {"name": "b"}
    assert diagnosis_of({"body": {}}, "d.json", "x.csv") == {"body": {}}           # a diagnose --json document
    assert diagnosis_of({"recordings": summary["recordings"][:1]}, "s", "z.csv") == {"name": "a"}
    with pytest.raises(InputError) as exc:
        diagnosis_of(summary, "summary.json", "z.csv")
    assert exc.value.problem == "a report summary of 2 diagnosed recordings (a, b), none of them 'z': give the " \
                                "recording of one of them (REC.csv or --example)"


def test_simulate_names_the_file_when_a_summary_does_not_hold_the_recording(cli, tmp_path):
    """Bad input: one line naming the summary, exit 2."""
    (tmp_path / "summary.json").write_text(json.dumps(
        {"recordings": [{"source": f"/d/{n}.csv", "diagnosis": {"body": {}}} for n in ("a", "b")]}))
    folder = _fmu_folder(tmp_path, ["testday_7kmh"])
    res = cli("simulate", folder, "--example", "7kmh", "--body", tmp_path / "summary.json")
    assert res.code == 2 and res.err.count("\n") == 1
    assert re.match(rf"cleatfmu: error: {re.escape(str(tmp_path / 'summary.json'))}: a report summary of 2 ", res.err)


def test_the_verdict_line_of_a_recording_says_what_its_diagnosis_left_unexplained():
    """A recording whose diagnosis named nothing while a channel stays far above the noise: its line in the
    verdict said "effects named: none"; it now carries the diagnosis' words (``summary``)."""
    from identification.diagnose.wording import effects_sentence

    left = {"share": 0.97, "window": [0.5, 1.2], "residual_to_noise": 30.0}
    doc = _diagnosis(unexplained=left)
    doc["effects"] = []
    doc["summary"] = effects_sentence(doc)
    html = _verdict(_result(doc))
    line = html[html.index("<li>run"):]
    line = line[:line.index("</li>")]
    assert "none named, yet the four-corner model leaves FL, FR, RL, RR above the noise floor" in line
    assert "up to 97 %" in line and "effects named: <b>none</b>" not in line
