"""Physical plausibility at the input boundaries: sidecar, time column, export parameters, rig and command options.

Each value out of its range (:mod:`identification.recording.plausibility`) ends in one
line naming the file or option, the value and the range, exit 2 and nothing
written; the explicit overrides (the sidecar's ``"out_of_range_ok"``,
``export --accept-out-of-range``) let a genuine value through.
"""

from __future__ import annotations

import json
import zipfile
import xml.etree.ElementTree as ET

import pytest

from conftest import analytic_recording, rewrite_sidecar
from identification.recording.examples import EXAMPLES, example_path
from identification.recording.plausibility import RANGES
from identification.recording import read_recording, write_recording
from identification.rig.params import PARAMS, RANGES as RIG_RANGES


def _one_line(res, *needles):
    assert res.code == 2 and res.out == "", (res.code, res.err)
    lines = res.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("cleatfmu: error: "), res.err
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


def test_every_rig_default_and_the_embedded_test_days_are_plausible():
    for key, (low, high, _) in RIG_RANGES.items():
        assert low <= PARAMS[key].default <= high, key
    for name in EXAMPLES:
        rec = read_recording(example_path(name))
        assert RANGES["speed_kmh"].low <= rec.speed_kmh <= RANGES["speed_kmh"].high
        assert RANGES["sampling_rate_hz"].low <= rec.sample_rate_hz <= RANGES["sampling_rate_hz"].high
        assert all(RANGES["wheel_load_kN"].contains(w / 1e3) for w in rec.wheel_load_N.values())


#: Rig option -> (the pipeline's quantity, factor from the option's unit to the quantity's).
SHARED = {"speed_kmh": ("speed_kmh", 1.0), "cleat.height_m": ("cleat_height_mm", 1e3),
          "cleat.width_m": ("cleat_width_mm", 1e3), "vehicle.wheelbase_m": ("wheelbase_m", 1.0),
          "sensor.rate_hz": ("sampling_rate_hz", 1.0), "sensor.highpass_hz": ("highpass_hz", 1.0),
          **{f"tire.{t}.load_N": ("wheel_load_kN", 1e-3) for t in ("FL", "FR", "RL", "RR")},
          **{f"tire.{t}.k_N_m": ("stiffness_N_m", 1.0) for t in ("FL", "FR", "RL", "RR")},
          **{f"tire.{t}.c_Ns_m": ("damping_Ns_m", 1.0) for t in ("FL", "FR", "RL", "RR")}}


def test_the_rig_ranges_of_recorded_quantities_are_the_pipelines():
    for key, (quantity, factor) in SHARED.items():
        low, high, _ = RIG_RANGES[key]
        assert (low * factor, high * factor) == pytest.approx((RANGES[quantity].low, RANGES[quantity].high)), key


@pytest.mark.parametrize("key,value,shown", [
    ("speed_kmh", 70.0, "speed_kmh 70 km/h is outside the plausible range 0.5-60 km/h"),
    ("speed_kmh", 0.4, "speed_kmh 0.4 km/h"),
    ("cleat_height_mm", 0.04, "cleat_height_mm 0.04 mm is outside the plausible range 2-200 mm"),
    ("cleat_width_mm", 1500, "cleat_width_mm 1500 mm"),
    ("wheelbase_m", 2770, "wheelbase_m 2770 m is outside the plausible range 0.5-10 m"),
    ("wheel_load_kN", {"FL": 11460, "FR": 11.6, "RL": 15.65, "RR": 15.51},
     "wheel_load_kN.FL 11460 kN is outside the plausible range 0.1-100 kN"),
    ("acquisition", {"anti_alias_order": 4, "anti_alias_cutoff_hz": 250, "highpass_hz": 50},
     "acquisition.highpass_hz 50 Hz is outside the plausible range 0-10 Hz"),
])
def test_a_sidecar_value_out_of_range_is_refused_unless_listed(cli, good_recording, key, value, shown):
    rewrite_sidecar(good_recording, **{key: value})
    res = cli("identify", good_recording)
    _one_line(res, f"{good_recording.with_suffix('.json')}: {shown}", '"out_of_range_ok"')
    waived = "highpass_hz" if key == "acquisition" else key
    rewrite_sidecar(good_recording, out_of_range_ok=[waived])
    rec = read_recording(good_recording)       # accepted as given, and the override is kept
    assert rec.extra["out_of_range_ok"] == [waived]
    back = write_recording(rec, good_recording.parent / "back")
    assert json.loads(back.with_suffix(".json").read_text())["out_of_range_ok"] == [waived]


@pytest.mark.parametrize("speed", [0.5, 60.0])
def test_the_range_bounds_are_inclusive(good_recording, speed):
    rewrite_sidecar(good_recording, speed_kmh=speed)
    assert read_recording(good_recording).speed_kmh == pytest.approx(speed)


@pytest.mark.parametrize("value,needle", [("speed_kmh", "must be a list"), (["speed"], "unknown quantity 'speed'"),
                                          ([1], "must be a list")])
def test_a_malformed_override_is_refused(cli, good_recording, value, needle):
    rewrite_sidecar(good_recording, out_of_range_ok=value)
    _one_line(cli("identify", good_recording), "run.json: out_of_range_ok", needle)


