"""The whole tractor on a road profile: the seat's acceleration against python-control's frequency response."""

import json
import math

import control
import numpy as np
import pytest

from identification.model import tire_law
from identification.comfort.ride import seat_acceleration
from identification.model.ride import RAMP_M, ride_model, seat_row
from identification.model.kernels import run_model
from identification.model.tractor import Body

from tractor_cases import C, K, LOADS, TIRES

WHEELBASE = 2.6
SPEED = 2.0          # m/s
SEAT_X, SEAT_Y = 1.4, 0.3


def _body(pivot):
    return Body(TIRES, LOADS, WHEELBASE, pitch=True, roll=True, pivot=pivot, pitch_index=0.8, roll_index=0.5,
                pivot_index=0.06)


def _laws():
    return [dict(tire_law.EXTENDED_DEFAULTS, stiffness=k, damping=c, static_load=w) for k, c, w in zip(K, C, LOADS)]


def _seat_transfer(body, omega):
    """Seat acceleration per unit road height under each tire at `omega`, from python-control: the linear
    tractor M q'' = J^T (K (r - J q) + C (r' - J q')), inputs (r, r')."""
    J, mass, _ = body.matrices()
    nq = J.shape[1]
    k, c = np.diag(K), np.diag(C)
    Minv = np.diag(1.0 / mass)
    A = np.block([[np.zeros((nq, nq)), np.eye(nq)], [-Minv @ J.T @ k @ J, -Minv @ J.T @ c @ J]])
    B = np.block([[np.zeros((nq, 8))], [Minv @ J.T @ k, Minv @ J.T @ c]])
    row = seat_row(body, seat_x_m=SEAT_X, seat_y=SEAT_Y)
    Cq = row @ A[nq:, :]
    D = row @ B[nq:, :]
    sys = control.ss(A, B, Cq[None, :], D[None, :])
    G = np.asarray(sys(1j * omega)).reshape(8)
    return G[:4] + 1j * omega * G[4:]        # r' = j omega r


@pytest.mark.parametrize("pivot", [False, True], ids=["rigid", "pivot"])
@pytest.mark.parametrize("wavelength_m", [1.0, 0.45])
def test_seat_acceleration_on_a_sinusoidal_left_track_matches_python_control(pivot, wavelength_m):
    amplitude = 0.01
    x = np.arange(0.0, 40.0, 0.002)
    left = amplitude * np.sin(2 * math.pi * x / wavelength_m)
    body = _body(pivot)
    model = ride_model(body, _laws(), speed_m_s=SPEED, road_x_m=x, road_left_m=left, road_right_m=np.zeros_like(x))
    traj = run_model(model, *model.grid(0.0, 12.0, 5e-4))
    seat = seat_acceleration(model, traj, seat_x_m=SEAT_X, seat_y=SEAT_Y)
    t = traj.time_s
    keep = t > (RAMP_M + WHEELBASE) / SPEED + 4.0        # both axles past the fade, the transient gone
    omega = 2 * math.pi * SPEED / wavelength_m
    # the left tires' roads: front sin(omega t), rear delayed by the wheelbase; right tracks flat
    G = _seat_transfer(body, omega)
    phasor = amplitude * (G[0] + G[2] * np.exp(-1j * omega * WHEELBASE / SPEED))
    expected = np.imag(phasor * np.exp(1j * omega * t[keep]))
    err = math.sqrt(np.mean((seat[keep] - expected) ** 2) / np.mean(expected ** 2))
    assert err < 0.005, err


def test_hubs_see_the_road_a_wheelbase_apart_and_the_faded_start():
    x = np.arange(0.0, 30.0, 0.01)
    left, right = 0.02 * np.sin(x), -0.01 * np.cos(x)
    model = ride_model(_body(False), _laws(), speed_m_s=SPEED, road_x_m=x, road_left_m=left, road_right_m=right)
    start, h, n = model.grid(0.0, 10.0, 1e-3)
    road = model.inputs(start, h, n)
    t = start + h * np.arange(n)
    assert np.all(road.road_z[:, 0] == 0.0) and np.all(road.road_vz[:, 0] == 0.0)   # starts on level ground
    late = t > (RAMP_M + WHEELBASE) / SPEED
    np.testing.assert_allclose(road.road_z[0, late], np.interp(SPEED * t[late], x, left), atol=1e-6)
    np.testing.assert_allclose(road.road_z[2, late], np.interp(SPEED * t[late] - WHEELBASE, x, left), atol=1e-6)
    np.testing.assert_allclose(road.road_z[3, late], np.interp(SPEED * t[late] - WHEELBASE, x, right), atol=1e-6)
    # the rate is the height's time derivative
    np.testing.assert_allclose(road.road_vz[1, 1:-1], np.gradient(road.road_z[1], h)[1:-1], atol=2e-4)


