"""One answer per tire and condition over repeated runs (:mod:`identification.report.campaign`): the pooled
estimator against a published example and hand computations, its coverage by simulation, the grouping rule,
the verdict's words, and a batch of repeated rig runs through ``cleatfmu report``."""

import csv
import json
import math

import numpy as np
import pytest

from identification.report.campaign import (ONE_RUN, campaign_conditions, group_runs, pool_runs, reml_tau2,
                                            rounded_interval, supported_step)
from identification.rig import run_rig, write_run

Z = 1.959963984540054          # the normal 97.5 % quantile
T2 = 4.302652729749464         # Student's t 97.5 % quantile, 2 degrees of freedom (tables: 4.303)


def test_reml_mean_and_fixed_effect_mean_match_normand_1999_table_ix():
    """Normand (1999, Stat. Med. 18:321-359), length of hospital stay, 9 studies: mean differences and
    variances of Table VIII, pooled in Table IX: fixed effect -3.49 (-5.03, -1.96); random effects with
    REML τ² 685.20, mean -15.12 (-32.67, 2.43) (a normal-quantile interval).  The variances are printed
    to two decimals, so the fixed-effect bounds agree to 0.015 only."""
    y = np.array([-20.0, -2, -55, -71, -4, 1, 11, -10, 7])
    v = np.array([40.59, 2.05, 15.28, 150.22, 20.19, 1.22, 95.38, 8.03, 20.69])
    p = pool_runs(y, np.sqrt(v))
    assert round(p["tau2"], 2) == 685.20
    assert round(p["value"], 2) == -15.12
    half = Z / math.sqrt(np.sum(1 / (v + p["tau2"])))
    assert (round(p["value"] - half, 2), round(p["value"] + half, 2)) == (-32.67, 2.43)
    assert round(p["within_only"]["value"], 2) == -3.49
    assert p["within_only"]["ci"] == pytest.approx([-5.03, -1.96], abs=0.015)
    # the HKSJ interval: t on 8 degrees of freedom (2.306) times sqrt(max(1, q) / Σw), q by hand
    w = 1 / (v + p["tau2"])
    q = max(1.0, float(np.sum(w * (y - p["value"]) ** 2)) / 8)
    assert p["ci"] == pytest.approx([p["value"] - 2.306004 * math.sqrt(q / w.sum()),
                                     p["value"] + 2.306004 * math.sqrt(q / w.sum())], rel=1e-6)


def test_three_runs_of_equal_precision_give_the_t_interval_of_their_mean():
    """k = 510, 530, 560 kN/m, each ±1 kN/m (SE): by hand, mean 533 333 N/m, sample variance
    (23 333² + 3 333² + 26 667²)/2 = 633.33e6 N²/m², REML τ² = 633.33e6 - 1e6 (equal variances), HKSJ
    q = 1, interval mean ± t(2) · sqrt(633.33e6/3) = ± 62 517 N/m; Cochran's Q = 1 266.67 on 2 degrees of
    freedom (p = exp(-Q/2)), I² = (Q - 2)/Q = 0.99842."""
    p = pool_runs([510e3, 530e3, 560e3], [1e3, 1e3, 1e3])
    assert p["value"] == pytest.approx(533_333.333, rel=1e-9)
    assert p["tau2"] == pytest.approx(1_900e6 / 3 - 1e6, rel=1e-8)
    assert p["between_run_sd"] == pytest.approx(math.sqrt(1_900e6 / 3 - 1e6), rel=1e-8)
    half = T2 * math.sqrt(1_900e6 / 9)
    assert half == pytest.approx(62_517, abs=1)
    assert p["ci"] == pytest.approx([533_333.333 - half, 533_333.333 + half], rel=1e-9)
    assert p["q"] == pytest.approx(3_800 / 3, rel=1e-9) and p["q_p"] == pytest.approx(math.exp(-1_900 / 3))
    assert p["i2"] == pytest.approx(0.99842, abs=1e-5)
    assert p["runs_disagree"] and p["source"] == "between-run scatter"
    assert p["within_only"]["ci"] == pytest.approx([533_333.333 - Z * 1e3 / math.sqrt(3),
                                                    533_333.333 + Z * 1e3 / math.sqrt(3)], rel=1e-9)
    for run in (510e3, 530e3, 560e3):                   # three runs: the interval always holds each of them
        assert p["ci"][0] < run < p["ci"][1]


