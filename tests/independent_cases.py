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
