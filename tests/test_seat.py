"""The suspended seat and its SEAT factor against independent references: python-control's frequency
response, the closed-form steady state, scipy's solve_ivp with the end stops, the ISO 2631-1 Annex A
weighting and the ISO 5007 class spectra coded here from their definitions, and the ride's physics."""

import json
import math

import control
import numpy as np
import pytest
from scipy import signal
from scipy.integrate import solve_ivp

from identification.comfort.seat import (DEFAULT_SEAT, SeatModel, class_of_mass, class_psd, class_record,
                                         class_seat_factor, seat_response, spectral_seat_factor)

#: A long-stroke seat: the default seat's suspension with ±100 mm free travel, linear on the class inputs.
LONG = SeatModel(travel_m=0.1)
#: ISO 5007 classes as the HVLab toolbox's hvtestspectrum.m gives them: high-pass, low-pass (8 poles) and scale,
#: and the unweighted RMS its hvtestsignal.m scales each test signal to (0.89-11.22 Hz band).
CLASSES = {"I": (3.0, 3.5, 9.25, 2.26), "II": (2.1, 2.6, 7.22, 1.94), "III": (1.95, 2.45, 5.85, 1.74)}


def _control_transmissibility(seat, f_hz):
    """Occupant / floor acceleration from python-control: the state (z, z') of the relative travel, input the
    floor acceleration, output the occupant's acceleration a_f + z'' = -(k z + c z') / m."""
    m, k, c = seat.mass_kg, seat.stiffness_N_per_m, seat.damping_N_s_per_m
    sys = control.ss([[0.0, 1.0], [-k / m, -c / m]], [[0.0], [-1.0]], [[-k / m, -c / m]], [[0.0]])
    return np.asarray(control.frequency_response(sys, 2 * np.pi * np.asarray(f_hz)).complex).ravel()


def _wk_magnitude(f_hz):
    """|Wk(f)| from ISO 2631-1:1997 Annex A (Table A.1: f1 0.4, f2 100, f3 = f4 12.5, Q4 0.63, f5 2.37,
    Q5 0.91, f6 3.35, Q6 0.91 Hz), coded from the formulas."""
    s = 2j * np.pi * np.asarray(f_hz, dtype=float)
    w = {n: 2 * np.pi * f for n, f in dict(f1=0.4, f2=100.0, f3=12.5, f4=12.5, f5=2.37, f6=3.35).items()}
    q = 1 / math.sqrt(2)
    hh = 1 / (1 + w["f1"] / (q * s) + (w["f1"] / s) ** 2)
    hl = 1 / (1 + s / (q * w["f2"]) + (s / w["f2"]) ** 2)
    ht = (1 + s / w["f3"]) / (1 + s / (0.63 * w["f4"]) + (s / w["f4"]) ** 2)
    hs = (1 + s / (0.91 * w["f5"]) + (s / w["f5"]) ** 2) / (1 + s / (0.91 * w["f6"]) + (s / w["f6"]) ** 2) \
        * (w["f5"] / w["f6"]) ** 2
    return np.abs(hh * hl * ht * hs)


def _class_psd(f_hz, name):
    """The class PSD from scipy's analog 8-pole Butterworth filters (not the package's closed form)."""
    fh, fl, g, _ = CLASSES[name]
    w = 2 * np.pi * np.asarray(f_hz)
    _, h_hp = signal.freqs(*signal.butter(8, 2 * np.pi * fh, "highpass", analog=True), worN=w)
    _, h_lp = signal.freqs(*signal.butter(8, 2 * np.pi * fl, "lowpass", analog=True), worN=w)
    return g * np.abs(h_hp * h_lp) ** 2


def test_transmissibility_matches_python_control():
    f = np.geomspace(0.05, 80.0, 400)
    for seat in (DEFAULT_SEAT, SeatModel(mass_kg=60.0, stiffness_N_per_m=4000.0, damping_N_s_per_m=150.0)):
        h = seat.transmissibility(f)
        assert np.max(np.abs(h - _control_transmissibility(seat, f)) / np.abs(h)) < 1e-9
        # the resonance near f_n and isolation above √2 f_n
        assert abs(h[np.argmin(abs(f - seat.natural_frequency_hz))]) > 1.5
        assert np.all(np.abs(h[f > 1.5 * seat.natural_frequency_hz]) < 1.0)


