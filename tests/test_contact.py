"""Tires that would pull: tension counted with the linear law, the lift-off law's ride against an independent
nonlinear simulation (scipy's solve_ivp, unilateral tires, no stepping code of the package)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from identification.comfort.contact import LOST_CONTACT_WARN_SHARE, contact_summary, episodes
from identification.comfort.iso2631 import comfort
from identification.comfort.ride import ROAD_SPACING_M, ride
from identification.comfort.road import road_profile
from identification.model.ride import RAMP_M
from identification.model.tractor import Body

from tractor_cases import C, K, LOADS, TIRES

G = 9.80665
WHEELBASE = 2.6
SPEED = 15 / 3.6
SEAT_X, SEAT_Y = 2.2, 0.3
PITCH_INDEX, ROLL_INDEX = 0.8, 0.5
DURATION = 20.0


def _hand_matrices():
    """J and M of the rigid tractor written out from the model's definition: heave z, pitch θ (nose up, the
    front hubs at +a θ, the rear at −b θ), roll scaled by the half-track w (hubs at (s − ȳ) w)."""
    W = np.array(LOADS)
    a = WHEELBASE * (W[2] + W[3]) / W.sum()
    b = WHEELBASE - a
    s = np.array([1.0, -1.0, 1.0, -1.0])
    ybar = (s * W).sum() / W.sum()
    J = np.column_stack([np.ones(4), [a, a, -b, -b], s - ybar])
    m = W.sum() / G
    return J, np.array([m, PITCH_INDEX * m * a * b, ROLL_INDEX * m]), np.array([1.0, a - SEAT_X, SEAT_Y - ybar])


def _independent_seat(road, t_eval):
    """Seat acceleration of the tractor with unilateral linear tires on `road`, by solve_ivp (RK45)."""
    J, mass, row = _hand_matrices()
    W, k, c = np.array(LOADS), np.array(K), np.array(C)
    offsets = np.array([0.0, 0.0, WHEELBASE, WHEELBASE])
    left = np.array([True, False, True, False])
    x, dx = road.x_m, road.spacing_m
    tracks = np.vstack([road.left_m, road.right_m])
    slopes = np.diff(tracks, axis=1) / dx                         # the linear interpolant's exact slope

    def road_under(t):
        pos = SPEED * t - offsets
        h = np.where(left, np.interp(pos, x, tracks[0], left=0.0, right=0.0),
                     np.interp(pos, x, tracks[1], left=0.0, right=0.0))
        i = np.clip((pos / dx).astype(int), 0, slopes.shape[1] - 1)
        slope = np.where(pos > 0, slopes[np.where(left, 0, 1), i], 0.0)
        u = np.clip(pos / RAMP_M, 0.0, 1.0)                       # the smoothstep fade over the first 5 m
        fade, dfade = u * u * (3 - 2 * u), np.where((u > 0) & (u < 1), 6 * u * (1 - u) / RAMP_M, 0.0)
        return fade * h, SPEED * (fade * slope + dfade * h)

    def accel(t, y):
        q, dq = y[:3], y[3:]
        r, dr = road_under(t)
        deflection = W / k + r - J @ q                           # static deflection W/k at q = 0, r = 0
        f = k * deflection + c * (dr - J @ dq)
        f = np.where((deflection > 0) & (f > 0), f, 0.0)
        return J.T @ (f - W) / mass, f

    def rhs(t, y):
        return np.concatenate([y[3:], accel(t, y)[0]])

    sol = solve_ivp(rhs, (0.0, t_eval[-1]), np.zeros(6), method="RK45", t_eval=t_eval, max_step=1e-3,
                    rtol=1e-5, atol=1e-8)
    assert sol.success
    qdd = np.column_stack([accel(t, y)[0] for t, y in zip(sol.t, sol.y.T)])
    forces = np.column_stack([accel(t, y)[1] for t, y in zip(sol.t, sol.y.T)])
    return row @ qdd, forces


def test_class_e_at_15_kmh_reports_lift_off_and_its_a_w_matches_an_independent_nonlinear_simulation():
    """Class E at 15 km/h: the linear tires pull (10-14 % of the ride), ``auto`` rides the lift-off law (a
    tire off the ground 9-22 % of the ride), and its seat a_w agrees with solve_ivp's within 1 % (measured
    0.02 %), the shares of lost contact within 0.003 (measured 0.0002)."""
    road = road_profile("E", SPEED * DURATION + 1.0, ROAD_SPACING_M, 3)
    body = Body(TIRES, LOADS, WHEELBASE, pitch=True, roll=True, pitch_index=PITCH_INDEX, roll_index=ROLL_INDEX)
    run = ride(body, {"t": (dict(zip(TIRES, K)), dict(zip(TIRES, C)))}, road=road, speed_m_s=SPEED,
               duration_s=DURATION, seat_x_m=SEAT_X, seat_y=SEAT_Y, tires="auto")["t"]
    assert run.contact["law"] == "lift-off"
    tension = {t: run.contact["tension"][t]["share"] for t in TIRES}
    lost = {t: run.contact["lost_contact"][t]["share"] for t in TIRES}
    assert max(tension.values()) > 0.02 and max(lost.values()) > LOST_CONTACT_WARN_SHARE
    seat, forces = _independent_seat(road, run.time_s)
    reference = comfort(seat, 1e3, "Wk")
    assert run.comfort.a_w == pytest.approx(reference.a_w, rel=0.01), (run.comfort.a_w, reference.a_w)
    step = float(run.time_s[1] - run.time_s[0])
    for j, t in enumerate(TIRES):
        assert lost[t] == pytest.approx(np.mean(forces[j] <= 0.0), abs=0.003), (t, lost[t])
        independent = episodes(forces[j] <= 0.0, step)     # how long and how often, as solve_ivp has it
        assert run.contact["lost_contact"][t]["longest_s"] == pytest.approx(independent["longest_s"], abs=0.005)
        assert run.contact["lost_contact"][t]["episodes"] == pytest.approx(independent["episodes"], rel=0.1, abs=2)


def test_episodes_count_runs_and_durations():
    mask = np.array([0, 1, 1, 0, 0, 1, 1, 1, 1, 0], dtype=bool)
    force = np.array([5.0, -1.0, -3.0, 2.0, 2.0, -0.5, -6.0, -1.0, -0.1, 4.0])
    e = episodes(mask, 0.01, force_n=force, load_n=2.0)
    assert e == {"share": 0.6, "episodes": 2, "longest_s": pytest.approx(0.04), "mean_s": pytest.approx(0.03),
                 "largest_pull": 3.0}
    assert episodes(np.zeros(5, bool), 0.01)["episodes"] == 0


def test_contact_summary_warns_above_the_threshold_only():
    def one(share, law="lift-off", lost=None):
        r = {"law": law, "tension": {t: {"share": share, "longest_s": 0.1, "largest_pull": 1.5} for t in TIRES}}
        if law == "lift-off":
            r["lost_contact"] = {t: {"share": lost, "episodes": 3 if lost else 0, "longest_s": 0.02 + lost}
                                 for t in TIRES}
        return r
    quiet = contact_summary([one(0.02, lost=0.005), one(0.0, "linear")], TIRES)
    assert quiet["warning"] is None and quiet["lost_contact_share"]["FL"] == pytest.approx(0.0025)
    loud = contact_summary([one(0.05, lost=0.03), one(0.01, lost=0.01)], TIRES)
    assert "off the ground 2.0%" in loud["warning"] and loud["lift_off_rides"] == 2
    assert loud["longest_lost_contact_s"]["FL"] == pytest.approx(0.05) and loud["lost_contact_episodes"]["RR"] == 3
    assert quiet["lost_contact_episodes"]["FL"] == 1.5          # the linear ride counts none
    linear = contact_summary([one(0.05, "linear")], TIRES)
    assert "pulls the hub 5.0%" in linear["warning"]


def test_ride_cli_on_class_e_reports_lost_contact_and_warns_in_one_line(cli):
    import json

    res = cli("ride", "--example", "7kmh", "--road", "E", "--speed-kmh", "15", "--compare", "final",
              "--realisations", "2", "--json")
    assert res.code == 0, res.err
    c = json.loads(res.out)["sets"]["final"]["expected"]["contact"]
    assert c["lift_off_rides"] == 2 and max(c["lost_contact_share"].values()) > LOST_CONTACT_WARN_SHARE
    assert max(c["tension_share"].values()) > 0.02 and c["warning"]
    assert res.err.count("\n") == 1 and res.err.startswith("cleatfmu: warning: set final: tire ")
    assert max(c["longest_lost_contact_s"].values()) > 0 and max(c["lost_contact_episodes"].values()) >= 1
    from identification.cli.ride import format_contact
    assert " times per road, at most " in format_contact(json.loads(res.out))
