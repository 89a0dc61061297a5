"""Cleat profiles: the sidecar's ``cleat_profile``, the rig's bevelled and polyline cleats, and the
co-simulation's road over them, against closed forms and brute-force integrals."""

import json

import numpy as np
import pytest

from identification.recording.cleat import CleatProfile, parse_profile
from identification.errors import InputError
from identification.recording import read_recording
from identification.rig import run_rig
from identification.rig.generate import write_run

H, W = 0.04, 0.10


@pytest.mark.parametrize("value, shape", [
    ("rectangular", [(0, 0), (0, 40), (100, 40), (100, 0)]),
    ({"bevel_mm": 10}, [(0, 0), (10, 40), (90, 40), (100, 0)]),
    ([[0, 10], [30, 40], [60, 40], [100, 0]], [(0, 10), (30, 40), (60, 40), (100, 0)]),
])
def test_profiles_parse_to_their_vertices(value, shape):
    p = parse_profile(value, H, W)
    assert [(round(x * 1e3, 9), round(z * 1e3, 9)) for x, z in zip(p.xs, p.zs)] == shape
    assert p.height_m == pytest.approx(H) and p.width_m == pytest.approx(W)
    x = np.array([-0.01, 0.005, 0.05, 0.095, 0.11])
    expected = np.interp(x * 1e3, [s[0] for s in shape], [s[1] for s in shape], left=0, right=0) / 1e3
    if p.is_rectangular:
        expected = np.where((x >= 0) & (x < W), H, 0.0)
    assert p.height(x) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("value, words", [
    ({"bevel_mm": 60}, "more than half the cleat width"),
    ({"bevel_mm": -1}, "bevel_mm must be a number > 0"),
    ({"slope": 1}, "expected {\"bevel_mm\": number}"),
    ([[5, 0], [100, 40]], "the first point's x must be 0"),
    ([[0, 0], [50, 40], [40, 40], [100, 0]], "x must not decrease"),
    ([[0, 0], [50, 30], [100, 0]], "highest point 30 mm is not cleat_height_mm 40"),
    ([[0, 0], [50, 40], [80, 0]], "last x 80 mm is not cleat_width_mm 100"),
    ([[0, 0], [50, "x"]], "each point must be [x_mm, z_mm]"),
    ("round", "expected \"rectangular\""),
])
def test_bad_profiles_are_refused_naming_the_key(value, words):
    with pytest.raises(InputError) as err:
        parse_profile(value, H, W, "rec.json")
    assert "cleat_profile" in err.value.problem and words in err.value.problem


@pytest.mark.parametrize("profile", [CleatProfile.rectangular(H, W), CleatProfile.bevelled(H, W, 0.02),
                                     parse_profile([[0, 10], [30, 40], [60, 40], [100, 0]], H, W)])
def test_the_footprint_average_is_the_integral_under_a_parabolic_pressure(profile):
    ell = 0.3
    s = np.linspace(-0.2, 0.3, 26)
    r, dr = profile.averaged(s, ell)
    x = np.linspace(-0.4, 0.5, 90001)
    z = profile.height(x)
    u = 2 * (x[None, :] - s[:, None]) / ell
    weight = np.where(np.abs(u) < 1, 1.5 / ell * (1 - u * u), 0.0)
    assert r == pytest.approx(np.trapezoid(weight * z[None, :], x, axis=1), abs=5e-6)   # quadrature over the edges
    e = 1e-6
    numeric = (profile.averaged(s + e, ell)[0] - profile.averaged(s - e, ell)[0]) / (2 * e)
    assert dr == pytest.approx(numeric, abs=1e-5)


def test_a_bevelled_cleat_in_the_rig_the_sidecar_and_back(tmp_path):
    """Point contact on a 10 mm bevel: the rig's hub acceleration is python-control's response of the
    corner (m, k, c) to the road z(v t) and its rate; the sidecar carries the profile."""
    import control

    run = run_rig((), {"cleat.bevel_m": 0.01, "sensor.noise_m_s2": 0.0, "sensor.rate_hz": 10000.0}, seed=0)
    truth, t = run.truth["tires"]["FL"], run.recording.time_s
    m, k, c = truth["mass"], truth["k"], truth["c"]
    profile, v = CleatProfile.bevelled(H, W, 0.01), 7.0 / 3.6
    s = v * (t - truth["arrival_s"])
    corner = control.ss([[0, 1], [-k / m, -c / m]], [[0, 0], [k / m, c / m]], [[-k / m, -c / m]], [[k / m, c / m]])
    ref = np.asarray(control.forced_response(corner, t, np.vstack([profile.height(s), v * profile.slope(s)])).outputs)
    assert np.max(np.abs(run.accel_true_m_s2[0] - ref.ravel())) < 2e-3 * np.max(np.abs(ref))
    csv, _ = write_run(run, tmp_path / "bevel")
    assert json.loads(csv.with_suffix(".json").read_text())["cleat_profile"] == {"bevel_mm": pytest.approx(10.0)}
    rec = read_recording(csv)
    assert rec.cleat_profile.kind == "bevel" and rec.cleat_profile.bevel_m == pytest.approx(0.01)
    poly = run_rig((), {"cleat.profile_mm": "0:0,10:40,90:40,100:0", "sensor.noise_m_s2": 0.0,
                        "sensor.rate_hz": 10000.0}, seed=0)
    assert np.max(np.abs(poly.accel_true_m_s2 - run.accel_true_m_s2)) < 1e-9