def test_a_sampling_rate_out_of_range_names_the_csv(cli, tmp_path):
    rec = analytic_recording(fs=40.0, duration=10.0, noise=0.01, tires=("FL",))
    csv_path = write_recording(rec, tmp_path / "slow")
    _one_line(cli("identify", csv_path), f"{csv_path}: sampling rate 40 Hz is outside the plausible range "
                                         f"50-100000 Hz", "slow.json")
    rewrite_sidecar(csv_path, out_of_range_ok=["sampling_rate_hz"])
    assert read_recording(csv_path).sample_rate_hz == pytest.approx(40.0)


def _params(tmp_path, **entry):
    doc = {"recording": "r.csv", "speed_kmh": 7.0,
           "tires": {"FL": {"k": 412345.0, "c": 2345.0, "mass": 1168.6, **entry}}}
    path = tmp_path / "p.json"
    path.write_text(json.dumps(doc))
    return path


def _stiffness_start(fmu) -> float:
    root = ET.fromstring(zipfile.ZipFile(fmu).read("modelDescription.xml"))
    return next(float(sv.find("Real").get("start")) for sv in root.iter("ScalarVariable")
                if sv.get("name") == "stiffness")


@pytest.mark.parametrize("entry,needle", [
    ({"k": 5e7}, "tire FL: stiffness k 5e+07 N/m is outside the plausible range 10000-1e+07 N/m"),
    ({"k": 5e3}, "tire FL: stiffness k 5000 N/m"),
    ({"c": 2e5}, "tire FL: damping c 200000 N*s/m is outside the plausible range 0-100000 N*s/m"),
    ({"mass": 20000.0}, "tire FL: corner mass 20000 kg"),
])
def test_export_refuses_implausible_parameters_unless_accepted(cli, tmp_path, entry, needle):
    params = _params(tmp_path, **entry)
    out = tmp_path / "o" / "FL.fmu"
    _one_line(cli("export", params, "-o", out, "--platforms", "linux64"), f"{params}: {needle}",
              "--accept-out-of-range")
    assert not (tmp_path / "o").exists()
    res = cli("export", params, "-o", out, "--platforms", "linux64", "--accept-out-of-range")
    assert res.code == 0, res.err
    assert _stiffness_start(out) == json.loads(params.read_text())["tires"]["FL"]["k"]


def test_export_refuses_an_implausible_unloaded_radius(cli, tmp_path):
    params = _params(tmp_path)
    _one_line(cli("export", params, "-o", tmp_path / "FL.fmu", "--unloaded-radius-m", "7.5"),
              "--unloaded-radius-m: unloaded radius 7.5 m is outside the plausible range 0.1-2 m")
    assert list(tmp_path.iterdir()) == [params]


@pytest.mark.parametrize("args,needle", [
    (("--param", "tire.FL.k_N_m=2e7"), "--param: tire.FL.k_N_m 2e+07 N/m is outside the plausible range"),
    (("--param", "tire.rr.c_Ns_m=1e6"), "--param: tire.RR.c_Ns_m 1e+06 N s/m is outside"),
    (("--param", "sensor.rate_hz=20"), "--param: sensor.rate_hz 20 Hz is outside the plausible range 50-100000 Hz"),
    (("--param", "duration_s=500", "--param", "sensor.rate_hz=5000"), "2.5e+06 samples, more than the rig's"),
    (("--param", "duration_s=1.5", "--param", "sensor.rate_hz=50"), "75 samples, fewer than a recording's 100"),
    (("--speed", "0.3"), "--speed: speed 0.3 km/h is outside the plausible range 0.5-60 km/h"),
    (("--speed", "nan"), "--speed: must be a finite number > 0 km/h"),
    (("--seed", "-3"), "--seed: must be >= 0"),
    (("--param", "solver.oversample=1000"), "--param: solver.oversample 1000 is outside the plausible range 1-64"),
])
def test_rig_options_out_of_range_are_refused(cli, tmp_path, args, needle):
    _one_line(cli("rig", *args, "-o", tmp_path / "sub" / "x"), needle)
    assert list(tmp_path.iterdir()) == []


def test_command_options_with_a_cost_are_bounded(cli, good_recording, tmp_path):
    _one_line(cli("simulate", tmp_path / "FL.fmu", good_recording, "--tire", "FL", "--max-step-s", "1e-6"),
              "--max-step-s: 1e-06 s is outside 1e-05-0.01 s")
    _one_line(cli("simulate", tmp_path / "FL.fmu", good_recording, "--tire", "FL", "--max-step-s", "0.008"),
              "--max-step-s: 0.008 s is too coarse for the low-pass at 100 Hz")
    _one_line(cli("diagnose", good_recording, "--workers", "65"), "--workers: 65 is outside 1-64")
    _one_line(cli("diagnose", good_recording, "--workers", "0"), "--workers: 0 is outside 1-64")


@pytest.mark.parametrize("scale,shown", [(1e-285, "e-284 m/s^2 is outside"), (0.0, " 0 m/s^2 is outside"),
                                         (1e6, "e+07 m/s^2 is outside")])
def test_a_channel_that_is_no_hub_acceleration_in_m_s2_is_refused(cli, tmp_path, scale, shown):
    rec = analytic_recording(tires=("FL", "RR"))   # FL peaks at 13.3 m/s^2
    rec.accel_m_s2["FL"][:] *= scale
    csv_path = write_recording(rec, tmp_path / "r", value_decimals=300 if scale < 1 else 5)
    _one_line(cli("identify", csv_path, "--tire", "RR"), f"{csv_path}: channel FL: largest acceleration ", shown,
              "the plausible range 0.01-1e+06 m/s^2")
