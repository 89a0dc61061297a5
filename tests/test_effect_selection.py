"""The selection's rule for an effect that acts on a narrow part of the data: a steady line.

A steady line (lugs, a periodic road) carries little of the residual energy where the model misses the
impact itself by more (a footprint of another shape), so the overall gain of a model that removes the
line stays far under the 25 % rule; the share of the line's energy it removes is judged instead.  An
effect that adds no parameter (unilateral contact) is held to its gate and the BIC only.
"""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from identification.diagnose import joint_select as js
from identification.diagnose.joint_evidence import local_gain

FS = 500.0
LINE_HZ = 17.0


def _problem(seed=0):
    """A channel holding a decaying impact response, a steady 17 Hz line and white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 4.0, 1.0 / FS)
    impact = np.where(t > 1.0, 8.0 * np.exp(-(t - 1.0) / 0.4) * np.sin(2 * math.pi * 3.0 * (t - 1.0)), 0.0)
    line = 0.3 * np.sin(2 * math.pi * LINE_HZ * t + 0.4)
    rec = SimpleNamespace(sample_rate_hz=FS, time_s=t)
    pb = SimpleNamespace(channels=("FL",), measured={"FL": impact + line + 0.02 * rng.standard_normal(t.size)},
                         window=t > 0.95, rec=rec)
    return pb, impact, line


def _fit(pb, prediction):
    model = SimpleNamespace(problem=pb, names=())
    return SimpleNamespace(model=model, prediction={"FL": prediction},
                           params={"lug_frequency_front": LINE_HZ, "lug_frequency_rear": LINE_HZ})


def test_the_share_of_the_line_removed_is_the_closed_form_one_minus_the_amplitude_ratio_squared():
    pb, impact, line = _problem()
    misfit = 0.6 * impact            # the impact missed by 40 %: far more energy than the line's
    base = _fit(pb, misfit)
    for kept in (0.0, 0.1, 0.3, 0.6):
        fit = _fit(pb, misfit + (1.0 - kept) * line)
        assert local_gain("periodic_disturbance", fit, base) == pytest.approx(1.0 - kept ** 2, abs=0.02), kept
    # a line of the wrong phase adds to the residual line: nothing removed
    wrong = _fit(pb, misfit - line)
    assert local_gain("periodic_disturbance", wrong, base) == 0.0
    # the overall gain of removing the whole line is small beside the impact's misfit
    w = pb.window
    r_base = (pb.measured["FL"] - misfit)[w]
    r_fit = (pb.measured["FL"] - misfit - line)[w]
    assert 1.0 - (r_fit @ r_fit) / (r_base @ r_base) < 0.25
    # effects judged on the whole residual alone have no local measure
    assert local_gain("friction_damping", wrong, base) is None


def _candidate(sse, local, gate=True, parameters=12):
    fit = SimpleNamespace(weighted_sse=lambda: sse, in_bounds=True,
                          model=SimpleNamespace(names=tuple(range(parameters))))
    return js.TractorCandidate("periodic_disturbance", fit, math.nan, math.nan, gate, False, {}, local)


@pytest.mark.parametrize("local, gate, qualified", [(0.95, True, True), (0.5, True, False), (None, True, False),
                                                     (0.95, False, False)])
def test_a_candidate_qualifies_on_the_line_it_removes_only_with_its_gate(local, gate, qualified):
    n, n_eff, current_sse, current_p = 40_000, 8_000.0, 1.0e6, 10
    cand = js._judge(_candidate(0.92e6, local, gate), current_sse, current_p, n, n_eff)
    assert cand.gain == pytest.approx(0.08)
    assert cand.delta_bic > js.MIN_DELTA_BIC
    assert cand.qualified is qualified


def test_the_line_rule_still_needs_the_information_criterion():
    # removing the line but not paying for its parameters (a gain of 0.01 % over 8000 samples)
    cand = js._judge(_candidate(0.9999e6, 0.99, parameters=30), 1.0e6, 10, 40_000, 8_000.0)
    assert cand.delta_bic < js.MIN_DELTA_BIC and not cand.qualified


def test_a_lines_frequency_is_refined_over_the_whole_window_where_the_quiet_start_is_too_short():
    from identification.diagnose.joint_start import periodic_start

    fs, f_true, f_other = 500.0, 19.81, 18.4
    t = np.arange(0.0, 3.5, 1.0 / fs)
    rng = np.random.default_rng(3)
    # the tire's own lugs and, weaker, another tire's carried across by the body: half a second before the
    # impact cannot tell them apart (a Hann window of 0.45 s resolves ~9 Hz), three seconds can
    lines = 0.3 * np.sin(2 * math.pi * f_true * t) + 0.2 * np.sin(2 * math.pi * f_other * t + 1.0)
    x = lines + 0.01 * rng.standard_normal(t.size)
    rec = SimpleNamespace(time_s=t, sample_rate_hz=fs, accel_m_s2={"FL": x}, mass_kg=lambda tire: 1200.0)
    kw = dict(first_impact_s=0.5, cutoff_hz=100.0, k=5e5, c=4e3, arrival=0.5)
    short = periodic_start(rec, "FL", **kw)["lug_frequency"]
    window = t >= 0.45
    refined = periodic_start(rec, "FL", residual=x, window=window, **kw)["lug_frequency"]
    resolution = fs / (1 << 16)
    assert abs(short - f_true) > 0.2
    assert refined == pytest.approx(f_true, abs=max(0.03, 2 * resolution))



@pytest.mark.parametrize("sse, gate, qualified", [(0.97e6, True, True), (0.97e6, False, False),
                                                  (0.9995e6, True, False)])
def test_an_effect_without_parameters_is_named_on_its_gate_and_the_bic(sse, gate, qualified):
    """Unilateral contact adds no parameter: a 3 % gain (BIC + 244 over 8000 samples) names it where its gate
    holds (the hub in free fall), none without the gate, and a gain the BIC does not see (0.05 %: + 4) neither."""
    n, n_eff, current_sse, current_p = 40_000, 8_000.0, 1.0e6, 10
    cand = js._judge(_candidate(sse, None, gate, parameters=current_p), current_sse, current_p, n, n_eff)
    assert cand.delta_bic == pytest.approx(-n_eff * math.log(sse / current_sse))
    assert cand.qualified is qualified
    # the same gain from a candidate with a parameter more is held to the 25 % rule
    more = js._judge(_candidate(sse, None, gate, parameters=current_p + 1), current_sse, current_p, n, n_eff)
    assert not more.qualified
