"""Enveloping on a ride: a tire with a footprint rolls on its track averaged over it with the law's contact
pressure.  Checked against the law's own closed-form average of a cleat, the footprint's closed-form
response to a road wave, the road PSD through that response (Monte Carlo), and the ride command."""

import json
import math

import numpy as np
import pytest

from identification.comfort.expected import psd_rating, realisation_seeds
from identification.comfort.ride import ROAD_SPACING_M, ride
from identification.comfort.road import road_profile
from identification.model.ride import enveloped_track, footprint_response, seat_row
from identification.model.tire_law import footprint_cleat
from identification.model.tractor import Body

from tractor_cases import C, K, LOADS, TIRES

H, W, XC = 0.04, 0.1, 3.0


@pytest.mark.parametrize("parabolic", [True, False], ids=["parabolic", "uniform"])
@pytest.mark.parametrize("footprint", [0.2, 0.45])
def test_a_cleat_averaged_over_the_footprint_is_the_tire_laws_own_average(parabolic, footprint):
    """The ride's discrete average of a road holding the test cleat against the law's closed form for its
    built-in cleat (one source of the pressure distribution): within 1.5 % of the cleat's height at a 1 mm
    grid, and the same area under the averaged profile."""
    x = np.arange(0.0, 6.0, 1e-3)
    track = np.where((x >= XC) & (x < XC + W), H, 0.0)
    xs, averaged = enveloped_track(x, track, footprint, parabolic=parabolic)
    closed = np.array([footprint_cleat(xi, footprint, XC, H, W, parabolic)[0] for xi in xs])
    assert np.max(np.abs(averaged - closed)) < 0.015 * H
    assert np.trapezoid(averaged, xs) == pytest.approx(H * W, rel=0.01)
    assert np.array_equal(enveloped_track(x, track, 0.0)[1], track)       # point contact: the track itself


@pytest.mark.parametrize("parabolic", [True, False], ids=["parabolic", "uniform"])
@pytest.mark.parametrize("wavelength", [0.25, 0.6, 2.0, 10.0])
def test_a_road_wave_is_attenuated_by_the_closed_form_footprint_response(parabolic, wavelength):
    x = np.arange(0.0, 40.0, 1e-3)
    _, averaged = enveloped_track(x, np.sin(2 * math.pi * x / wavelength), 0.35, parabolic=parabolic)
    middle = slice(5000, 35000)
    gain = np.dot(averaged[middle], np.sin(2 * math.pi * x[middle] / wavelength)) / \
        np.dot(np.sin(2 * math.pi * x[middle] / wavelength), np.sin(2 * math.pi * x[middle] / wavelength))
    assert gain == pytest.approx(float(footprint_response(1.0 / wavelength, 0.35, parabolic=parabolic)), abs=3e-3)


def test_rides_with_footprints_match_the_road_psd_through_the_footprint_response():
    """√(mean a_w²) over 8 rides of 120 s at 2 m/s on class C with 0.35/0.45 m footprints against the PSD
    with each tire's column of H times its footprint response; the footprints take off a measurable share."""
    body = Body(TIRES, LOADS, 2.6, pitch=True, roll=True, pitch_index=0.8, roll_index=0.5)
    sets = {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}
    footprint = {"FL": 0.35, "FR": 0.35, "RL": 0.45, "RR": 0.45}
    squares = []
    for s in realisation_seeds(3, 8):
        road = road_profile("C", 2.0 * 120.0 + 1.0, ROAD_SPACING_M, s)
        run = ride(body, sets, road=road, speed_m_s=2.0, duration_s=120.0, seat_x_m=2.2, seat_y=0.3,
                   footprints={"t": footprint})["t"]
        assert run.footprints == footprint and run.to_json()["footprint_m"] == footprint
        squares.append(run.comfort.a_w ** 2)
    squares = np.array(squares)
    row = seat_row(body, seat_x_m=2.2, seat_y=0.3)
    road = road_profile("C", 10.0, ROAD_SPACING_M, 0)
    predicted = psd_rating(body, *sets["t"], row, road=road, speed_m_s=2.0, footprints_m=footprint)
    point = psd_rating(body, *sets["t"], row, road=road, speed_m_s=2.0)
    ratio = math.sqrt(squares.mean()) / predicted
    standard_error = squares.std(ddof=1) / squares.mean() / math.sqrt(squares.size) / 2.0
    assert abs(ratio - 1.0) < 3.0 * standard_error + 0.01, (ratio, standard_error)
    assert predicted < 0.9 * point                      # the footprints matter here: the check has teeth


@pytest.fixture
def diagnosis(example_diagnosis):
    """The embedded 7 km/h day's ``diagnose --json`` document, as a file (``ride --body`` takes it)."""
    return example_diagnosis


