"""``cleatfmu rig``, determinism, and the embedded test day."""

import json

import numpy as np
import pytest

from identification.recording.examples import EXAMPLES, example_path, truth_path
from identification.recording import read_recording
from identification.rig.testday import TESTDAY, write_testday


def test_rig_cli_writes_recording_and_truth(cli, tmp_path):
    res = cli("rig", "--effect", "enveloping,lift_off", "--speed", "10", "--seed", "3",
              "--param", "sensor.rate_hz=2000", "--param", "cleat.height_m=0.05", "-o", tmp_path / "run")
    assert res.code == 0, res.err
    assert res.out.split() == [str(tmp_path / f"run{s}") for s in (".csv", ".json", ".truth.json")]
    rec = read_recording(tmp_path / "run.csv")
    assert rec.sample_rate_hz == pytest.approx(2000.0) and rec.speed_kmh == pytest.approx(10.0)
    assert rec.cleat_height_m == pytest.approx(0.05) and rec.tires == ("FL", "FR", "RL", "RR")
    meta = json.loads((tmp_path / "run.json").read_text())
    assert "enveloping" not in json.dumps(meta)  # the recording does not give the truth away
    truth = json.loads((tmp_path / "run.truth.json").read_text())
    assert truth["format"] == "cleat-rig-truth/1" and truth["recording"] == "run.csv"
    assert set(truth["effects"]) == {"enveloping", "lift_off"} and truth["seed"] == 3
    assert truth["parameters"]["sensor.rate_hz"] == 2000.0


def test_same_seed_gives_byte_identical_files(cli, tmp_path):
    args = ("rig", "--effect", "axle_coupling,periodic_disturbance", "--seed", "11")
    assert cli(*args, "-o", tmp_path / "a").code == 0
    assert cli(*args, "-o", tmp_path / "b").code == 0
    assert cli("rig", "--effect", "axle_coupling,periodic_disturbance", "--seed", "12", "-o", tmp_path / "c").code == 0
    for suffix in (".csv", ".json"):
        assert (tmp_path / f"a{suffix}").read_bytes() == (tmp_path / f"b{suffix}").read_bytes()
    assert (tmp_path / "a.csv").read_bytes() != (tmp_path / "c.csv").read_bytes()
    ta, tb = (json.loads((tmp_path / f"{n}.truth.json").read_text()) for n in "ab")
    ta.pop("recording"), tb.pop("recording")
    assert ta == tb


@pytest.mark.parametrize("args,needle", [
    (("--effect", "wobble"), "unknown effect 'wobble'"),
    (("--param", "tire.FL.k_N_m=-5"), "tire.FL.k_N_m must be > 0"),
    (("--param", "nope=1"), "unknown parameter 'nope'"),
    (("--param", "sensor.channels=FL,XX"), "subset of FL,FR,RL,RR"),
    (("--param", "vehicle.mass_kg=3000"), "does not match the wheel loads"),
    (("--param", "speed_kmh"), "expected key=value"),
    (("--param", "axle_coupling.front_axle_pivot=2"), "axle_coupling.front_axle_pivot must be 0 or 1"),
    (("--param", "axle_coupling.front_axle_pivot=0.5"), "axle_coupling.front_axle_pivot must be 0 or 1"),
    (("--param", "cleat.stagger_m=nan"), "cleat.stagger_m must be finite"),
])
def test_rig_bad_input_one_line_exit_2_nothing_written(cli, tmp_path, args, needle):
    res = cli("rig", *args, "-o", tmp_path / "x")
    assert res.code == 2 and res.out == ""
    assert len(res.err.strip().splitlines()) == 1 and needle in res.err
    assert list(tmp_path.iterdir()) == []


def test_list_params(cli):
    res = cli("rig", "--list-params")
    assert res.code == 0
    assert "enveloping.footprint_front_m" in res.out and "tire.RR.c_Ns_m" in res.out
    assert "axle_coupling.front_axle_pivot" in res.out and "axle_coupling.front_axle_roll_inertia_kg_m2" in res.out
    assert "negative: the left one beyond the right" in res.out


def test_rig_cli_pivoting_axle_and_negative_stagger(cli, tmp_path):
    res = cli("rig", "--effect", "axle_coupling", "--param", "axle_coupling.front_axle_pivot=1",
              "--param", "cleat.stagger_m=-0.1", "--param", "duration_s=2", "-o", tmp_path / "p")
    assert res.code == 0, res.err
    truth = json.loads((tmp_path / "p.truth.json").read_text())
    assert truth["body"]["front_axle"] == "pivot" and truth["parameters"]["cleat.stagger_m"] == -0.1
    assert truth["tires"]["FR"]["arrival_s"] < truth["tires"]["FL"]["arrival_s"]


def test_embedded_test_day_is_small_readable_and_regenerable(tmp_path):
    total = 0
    for name, stem in EXAMPLES.items():
        rec = read_recording(example_path(name))
        assert rec.tires == ("FL", "FR", "RL", "RR")
        assert rec.speed_kmh == pytest.approx(float(name.removesuffix("kmh")))
        assert rec.cleat_height_m == pytest.approx(0.040)
        truth = json.loads(truth_path(name).read_text())
        assert {"enveloping", "axle_coupling"} <= set(truth["effects"])
        assert truth["parameters"]["sensor.noise_m_s2"] > 0
        total += sum(p.stat().st_size for p in example_path(name).parent.glob(f"{stem}.*"))
    assert total < 500_000
    # The files are what the test-day definition produces (to the written precision).
    write_testday(tmp_path)
    for stem in TESTDAY:
        fresh = read_recording(tmp_path / f"{stem}.csv")
        shipped = read_recording(example_path(next(k for k, v in EXAMPLES.items() if v == stem)))
        for tire in fresh.tires:
            assert np.max(np.abs(fresh.accel_m_s2[tire] - shipped.accel_m_s2[tire])) <= 2e-3