def test_runs_that_agree_keep_an_interval_no_narrower_than_their_fits_allow():
    """100, 101, 99 with SE 2 each: sample variance 1 < 4, so τ² = 0; q = (0.5/4)/2 < 1 is raised to 1:
    100 ± t(2) · sqrt(4/3) = ± 4.968; Q = 0.5, p = exp(-0.25) = 0.7788, I² = 0: the runs agree."""
    p = pool_runs([100.0, 101.0, 99.0], [2.0, 2.0, 2.0])
    assert p["tau2"] == 0.0 and p["between_run_sd"] == 0.0
    assert p["ci"] == pytest.approx([100 - 4.968, 100 + 4.968], abs=1e-3)
    assert p["q_p"] == pytest.approx(0.7788, abs=1e-4) and p["i2"] == 0.0 and not p["runs_disagree"]


def test_reml_maximises_the_restricted_likelihood_with_unequal_variances():
    """Against a brute-force search of the restricted log-likelihood
    -½ Σ log(v+τ²) - ½ log Σ w - ½ Σ w (y - μ)², written out here."""
    y, v = np.array([0.0, 3.0, 10.0, 4.0]), np.array([1.0, 2.0, 4.0, 0.5])

    def restricted(t2):
        w = 1 / (v + t2)
        mu = np.sum(w * y) / np.sum(w)
        return -0.5 * (np.sum(np.log(v + t2)) + np.log(np.sum(w)) + np.sum(w * (y - mu) ** 2))
    grid = np.linspace(0, 100, 1_000_001)
    best = grid[np.argmax([restricted(t) for t in grid[::1000]]) * 1000]
    fine = np.linspace(max(0, best - 0.2), best + 0.2, 40_001)
    expected = fine[np.argmax([restricted(t) for t in fine])]
    assert reml_tau2(y, v) == pytest.approx(expected, abs=2e-5)


def test_one_run_keeps_its_own_interval_and_bad_input_is_refused():
    p = pool_runs([5.2e5], [1e3])
    assert p["n"] == 1 and p["between_run_sd"] is None and p["source"] == "within-run only"
    assert p["ci"] == pytest.approx([5.2e5 - Z * 1e3, 5.2e5 + Z * 1e3])
    for bad in (([], []), ([1.0, 2.0], [1.0]), ([1.0], [0.0]), ([np.nan], [1.0])):
        with pytest.raises(ValueError):
            pool_runs(*bad)


@pytest.mark.parametrize("n", [2, 3, 5])
def test_the_pooled_interval_covers_the_true_k_95_percent_of_the_time_and_the_fit_intervals_do_not(n):
    """2000 campaigns of n runs: true k 550 kN/m, between-run SD 4 % (the paper's ±8 % as two SDs), each
    run's fit SE drawn in 0.03-0.3 % (what a joint fit gives).  With coverage 95 % the count of 2000 is
    binomial, SD sqrt(0.95·0.05/2000) = 0.49 %: it must lie within ±3 SD, 93.5-96.5 %.  The fixed-effect
    interval of the fit intervals alone undercovers (below 20 %)."""
    rng = np.random.default_rng(100 + n)
    k, hit, hit_within = 550e3, 0, 0
    for _ in range(2000):
        s = k * rng.uniform(3e-4, 3e-3, n)
        y = k + rng.normal(0, 0.04 * k, n) + rng.normal(0, s)
        p = pool_runs(y, s)
        hit += p["ci"][0] <= k <= p["ci"][1]
        hit_within += p["within_only"]["ci"][0] <= k <= p["within_only"]["ci"][1]
    assert 0.935 <= hit / 2000 <= 0.965, hit / 2000
    assert hit_within / 2000 < 0.2, hit_within / 2000


def test_without_scatter_the_pooled_interval_is_conservative_not_narrow():
    """No between-run scatter, three runs of SE 1 %: the HKSJ interval (q raised to 1, t on 2 degrees of
    freedom) covers at least 95 % (binomial bound as above: ≥ 93.5 %)."""
    rng = np.random.default_rng(7)
    s = np.full(3, 0.01)
    cover = np.mean([(lambda p: p["ci"][0] <= 1 <= p["ci"][1])(pool_runs(1 + rng.normal(0, s), s))
                     for _ in range(2000)])
    assert cover >= 0.935, cover