def test_ride_command_rolls_the_tires_on_the_diagnosed_footprints(cli, tmp_path, diagnosis):
    res = cli("ride", "--example", "7kmh", "--compare", "paper,final", "--realisations", "2", "--json")
    assert res.code == 0, res.err
    doc = json.loads(res.out)                  # (diagnosed here; below from the document, as --body reads it)
    diag = json.loads(diagnosis.read_text())
    assert "enveloping" in diag["effects"]
    fitted = {t: diag["tires"][t]["parameters"]["footprint"]["value"] for t in TIRES}
    for entry in doc["sets"].values():
        assert entry["footprint_m"] == pytest.approx(fitted, rel=1e-9)
    body = json.loads(cli("ride", "--example", "7kmh", "--compare", "paper,final", "--realisations", "2",
                          "--json", "--body", diagnosis).out)
    assert body["sets"]["final"]["footprint_m"] == pytest.approx(fitted, rel=1e-9)
    off = json.loads(cli("ride", "--example", "7kmh", "--compare", "paper,final", "--realisations", "2",
                         "--json", "--enveloping", "off", "--body", diagnosis).out)
    assert all("footprint_m" not in e for e in off["sets"].values())
    assert doc["sets"]["final"]["expected"]["a_w"]["mean"] < 0.9 * off["sets"]["final"]["expected"]["a_w"]["mean"]
    text = cli("ride", "--example", "7kmh", "--compare", "final", "--realisations", "1", "--body", diagnosis)
    assert "roll with the footprints the diagnosis fitted (front 0.30 m, rear 0.38 m; enveloping)" in text.out
    refused = cli("ride", "--example", "7kmh", "--compare", "final", "--realisations", "1", "--ssp",
                  str(tmp_path / "ssp"), "--body", diagnosis)
    assert refused.code == 2 and refused.err.count("\n") == 1 and "--enveloping off" in refused.err
    assert not (tmp_path / "ssp").exists()


def test_the_seats_band_spectra_add_up_to_its_weighted_rms_and_average_over_the_roads(cli, tmp_path, diagnosis):
    """A ride's one-third-octave bands of the seat's weighted x, y, z hold their a_w (Parseval: the bands tile
    the weighting's range) within 4 %; the expected spectrum over the roads is the root mean square of the rides'
    bands; the command prints and plots it."""
    from identification.comfort.spectra import ThirdOctave, expected_bands

    body = Body(TIRES, LOADS, 2.6, pitch=True, roll=True, pitch_index=0.8, roll_index=0.5)
    sets = {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}
    runs = [ride(body, sets, road=road_profile("C", 2.0 * 200.0 + 1.0, ROAD_SPACING_M, s), speed_m_s=2.0,
                 duration_s=200.0, seat_x_m=2.2, seat_y=0.3)["t"] for s in (1, 2)]
    for run in runs:        # (Welch's segments cover all but the last few seconds, Hann-weighted)
        assert math.sqrt(np.sum(run.bands["z"].rms_m_s2 ** 2)) == pytest.approx(run.comfort.a_w, rel=0.04)
        for axis in ("x", "y", "z"):
            assert math.sqrt(np.sum(run.bands[axis].rms_m_s2 ** 2)) == pytest.approx(run.axes.axes[axis].a_w,
                                                                                    rel=0.04)
    both = expected_bands([r.bands["z"] for r in runs])
    np.testing.assert_allclose(both.rms_m_s2, np.sqrt((runs[0].bands["z"].rms_m_s2 ** 2 +
                                                        runs[1].bands["z"].rms_m_s2 ** 2) / 2), rtol=1e-12)
    with pytest.raises(ValueError):
        expected_bands([runs[0].bands["z"], ThirdOctave(np.array([1.0]), ["1"], np.array([1.0]))])
    res = cli("ride", "--example", "7kmh", "--compare", "paper,final", "--realisations", "2", "--bands",
              "--bands-plot", str(tmp_path / "bands.png"), "--body", diagnosis)
    assert res.code == 0, res.err
    assert "seat's one-third-octave bands, expected over 2 road(s)" in res.out and "  z (Wk)  Hz " in res.out
    assert (tmp_path / "bands.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    doc = json.loads(cli("ride", "--example", "7kmh", "--compare", "final", "--realisations", "2", "--json",
                         "--body", diagnosis).out)
    z = doc["sets"]["final"]["expected"]["third_octave"]["z"]
    assert z["nominal_hz"][0] == "0.5" and z["nominal_hz"][-1] == "80"
    assert math.sqrt(sum(v ** 2 for v in z["rms_m_s2"])) == pytest.approx(
        doc["sets"]["final"]["expected"]["psd"]["monte_carlo_rms_a_w"], rel=0.1)