@pytest.mark.parametrize("f_hz", [0.7, 1.6, 4.0, 12.0])
def test_sine_floor_gives_the_closed_form_steady_state(f_hz):
    """a_f = A sin ωt: once the start has decayed, the occupant's a = A |H| sin(ωt + ∠H), H = (k + jωc) /
    (k − mω² + jωc), and the travel z = −A m sin(ωt + ∠G) |G|, G = 1 / (k − mω² + jωc)."""
    fs, amp = 500.0, 0.5
    t = np.arange(int(30 * fs)) / fs
    w = 2 * np.pi * f_hz
    m, k, c = DEFAULT_SEAT.mass_kg, DEFAULT_SEAT.stiffness_N_per_m, DEFAULT_SEAT.damping_N_s_per_m
    h = (k + 1j * w * c) / (k - m * w * w + 1j * w * c)
    g = 1 / (k - m * w * w + 1j * w * c)
    r = seat_response(DEFAULT_SEAT, amp * np.sin(w * t), fs)
    late = t > 20.0                   # 20 s: the start decays as exp(-ζ ω_n t), 1e-26
    expected = amp * abs(h) * np.sin(w * t + np.angle(h))
    travel = -amp * m * abs(g) * np.sin(w * t + np.angle(g))
    # the floor is linear between its samples: the sine's chord error is at most (ω/fs)²/8 of its amplitude
    tol = (w / fs) ** 2 / 8 + 1e-7
    assert np.sqrt(np.mean((r.seat_m_s2[late] - expected[late]) ** 2)) < tol * amp * abs(h)
    assert np.sqrt(np.mean((r.travel_m[late] - travel[late]) ** 2)) < tol * amp * m * abs(g)
    assert r.end_stop_hits == 0 and r.end_stop_share == 0.0


@pytest.mark.parametrize("name", ["I", "II", "III"])
def test_seat_factor_of_the_linear_seat_within_2_percent_of_the_frequency_domain(name):
    """Time domain (a random record of the class, the seat stepped, both Wk-weighted by the package) against
    √(∫|Wk H|² S df / ∫|Wk|² S df) with python-control's H, Annex A's Wk and scipy's Butterworth PSD."""
    f = np.linspace(0.05, 60.0, 60000)
    wk2s = _wk_magnitude(f) ** 2 * _class_psd(f, name)
    h = _control_transmissibility(LONG, f)
    reference = math.sqrt(np.trapezoid(wk2s * np.abs(h) ** 2, f) / np.trapezoid(wk2s, f))
    got = class_seat_factor(LONG, name, duration_s=60.0, seed=3)
    assert got["end_stops"]["hits"] == 0                        # the linear regime the reference describes
    assert got["seat_factor"] == pytest.approx(reference, rel=0.02)       # measured 0.1-0.3 % low
    assert got["seat_factor_linear"] == pytest.approx(reference, rel=0.005)
    # the floor's unweighted RMS is the class's, which the toolbox's test signals are scaled to
    assert got["input_rms"] == pytest.approx(CLASSES[name][3], rel=0.01)
    assert math.sqrt(np.trapezoid(_class_psd(f, name), f)) == pytest.approx(CLASSES[name][3], rel=0.01)


def test_class_of_a_tractor_mass():
    assert [class_of_mass(m) for m in (1500.0, 3600.0, 3601.0, 6500.0, 6501.0, 15000.0)] == \
        ["I", "I", "II", "II", "III", "III"]


def test_class_record_has_the_class_psd():
    fs = 200.0
    x = class_record("II", duration_s=400.0, sample_rate_hz=fs, seed=5)
    f, pxx = signal.welch(x, fs, nperseg=4096)
    band = (f > 1.8) & (f < 3.0)
    assert np.mean(pxx[band]) == pytest.approx(np.mean(_class_psd(f[band], "II")), rel=0.05)
    assert np.std(x) == pytest.approx(CLASSES["II"][3], rel=0.01)
    assert np.allclose(class_psd(f, "II"), _class_psd(f, "II"), rtol=1e-9, atol=1e-12)


