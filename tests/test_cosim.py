"""Quarter-tractor co-simulation of the tire FMU with fmpy: exactness, convergence, closure, CLI."""

import json
import math
import re

import control
import numpy as np
import pytest

from build_scripts import build_fmu
from identification.fmu.cosim import run_quarter_tractor
from identification.recording.preprocess import lowpass
from identification.recording import STANDARD_GRAVITY, write_recording
from identification.rig import run_rig
from identification.fmu.validation import box_average, simulate_recording
from identification.identify.waveform import identify_waveform_recording

M, K, C = 11460 / STANDARD_GRAVITY, 550e3, 4200.0
H, W = 0.04, 0.10


@pytest.fixture(scope="module")
def tire_fmu(tmp_path_factory):
    return build_fmu("point_contact", tmp_path_factory.mktemp("fmu") / "tire.fmu",
                     start_values={"stiffness": K, "damping": C, "unloaded_radius": 0.68})


def control_box_acceleration(times, *, t1, speed, ts):
    """Exact mean hub acceleration over each sample interval, from python-control.

    The corner's transfer from road rate ṙ to hub velocity is (cs + k)/(ms² + cs + k) (strictly
    proper); the cleat is ṙ = H δ(t - t1) - H δ(t - t1 - w/v).  The mean acceleration over
    [t - ts/2, t + ts/2] is the velocity difference over the interval divided by ts.
    """
    sys = control.ss(control.tf([C, K], [M, C, K]))
    dt = 1e-5
    grid = np.arange(0.0, times[-1] + 1.0, dt)
    resp = np.asarray(control.impulse_response(sys, grid).outputs).ravel()

    def velocity(t):
        v = np.zeros_like(t)
        for edge, sign in ((t1, 1.0), (t1 + W / speed, -1.0)):
            tau = t - edge
            ok = tau >= 0
            v[ok] += sign * H * np.interp(tau[ok], grid, resp)
        return v
    return (velocity(times + ts / 2) - velocity(times - ts / 2)) / ts


def cosim_nrmse(fmu, *, speed, t1, max_step, ts=1e-3, duration=4.0):
    res = run_quarter_tractor(fmu, mass_kg=M, speed_m_s=speed, cleat_height_m=H, cleat_width_m=W, arrival_s=t1,
                              t0_s=0.0, duration_s=duration, max_step_s=max_step)
    times = np.arange(0.01, duration - 0.01, ts)
    # both through the preprocessing low-pass, as every comparison with a recording is made
    sim = lowpass(box_average(res, times, ts), sample_rate_hz=1 / ts)
    ref = lowpass(control_box_acceleration(times, t1=t1, speed=speed, ts=ts), sample_rate_hz=1 / ts)
    return float(np.sqrt(np.mean((sim - ref) ** 2)) / np.sqrt(np.mean(ref ** 2))), res


@pytest.mark.parametrize("speed,t1", [(7 / 3.6, 0.5123), (10 / 3.6, 0.3007)])
def test_cosim_matches_python_control(tire_fmu, speed, t1):
    err, res = cosim_nrmse(tire_fmu, speed=speed, t1=t1, max_step=2.5e-4)
    assert err <= 0.005
    assert err < 1e-3, err
    # the master found the static equilibrium itself: the tire carries the weight at rest
    assert res.force_n[0] == pytest.approx(M * STANDARD_GRAVITY, rel=1e-9)
    assert res.static_hub_z_m == pytest.approx(0.68 - M * STANDARD_GRAVITY / K, rel=1e-9)
    assert abs(res.hub_accel_m_s2[:100]).max() < 1e-6


def test_cosim_converges_second_order(tire_fmu):
    errors = [cosim_nrmse(tire_fmu, speed=7 / 3.6, t1=0.5123, max_step=h, duration=3.0)[0]
              for h in (1e-3, 5e-4, 2.5e-4, 1.25e-4)]
    for a, b in zip(errors, errors[1:]):
        assert b < a / 2.5, errors   # second order: ~4x per halving


