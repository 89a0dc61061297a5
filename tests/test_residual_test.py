"""The noise-floor test of a residual (`identification.model.fitting.residual_test`): over the window and over
its worst stretch, against closed forms and the chi-square distribution."""

import numpy as np
import pytest
from scipy import stats

from identification.model.fitting import LOCAL_RATIO, LOCAL_SPAN_S, UNEXPLAINED_RATIO, residual_test

FS = 1000.0


def test_constant_residual_is_its_amplitude_over_the_noise():
    out = residual_test(np.full(3000, 0.2), 0.1, FS)
    assert out["residual_to_noise"] == pytest.approx(2.0)
    assert out["worst_span_to_noise"] == pytest.approx(2.0)
    assert not out["at_noise"]                       # 2x > UNEXPLAINED_RATIO over the window


@pytest.mark.parametrize("seed", range(5))
def test_white_noise_at_its_own_level_passes(seed):
    sigma = 0.05
    r = np.random.default_rng(seed).normal(0.0, sigma, 6000)
    out = residual_test(r, sigma, FS)
    assert out["residual_to_noise"] == pytest.approx(1.0, abs=0.05)
    assert out["worst_span_to_noise"] < 1.6          # 60 stretches of 100 samples: chi2(100)/100 stays near 1
    assert out["at_noise"]


def test_a_misfit_in_one_stretch_is_found_where_the_window_dilutes_it():
    sigma, burst = 0.05, 4.0
    rng = np.random.default_rng(7)
    r = rng.normal(0.0, sigma, 5000)
    m = int(LOCAL_SPAN_S * FS)
    at = 2300                                           # a stretch of the grid: samples 2300-2399
    t = np.arange(m) / FS
    r[at:at + m] += burst * sigma * np.sqrt(2) * np.sin(2 * np.pi * 30 * t)   # RMS burst * sigma, 3 periods
    out = residual_test(r, sigma, FS)
    # closed forms: over the window sqrt(1 + burst^2 m / n), over the stretch sqrt(1 + burst^2)
    assert out["residual_to_noise"] == pytest.approx(np.sqrt(1 + burst ** 2 * m / r.size), rel=0.05)
    assert out["residual_to_noise"] < UNEXPLAINED_RATIO
    assert out["worst_span_to_noise"] == pytest.approx(np.sqrt(1 + burst ** 2), rel=0.1)
    assert out["worst_span"] == [at, at + m]
    timed = residual_test(r, sigma, FS, time_s=10.0 + np.arange(r.size) / FS)
    assert timed["worst_span_s"] == pytest.approx([10.0 + at / FS, 10.0 + (at + m - 1) / FS])
    assert not out["at_noise"]


def test_the_local_ratio_is_beyond_noise_at_the_lowest_cut_off():
    # the documented false-alarm chance: n = 2 f_c LOCAL_SPAN_S independent samples per stretch, noise alone
    # over LOCAL_RATIO in RMS means chi2(n) > n LOCAL_RATIO^2; 16 at a 200 Hz recording's default cut-off
    # (80 Hz), 4 at a 20 Hz cut-off
    for cutoff_hz, bound in ((80.0, 1e-20), (20.0, 1e-6)):
        n = round(2 * cutoff_hz * LOCAL_SPAN_S)
        assert stats.chi2.sf(n * LOCAL_RATIO ** 2, n) < bound


def test_short_residual_and_bad_arguments():
    out = residual_test(np.full(10, 0.1), 0.1, FS)      # shorter than one stretch: the whole is the stretch
    assert out["worst_span_to_noise"] == pytest.approx(1.0) and out["worst_span"] == [0, 10]
    with pytest.raises(ValueError, match="noise_rms"):
        residual_test(np.zeros(10), 0.0, FS)
    with pytest.raises(ValueError, match="sample_rate_hz"):
        residual_test(np.zeros(10), 0.1, -1.0)


def test_unexplained_names_a_channel_whose_misfit_sits_in_one_stretch():
    from types import SimpleNamespace

    from identification.diagnose.joint_fit import unexplained

    sigma, n = 0.05, 5000
    rng = np.random.default_rng(3)
    time_s = np.arange(n) / FS
    measured = np.sin(2 * np.pi * 12 * time_s) * np.exp(-time_s)
    noisy = measured + rng.normal(0.0, sigma, n)
    pb = SimpleNamespace(window=np.ones(n, dtype=bool), rec=SimpleNamespace(time_s=time_s, sample_rate_hz=FS),
                         measured={"FL": noisy}, noise={"FL": sigma}, steady_lines={})
    assert unexplained(pb, {"FL": measured}, "FL") is None            # the residual is the noise
    wrong = measured.copy()
    wrong[1200:1300] += 4 * sigma * np.sqrt(2) * np.sin(2 * np.pi * 30 * time_s[:100])
    left = unexplained(pb, {"FL": wrong}, "FL")
    assert left is not None and left["residual_to_noise"] < UNEXPLAINED_RATIO
    assert left["worst_span_to_noise"] > LOCAL_RATIO
    assert left["worst_span"] == pytest.approx([1.2, 1.299])