def test_values_are_rounded_to_two_significant_digits_of_the_half_width():
    # half-width 48 kN/m: 1 kN/m steps, bounds outwards
    assert supported_step(48_024.6) == 1000.0 and supported_step(2.94) == 0.1 and supported_step(0.0123) == 0.001
    assert rounded_interval(551_819.78, 503_795.21, 599_844.34) == {"value": 552_000.0,
                                                                    "ci": [503_000.0, 600_000.0], "step": 1000.0}
    assert rounded_interval(4199.08, 4196.14, 4202.02) == {"value": 4199.1, "ci": [4196.1, 4202.1], "step": 0.1}


def _run(tire="FL", speed=7.0, load=11_460.0, names=None, k=5.5e5, rec="r"):
    return {"recording": rec, "tire": tire, "speed_kmh": speed, "wheel_load_N": load, "names": names or {},
            "k": k, "k_ci": [k - 500, k + 500], "c": 4.2e3, "c_ci": [4.19e3, 4.21e3]}


def test_runs_of_one_condition_share_position_speed_load_and_names():
    runs = [_run(speed=7.0, rec="a"), _run(speed=7.4, rec="b"), _run(speed=7.6, rec="c"),
            _run(speed=7.1, load=11_460.0 * 1.05, rec="d"), _run(speed=7.0, tire="FR", rec="e"),
            _run(speed=7.0, names={"vehicle": "tractor B"}, rec="f"), _run(speed=7.2, load=11_600.0, rec="g")]
    groups = {tuple(r["recording"] for r in g) for g in group_runs(runs)}
    # within 0.5 km/h of the slowest (a: 7.0) and within 2 % of its load: a, g, b; 7.6 km/h apart
    assert groups == {("a", "g", "b"), ("c",), ("d",), ("e",), ("f",)}
    rows = campaign_conditions(runs)
    assert sorted(row["runs"] for row in rows if row["tire"] == "FL" and not row["names"]) == [1, 1, 3]
    single = next(row for row in rows if row["recordings"] == ["c"])
    assert single["interval_source"] == "within-run only" and single["note"].startswith(ONE_RUN)
    assert single["k"]["ci"] == [5.5e5 - 500, 5.5e5 + 500]      # its own interval, as the fit gave it


def test_runs_at_another_inflation_pressure_are_another_condition():
    """The pressure changes a tire's k (Lines & Murphy): runs 5 % or more apart are not pooled, and a run
    whose sidecar gives no pressure is pooled only with runs without one."""
    runs = [dict(_run(rec=r), pressure_Pa=p) for r, p in
            (("a", 160e3), ("b", 164e3), ("c", 120e3), ("d", None), ("e", None), ("f", 170e3))]
    groups = {tuple(r["recording"] for r in g) for g in group_runs(runs)}
    assert groups == {("a", "b"), ("c",), ("d", "e"), ("f",)}
    rows = {tuple(row["recordings"]): row for row in campaign_conditions(runs)}
    assert rows[("a", "b")]["inflation_pressure_Pa"] == pytest.approx(162e3)
    assert rows[("d", "e")]["inflation_pressure_Pa"] is None


def test_a_tire_named_per_position_is_its_own_condition():
    from identification.report.campaign import condition_names
    assert condition_names({"tire": {"FL": "380/85 R 28", "RL": "460/85 R 38"}, "vehicle": "T1"}, "FL") == \
        {"vehicle": "T1", "tire": "380/85 R 28"}
    assert condition_names({"description": "run 3"}, "FL") == {}


