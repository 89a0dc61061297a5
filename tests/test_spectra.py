"""One-third-octave band spectra (IEC 61260-1 base-10 bands) and the comfort command's band, MTVV-window
and wording options, against closed forms."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from identification.comfort.spectra import band_centres, third_octave


def _pink(fs: float, duration_s: float, c: float, seed: int) -> np.ndarray:
    """Pink noise of one-sided PSD c / f: a sinusoid per FFT bin of power c / f · df, random phases."""
    n = int(fs * duration_s)
    f = np.fft.rfftfreq(n, 1.0 / fs)
    amp = np.zeros_like(f)
    amp[1:] = np.sqrt(2.0 * c / f[1:] * f[1])
    phase = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, f.size)
    return np.fft.irfft(amp * np.exp(1j * phase) * n / 2, n)


def test_band_centres_are_the_base_10_series_with_their_nominal_names():
    exact, labels = band_centres(0.5, 80.0)
    assert labels[:6] == ["0.5", "0.63", "0.8", "1", "1.25", "1.6"] and labels[-3:] == ["50", "63", "80"]
    np.testing.assert_allclose(exact, 10.0 ** (np.arange(-3, 20) / 10.0), rtol=1e-12)


@pytest.mark.parametrize("fs,duration_s", [(512.0, 600.0), (256.0, 300.0)])
def test_pink_noise_has_the_same_level_in_every_band_within_half_a_db_of_theory(fs, duration_s):
    """Pink noise S(f) = c / f holds c ln(10^(1/10)) in every base-10 one-third-octave band."""
    c = 0.01
    bands = third_octave(_pink(fs, duration_s, c, seed=3), fs)
    theory_db = 10.0 * math.log10(c * math.log(10.0 ** 0.1)) - 20.0 * math.log10(1e-6)
    assert np.max(np.abs(bands.level_db - theory_db)) < 0.5, bands.level_db - theory_db


def test_a_sinusoid_falls_in_its_band_with_its_rms():
    fs = 512.0
    t = np.arange(int(60 * fs)) / fs
    bands = third_octave(2.0 * np.sin(2 * np.pi * 5.0 * t), fs)
    i = bands.labels.index("5")
    assert bands.rms_m_s2[i] == pytest.approx(2.0 / math.sqrt(2.0), rel=0.01)
    assert np.sum(bands.rms_m_s2 ** 2) == pytest.approx(2.0, rel=0.01)


def _record(path, t, z):
    path.write_text("time_s,z\n" + "\n".join(f"{a:.6f},{b:.6f}" for a, b in zip(t, z)) + "\n")
    return path


def test_comfort_reports_bands_and_takes_a_short_mtvv_window(cli, tmp_path):
    fs = 512.0
    t = np.arange(int(0.6 * fs)) / fs
    short = _record(tmp_path / "short.csv", t, np.sin(2 * np.pi * 8.0 * t))
    res = cli("comfort", short)
    assert res.code == 2 and "--mtvv-window-s" in res.err and len(res.err.strip().splitlines()) == 1
    res = cli("comfort", short, "--mtvv-window-s", "0.25", "--json")
    assert res.code == 0, res.err
    doc = json.loads(res.out)
    assert doc["mtvv_window_s"] == 0.25 and doc["third_octave"] is None          # too short for 0.5 Hz bands
    # a steady sinusoid: every 0.25 s window holds two periods, MTVV = a_w (ISO 2631-1 6.3.1)
    assert doc["mtvv"] == pytest.approx(doc["a_w"], rel=0.05)
    long = _record(tmp_path / "long.csv", np.arange(int(30 * fs)) / fs,
                   np.sin(2 * np.pi * 5.0 * np.arange(int(30 * fs)) / fs))
    doc = json.loads(cli("comfort", long, "--json").out)
    bands = doc["third_octave"]
    i = bands["nominal_hz"].index("5")
    assert bands["rms_m_s2"][i] == pytest.approx(doc["a_w"], rel=0.01)         # all of a_w is in the 5 Hz band
    res = cli("comfort", long, "--bands", "--plot", tmp_path / "bands.png")
    assert res.code == 0 and "one-third-octave" in res.out and (tmp_path / "bands.png").stat().st_size > 1000


def test_a_decaying_ring_is_not_called_a_shock_but_the_standards_rule_is_stated(cli, tmp_path):
    """A lightly damped response that decays within the record trips MTVV/a_w > 1.5: the output says what
    ISO 2631-1 6.3.3 says (the RMS may underestimate), not that it is a shock."""
    fs = 512.0
    t = np.arange(int(20 * fs)) / fs
    ring = np.exp(-0.5 * t) * np.sin(2 * np.pi * 4.0 * t)
    res = cli("comfort", _record(tmp_path / "ring.csv", t, ring))
    assert res.code == 0
    assert "MTVV/a_w" in res.out and "6.3.3" in res.out and "may underestimate" in res.out
    assert "shocks, which" not in res.out
