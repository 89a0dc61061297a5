"""cleat-recording/1: read, validate, write."""

import json

import numpy as np
import pytest
from conftest import analytic_recording

from identification.errors import InputError
from identification.recording import JITTER_TOLERANCE, read_recording, write_recording


def test_round_trip_keeps_values_units_and_extra_keys(tmp_path):
    rec = analytic_recording(tires=("FL", "RR"))
    csv_path = write_recording(rec, tmp_path / "a", value_decimals=6)
    meta = json.loads(csv_path.with_suffix(".json").read_text())
    meta["operator"] = {"name": "x", "shift": 2}
    csv_path.with_suffix(".json").write_text(json.dumps(meta))
    back = read_recording(csv_path)
    assert back.tires == ("FL", "RR")
    assert back.speed_m_s == pytest.approx(7 / 3.6)
    assert back.cleat_height_m == pytest.approx(0.04) and back.cleat_width_m == pytest.approx(0.1)
    assert back.wheel_load_N == pytest.approx({"FL": 11460.0, "RR": 15510.0})
    assert back.sample_rate_hz == pytest.approx(1000.0)
    assert np.max(np.abs(back.accel_m_s2["FL"] - rec.accel_m_s2["FL"])) <= 5e-7
    assert back.extra == {"operator": {"name": "x", "shift": 2}}
    # extra keys survive a rewrite
    again = write_recording(back, tmp_path / "b")
    assert json.loads(again.with_suffix(".json").read_text())["operator"] == {"name": "x", "shift": 2}


def test_sidecar_found_by_stem_and_loads_only_for_channels(tmp_path):
    rec = analytic_recording(tires=("RL",))
    csv_path = write_recording(rec, tmp_path / "only_rl")
    assert csv_path.name == "only_rl.csv" and csv_path.with_suffix(".json").exists()
    assert read_recording(csv_path).tires == ("RL",)


def test_jitter_within_tolerance_accepted_beyond_refused(tmp_path):
    rec = analytic_recording(tires=("FL",))
    lines = write_recording(rec, tmp_path / "j", value_decimals=4).read_text().splitlines()

    def with_time_shift(frac, name):
        out = list(lines)
        t, rest = out[1001].split(",", 1)
        out[1001] = f"{float(t) + frac * 1e-3:.7f},{rest}"
        (tmp_path / f"{name}.csv").write_text("\n".join(out) + "\n")
        (tmp_path / f"{name}.json").write_text((tmp_path / "j.json").read_text())
        return tmp_path / f"{name}.csv"

    read_recording(with_time_shift(0.8 * JITTER_TOLERANCE, "ok"))
    with pytest.raises(InputError, match="not uniformly sampled"):
        read_recording(with_time_shift(1.5 * JITTER_TOLERANCE, "bad"))


def test_write_is_all_or_nothing(tmp_path):
    rec = analytic_recording(tires=("FL",))
    with pytest.raises(InputError):
        write_recording(rec, tmp_path / "missing_dir" / "x")
    with pytest.raises(InputError):
        write_recording(rec, tmp_path / "x", time_decimals=2)  # cannot represent 1 ms steps
    assert list(tmp_path.iterdir()) == []