def test_no_coupling_delay_negative_damping(tire_fmu):
    """A one-step delay would act as a negative damper k·h; the decay rate must not show it."""
    h = 1e-3
    res = run_quarter_tractor(tire_fmu, mass_kg=M, speed_m_s=7 / 3.6, cleat_height_m=H, cleat_width_m=W,
                              arrival_s=0.3, t0_s=0.0, duration_s=3.0, max_step_s=h)
    z = res.hub_z_m - res.static_hub_z_m
    t = res.time_s
    sel = t > 0.5
    peaks = [i for i in np.flatnonzero(sel)[1:-1] if z[i] > z[i - 1] and z[i] >= z[i + 1]]
    rate = -np.polyfit(t[peaks], np.log(z[peaks]), 1)[0]
    true_rate = C / (2 * M)
    delayed_rate = (C - K * h) / (2 * M)     # what a one-step delay would give
    assert rate == pytest.approx(true_rate, rel=0.01)
    assert abs(rate - true_rate) < abs(rate - delayed_rate) / 10


@pytest.fixture(scope="module")
def baseline_runs():
    return {speed: run_rig((), {"speed_kmh": speed, "sensor.noise_m_s2": 0.05}, seed=int(speed))
            for speed in (7.0, 10.0)}


def _export(cli, tmp_path, rec, tire, method):
    csv_path = write_recording(rec, tmp_path / "rec")
    res = cli("identify", csv_path, "--json", "--method", method)
    assert res.code == 0, res.err
    (tmp_path / "params.json").write_text(res.out)
    assert cli("export", tmp_path / "params.json", "--tire", tire, "-o", tmp_path / f"{tire}.fmu").code == 0
    return csv_path, tmp_path / f"{tire}.fmu"


@pytest.mark.parametrize("speed", [7.0, 10.0])
@pytest.mark.parametrize("tire", ["FL", "RR"])
def test_closed_loop_on_rig_baseline(cli, tmp_path, baseline_runs, speed, tire):
    """recording -> identify -> export -> simulate: NRMSE <= 5 %, waveform k within 2 %, c within 5 %."""
    run = baseline_runs[speed]
    truth = run.truth["tires"][tire]
    wave = identify_waveform_recording(run.recording, [tire])[tire]
    assert wave.k == pytest.approx(truth["k"], rel=0.02)
    assert wave.c == pytest.approx(truth["c"], rel=0.05)
    assert wave.k_ci[0] < wave.k < wave.k_ci[1] and wave.c_ci[0] < wave.c < wave.c_ci[1]
    csv_path, fmu = _export(cli, tmp_path, run.recording, tire, "waveform")
    res = cli("simulate", fmu, csv_path, "--tire", tire, "--json")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    assert doc["nrmse"] <= 0.05, doc["nrmse"]
    assert doc["r2"] > 0.99
    exported = json.loads((tmp_path / "params.json").read_text())["tires"][tire]
    assert doc["k_fmu"] == pytest.approx(exported["k"], rel=1e-12)
    assert doc["c_fmu"] == pytest.approx(exported["c"], rel=1e-12)


def test_an_alignment_at_its_search_limit_is_reported_as_a_warning(tire_fmu, baseline_runs):
    from dataclasses import replace

    from identification.fmu.validation import MAX_ALIGNMENT_S

    cmp = simulate_recording(tire_fmu, baseline_runs[7.0].recording, "FL")
    assert not cmp.alignment_at_limit and cmp.warnings == []
    stuck = replace(cmp, alignment_s=MAX_ALIGNMENT_S)
    assert stuck.alignment_at_limit and "search limit" in stuck.warnings[0] and "+30.0 ms" in stuck.warnings[0]
    assert stuck.to_json()["alignment_at_limit"] is True
    from identification.cli.simulate import _text

    assert "warning: the alignment of simulated to measured acceleration reached its search limit" in \
        _text(stuck, baseline_runs[7.0].recording)
    assert "warning" not in _text(cmp, baseline_runs[7.0].recording)


