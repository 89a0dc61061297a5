"""The seat's three axes: a record of known sinusoids against the ISO 2631-1 vector sum computed by hand, and
the ride's fore-aft and lateral accelerations against the hubs' own."""

import json
import math

import numpy as np
import pytest

from identification.comfort.ride import ROAD_SPACING_M, ride
from identification.comfort.road import road_profile
from identification.comfort.seat_axes import three_axis
from identification.model.tractor import Body

from tractor_cases import C, K, LOADS, TIRES


def _hand_weighting(f, f1, f2, f3, f4, q4, f5=None, q5=None, f6=None, q6=None):
    """|W(f)| from ISO 2631-1 Annex A's formulas with s = j 2 pi f: high-pass and low-pass (Butterworth,
    Q = 1/sqrt 2), the a-v transition and, for Wk, the upward step; Table A.1's parameters."""
    s = 2j * math.pi * f
    w = {n: 2 * math.pi * v for n, v in dict(f1=f1, f2=f2, f3=f3, f4=f4).items()}
    hh = 1 / (1 + math.sqrt(2) * w["f1"] / s + (w["f1"] / s) ** 2)
    hl = 1 / (1 + math.sqrt(2) * s / w["f2"] + (s / w["f2"]) ** 2)
    ht = (1 + s / w["f3"]) / (1 + s / (q4 * w["f4"]) + (s / w["f4"]) ** 2)
    h = hh * hl * ht
    if f5 is not None:
        w5, w6 = 2 * math.pi * f5, 2 * math.pi * f6
        h *= (1 + s / (q5 * w5) + (s / w5) ** 2) / (1 + s / (q6 * w6) + (s / w6) ** 2) * (w5 / w6) ** 2
    return abs(h)


def _wk(f):
    return _hand_weighting(f, 0.4, 100.0, 12.5, 12.5, 0.63, 2.37, 0.91, 3.35, 0.91)


def _wd(f):
    return _hand_weighting(f, 0.4, 100.0, 2.0, 2.0, 0.63)


AMPLITUDES = {"x": (0.9, 1.6), "y": (0.6, 3.15), "z": (1.3, 5.0)}    # axis: (peak m/s², Hz)


def _record(fs=400.0, duration=30.0):
    t = np.arange(int(fs * duration)) / fs
    return t, {a: amp * np.sin(2 * math.pi * f * t) for a, (amp, f) in AMPLITUDES.items()}


def _expected():
    aw = {"x": AMPLITUDES["x"][0] / math.sqrt(2) * _wd(AMPLITUDES["x"][1]),
          "y": AMPLITUDES["y"][0] / math.sqrt(2) * _wd(AMPLITUDES["y"][1]),
          "z": AMPLITUDES["z"][0] / math.sqrt(2) * _wk(AMPLITUDES["z"][1])}
    return aw, math.sqrt((1.4 * aw["x"]) ** 2 + (1.4 * aw["y"]) ** 2 + aw["z"] ** 2)


def test_three_sinusoids_give_the_iso_vector_sum_within_1_percent():
    """a_wi = A_i / sqrt 2 |W_i(f_i)| by hand, a_v = sqrt((1.4 a_wx)² + (1.4 a_wy)² + a_wz²) (ISO 2631-1 6.5), the
    worst axis's A(8) = max k_i a_wi (8 h exposure)."""
    _, acc = _record()
    r = three_axis(acc["x"], acc["y"], acc["z"], 400.0, exposure_h=8.0)
    aw, vector = _expected()
    for a in "xyz":
        assert r.axes[a].a_w == pytest.approx(aw[a], rel=0.01), a
    assert r.vector_sum_health == pytest.approx(vector, rel=0.01)
    assert r.vector_sum_comfort == pytest.approx(math.sqrt(sum(v * v for v in aw.values())), rel=0.01)
    k = {"x": 1.4, "y": 1.4, "z": 1.0}
    worst = max("xyz", key=lambda a: k[a] * aw[a])
    assert r.a8_axis == worst and r.a8 == pytest.approx(k[worst] * aw[worst], rel=0.01)


