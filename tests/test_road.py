"""ISO 8608 road profiles: the class's PSD, the coherence model between tracks, seeds, the cleat, bad input."""

import numpy as np
import pytest

from identification.comfort.road import (CLEAT_HEIGHT_M, ISO8608_BAND_CPM, ISO8608_GD_N0_M3, RoadProfile,
                                         cleat_profile, iso8608_psd, profile_height, road_profile, track_coherence)
from identification.errors import InputError

SPACING = 0.05          # m: Nyquist 10 cycles/m, well above the band's 2.83
LENGTH = 3000.0         # m
SEEDS = range(12)
NPERSEG = 4096          # Welch segments of 204.8 m: resolution 0.0049 cycles/m
#: Band checked: away from the edges 0.011 and 2.83 cycles/m, where a Welch bin straddles the band limit
#: and where the lowest one-third octaves hold a single bin.
CHECKED_CPM = (0.03, 2.5)


@pytest.fixture(scope="module")
def spectra():
    """Welch auto- and cross-spectra of class C, averaged over the seeds."""
    from scipy import signal

    fs = 1.0 / SPACING
    pll = prr = plr = 0.0
    for seed in SEEDS:
        road = road_profile("C", LENGTH, SPACING, seed)
        n, a = signal.welch(road.left_m, fs=fs, nperseg=NPERSEG)
        _, b = signal.welch(road.right_m, fs=fs, nperseg=NPERSEG)
        _, ab = signal.csd(road.left_m, road.right_m, fs=fs, nperseg=NPERSEG)
        pll, prr, plr = pll + a, prr + b, plr + ab
    k = len(SEEDS)
    return n, pll / k, prr / k, plr / k


def _third_octaves(n):
    """Boolean masks of the Welch bins in each one-third octave inside CHECKED_CPM."""
    edges = CHECKED_CPM[0] * 2.0 ** (np.arange(0, 40) / 3.0)
    edges = edges[edges <= CHECKED_CPM[1]]
    return [(n >= lo) & (n < hi) for lo, hi in zip(edges[:-1], edges[1:])]


def test_class_values_and_psd_shape():
    assert ISO8608_GD_N0_M3["A"] == 16e-6 and ISO8608_GD_N0_M3["E"] == 4096e-6
    names = list(ISO8608_GD_N0_M3)
    assert all(ISO8608_GD_N0_M3[b] == 4 * ISO8608_GD_N0_M3[a] for a, b in zip(names, names[1:]))
    psd = iso8608_psd([0.005, 0.05, 0.1, 0.2, 3.0], "b")
    assert psd.tolist() == pytest.approx([0.0, 4 * 64e-6, 64e-6, 64e-6 / 4, 0.0])


@pytest.mark.parametrize("track", ["left", "right"])
def test_averaged_welch_psd_is_the_class_psd_within_10_percent(spectra, track):
    n, pll, prr, _ = spectra
    estimate = pll if track == "left" else prr
    bands = _third_octaves(n)
    assert len(bands) >= 15
    for sel in bands:
        ratio = estimate[sel].mean() / iso8608_psd(n[sel], "C").mean()
        assert ratio == pytest.approx(1.0, abs=0.10), (n[sel][0], ratio)


def test_estimated_coherence_follows_the_exponential_model(spectra):
    n, pll, prr, plr = spectra
    coherence = np.abs(plr) ** 2 / (pll * prr)
    for sel in _third_octaves(n):
        model = track_coherence(n[sel]).mean()
        assert coherence[sel].mean() == pytest.approx(model, abs=0.03), n[sel][0]
    assert track_coherence(0.1, 1.8, decay=2.0) == pytest.approx(np.exp(-0.36))