def test_one_corner_on_the_whole_tractor_test_day_says_it_cannot_explain_it(tire_fmu):
    """The embedded test day is a whole tractor (a rigid body couples the tires): one corner under its own
    mass misses it by far more than the noise, and the comparison says so and what to run instead."""
    from identification.recording.examples import example_path
    from identification.recording import read_recording

    rec = read_recording(example_path("7kmh"))
    cmp = simulate_recording(tire_fmu, rec, "FL")
    assert max(w.error_to_noise for w in cmp.windows.values()) > 10
    body = [w for w in cmp.warnings if "whole-tractor recording" in w]
    assert body and "--body DIAG.json" in body[0], cmp.warnings
    # the ratio quoted is the named window's own (it once quoted another window's)
    m = re.search(r"the misfit is (\d+) x the noise in the (\w+) window", body[0])
    assert m and int(m.group(1)) == round(cmp.windows[m.group(2)].error_to_noise), (body[0], cmp.windows)


@pytest.mark.parametrize("method", ["paper", "waveform"])
def test_closure_reidentifies_the_fmu(tire_fmu, baseline_runs, method):
    rec = baseline_runs[7.0].recording
    for tire in ("FR", "RL"):
        cmp = simulate_recording(tire_fmu, rec, tire, method=method)
        assert cmp.k_reidentified == pytest.approx(K, rel=0.01), (tire, method)
        assert cmp.c_reidentified == pytest.approx(C, rel=0.02), (tire, method)
        assert cmp.k_fmu == K and cmp.c_fmu == C