@pytest.mark.parametrize("height_m, bevel_m, speed_kmh, tire", [(0.04, 0.0, 7.0, "FL"), (0.04, 0.01, 7.0, "FL"),
                                                            (0.01, 0.003, 7.0, "RR"), (0.04, 0.02, 10.0, "FL")])
def test_a_correct_fmu_co_simulates_at_the_noise_floor(tmp_path, height_m, bevel_m, speed_kmh, tire):
    """The rig's own k and c as an FMU, riding the recording's cleat profile through its acquisition chain:
    NRMSE within 1.5 x the noise-only NRMSE (the noise RMS over the measured RMS of the compared window);
    riding a rectangle of the same height and width instead misses a bevelled cleat by far more."""
    from dataclasses import replace

    from identification.fmu.export import export_fmu
    from identification.fmu.validation import simulate_recording

    run = run_rig((), {"cleat.height_m": height_m, "cleat.bevel_m": bevel_m, "speed_kmh": speed_kmh,
                       "sensor.noise_m_s2": 0.05}, seed=3)
    csv, _ = write_run(run, tmp_path / "bevel")
    rec = read_recording(csv)
    truth = run.truth["tires"][tire]
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"recording": str(csv), "speed_kmh": speed_kmh,
                                  "tires": {tire: {"k": truth["k"], "c": truth["c"]}}}))
    export_fmu(params, tmp_path / "t.fmu", tire=tire, backend="native")
    cmp = simulate_recording(tmp_path / "t.fmu", rec, tire)
    sig, t = cmp.measured_signal, rec.time_s
    sel = (t >= sig.impact_s - 0.05) & (t <= sig.window_end_s)
    noise_only = sig.noise_m_s2 / np.sqrt(np.mean(sig.filtered_m_s2[sel] ** 2))
    assert cmp.nrmse <= 1.5 * noise_only, (cmp.nrmse, noise_only)
    assert all(w.error_to_noise < 1.5 for w in cmp.windows.values()), cmp.windows
    assert cmp.warnings == []
    if bevel_m:
        square = simulate_recording(tmp_path / "t.fmu", replace(rec, cleat_profile=None), tire)
        assert square.nrmse > 3 * noise_only, (square.nrmse, noise_only)


def test_a_rectangle_given_as_points_is_the_rectangular_road_on_any_grid():
    """The profile's road on a grid (:meth:`CleatProfile.on_grid`) against the record's own rectangular
    cleat road, two separate codes: the same heights, rates and edges, edges on and off grid points."""
    from identification.model import Cleat, cleat_inputs

    points = CleatProfile((0.0, 0.0, W, W), (0.0, H, H, 0.0), "points")
    for arrival in (0.5, 0.50037):
        for h in (1e-3, 3.7e-4):
            start, n = 0.4, 800
            t = start + h * np.arange(n)
            road, rate, edges = points.on_grid(t, arrival_s=arrival, speed_m_s=7 / 3.6, step_s=h)
            ref_road, ref_rate, _, _, ref_edges = cleat_inputs(start, h, n, arrival_s=arrival,
                                                               cleat=Cleat(H, W, 7 / 3.6), external=True)
            np.testing.assert_allclose(road, ref_road, rtol=0, atol=1e-15)
            np.testing.assert_allclose(rate, ref_rate, rtol=1e-12, atol=0)
            assert [i for i, _ in edges] == [i for i, _ in ref_edges]
            assert np.allclose([te for _, te in edges], [te for _, te in ref_edges], rtol=0, atol=1e-12)


def test_the_built_in_cleat_of_a_profile():
    """Tires that carry the cleat themselves (footprint models, extended FMUs) take a trapezoid: a bevel's own,
    and for points the trapezoid of the same height, width and area (exact when the points are one)."""
    assert CleatProfile.rectangular(H, W).builtin_bevel_m == 0.0
    assert CleatProfile.bevelled(H, W, 0.013).builtin_bevel_m == 0.013
    trapezoid = parse_profile([[0, 0], [13, 40], [87, 40], [100, 0]], H, W)
    assert trapezoid.builtin_bevel_m == pytest.approx(0.013) and trapezoid.builtin_exact
    ramp = parse_profile([[0, 0], [60, 40], [100, 40], [100, 0]], H, W)    # area 0.7 H w: a 30 mm bevel
    assert ramp.builtin_bevel_m == pytest.approx(0.030) and not ramp.builtin_exact


def test_the_tractor_diagnosis_rides_a_bevelled_cleat():
    """A 15 mm bevel at 10 km/h on the rigid tractor with no effect: the joint fit over the profile finds every
    k within 1 % and c within 3 % and names nothing (over a rectangle: c up to 7 % off, measured)."""
    from identification.diagnose.run import run_tractor_diagnosis

    run = run_rig((), {"cleat.bevel_m": 0.015, "speed_kmh": 10.0, "cleat.stagger_m": 0.027}, seed=0)
    diag, gain = run_tractor_diagnosis(run.recording)
    doc = diag.to_json(nrmse_before=gain.nrmse_before, nrmse_after=gain.nrmse_after)
    assert doc["effects"] == []
    for t, est in doc["tires"].items():
        truth = run.truth["tires"][t]
        assert est["k"] == pytest.approx(truth["k"], rel=0.01), t
        assert est["c"] == pytest.approx(truth["c"], rel=0.03), t
