"""Recordings of the independent simulator (``tests/independent``) for the tests that diagnose one: generated
into a folder, then read and conditioned as the commands do it (focused on the impacts, decimated to the
cut-off).  Kept outside ``tests/independent``, which shares nothing with the fitter, not even its reader."""

from __future__ import annotations

import json
from pathlib import Path

from identification.recording import read_recording
from identification.recording.preprocess import default_cutoff_hz
from identification.recording.window import decimate, focus


def independent_recording(setting: str, seed: int, folder: Path):
    """(the conditioned recording, its cut-off Hz, the truth document) of `setting` drawn with `seed`."""
    from tests.independent.generate import draw, run, write

    sc = draw(setting, seed)
    stem = write(sc, run(sc), Path(folder) / f"{setting.replace(' ', '_')}_{seed}")
    truth = json.loads(stem.with_suffix(".truth.json").read_text())
    rec = read_recording(stem.with_suffix(".csv"))
    cutoff = default_cutoff_hz(rec.sample_rate_hz)
    return decimate(focus(rec, cutoff_hz=cutoff, announce=False), cutoff_hz=cutoff), cutoff, truth


def independent_diagnosis(setting: str, seed: int, folder: Path):
    """(the whole-tractor diagnosis, the truth document) of `setting` drawn with `seed`."""
    from identification.diagnose.joint_select import diagnose_tractor

    rec, cutoff, truth = independent_recording(setting, seed, folder)
    return diagnose_tractor(rec, cutoff_hz=cutoff), truth


def assert_tires_hold_the_truth(diagnosis, truth, *, c_interval: bool = False) -> None:
    """Every tire of `diagnosis` within the issue's 3 % of the truth's k and 10 % of its c, its k interval
    holding the truth's k (and its c interval the truth's c, with `c_interval`)."""
    reported = diagnosis.to_json()["tires"]
    for w, t in truth["tires"].items():
        got = reported[w]
        assert abs(got["k"] / t["k"] - 1) < 0.03, (w, got["k"], t["k"])
        assert abs(got["c"] / t["c"] - 1) < 0.10, (w, got["c"], t["c"])
        assert got["k_ci"][0] <= t["k"] <= got["k_ci"][1], (w, got["k_ci"], t["k"])
        if c_interval:
            assert got["c_ci"][0] <= t["c"] <= got["c_ci"][1], (w, got["c_ci"], t["c"])