def test_the_verdict_names_where_each_interval_comes_from():
    """A made-up batch: three runs at 7 km/h that scatter, one at 10 km/h."""
    from identification.report.batch import BatchResult, DiagnosisReport, RecordingReport, TireReport
    from identification.report.html import build_tables
    from identification.report.verdict import verdict_section

    recs = []
    for stem, speed, k in (("a", 7.0, 5.1e5), ("b", 7.0, 5.3e5), ("c", 7.0, 5.6e5), ("d", 10.0, 5.4e5)):
        tire = {"k": k, "c": 4.3e3, "k_ci": [k - 1e3, k + 1e3], "c_ci": [4.29e3, 4.31e3], "nrmse_after": 0.012,
                "noise_nrmse": 0.01, "unexplained": None}
        recs.append(RecordingReport(source=f"/d/{stem}.csv", stem=stem, ok=True, speed_kmh=speed,
                                    sample_rate_hz=1e3, wheel_load_N={"FL": 11_460.0},
                                    tires=[TireReport(recording=stem, tire="FL")],
                                    diagnosis=DiagnosisReport(recording=stem, diagnosis={
                                        "effects": [], "tires": {"FL": tire}, "warnings": []})))
    result = BatchResult(recordings=recs, out_dir="/out", seconds=1.0, timings={})
    tables = build_tables(result, {})
    html = verdict_section(result, tables)
    rows = [dict(zip(tables["campaign"].columns, r)) for r in tables["campaign"].rows]
    assert [(r["tire"], r["speed_km_h"], r["runs"]) for r in rows] == [("FL", 7.0, 3), ("FL", 10.0, 1)]
    assert rows[0]["interval_source"] == "between-run scatter" and rows[1]["interval_source"] == "within-run only"
    # 533 333 ± 62 517 N/m as in the hand computation above: shown to whole kN/m, the bounds outwards
    assert rows[0]["k_N_m"] == 533_000.0 and rows[0]["k_ci_low"] <= 510e3 and rows[0]["k_ci_high"] >= 560e3
    assert "<b>533</b>" in html and "between-run scatter of 3 runs" in html and ONE_RUN in html
    assert "disagree beyond their fit intervals" in html
    intro = html[:html.index("</p>")]
    assert 'class="ok"' not in intro and "1 condition(s) disagree" in intro


@pytest.fixture(scope="module")
def campaign_day(tmp_path_factory):
    """Three FL-only rig runs at 7 and at 10 km/h whose tire k differs by -3, 0 and +4 % (the scatter of
    repeated real runs), and one run at 5 km/h."""
    folder = tmp_path_factory.mktemp("campaign")
    for speed in (7.0, 10.0):
        for i, f in enumerate((0.97, 1.0, 1.04)):
            write_run(run_rig((), {"sensor.channels": "FL", "speed_kmh": speed, "tire.FL.k_N_m": 550e3 * f},
                              seed=20 + i), folder / f"run_{speed:g}kmh_{i}")
    write_run(run_rig((), {"sensor.channels": "FL", "speed_kmh": 5.0}, seed=30), folder / "run_5kmh_0")
    return folder


def test_a_batch_of_repeated_runs_gives_one_row_per_tire_and_speed(cli, campaign_day, tmp_path):
    out = tmp_path / "out"
    res = cli("report", campaign_day, "-o", out, "--workers", "2")
    assert res.code == 0, res.err
    runs = list(csv.DictReader((out / "tables" / "verdict.csv").open()))
    rows = list(csv.DictReader((out / "tables" / "campaign.csv").open()))
    assert len(runs) == 7 and [(r["tire"], float(r["speed_km_h"]), int(r["runs"])) for r in rows] == \
        [("FL", 5.0, 1), ("FL", 7.0, 3), ("FL", 10.0, 3)]
    summary = json.loads((out / "summary.json").read_text())
    assert [(c["tire"], round(c["speed_m_s"] * 3.6, 6), c["runs"]) for c in summary["campaign"]] == \
        [("FL", 5.0, 1), ("FL", 7.0, 3), ("FL", 10.0, 3)]
    html = (out / "report.html").read_text()
    verdict = html[html.index('<section id="recommended">'):html.index("</section>")]
    for row, doc in zip(rows, summary["campaign"]):
        members = [r for r in runs if r["recording"] in row["recordings"].split()]
        assert len(members) == int(row["runs"])
        if doc["runs"] == 3:
            assert row["interval_source"] == doc["interval_source"] == "between-run scatter"
            # the interval holds every run's k (as table and as JSON) and the runs' true mean
            for r in members:
                assert float(row["k_ci_low"]) < float(r["k_N_m"]) < float(row["k_ci_high"])
                assert doc["k"]["ci"][0] < float(r["k_N_m"]) < doc["k"]["ci"][1]
            assert doc["k"]["ci"][0] < 550e3 * (0.97 + 1 + 1.04) / 3 < doc["k"]["ci"][1]
            assert doc["k"]["runs_disagree"] and row["runs_disagree"] == "True"
            assert 0.02 < doc["k"]["between_run_sd"] / doc["k"]["value"] < 0.05
            # rounded to 2 significant digits of the half-width (about 48 kN/m: whole kN/m)
            assert doc["k"]["rounded"]["step"] == 1000.0 and float(row["k_N_m"]) % 1000 == 0
        else:
            assert row["interval_source"] == "within-run only" and row["note"].startswith(ONE_RUN)
            assert [float(row["k_ci_low"]), float(row["k_ci_high"])] == pytest.approx(
                [float(members[0]["k_ci_low"]), float(members[0]["k_ci_high"])], abs=1.0)
    assert "between-run scatter" in verdict and ONE_RUN in verdict and "within-run only" in verdict
    assert 'href="tables/campaign.csv"' in html