def test_large_input_hits_the_end_stops_and_the_travel_stays_near_the_free_travel():
    """A 5 m/s² sine at the natural frequency: the linear seat would travel about 80 mm; with ±50 mm and the
    end stops the travel stays close to 50 mm, and the motion is scipy's solve_ivp of the same equation."""
    seat, fs, amp = DEFAULT_SEAT, 500.0, 5.0
    w = 2 * np.pi * seat.natural_frequency_hz
    m, k, c, d, ks = (seat.mass_kg, seat.stiffness_N_per_m, seat.damping_N_s_per_m, seat.travel_m,
                      seat.end_stop_stiffness_N_per_m)
    linear = amp * m / abs(k - m * w * w + 1j * w * c)
    assert linear > 1.5 * d
    t = np.arange(int(20 * fs)) / fs
    r = seat_response(seat, amp * np.sin(w * t), fs)

    def rhs(tt, y):
        z, v = y
        stop = ks * (z - d) if z > d else ks * (z + d) if z < -d else 0.0
        return [v, -(c * v + k * z + stop) / m - amp * np.sin(w * tt)]

    ref = solve_ivp(rhs, (0, t[-1]), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-10, atol=1e-12, max_step=2e-3)
    assert np.sqrt(np.mean((r.travel_m - ref.y[0]) ** 2)) < 1e-3 * d
    hit = np.abs(ref.y[0]) > d
    assert r.end_stop_hits == int(np.count_nonzero(hit[1:] & ~hit[:-1]))
    assert r.end_stop_hits >= 2 * 20 * seat.natural_frequency_hz * 0.8      # both stops, nearly every cycle
    assert d < r.max_travel_m < 1.25 * d
    assert r.end_stop_share == pytest.approx(hit.mean(), abs=2e-3)


def _body():
    from identification.model.tractor import Body
    from tractor_cases import LOADS, TIRES

    return Body(TIRES, LOADS, 2.6, pitch=True, roll=True, pitch_index=0.8, roll_index=0.5)


def test_ride_on_a_soft_seat_isolates_and_a_stiff_seat_follows_the_floor():
    """On a class C road the floor's Wk-weighted motion lies above 1.4 Hz: a 1 Hz seat isolates it (SEAT < 1),
    a 40 Hz seat passes it (SEAT 1 +- 2 %); both as the linear seat predicts from the floor's own spectrum
    (Welch PSD through python-control's H and Annex A's Wk)."""
    from identification.comfort.ride import ROAD_SPACING_M, ride
    from identification.comfort.road import road_profile
    from tractor_cases import C, K, TIRES

    seats = {"soft": SeatModel(stiffness_N_per_m=3600.0, damping_N_s_per_m=340.0, travel_m=0.1),
             "stiff": SeatModel(stiffness_N_per_m=90.0 * (2 * math.pi * 40.0) ** 2, damping_N_s_per_m=22600.0)}
    sets = {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}
    road = road_profile("C", 2.0 * 40.0 + 1.0, ROAD_SPACING_M, 2)
    runs = {name: ride(_body(), sets, road=road, speed_m_s=2.0, duration_s=40.0, seat=seat)["t"]
            for name, seat in seats.items()}
    floor = runs["soft"].suspension.floor
    assert runs["stiff"].suspension.floor.a_w == pytest.approx(floor.a_w, rel=1e-12)
    for name, run in runs.items():
        assert run.comfort.a_w == pytest.approx(run.suspension.seat_factor * floor.a_w)
        assert run.axes.axes["z"].a_w == pytest.approx(run.comfort.a_w)
        assert run.suspension.response.end_stop_hits == 0
        fs = 1.0 / (run.time_s[1] - run.time_s[0])
        f, pxx = signal.welch(run.suspension.floor_m_s2, fs, nperseg=8192)
        wk2s = _wk_magnitude(f[1:]) ** 2 * pxx[1:]
        linear = math.sqrt(np.sum(wk2s * np.abs(_control_transmissibility(seats[name], f[1:])) ** 2) / np.sum(wk2s))
        assert run.suspension.seat_factor == pytest.approx(linear, rel=0.05), name
    assert runs["soft"].suspension.seat_factor < 0.6 and runs["soft"].comfort.a_w < floor.a_w
    assert runs["stiff"].suspension.seat_factor == pytest.approx(1.0, abs=0.02)


