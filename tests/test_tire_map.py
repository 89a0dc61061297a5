"""The tire map: k and c over speed from a batch of rig runs, its FMU, and the ride at the map's speed.

The truth is the rig's: the runs at 4, 7, 10 and 14 km/h are driven with tire k and c set to a known linear
law in speed (:data:`K0`, :data:`C0`, :data:`K_SLOPE`, :data:`C_SLOPE`).  The map is fitted on the report's
recommended values (the whole-tractor diagnosis's k, c with their 95 % intervals).  The fit itself is checked
against numpy's weighted polyfit and its defining properties.
"""

from __future__ import annotations

import json
import os
import math

import numpy as np
import pytest

from identification.cli import main
from identification.errors import InputError
from identification.identify.tire_map import Z95, check_map, fit_curve, fit_map, map_values

TIRES = ("FL", "FR", "RL", "RR")
SPEEDS_KMH = (4.0, 7.0, 10.0, 14.0)
#: The rig's tire law: k = K0 (1 + K_SLOPE (v - 7 km/h)), c = C0 (1 + C_SLOPE (v - 7 km/h)).
K0 = {"FL": 550e3, "FR": 520e3, "RL": 420e3, "RR": 450e3}
C0 = {"FL": 4200.0, "FR": 4300.0, "RL": 2400.0, "RR": 2500.0}
K_SLOPE, C_SLOPE = -0.01, -0.03
PRESSURE_KPA = 160.0


def truth(tire: str, speed_kmh: float) -> tuple[float, float]:
    return K0[tire] * (1 + K_SLOPE * (speed_kmh - 7.0)), C0[tire] * (1 + C_SLOPE * (speed_kmh - 7.0))


# ----------------------------------------------------------------------------- the fit


def test_weighted_fit_is_numpys_weighted_polyfit_when_the_intervals_explain_the_runs():
    v = np.array([1.0, 1.5, 2.0, 3.0, 3.5, 4.0])
    sigma = np.array([50.0, 80.0, 60.0, 120.0, 90.0, 70.0])
    y = 5e5 - 2e4 * v + sigma * np.array([0.3, -0.5, 0.2, 0.4, -0.6, 0.1])
    fit = fit_curve(v, y, y - Z95 * sigma, y + Z95 * sigma)
    coef, cov = np.polyfit(v, y, 1, w=1 / sigma, cov="unscaled")
    assert fit.degree == 1 and fit.scatter == 0.0 and fit.dof == 4
    np.testing.assert_allclose(fit.coefficients, coef[::-1], rtol=1e-10)
    np.testing.assert_allclose(fit.covariance, cov[::-1, ::-1], rtol=1e-8)
    x = np.array([1.0, 2.5])
    assert fit.band(2.5) == pytest.approx(Z95 * math.sqrt(x @ cov[::-1, ::-1] @ x), rel=1e-8)
    assert fit.chi2 == pytest.approx(np.sum(((y - np.polyval(coef, v)) / sigma) ** 2), rel=1e-8)


def test_scatter_beyond_the_intervals_adds_a_between_run_variance_that_makes_chi2_its_dof():
    rng = np.random.default_rng(4)
    v = np.repeat([1.0, 2.0, 3.0, 4.0], 2)
    sigma = np.full(v.size, 40.0)
    y = 4e5 - 1e4 * v + 600.0 * rng.standard_normal(v.size)      # scatter 15 x the intervals
    fit = fit_curve(v, y, y - Z95 * sigma, y + Z95 * sigma)
    assert fit.degree == 1 and fit.scatter > 200.0
    # the defining property, recomputed here: weighted residual sum with sigma^2 + tau^2 equals the dof
    w = 1 / (sigma ** 2 + fit.scatter ** 2)
    coef = np.polyfit(v, y, 1, w=np.sqrt(w))
    assert np.sum(w * (y - np.polyval(coef, v)) ** 2) == pytest.approx(fit.dof, rel=1e-6)
    np.testing.assert_allclose(fit.coefficients, coef[::-1], rtol=1e-9)
    # the band holds the scatter: wider than the fit's covariance alone
    x = np.array([1.0, 2.5])
    assert fit.band(2.5) == pytest.approx(Z95 * math.sqrt(x @ fit.covariance @ x + fit.scatter ** 2), rel=1e-12)