def test_simulate_json_shape_and_plot(cli, tmp_path, tire_fmu, baseline_runs):
    csv_path = write_recording(baseline_runs[10.0].recording, tmp_path / "rec")
    res = cli("simulate", tire_fmu, csv_path, "--tire", "FL", "--json", "--plot", tmp_path / "fl.png")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    assert set(doc) == {"tire", "nrmse", "r2", "alignment_s", "alignment_at_limit", "warnings", "k_fmu", "c_fmu",
                        "k_reidentified", "c_reidentified", "decay_rate_measured", "decay_rate_simulated", "windows"}
    # the rig's tire in the FMU: aligned within a few ms, far from the search limit, no warning
    assert abs(doc["alignment_s"]) < 0.01 and not doc["alignment_at_limit"] and doc["warnings"] == []
    assert doc["tire"] == "FL"
    assert set(doc["windows"]) == {"impact", "free_decay", "other_axle"}
    for w in doc["windows"].values():
        assert w["start_s"] < w["end_s"] and 0 <= w["misfit_share"] <= 1
        assert set(w) >= {"nrmse", "rms_error_m_s2", "error_to_noise", "misfit_share"}
    assert sum(w["misfit_share"] for w in doc["windows"].values()) == pytest.approx(1.0)
    assert doc["decay_rate_measured"] > 0 and doc["decay_rate_simulated"] > 0
    png = (tmp_path / "fl.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    text = cli("simulate", tire_fmu, csv_path, "--tire", "FL")
    assert text.code == 0 and "NRMSE" in text.out and "most wrong" in text.out


def test_axle_coupling_shows_in_the_other_axle_window(cli, tmp_path):
    """The point-contact FMU cannot see the other axle: NRMSE rises and the misfit sits there."""
    from identification.recording import read_recording
    runs = {name: run_rig(effects, seed=3) for name, effects in (("base", ()), ("coupled", ("axle_coupling",)))}
    for tire in ("FL", "RL"):
        cmp = {}
        for name, run in runs.items():
            folder = tmp_path / name / tire
            folder.mkdir(parents=True)
            csv_path, fmu = _export(cli, folder, run.recording, tire, "paper")
            cmp[name] = simulate_recording(fmu, read_recording(csv_path), tire)
        base, coupled = cmp["base"], cmp["coupled"]
        assert coupled.nrmse > 2 * base.nrmse
        assert coupled.worst_window == "other_axle", {n: w.misfit_share for n, w in coupled.windows.items()}
        assert coupled.windows["other_axle"].misfit_share > 0.5
        assert coupled.windows["other_axle"].error_to_noise > 10 * base.windows["other_axle"].error_to_noise


def test_waveform_identify_cli(cli, tmp_path, baseline_runs):
    csv_path = write_recording(baseline_runs[7.0].recording, tmp_path / "rec")
    res = cli("identify", csv_path, "--method", "waveform", "--json")
    doc = json.loads(res.out)
    for tire, entry in doc["tires"].items():
        assert set(entry) == {"k", "c", "T", "delta", "zeta", "omega_n", "r2", "n_peaks", "mass", "k_ci", "c_ci",
                              "decay_misfit", "warning", "window_shift", "skipped_peaks", "amplitude_move", "floor"}
        assert all(abs(entry["window_shift"][q]) < 0.01 * entry[q] for q in "kc")   # one mode: little move
        assert all(entry["amplitude_move"][q] < 0.01 * entry[q] for q in "kc")      # a linear tire: halves agree
        assert entry["floor"] == {"k": 0.01, "c": 0.01}
        assert entry["skipped_peaks"] == 0                                            # and from its first peak
        assert entry["warning"] is None and entry["decay_misfit"] < 2.0     # the rig's baseline: one mode
        lo, hi = entry["k_ci"]
        assert lo < entry["k"] < hi
        assert entry["omega_n"] ** 2 * entry["mass"] == pytest.approx(entry["k"], rel=1e-12)
        assert entry["zeta"] == pytest.approx(entry["c"] / (2 * math.sqrt(entry["k"] * entry["mass"])), rel=1e-9)
    table = cli("identify", csv_path, "--method", "waveform")
    assert "95 % confidence intervals" in table.out


def test_waveform_intervals_cover_the_truth_at_the_stated_rate():
    """Over 12 noisy baseline draws, the 95 % intervals of k and c must cover the truth nearly always."""
    hits, total = 0, 0
    for seed in range(6):
        run = run_rig((), {"sensor.noise_m_s2": 0.2}, seed=100 + seed)
        for tire, r in identify_waveform_recording(run.recording, ["FL", "RR"]).items():
            truth = run.truth["tires"][tire]
            hits += (r.k_ci[0] <= truth["k"] <= r.k_ci[1]) + (r.c_ci[0] <= truth["c"] <= r.c_ci[1])
            total += 2
    assert hits >= total - 3, (hits, total)


@pytest.mark.parametrize("case,needle", [("missing_fmu", "no such file"), ("not_fmu", "not a readable FMU"),
                                         ("bad_tire", "tire RR is not in the recording"),
                                         ("plot_suffix", "must end with .png")])
def test_simulate_bad_input(cli, tmp_path, tire_fmu, baseline_runs, case, needle):
    rec = baseline_runs[7.0].recording
    from identification.recording import Recording
    only_fl = Recording(time_s=rec.time_s, accel_m_s2={"FL": rec.accel_m_s2["FL"]}, speed_m_s=rec.speed_m_s,
                        cleat_height_m=rec.cleat_height_m, cleat_width_m=rec.cleat_width_m,
                        wheelbase_m=rec.wheelbase_m, wheel_load_N={"FL": rec.wheel_load_N["FL"]})
    csv_path = write_recording(only_fl, tmp_path / "rec")
    fmu, extra = tire_fmu, []
    if case == "missing_fmu":
        fmu = tmp_path / "nope.fmu"
    elif case == "not_fmu":
        fmu = tmp_path / "junk.fmu"
        fmu.write_text("not a zip")
    elif case == "bad_tire":
        extra = ["--tire", "RR"]
    else:
        extra = ["--plot", tmp_path / "out.jpg"]
    res = cli("simulate", fmu, csv_path, *extra)
    assert res.code == 2 and res.out == ""
    assert len(res.err.strip().splitlines()) == 1 and needle in res.err
    assert not (tmp_path / "out.jpg").exists()
