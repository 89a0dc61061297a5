"""Cleat arrivals of a whole-tractor recording: the joint search, and the search with each axle's k scaled.

The rig's truth (arrivals, k, c) is the reference; the searches never read it.
"""

import math

import numpy as np
import pytest

from identification.diagnose.joint_timing import BODY_DEFAULTS, joint_timing, scaled_timing
from identification.model.fitting import TractorProblem
from identification.rig import run_rig

#: A tractor with a pivoting front axle and enveloping tires at 5.2 km/h, the right cleat 0.1 s first (a
#: sweep draw where the waveform fits put the rear k about twice the truth and the diagnosis, started there,
#: failed before the scaled search).
PIVOT_ENVELOPING = {
    "speed_kmh": 5.237, "sensor.rate_hz": 2000.0, "sensor.noise_m_s2": 0.074,
    "tire.FL.k_N_m": 564.1e3, "tire.FL.c_Ns_m": 3317.0, "tire.FR.k_N_m": 640.4e3, "tire.FR.c_Ns_m": 3309.0,
    "tire.RL.k_N_m": 426.5e3, "tire.RL.c_Ns_m": 2002.0, "tire.RR.k_N_m": 457.6e3, "tire.RR.c_Ns_m": 2187.0,
    "axle_coupling.pitch_dynamic_index": 0.694, "axle_coupling.roll_gyration_m": 0.514,
    "cleat.stagger_m": -0.1419, "axle_coupling.front_axle_pivot": 1,
    "axle_coupling.front_axle_roll_inertia_kg_m2": 103.0,
    "enveloping.footprint_front_m": 0.307, "enveloping.footprint_rear_m": 0.363,
}
PIVOT_BODY = (("axle_coupling", "roll_coupling", "front_axle_pivot"),
              dict(BODY_DEFAULTS, pitch_index=0.7, roll_index=0.35))


@pytest.fixture(scope="module")
def pivot_run():
    run = run_rig(("axle_coupling", "enveloping"), PIVOT_ENVELOPING, seed=200568185)
    return run, TractorProblem.from_recording(run.recording)


def _errors_ms(found, truth):
    tires = truth["tires"]
    true = (tires["FL"]["arrival_s"], tires["FR"]["arrival_s"] - tires["FL"]["arrival_s"],
            tires["RL"]["arrival_s"] - tires["FL"]["arrival_s"])
    return np.abs(1e3 * (np.array([found["arrival"], found["stagger"], found["delay"]]) - np.array(true)))


def test_the_joint_search_places_every_arrival_with_the_true_tires(pivot_run):
    run, pb = pivot_run
    tires = run.truth["tires"]
    start = {f"{q}_{t}": tires[t][q] for t in pb.channels for q in "kc"}
    found = joint_timing(pb, start, 0.3, hypotheses=[PIVOT_BODY])
    # a typical footprint (0.3 m) and default indices, not the rig's: the rear footprint's 0.363 m puts its
    # leading edge (0.363 - 0.3) / 2 / v = 22 ms earlier than the search's
    assert np.all(_errors_ms(found, run.truth) < (10.0, 10.0, 25.0)), _errors_ms(found, run.truth)
    assert found["score"] < 0   # the model explains part of the signal energy


def test_rear_k_twice_the_truth_misplaces_the_rear_arrivals_and_the_scaled_search_recovers_them(pivot_run):
    run, pb = pivot_run
    tires = run.truth["tires"]
    wrong = {}
    for t in pb.channels:
        m = 1.0 if t.startswith("F") else 2.0
        wrong[f"k_{t}"], wrong[f"c_{t}"] = tires[t]["k"] * m, tires[t]["c"] * math.sqrt(m)
    plain = joint_timing(pb, wrong, 0.3, hypotheses=[PIVOT_BODY])
    assert _errors_ms(plain, run.truth)[2] > 40.0          # the front/rear delay, off by over 40 ms
    scaled = scaled_timing(pb, wrong, 0.3, hypotheses=[PIVOT_BODY])
    assert np.all(_errors_ms(scaled, run.truth) < (10.0, 10.0, 25.0)), _errors_ms(scaled, run.truth)
    assert scaled["score"] < plain["score"]
    for t in ("RL", "RR"):   # the rear k brought back near the truth (multipliers 0.55 .. 1.25)
        assert scaled["tires"][f"k_{t}"] == pytest.approx(tires[t]["k"], rel=0.15)
    for t in ("FL", "FR"):
        assert scaled["tires"][f"k_{t}"] == pytest.approx(tires[t]["k"], rel=0.3)


@pytest.mark.parametrize("fit_scale", [False, True])
def test_compiled_coarse_minimum_is_the_first_minimum_of_the_score_array(fit_scale):
    """The search's compiled one-pass minimum against numpy's argmin (first occurrence) of the scores
    written out over (stagger, delay, arrival): Q - 2 L, or with the responses' scale fitted -L²/Q (0 for a
    scale of 0), with ties, records' edges (-inf) and rows of no arrival."""
    from identification.diagnose.joint_timing import _coarse_min, _coarse_min_arrays

    rng = np.random.default_rng(3)
    for trial in range(40):
        s, d, i = rng.integers(1, 7, size=3)
        front = rng.integers(-3, 4, size=(s, i)).astype(float)     # integers: ties are common
        back = rng.integers(-3, 4, size=(s, d + i - 1)).astype(float)
        back[rng.random(back.shape) < 0.2] = -np.inf
        crossed = rng.integers(-2, 3, size=(s, d)).astype(float)
        if trial == 0:
            back[:] = -np.inf                                       # nothing inside the record
        scores = np.full((s, d, i), np.nan)
        for a in range(s):
            for b in range(d):
                for c in range(i):
                    lin, q = front[a, c] + back[a, b + c], 10.0 + crossed[a, b]
                    if not fit_scale:
                        scores[a, b, c] = q - 2 * lin
                    else:
                        scores[a, b, c] = (math.inf if not math.isfinite(lin) else
                                           -lin * lin / q if lin > 0 and q > 0 else 0.0)
        j = int(np.argmin(scores))
        expect = (float(scores.flat[j]),) + tuple(int(k) for k in np.unravel_index(j, scores.shape))
        got = _coarse_min(10.0, crossed, front, back, fit_scale)
        if not math.isfinite(expect[0]):
            assert math.isinf(got[0]) and math.isinf(_coarse_min_arrays(10.0, crossed, front, back, fit_scale)[0])
            continue
        assert tuple(got) == expect
        assert _coarse_min_arrays(10.0, crossed, front, back, fit_scale) == expect