def test_degree_linear_by_default_quadratic_only_where_the_runs_demand_it_never_beyond_the_speeds():
    v = np.array([1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0])
    sigma = np.full(v.size, 30.0)
    wiggle = sigma * np.array([0.4, -0.3, 0.5, -0.6, 0.2, 0.3, -0.4])
    linear = 5e5 - 2e4 * v + wiggle
    curved = 5e5 - 2e4 * v + 3e3 * (v - 2.5) ** 2 + wiggle
    assert fit_curve(v, linear, linear - Z95 * sigma, linear + Z95 * sigma).degree == 1
    fit = fit_curve(v, curved, curved - Z95 * sigma, curved + Z95 * sigma)
    assert fit.degree == 2 and fit.coefficients[2] == pytest.approx(3e3, rel=0.05)
    # three distinct speeds allow two terms; two allow one (a constant, the weighted mean)
    three = np.array([1.0, 2.0, 4.0])
    bent = 5e5 + 3e4 * (three - 2) ** 2                            # curved far beyond its intervals
    fit = fit_curve(three, bent, bent - 10.0, bent + 10.0)
    assert fit.degree == 1 and fit.scatter > 1e3
    two = fit_curve([1.0, 1.0, 3.0], [10.0, 12.0, 20.0], [9.0, 11.0, 19.0], [11.0, 13.0, 21.0])
    assert two.degree == 0
    with pytest.raises(ValueError, match="two distinct speeds"):
        fit_curve([2.0, 2.0], [1.0, 1.0], [0.5, 0.5], [1.5, 1.5])


def _run(tire, speed, k, c, pressure=None):
    return {"recording": f"r{speed}", "tire": tire, "speed_m_s": speed, "k": k, "k_ci": [k - 100, k + 100],
            "c": c, "c_ci": [c - 10, c + 10], "wheel_load_N": 12e3, "inflation_pressure_Pa": pressure}


def test_map_states_its_tested_range_holds_outside_and_refuses_mixed_pressures():
    runs = [_run("FL", v, 5e5 - 1e4 * v, 4e3 - 300 * v, 160e3) for v in (1.0, 2.0, 3.0)]
    doc = check_map(fit_map(runs, source="test"), "test")
    m = doc["tires"]["FL"]
    assert m["tested_speed_m_s"] == [1.0, 3.0] and m["inflation_pressure_Pa"] == [160e3, 160e3]
    inside, above = map_values(m, 2.5), map_values(m, 5.0)
    assert inside["k"] == pytest.approx(5e5 - 2.5e4, rel=1e-9) and not inside["extrapolation"]
    assert above["k"] == pytest.approx(5e5 - 3e4, rel=1e-9) and above["extrapolation"]   # held at the last node
    assert map_values(m, 0.5)["extrapolation"]
    mixed = runs + [_run("FL", 4.0, 4.6e5, 2.8e3, 200e3)]
    with pytest.raises(InputError, match="different inflation pressures"):
        fit_map(mixed, source="test")
    with pytest.raises(InputError, match="two distinct speeds"):
        fit_map([_run("RR", 2.0, 4e5, 3e3)], source="test")


# ----------------------------------------------------------------------------- the sidecar's pressure


@pytest.mark.parametrize("value, problem", [
    (1.6, "outside the plausible range 20-1000 kPa"), ("high", "must be a number (kPa)"),
    ({"FL": 150}, "has no entry for channel FR"), ({"XL": 150}, "unknown tire 'XL'"),
    ({"FL": -1, "FR": 1, "RL": 1, "RR": 1}, "inflation_pressure_kPa.FL must be a finite number > 0")])
def test_inflation_pressure_in_the_sidecar_is_checked_in_one_line(good_recording, cli, value, problem):
    from conftest import rewrite_sidecar

    rewrite_sidecar(good_recording, inflation_pressure_kPa=value)
    res = cli("identify", good_recording)
    assert res.code == 2 and problem in res.err and str(good_recording.with_suffix(".json")) in res.err
    assert len(res.err.strip().splitlines()) == 1


def test_inflation_pressure_one_number_or_per_tire_is_read_in_pa_and_written_back(good_recording):
    from conftest import rewrite_sidecar
    from identification.recording import read_recording

    rewrite_sidecar(good_recording, inflation_pressure_kPa=160)
    assert read_recording(good_recording).inflation_pressure_Pa == {t: 160e3 for t in TIRES}
    per_tire = {"FL": 150, "FR": 150, "RL": 120.5, "RR": 120.5}
    rewrite_sidecar(good_recording, inflation_pressure_kPa=per_tire)
    rec = read_recording(good_recording)
    assert rec.inflation_pressure_Pa == {t: 1e3 * p for t, p in per_tire.items()}
    assert rec.sidecar()["inflation_pressure_kPa"] == per_tire and "inflation_pressure_kPa" not in rec.extra