def test_seat_a_w_in_rides_on_an_iso_8608_road_matches_the_spectral_prediction():
    """The occupant's a_w over three 300 s rides on class C roads against √(∫ |Wk H|² Σ_ij G_i S_ij G_j* df), with
    the floor's transfers G_i and the seat's H from python-control, Annex A's Wk coded here (tests/test_ride.py's
    reference with the seat added); the package's own PSD prediction (``psd_rating`` with the seat) as well."""
    from identification.comfort.expected import psd_rating
    from identification.comfort.ride import ROAD_SPACING_M, ride
    from identification.comfort.road import iso8608_psd, road_profile, track_coherence
    from identification.model.ride import seat_row
    from test_ride import SEAT_X, SEAT_Y, SPEED, WHEELBASE, _body as ride_body, _seat_transfer
    from tractor_cases import C, K, TIRES

    seat = SeatModel(stiffness_N_per_m=3600.0, damping_N_s_per_m=340.0, travel_m=0.1)
    body, duration, squares = ride_body(False), 300.0, []
    sets = {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}
    for seed in (1, 2, 3):
        road = road_profile("C", SPEED * duration + 1.0, ROAD_SPACING_M, seed)
        run = ride(body, sets, road=road, speed_m_s=SPEED, duration_s=duration, seat_x_m=SEAT_X, seat_y=SEAT_Y,
                   seat=seat)["t"]
        assert run.suspension.response.end_stop_hits == 0
        squares.append(run.comfort.a_w ** 2)
    simulated = math.sqrt(np.mean(squares))
    f = np.linspace(0.05, 40.0, 8000)
    n = f / SPEED
    S = iso8608_psd(n, "C") / SPEED
    gamma = np.sqrt(track_coherence(n, road.track_width_m, decay=road.coherence_decay))
    delay = np.array([0.0, 0.0, WHEELBASE / SPEED, WHEELBASE / SPEED])
    left = np.array([True, False, True, False])
    floor_psd = np.zeros_like(f)
    for m, fm in enumerate(f):
        G = _seat_transfer(body, 2 * math.pi * fm) * np.exp(-2j * math.pi * fm * delay)
        floor_psd[m] = np.real(G @ (np.where(left[:, None] == left[None, :], 1.0, gamma[m]) * S[m]) @ G.conj())
    h2 = np.abs(_control_transmissibility(seat, f)) ** 2
    predicted = math.sqrt(np.trapezoid(_wk_magnitude(f) ** 2 * h2 * floor_psd, f))
    assert simulated == pytest.approx(predicted, rel=0.03), (simulated, predicted)        # measured -0.4 %
    package = psd_rating(body, dict(zip(TIRES, K)), dict(zip(TIRES, C)), seat_row(body, seat_x_m=SEAT_X, seat_y=SEAT_Y),
                         road=road, speed_m_s=SPEED, transfer=seat.transmissibility)
    assert package == pytest.approx(predicted, rel=0.01)


@pytest.fixture
def seat_file(tmp_path):
    def write(text, name="seat.json"):
        path = tmp_path / name
        path.write_text(text)
        return path
    return write


