"""The arrival search with the responses' scale fitted, on a recording of the independent simulator.

A slow pass (5.4 km/h) over a wide cleat with an undeclared bevel (``tests/independent``, tuning seed 132
of "corners": four independent corners, left and right cleats 3 ms apart): a point contact's responses are
far larger than the hubs' and every timing of the plain search misfits the record more than no model at
all; the plain search then prefers a stagger of about +0.25 s, whose responses cancel each other.  With the
responses' common scale fitted, the timing that explains the record is found
(:func:`identification.diagnose.joint_timing.joint_timing`, ``fit_scale``).  Checked against the
independent engine's scenario (its cleats' positions and speed), which shares no code with the fitter.
"""

from __future__ import annotations

import warnings

import pytest

pytest.importorskip("exudyn", reason="the independent simulator needs exudyn (the test extra)")
warnings.filterwarnings("ignore", category=DeprecationWarning, module="exudyn")
pytestmark = pytest.mark.independent   # generated and diagnosed: CI's sweeps step (docs/testing.md)

from identification.diagnose.joint_start import starting_values  # noqa: E402
from identification.model.fitting import TractorProblem  # noqa: E402
from tests.independent_cases import independent_recording  # noqa: E402


@pytest.fixture(scope="module")
def slow_wide_cleat(tmp_path_factory):
    rec, cutoff, truth = independent_recording("corners", 132, tmp_path_factory.mktemp("independent"))
    pb = TractorProblem.from_recording(rec, cutoff_hz=cutoff)
    speed = truth["scenario"]["speed_kmh"] / 3.6
    return pb, {"stagger": truth["scenario"]["stagger_m"] / speed}


def test_the_fitted_scale_search_finds_the_stagger_the_plain_one_misses(slow_wide_cleat):
    pb, truth = slow_wide_cleat
    plain, scaled = starting_values(pb), starting_values(pb, fit_scale=True)
    assert abs(plain["stagger"] - truth["stagger"]) > 0.1          # s: the failure the scale is for
    assert abs(scaled["stagger"] - truth["stagger"]) < 0.02, scaled["stagger"]
    # with the footprint too: at least four times closer than the plain search's
    off = {name: abs(s["enveloped"]["stagger"] - truth["stagger"]) for name, s in (("plain", plain), ("scaled", scaled))}
    assert off["scaled"] < off["plain"] / 4, off