# ----------------------------------------------------------------------------- rig batch -> map -> FMU, ride


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    """Rig runs at 4, 7, 10 and 14 km/h (all four tires on the linear law in speed, 160 kPa declared), their
    report and the map of it: (report folder, map folder, runs folder)."""
    from identification.rig import run_rig, write_run

    root = tmp_path_factory.mktemp("tiremap")
    runs = root / "runs"
    runs.mkdir()
    for v in SPEEDS_KMH:
        params = {"speed_kmh": v, "sensor.rate_hz": 500.0, "duration_s": 0.5 + 2.77 / (v / 3.6) + 1.2}
        for t in TIRES:
            params[f"tire.{t}.k_N_m"], params[f"tire.{t}.c_Ns_m"] = truth(t, v)
        csv, _ = write_run(run_rig((), params, seed=int(v)), runs / f"rig_{int(v):02d}kmh")
        sidecar = csv.with_suffix(".json")
        sidecar.write_text(json.dumps(dict(json.loads(sidecar.read_text()), inflation_pressure_kPa=PRESSURE_KPA)))
    report = root / "report"
    main(["report", str(runs), "-o", str(report), "--workers", "2"])
    assert (report / "summary.json").is_file()
    out = root / "map"
    assert main(["map", str(report), "-o", str(out), "--platforms", "linux64"]) == 0
    return report, out, runs


def _recommended(report) -> dict:
    """{(tire, speed km/h): recommended entry} from the report's summary.json."""
    doc = json.loads((report / "summary.json").read_text())
    return {(t, round(r["conditions"]["speed_m_s"] * 3.6, 6)): e["recommended"]
            for r in doc["recordings"] for t, e in r["tires"].items()}


def test_map_of_the_batch_covers_the_tested_speeds_and_holds_the_rig_truth(batch):
    report, out, _ = batch
    doc = json.loads((out / "tire_map.json").read_text())
    assert sorted(doc["tires"]) == list(TIRES) and doc["skipped"] == {}
    recommended = _recommended(report)
    for t, m in doc["tires"].items():
        assert m["tested_speed_m_s"] == pytest.approx([4 / 3.6, 14 / 3.6], rel=1e-12)
        assert m["inflation_pressure_Pa"] == [PRESSURE_KPA * 1e3] * 2 and len(m["runs"]) == 4
        assert all(recommended[(t, v)] is not None for v in SPEEDS_KMH)
        for v in (5.5, 8.5, 12.0):        # between the runs: the law the rig was driven with, within the band
            at = map_values(m, v / 3.6)
            k, c = truth(t, v)
            assert abs(at["k"] - k) <= at["k_band"] and abs(at["c"] - c) <= at["c_band"], (t, v, at, k, c)


def _fmu_k_c(fmu, speeds_kmh, messages):
    """k, c read from the FMU's force at a known deflection (rate 0) and a known rate (deflection 0) per speed,
    with its ``extrapolating`` flag (fmpy, logging on)."""
    from build_scripts.runners import open_fmpy_slave, variable_refs

    refs = {n: r for n, (r, _) in variable_refs(fmu).items()}
    slave = open_fmpy_slave(fmu, logger=lambda status, category, message: messages.append((status, category,
                                                                                         message)))
    out = []
    try:
        r0 = slave.getReal([refs["unloaded_radius"]])[0]
        names = [refs[n] for n in ("speed", "hub_z", "hub_vz", "road_z", "road_vz")]
        for i, v in enumerate(speeds_kmh):
            slave.setReal(names, [v / 3.6, r0 - 0.02, 0.0, 0.0, 0.0])
            k = slave.getReal([refs["force_z"]])[0] / 0.02
            slave.setReal(names, [v / 3.6, r0, -0.3, 0.0, 0.0])
            c = slave.getReal([refs["force_z"]])[0] / 0.3
            out.append((k, c, bool(slave.getBoolean([refs["extrapolating"]])[0])))
            slave.doStep(1e-3 * i, 1e-3)
        slave.terminate()
    finally:
        slave.freeInstance()
    return out