def test_comfort_cli_rates_a_three_axis_record(cli, tmp_path):
    t, acc = _record()
    path = tmp_path / "seat.csv"
    rows = (",".join(repr(float(v)) for v in (t[i], acc["x"][i], acc["y"][i], acc["z"][i])) for i in range(t.size))
    path.write_text("time,ax,ay,az\n" + "\n".join(rows) + "\n")
    res = cli("comfort", path, "--axes", "ax,ay,az", "--json")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    aw, vector = _expected()
    assert doc["vector_sum_health"] == pytest.approx(vector, rel=0.01)
    assert doc["axes"]["x"]["weighting"] == "Wd" and doc["axes"]["z"]["weighting"] == "Wk"
    assert doc["exposure"]["a8_status"] in ("below_action", "above_action", "above_limit")
    text = cli("comfort", path, "--axes", "ax,ay,az")
    assert text.code == 0 and "vector sum" in text.out
    bad = cli("comfort", path, "--axes", "ax,ay")
    assert bad.code == 2 and bad.err.startswith("cleatfmu: error: --axes:") and bad.err.count("\n") == 1
    bad = cli("comfort", path, "--axes", "ax,ay,nope")
    assert bad.code == 2 and bad.err.startswith("cleatfmu: error: --axes:")


def test_ride_fore_aft_and_lateral_are_the_pitch_and_roll_at_the_seat_height():
    """x = -h θ'' and y = -h φ'' with θ'' = (ü_FL - ü_RL) / L and φ'' = (ü_FL - ü_FR) / B from the hub
    accelerations of the rigid tractor (the ride's own output), h the seat height, B the track width."""
    from identification.model.kernels import run_model
    from identification.model.ride import ride_model
    from identification.comfort.ride import _point_contact

    body = Body(TIRES, LOADS, 2.6, pitch=True, roll=True, pitch_index=0.8, roll_index=0.5)
    road = road_profile("C", 2.0 * 20 + 1, ROAD_SPACING_M, 4)
    sets = {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}
    run = ride(body, sets, road=road, speed_m_s=2.0, duration_s=20.0, seat_x_m=2.2, seat_height_m=1.2)["t"]
    model = ride_model(body, [_point_contact(k, c, w) for k, c, w in zip(K, C, LOADS)], speed_m_s=2.0,
                       road_x_m=road.x_m, road_left_m=road.left_m, road_right_m=road.right_m)
    traj = run_model(model, *model.grid(0.0, 20.0, 1e-3))
    keep = traj.time_s >= run.time_s[0]
    u = traj.hub_accel_m_s2[:, keep]
    pitch, roll = (u[0] - u[2]) / 2.6, (u[0] - u[1]) / road.track_width_m
    fs = 1e3
    hand = three_axis(-1.2 * pitch, -1.2 * roll, run.seat_m_s2, fs)
    for a in "xyz":
        assert run.axes.axes[a].a_w == pytest.approx(hand.axes[a].a_w, rel=1e-9), a
    assert run.axes.axes["x"].a_w > 0.05 and run.axes.axes["y"].a_w > 0.05


def test_comfort_axes_takes_its_mtvv_window_and_refuses_the_band_spectra(cli, tmp_path):
    """A 0.5 s burst of an 8 Hz sine on z in a quiet 12 s record: a 0.5 s running RMS window holds the whole
    burst, a 1 s window half burst and half quiet, so MTVV(0.5 s) / MTVV(1 s) = √2 (the weighting's few-ms
    transients aside).  Before, --axes rated every axis with a 1 s window whatever --mtvv-window-s said, and
    took --bands without giving them."""
    fs = 400.0
    t = np.arange(int(12 * fs)) / fs
    z = np.where((t >= 6.0) & (t < 6.5), np.sin(2 * np.pi * 8.0 * t), 0.0)
    quiet = 1e-3 * np.sin(2 * np.pi * 3.0 * t)
    path = tmp_path / "burst.csv"
    rows = (f"{a:.6f},{b:.9g},{b:.9g},{c:.9g}" for a, b, c in zip(t, quiet, z))
    path.write_text("time,ax,ay,az\n" + "\n".join(rows) + "\n")
    mtvv = {}
    for tau in (0.5, 1.0):
        res = cli("comfort", path, "--axes", "ax,ay,az", "--mtvv-window-s", str(tau), "--json")
        assert res.code == 0, res.err
        mtvv[tau] = json.loads(res.out)["axes"]["z"]["mtvv"]
    assert mtvv[0.5] / mtvv[1.0] == pytest.approx(math.sqrt(2.0), rel=0.03)
    bad = cli("comfort", path, "--axes", "ax,ay,az", "--bands")
    assert bad.code == 2 and bad.err == "cleatfmu: error: --bands: does not apply with --axes\n", bad.err