def test_the_pooled_answer_is_written_as_a_tire_fmu_that_carries_it(cli, campaign_day, tmp_path):
    """Each condition of repeated runs gets params/campaign/<name>.json and fmu/campaign/<name>.fmu with the
    pooled (unrounded) k and c; the FMU validates and simulates the static wheel load in fmpy."""
    from fmpy import read_model_description, simulate_fmu
    from fmpy.validation import validate_fmu
    out = tmp_path / "out"
    res = cli("report", campaign_day, "-o", out, "--workers", "2")
    assert res.code == 0, res.err
    summary = json.loads((out / "summary.json").read_text())
    rows = {(c["tire"], round(c["speed_m_s"] * 3.6, 6)): c for c in summary["campaign"]}
    assert rows[("FL", 5.0)]["files"] is None              # one run: its own files are the answer
    assert sorted(p.name for p in (out / "fmu" / "campaign").iterdir()) == ["FL_10kmh.fmu", "FL_7kmh.fmu"]
    for speed in (7.0, 10.0):
        row = rows[("FL", speed)]
        params = json.loads((out / row["files"]["params"]).read_text())["tires"]["FL"]
        assert params["k"] == row["k"]["value"] and params["k_ci"] == row["k"]["ci"] and params["runs"] == 3
        fmu = out / row["files"]["fmu"]
        assert validate_fmu(str(fmu)) == []
        starts = {v.name: v.start for v in read_model_description(str(fmu)).modelVariables}
        assert float(starts["stiffness"]) == pytest.approx(row["k"]["value"], rel=1e-12)
        assert float(starts["damping"]) == pytest.approx(row["c"]["value"], rel=1e-12)
        result = simulate_fmu(str(fmu), stop_time=0.5, output=["force_z"])
        assert result["force_z"][-1] == pytest.approx(row["wheel_load_N"], rel=1e-3)
        assert f'href="{row["files"]["fmu"]}"' in (out / "report.html").read_text()


def test_one_interval_reads_the_same_in_the_campaign_row_and_the_recordings_row():
    """Before: 549.67–550.28 in the campaign row, 549.67–550.27 in the per-recording row (nearest rounding);
    both now round to the digits the interval supports, the bounds outwards."""
    from identification.report.tables import _shown, _value_interval_cells

    value, ci = 550_000.0, (549_670.4, 550_275.3)
    r = rounded_interval(value, *ci)
    assert _value_interval_cells(value, ci, ".2f") == [
        f'<td><b>{_shown(r["value"], r["step"], 1e-3)}</b></td>',
        f'<td>{_shown(r["ci"][0], r["step"], 1e-3)}–{_shown(r["ci"][1], r["step"], 1e-3)}</td>']
    assert _value_interval_cells(value, ci, ".2f")[1] == "<td>549.67–550.28</td>"
    assert _value_interval_cells(4188.0, (4178.8, 4195.3), ".3f")[1] == "<td>4.1788–4.1953</td>"
    assert _value_interval_cells(4188.0, (0.0, math.inf), ".3f")[1] == "<td>0.000–inf</td>"    # unbounded
