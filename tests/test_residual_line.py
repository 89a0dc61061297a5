"""A steady line left in a diagnosis' residual is named, with its frequency and amplitude (closed forms)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from identification.diagnose.joint_fit import LINE_SHARE, residual_line, unexplained
from identification.model.fitting import TractorProblem
from identification.rig import run_rig


def test_the_line_of_a_residual_is_found_to_a_fraction_of_its_resolution():
    fs, f, a = 500.0, 27.31, 0.42
    t = np.arange(0, 4.0, 1 / fs)
    rng = np.random.default_rng(3)
    r = a * np.sin(2 * np.pi * f * t + 0.7) + 0.3 + rng.normal(0, 0.05, t.size)
    found = residual_line(t, r, 26.0)                     # a quiet stretch's peak, 1.3 Hz off
    assert found["frequency_hz"] == pytest.approx(f, abs=0.02)
    assert found["amplitude_m_s2"] == pytest.approx(a, rel=0.02)
    # the sinusoid's energy a² / 2 per sample against the residual's (the constant and the noise too)
    expected = (a * a / 2) / float(np.mean(r * r))
    assert found["share_of_residual"] == pytest.approx(expected, rel=0.03)


@pytest.fixture(scope="module")
def rig_with_a_line():
    """A rig recording and the same with a 31.7 Hz, 0.5 m/s² line on every channel (no orders: the
    conditioning leaves it to the diagnosis)."""
    run = run_rig((), {"duration_s": 5.0}, seed=2)
    rec = run.recording
    line = 0.5 * np.sin(2 * np.pi * 31.7 * rec.time_s + 1.1)
    lined = dataclasses.replace(rec, accel_m_s2={c: x + line for c, x in rec.accel_m_s2.items()})
    return TractorProblem.from_recording(rec), TractorProblem.from_recording(lined)


def test_what_a_model_leaves_names_a_steady_line_it_does_not_explain(rig_with_a_line):
    clean, lined = rig_with_a_line
    for c in lined.channels:
        assert lined.steady_lines.get(c), c                      # seen in the quiet stretch
        # a "model" that explains the cleat's response exactly and not the line: the clean measurement
        left = unexplained(lined, clean.measured, c)
        assert left is not None, c
        line = left["steady_line"]
        assert line["frequency_hz"] == pytest.approx(31.7, abs=0.02), c
        # the analysis low-pass (zero-phase Butterworth, 100 Hz) passes 31.7 Hz at |H|² = 1 / (1 + (f/fc)^8)
        assert line["amplitude_m_s2"] == pytest.approx(0.5 / (1 + (31.7 / 100) ** 8), rel=0.03), c
        assert line["share_of_residual"] > 0.9, c


def test_a_residual_without_the_line_names_none(rig_with_a_line):
    clean, lined = rig_with_a_line
    for c in lined.channels:
        # the model explains the line (its residual is the noise and a small misfit of the response)
        prediction = {ch: lined.measured[ch] + (0.2 * np.sin(2 * np.pi * 3.0 * lined.rec.time_s) if ch == c else 0)
                      for ch in lined.channels}
        left = unexplained(lined, prediction, c)
        assert left is not None and "steady_line" not in left, c
        assert residual_line(lined.rec.time_s[lined.window], (prediction[c] - lined.measured[c])[lined.window],
                             31.7)["share_of_residual"] < LINE_SHARE
        assert math.isfinite(left["residual_to_noise"])


def test_the_report_verdict_names_the_line_as_the_command_does():
    from identification.report.tables import unexplained_flag
    left = {"share": 0.53, "window": [0.69, 3.92], "residual_to_noise": 16.2,
            "steady_line": {"frequency_hz": 34.3512, "amplitude_m_s2": 0.6712, "share_of_residual": 0.781}}
    cell = unexplained_flag(left, 0.731, 0.045)
    assert "78 % of that residual is a steady 34.35 Hz line of 0.67 m/s²" in cell
    assert "intervals conditional on the model" in cell
    assert "steady" not in unexplained_flag(dict(left, steady_line=None), 0.731, 0.045)