def test_seat_a_w_on_an_iso_8608_road_matches_the_spectral_prediction():
    """a_w of the simulated ride against sqrt(∫ |Wk|² Σ_ij G_i S_ij G_j* df): python-control's seat transfers,
    the class's PSD seen at the speed, the rear inputs a wheelbase later, the tracks' coherence."""
    from identification.comfort.iso2631 import weighting_response
    from identification.comfort.ride import ROAD_SPACING_M, ride
    from identification.comfort.road import iso8608_psd, road_profile, track_coherence

    body = _body(False)
    duration, seats = 300.0, []
    sets = {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}
    for seed in (1, 2, 3):
        road = road_profile("C", SPEED * duration + 1.0, ROAD_SPACING_M, seed)
        run = ride(body, sets, road=road, speed_m_s=SPEED, duration_s=duration, seat_x_m=SEAT_X, seat_y=SEAT_Y)["t"]
        seats.append(run.comfort.a_w ** 2)
    simulated = math.sqrt(np.mean(seats))

    f = np.linspace(0.05, 40.0, 8000)
    n = f / SPEED
    S = iso8608_psd(n, "C") / SPEED                       # one-sided temporal PSD of each track, m²/Hz
    gamma = np.sqrt(track_coherence(n, road.track_width_m, decay=road.coherence_decay))
    delay = np.array([0.0, 0.0, WHEELBASE / SPEED, WHEELBASE / SPEED])
    left = np.array([True, False, True, False])
    seat_psd = np.zeros_like(f)
    for m, fm in enumerate(f):
        w = 2 * math.pi * fm
        G = _seat_transfer(body, w) * np.exp(-1j * w * delay)
        coh = np.where(left[:, None] == left[None, :], 1.0, gamma[m])
        seat_psd[m] = np.real(G @ (coh * S[m]) @ G.conj())
    weighted = np.abs(weighting_response(f, "Wk")) ** 2 * seat_psd
    predicted = math.sqrt(np.trapezoid(weighted, f))
    # per seed the a_w scatter about 1 %; measured -0.2 % (a 5 cm road grid: -3 %, its linear interpolation)
    assert simulated == pytest.approx(predicted, rel=0.03), (simulated, predicted)


@pytest.mark.parametrize("args, source", [
    (["--road", "Q"], "--road"),
    (["--compare", "paper,foo"], "--compare"),
    (["--compare", "static=abc"], "--compare"),
    (["--compare", "static=5"], "--compare"),
    (["--compare", "final,final"], "--compare"),
    (["--duration-s", "2"], "--duration-s"),
    (["--speed-kmh", "nan"], "--speed-kmh"),
    (["--seat-y", "7"], "--seat-y"),
    (["--seat-x-m", "40"], "--seat-x-m"),
    (["--exposure-h", "30"], "--exposure-h"),
    (["--realisations", "0"], "--realisations"),
    (["--seed", "-1"], "--seed"),
    (["--seat-height-m", "9"], "--seat-height-m"),
])
def test_ride_bad_options_end_in_one_line_exit_2_and_nothing_written(cli, tmp_path, args, source):
    plot = tmp_path / "ride.png"
    r = cli("ride", "--example", "7kmh", "--plot", plot, *args)
    assert r.code == 2, r
    assert r.err.count("\n") == 1 and r.err.startswith(f"cleatfmu: error: {source}:"), r.err
    assert r.out == "" and not plot.exists()


def test_static_set_from_a_compression_test_file(tmp_path):
    """static=FILE takes the compression test's eq. 18 stiffness (a line of 295.08 kN/m through the points)."""
    from identification.comfort.ride import _stiffness, check_set_names

    d = np.linspace(0.0, 0.03, 31)
    path = tmp_path / "compression.csv"
    path.write_text("deformation_m,force_N\n" + "".join(f"{float(x)!r},{float(295.08e3 * x + 120.0)!r}\n" for x in d))
    assert check_set_names([f"static={path}", "final"]) == [f"static={path}", "final"]
    assert _stiffness(f"static={path}") == pytest.approx(295.08e3, rel=1e-9)
    with pytest.raises(Exception, match="compression test's CSV"):
        _stiffness(f"static={tmp_path / 'missing.csv'}")


def test_fmu_set_takes_k_and_c_from_the_four_tire_fmus(tmp_path):
    """fmu=DIR: the stiffness and damping the exported tire FMUs carry (their start values), per tire."""
    from build_scripts import build_fmu
    from identification.comfort.ride import _fmu_set, check_set_names
    from identification.errors import InputError

    values = {"FL": (431e3, 2100.0), "FR": (447e3, 2300.0), "RL": (512e3, 3900.0), "RR": (530e3, 4100.0)}
    for t, (k, c) in values.items():
        build_fmu("point_contact", tmp_path / f"day_{t}.fmu", backend="native", platforms=["linux64"],
                  start_values={"stiffness": k, "damping": c})
    assert check_set_names([f"fmu={tmp_path}", "final"]) == [f"fmu={tmp_path}", "final"]
    k, c = _fmu_set(f"fmu={tmp_path}")
    assert k == {t: v[0] for t, v in values.items()} and c == {t: v[1] for t, v in values.items()}
    (tmp_path / "day_RR.fmu").unlink()
    with pytest.raises(InputError, match=r"\*_RR\.fmu"):
        check_set_names([f"fmu={tmp_path}"])


def test_params_set_takes_k_and_c_from_an_identify_json_of_the_four_tires(tmp_path, cli):
    """params=FILE: the k and c of ``identify --json`` (here of the embedded day, paper's method), per tire;
    a file lacking a tire is refused naming it."""
    from identification.comfort.ride import _params_set, check_set_names
    from identification.errors import InputError

    res = cli("identify", "--example", "7kmh", "--json")
    assert res.code == 0, res.err
    path = tmp_path / "params.json"
    path.write_text(res.out)
    tires = json.loads(res.out)["tires"]
    assert check_set_names([f"params={path}", "final"]) == [f"params={path}", "final"]
    k, c = _params_set(f"params={path}")
    assert k == {t: tires[t]["k"] for t in ("FL", "FR", "RL", "RR")}
    assert c == {t: tires[t]["c"] for t in ("FL", "FR", "RL", "RR")}
    doc = json.loads(res.out)
    del doc["tires"]["RL"]
    path.write_text(json.dumps(doc))
    with pytest.raises(InputError, match="no tire 'RL'") as info:
        check_set_names([f"params={path}"])
    assert str(path) in str(info.value)