def test_seat_command_prints_every_class_and_json(cli, seat_file):
    path = seat_file(json.dumps({"mass_kg": 80, "stiffness_N_per_m": 5000, "comment": "soft"}))
    r = cli("seat", path, "--class", "II", "--duration-s", "20", "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    seat = SeatModel(mass_kg=80.0, stiffness_N_per_m=5000.0)
    assert doc["seat"]["natural_frequency_hz"] == pytest.approx(math.sqrt(5000 / 80) / (2 * math.pi))
    assert doc["seat"]["damping_N_s_per_m"] == DEFAULT_SEAT.damping_N_s_per_m
    (row,) = doc["classes"]
    assert row["class"] == "II" and row["seat_factor_linear"] == pytest.approx(spectral_seat_factor(seat, "II"))
    r = cli("seat", "--duration-s", "10")
    assert r.code == 0 and [line.split()[0] for line in r.out.splitlines()[3:6]] == ["I", "II", "III"], r.out


@pytest.mark.parametrize("text, args, problem", [
    (None, ["missing.json"], "no such file"),
    ("{\"mass_kg\": 90,", [], "malformed JSON"),
    ("{\"mass_kg\": 90, \"mass_kg\": 80}", [], "appears twice"),
    ("[90]", [], "JSON object"),
    ("{\"mass\": 90}", [], "unknown key 'mass'"),
    ("{\"mass_kg\": -5}", [], "mass_kg"),
    ("{\"travel_m\": \"50 mm\"}", [], "travel_m must be a number"),
    ("{\"damping_N_s_per_m\": true}", [], "damping_N_s_per_m must be a number"),
    ("{}", ["--class", "IV"], "--class"),
    ("{}", ["--duration-s", "1"], "--duration-s"),
])
def test_bad_seat_files_and_options_end_in_one_line_exit_2(cli, seat_file, text, args, problem):
    path = seat_file(text) if text is not None else None
    argv = [path] + args if path is not None else args
    r = cli("seat", *argv)
    assert r.code == 2, r
    assert r.err.count("\n") == 1 and r.err.startswith("cleatfmu: error: ") and problem in r.err, r.err
    assert "Traceback" not in r.err and r.out == ""
    if path is not None and not args:
        assert str(path) in r.err
        r = cli("ride", "--example", "7kmh", "--seat", path)
        assert r.code == 2 and r.err.count("\n") == 1 and str(path) in r.err and problem in r.err, r.err


def test_ride_seat_on_the_embedded_example(cli, seat_file, example_diagnosis):
    """``ride --seat`` on the 7 km/h day: a 1 Hz seat isolates the floor (SEAT < 1); x and y are the floor's."""
    path = seat_file(json.dumps({"stiffness_N_per_m": 3600, "damping_N_s_per_m": 340}))
    r = cli("ride", "--example", "7kmh", "--compare", "final", "--duration-s", "20", "--realisations", "1",
            "--seat", path, "--workers", "1", "--json", "--body", example_diagnosis)
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    entry = doc["sets"]["final"]
    susp = entry["suspended_seat"]
    assert doc["seat"]["suspension"]["stiffness_N_per_m"] == 3600 and "suspended seat" in doc["seat"]["values"]
    assert entry["a_w"] == susp["seat"]["a_w"] < susp["floor"]["a_w"]
    assert susp["seat_factor"] == pytest.approx(entry["a_w"] / susp["floor"]["a_w"]) and susp["seat_factor"] < 1.0
    assert entry["three_axes"]["axes"]["z"]["a_w"] == pytest.approx(entry["a_w"])
    assert entry["expected"]["psd"]["seat_factor_linear"] < 1.0
    assert entry["expected"]["seat_factor"]["mean"] == pytest.approx(susp["seat_factor"])
    # the tractor's ISO 5007 class by its mass (ISO 5007's scope: I up to 3600 kg, II to 6500 kg, III above)
    iso = doc["seat"]["iso5007"]
    mass = iso["tractor_mass_kg"]
    assert iso["class"] == ("I" if mass <= 3600 else "II" if mass <= 6500 else "III")
    f = np.linspace(0.05, 60.0, 60000)
    wk2s = _wk_magnitude(f) ** 2 * _class_psd(f, iso["class"])
    h2 = np.abs(_control_transmissibility(SeatModel(stiffness_N_per_m=3600, damping_N_s_per_m=340), f)) ** 2
    assert iso["seat_factor_linear"] == pytest.approx(math.sqrt(np.trapezoid(wk2s * h2, f) / np.trapezoid(wk2s, f)),
                                                      rel=0.005)
