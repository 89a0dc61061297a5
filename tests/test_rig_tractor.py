"""The rigid and the pivoting-front-axle tractor against independent linear references, and the stagger sign.

The references are built here from the geometry alone (wheel loads, wheelbase,
track, inertias): generalized coordinates, J, M, K = Jᵀ diag(k) J and
C = Jᵀ diag(c) J, with python-control's impulse responses to the road rate.
Nothing of the rig's plant is imported.
"""

import control
import numpy as np
import pytest

from identification.recording import STANDARD_GRAVITY
from identification.rig import run_rig

FS = 1000.0
TIRES = ("FL", "FR", "RL", "RR")
# 7.2 km/h = 2 m/s: t0, the cleat's edges, the stagger and the wheelbase all fall on the 1 kHz grid.
PLANT_ONLY = {"speed_kmh": 7.2, "sensor.noise_m_s2": 0.0, "sensor.aa_order": 0, "sensor.highpass_hz": 0.0}


def nrmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b ** 2)))


def pulse_response(sys, pulses, n):
    """Outputs (n_out, n) at t = j / FS, j < n, of `sys` (D ignored) to road-rate impulses.

    `pulses` is a list of (time s, input index, area); times may be negative (before the record).
    """
    idx = [(int(round(t * FS)), i, a) for t, i, a in pulses]
    for (t, _, _), (j, _, _) in zip(pulses, idx):
        assert abs(j / FS - t) < 1e-9, t
    extra = max(0, -min(j for j, _, _ in idx))
    sys = control.ss(sys.A, sys.B, sys.C, np.zeros_like(sys.D))  # the impulse itself is not sampled
    resp = np.asarray(control.impulse_response(sys, np.arange(n + extra) / FS).outputs)
    resp = resp.reshape(sys.noutputs, sys.ninputs, -1)
    y = np.zeros((sys.noutputs, n))
    for j, i, a in idx:
        k0 = max(j, 0)
        y[:, k0:] += a * resp[:, i, k0 - j: n - j]
    return y


def cleat_pulses(p, arrivals, tires=range(4), signs=(1, 1, 1, 1)):
    """Rectangular cleat under each tire as road-rate impulses: +H at the arrival, -H a width later."""
    h, dt = p["cleat.height_m"], p["cleat.width_m"] / (p["speed_kmh"] / 3.6)
    out = []
    for k, i in enumerate(tires):
        out += [(arrivals[i], k, signs[k] * h), (arrivals[i] + dt, k, -signs[k] * h)]
    return out


def expected_arrivals(p):
    v = p["speed_kmh"] / 3.6
    s, L = p["cleat.stagger_m"], p["vehicle.wheelbase_m"]
    return p["t0_s"] + np.array([0.0, s, L, L + s]) / v


def tractor_reference(p):
    """State space (road rate of the four tires -> four hub accelerations) of the tractor in `p`."""
    load = np.array([p[f"tire.{t}.load_N"] for t in TIRES])
    k = np.array([p[f"tire.{t}.k_N_m"] for t in TIRES])
    c = np.array([p[f"tire.{t}.c_Ns_m"] for t in TIRES])
    L, half = p["vehicle.wheelbase_m"], p["vehicle.track_m"] / 2
    mass = load.sum() / STANDARD_GRAVITY
    x = np.array([L, L, 0.0, 0.0])
    yl = np.array([half, -half, half, -half])
    x_cg, y_cg = load @ x / load.sum(), load @ yl / load.sum()
    a, b = L - x_cg, x_cg
    masses = [mass, p["axle_coupling.pitch_dynamic_index"] * mass * a * b,
              mass * p["axle_coupling.roll_gyration_m"] ** 2]
    if p["axle_coupling.front_axle_pivot"]:
        # (z, theta, phi body roll, psi front-axle roll); the pivot at y = 0 moves with the body
        J = np.array([[1.0, L - x_cg, -y_cg, half],
                      [1.0, L - x_cg, -y_cg, -half],
                      [1.0, -x_cg, half - y_cg, 0.0],
                      [1.0, -x_cg, -half - y_cg, 0.0]])
        masses.append(p["axle_coupling.front_axle_roll_inertia_kg_m2"])
    else:
        J = np.column_stack([np.ones(4), x - x_cg, yl - y_cg])
    n = J.shape[1]
    Mi = np.diag(1.0 / np.array(masses))
    K, C = J.T @ np.diag(k) @ J, J.T @ np.diag(c) @ J
    # states (q, q', r), input r'
    A = np.zeros((2 * n + 4, 2 * n + 4))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -Mi @ K
    A[n:2 * n, n:2 * n] = -Mi @ C
    A[n:2 * n, 2 * n:] = Mi @ J.T @ np.diag(k)
    B = np.vstack([np.zeros((n, 4)), Mi @ J.T @ np.diag(c), np.eye(4)])
    return control.ss(A, B, J @ A[n:2 * n], J @ B[n:2 * n]), J, load