def test_map_fmus_reproduce_each_speeds_recommended_k_c_and_flag_20_kmh(batch):
    report, out, _ = batch
    from fmpy.validation import validate_fmu

    recommended = _recommended(report)
    doc = json.loads((out / "tire_map.json").read_text())
    for t in TIRES:
        fmu = out / f"tire_map_{t}.fmu"
        assert validate_fmu(str(fmu)) == []
        messages = []
        got = _fmu_k_c(fmu, [*SPEEDS_KMH, 20.0, 22.0, 8.5, 20.0], messages)
        for (k, c, outside), v in zip(got, SPEEDS_KMH):
            best = recommended[(t, v)]
            assert best["k_ci"][0] <= k <= best["k_ci"][1] and best["c_ci"][0] <= c <= best["c_ci"][1], (t, v)
            assert not outside
        # 20 km/h: flagged, logged once per excursion (not again at 22 km/h; again after 8.5 km/h), k, c held
        assert [g[2] for g in got[4:]] == [True, True, False, True]
        warnings = [m for m in messages if m[1] == "logStatusWarning"]
        assert len(warnings) == 2 and all(m[0] == 1 and "20 km/h" in m[2] and "extrapolation" in m[2]
                                          for m in warnings), messages
        nodes = doc["tires"][t]["nodes"]
        assert got[4][:2] == pytest.approx((nodes["k"][-1], nodes["c"][-1]), rel=1e-12)
        assert got[6][:2] == pytest.approx((np.interp(8.5 / 3.6, nodes["speed_m_s"], nodes["k"]),
                                            np.interp(8.5 / 3.6, nodes["speed_m_s"], nodes["c"])), rel=1e-12)


def test_ride_uses_the_maps_values_at_its_speed(batch, cli):
    report, out, runs = batch
    path = out / "tire_map.json"
    doc = json.loads(path.read_text())
    common = ("ride", runs / "rig_07kmh.csv", "--body", report / "summary.json", "--realisations", "1",
              "--duration-s", "10", "--json")
    res = cli(*common, "--speed-kmh", "8.5", "--compare", f"final,map={path}")
    assert res.code == 0, res.err
    entry = json.loads(res.out)["sets"][f"map={path}"]
    for t in TIRES:
        nodes = doc["tires"][t]["nodes"]
        assert entry["k"][t] == pytest.approx(np.interp(8.5 / 3.6, nodes["speed_m_s"], nodes["k"]), rel=1e-12)
        assert entry["c"][t] == pytest.approx(np.interp(8.5 / 3.6, nodes["speed_m_s"], nodes["c"]), rel=1e-12)
        assert entry["map"][t]["extrapolation"] is False
    res = cli(*common, "--speed-kmh", "20", "--compare", f"map={path}")
    assert res.code == 0 and "outside the map's tested speeds of FL, FR, RL, RR" in res.err


def test_map_command_refuses_bad_input_in_one_line(batch, cli, tmp_path):
    report, out, _ = batch
    cases = [(("map", tmp_path / "none", "-o", tmp_path / "o"), "no report here"),
             (("map", report, "-o", tmp_path / "o", "--tire", "XX"), "XX"),
             (("map", report, "-o", tmp_path / "o", "--pressure-kpa", "200"), "no run with recommended k and c at 200"),
             (("map", out / "tire_map.json", "-o", tmp_path / "o"), "not a cleatfmu report summary"),
             (("ride", "--example", "7kmh", "--compare", f"map={report / 'summary.json'}"), "not a cleatfmu tire map")]
    for args, problem in cases:
        res = cli(*args)
        assert res.code == 2 and problem in res.err and len(res.err.strip().splitlines()) == 1, (args, res.err)
    assert not (tmp_path / "o").exists()
    old = json.loads((report / "summary.json").read_text())
    for r in old["recordings"]:
        r.pop("conditions")
    (tmp_path / "summary.json").write_text(json.dumps(old))
    res = cli("map", tmp_path / "summary.json", "-o", tmp_path / "o")
    assert res.code == 2 and "older cleatfmu" in res.err


def test_map_writes_its_folder_as_one_set_one_run_at_a_time(batch, cli, tmp_path):
    """A second map into a folder another run is writing is refused naming that run; a map written over an
    earlier one replaces its files and keeps the folder's other files.  Before: two maps at once both ended 0,
    one of 12 with the JSON of one run beside the FMUs of the other."""
    from identification._folders import FolderSet

    report, _, _ = batch
    out = tmp_path / "map"
    with FolderSet(out):                       # another run holds the folder
        res = cli("map", report, "-o", out, "--no-fmu")
        assert res.code == 2 and f"another cleatfmu run (pid {os.getpid()})" in res.err, res.err
        assert len(res.err.strip().splitlines()) == 1
    assert list(out.iterdir()) == []           # the holder's (empty) set: the refused run wrote nothing
    (out / "notes.txt").write_text("mine")
    res = cli("map", report, "-o", out, "--no-fmu")
    assert res.code == 0, res.err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "tire_map.json"]
    assert f"wrote {out / 'tire_map.json'}" in res.out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map"]       # nothing beside it