def test_zero_decay_gives_identical_tracks_and_the_variance_is_the_band_integral():
    road = road_profile("D", 2000.0, 0.1, 3, coherence_decay=0.0)
    np.testing.assert_allclose(road.right_m, road.left_m, atol=1e-15)
    lo, hi = ISO8608_BAND_CPM
    variance = ISO8608_GD_N0_M3["D"] * 0.1 ** 2 * (1 / lo - 1 / hi)     # integral of Gd over the band
    assert road.period_m >= 8 / lo
    assert np.var(road.left_m) == pytest.approx(variance, rel=0.03)


def test_seed_reproduces_and_another_seed_differs():
    a = road_profile("B", 200.0, 0.1, 7)
    b = road_profile("B", 200.0, 0.1, 7)
    c = road_profile("B", 200.0, 0.1, 8)
    assert isinstance(a, RoadProfile)
    np.testing.assert_array_equal(a.left_m, b.left_m)
    np.testing.assert_array_equal(a.right_m, b.right_m)
    assert not np.allclose(a.left_m, c.left_m)
    assert a.x_m[0] == 0.0 and a.x_m[-1] == pytest.approx(200.0) and a.x_m.size == 2001
    meta = a.metadata
    assert meta["road_class"] == "B" and meta["seed"] == 7 and meta["track_width_m"] == 1.8
    assert meta["coherence_model"] == "exp(-a n B)"


def test_height_interpolates_each_track():
    road = road_profile("A", 50.0, 0.1, 1)
    x = np.array([0.0, 0.05, 10.03, 50.0])
    for track, heights in (("left", road.left_m), ("right", road.right_m)):
        got = profile_height(road, x, track)
        assert got[0] == heights[0] and got[-1] == heights[-1]
        assert got[1] == pytest.approx(0.5 * (heights[0] + heights[1]))
        np.testing.assert_array_equal(road.height(x, track), got)
    assert profile_height(road, [-1.0, 60.0], "left", fill=0.0).tolist() == [0.0, 0.0]
    with pytest.raises(InputError, match="leave the profile"):
        profile_height(road, [60.0])
    with pytest.raises(InputError, match="track"):
        profile_height(road, [1.0], "middle")


def test_cleat_profile_on_the_grid():
    x = np.arange(0.0, 10.0, 0.01)
    cleat = cleat_profile(x, 2.0, 0.1)
    on = x[cleat > 0]
    assert set(cleat) == {0.0, CLEAT_HEIGHT_M}
    assert on[0] == pytest.approx(2.0) and on[-1] == pytest.approx(2.09) and on.size == 10
    assert cleat_profile(x, 2.0, 0.1, height_m=0.075).max() == 0.075
    with pytest.raises(InputError, match="narrower"):
        cleat_profile(x, 2.0, 0.005)
    with pytest.raises(InputError, match="inside the grid"):
        cleat_profile(x, 9.95, 0.1)


@pytest.mark.parametrize("args, kwargs, match", [
    (("Z", 100.0, 0.1, 0), {}, "unknown ISO 8608 class"),
    (("A", -5.0, 0.1, 0), {}, "length"),
    (("A", 0.0, 0.1, 0), {}, "length"),
    (("A", 100.0, 0.0, 0), {}, "spacing"),
    (("A", 100.0, 0.2, 0), {}, "too coarse"),
    (("A", 100.0, 0.1, 0), {"band_cpm": (0.05, 6.0)}, "too coarse"),
    (("A", 100.0, 0.1, -1), {}, "seed"),
    (("A", 100.0, 0.1, 1.5), {}, "seed"),
    (("A", 100.0, 0.1, 0), {"track_width_m": 0.0}, "track width"),
    (("A", 100.0, 0.1, 0), {"coherence_decay": -1.0}, "decay"),
    (("A", 100.0, 0.1, 0), {"band_cpm": (1.0, 0.5)}, "band"),
    (("A", float("nan"), 0.1, 0), {}, "length"),
])
def test_bad_arguments_raise_input_error(args, kwargs, match):
    with pytest.raises(InputError, match=match):
        road_profile(*args, **kwargs)