def edge_mask(n, pulses):
    keep = np.ones(n, bool)  # the value exactly on a step is one-sided: skip those samples
    keep[[int(round(t * FS)) for t, _, _ in pulses if 0 <= round(t * FS) < n]] = False
    return keep


@pytest.mark.parametrize("pivot,stagger,loads", [
    (0, 0.2, {}), (1, 0.2, {}),
    (0, -0.2, {"tire.FL.load_N": 11800.0, "tire.RR.load_N": 15300.0}),  # off-centre centre of gravity
    (1, -0.2, {"tire.FL.load_N": 11800.0, "tire.RR.load_N": 15300.0}),
])
def test_tractor_matches_python_control(pivot, stagger, loads):
    run = run_rig(("axle_coupling",), dict(PLANT_ONLY, **loads, **{"cleat.stagger_m": stagger,
                                                                   "axle_coupling.front_axle_pivot": pivot}))
    p = run.truth["parameters"]
    arrivals = expected_arrivals(p)
    assert [run.truth["tires"][t]["arrival_s"] for t in TIRES] == pytest.approx(arrivals, abs=1e-12)
    sys, J, load = tractor_reference(p)
    assert run.truth["body"]["front_axle"] == ("pivot" if pivot else "rigid")
    assert abs(run.truth["body"]["cg_left_of_centre_m"]) > (0.005 if loads else -1)
    pulses = cleat_pulses(p, arrivals)
    n = run.recording.time_s.size
    ref = pulse_response(sys, pulses, n)
    keep = edge_mask(n, pulses)
    for i, tire in enumerate(TIRES):
        err = nrmse(run.recording.accel_m_s2[tire][keep], ref[i][keep])
        assert err < 1e-4, (tire, err)
    # the given static loads are the equilibrium (a wrong G would show ~1 m/s2 here; 1e-8 is solver noise)
    assert np.max(np.abs(run.accel_true_m_s2[:, :int(0.9 * arrivals.min() * FS)])) < 1e-6


SYMMETRIC_TIRES = {"tire.FR.k_N_m": 550e3, "tire.FR.c_Ns_m": 4200.0, "tire.RR.k_N_m": 420e3, "tire.RR.c_Ns_m": 2400.0}


def test_pivoting_front_axle_carries_no_roll_moment():
    """With equal front tires, I_axle psi'' = (track/2)(F_FL - F_FR) involves psi alone.

    The front hubs' difference a_FL - a_FR = track psi'' is then a one-degree-of-freedom
    response to the road difference, whatever the body does; and the body, with its centre of
    gravity on the centre line, does not roll before the rear tires meet their cleats.
    """
    over = dict(PLANT_ONLY, **SYMMETRIC_TIRES, **{"cleat.stagger_m": 0.2})
    piv = run_rig(("axle_coupling",), dict(over, **{"axle_coupling.front_axle_pivot": 1,
                                                   "axle_coupling.front_axle_roll_inertia_kg_m2": 150.0}))
    rigid = run_rig(("axle_coupling",), over)
    p = piv.truth["parameters"]
    T, I_axle = p["vehicle.track_m"], p["axle_coupling.front_axle_roll_inertia_kg_m2"]
    k, c = p["tire.FL.k_N_m"], p["tire.FL.c_Ns_m"]
    axle = control.ss(control.tf([T * T / 2 * c, T * T / 2 * k, 0.0], [I_axle, c * T * T / 2, k * T * T / 2]))
    arrivals = expected_arrivals(p)
    pulses = cleat_pulses(p, arrivals, tires=(0, 1), signs=(1, -1))
    for i in range(len(pulses)):
        pulses[i] = (pulses[i][0], 0, pulses[i][2])  # one input: the road difference r_FL - r_FR
    n = piv.recording.time_s.size
    ref = pulse_response(axle, pulses, n)[0]
    keep = edge_mask(n, pulses)
    acc = {name: run.recording.accel_m_s2 for name, run in (("pivot", piv), ("rigid", rigid))}
    diff = {name: a["FL"] - a["FR"] for name, a in acc.items()}
    assert nrmse(diff["pivot"][keep], ref[keep]) < 1e-4
    assert nrmse(diff["rigid"][keep], ref[keep]) > 0.3  # the check can tell a rigid axle
    before_rear = piv.recording.time_s < arrivals[2:].min() - 1e-3
    roll = {name: np.abs(a["RL"] - a["RR"])[before_rear].max() for name, a in acc.items()}
    assert roll["pivot"] < 1e-8 * np.abs(acc["pivot"]["FL"]).max(), roll
    assert roll["rigid"] > 0.1, roll


@pytest.mark.parametrize("effects,pivot", [((), 0), (("axle_coupling",), 0), (("axle_coupling",), 1)])
def test_negative_stagger_right_cleat_first(effects, pivot):
    run = run_rig(effects, dict(PLANT_ONLY, **{"cleat.stagger_m": -0.3, "axle_coupling.front_axle_pivot": pivot}))
    tt = run.truth["tires"]
    arr = {t: tt[t]["arrival_s"] for t in TIRES}
    assert arr["FR"] < arr["FL"] < arr["RR"] < arr["RL"]
    assert [arr[t] for t in TIRES] == pytest.approx([0.5, 0.35, 1.885, 1.735], abs=1e-12)
    assert tt["FR"]["excitation_s"][0] < tt["FL"]["excitation_s"][0]
    assert tt["RR"]["excitation_s"][0] < tt["RL"]["excitation_s"][0]
    t, acc = run.recording.time_s, dict(zip(TIRES, run.accel_true_m_s2))
    assert t[np.argmax(np.abs(acc["FR"]) > 1.0)] == pytest.approx(0.35, abs=2e-3)  # nothing moves before
    if not pivot:  # the right hub moves first and most, right after its hit (a pivoting axle moves both front hubs alike)
        win = (t >= 0.35) & (t < 0.37)
        assert np.abs(acc["FR"][win]).max() > 3 * np.abs(acc["FL"][win]).max()
        win = (t >= 1.735) & (t < 1.755)
        assert np.abs(acc["RR"][win]).max() > 3 * np.abs(acc["RL"][win]).max()


def test_simulation_starts_before_the_earliest_hit():
    """A right-hand cleat so far ahead that FR hits it before t = 0: the record starts mid-response."""
    run = run_rig((), dict(PLANT_ONLY, **{"cleat.stagger_m": -0.5, "t0_s": 0.1, "duration_s": 2.0}))
    p = run.truth["parameters"]
    fr = run.truth["tires"]["FR"]
    assert fr["arrival_s"] == pytest.approx(-0.15, abs=1e-12)
    m, k, c = fr["mass"], fr["k"], fr["c"]
    corner = control.ss(control.tf([c, k, 0.0], [m, c, k]))
    n = run.recording.time_s.size
    pulses = [(t, 0, a) for t, _, a in cleat_pulses(p, expected_arrivals(p), tires=(1,))]
    ref = pulse_response(corner, pulses, n)[0]
    assert abs(ref[0]) > 1.0  # still ringing at t = 0
    assert nrmse(run.recording.accel_m_s2["FR"], ref) < 1e-4


@pytest.mark.parametrize("pivot", [0, 1])
def test_truth_reports_body_indices(pivot):
    over = {"duration_s": 1.5, "axle_coupling.front_axle_pivot": pivot, "axle_coupling.roll_gyration_m": 0.7,
            "axle_coupling.pitch_dynamic_index": 0.9, "axle_coupling.front_axle_roll_inertia_kg_m2": 150.0}
    body = run_rig(("axle_coupling",), over).truth["body"]
    half = 1.90 / 2
    loads = {"FL": 11460.0, "FR": 11600.0, "RL": 15650.0, "RR": 15510.0}
    mass = sum(loads.values()) / STANDARD_GRAVITY
    assert body["mass_kg"] == pytest.approx(mass, rel=1e-12)
    assert body["roll_dynamic_index"] == pytest.approx(0.7 ** 2 / half ** 2, rel=1e-12)
    assert body["roll_inertia_kg_m2"] == pytest.approx(mass * 0.7 ** 2, rel=1e-12)
    assert body["pitch_dynamic_index"] == pytest.approx(
        body["pitch_inertia_kg_m2"] / (mass * body["cg_behind_front_axle_m"] * body["cg_ahead_of_rear_axle_m"]),
        rel=1e-12)
    assert body["pitch_dynamic_index"] == pytest.approx(0.9, rel=1e-12)
    assert {"cg_behind_front_axle_m", "cg_ahead_of_rear_axle_m", "cg_left_of_centre_m"} <= set(body)
    if pivot:
        m_front = (loads["FL"] + loads["FR"]) / STANDARD_GRAVITY
        assert body["front_axle"] == "pivot"
        assert body["front_axle_roll_inertia_kg_m2"] == 150.0
        assert body["front_axle_roll_index"] == pytest.approx(150.0 / (m_front * half ** 2), rel=1e-12)
    else:
        assert body["front_axle"] == "rigid"
        assert "front_axle_roll_index" not in body and "front_axle_roll_inertia_kg_m2" not in body
