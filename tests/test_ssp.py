"""The whole tractor as an SSP 1.0 system of native FMUs (body + four tires), run in fmpy, libcosim and a
C master without Python, against the project's master and against the linear system's exact response."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from identification.model import Cleat, TractorModel
from identification.model.tractor import Body
from identification.recording import TIRES
from identification.fmu.ssp import write_tractor_ssp
from identification.fmu.ssp_run import (master_reference, read_system, relative_deviation, run_ssp_fmpy,
                                     run_ssp_libcosim, ssd_step)
from identification.model.tire_law import EXTENDED_DEFAULTS
from native_fixtures import _compile_host, extract, guid

SPEED = 7.0 / 3.6
WHEELBASE = 2.6
LOADS = (14000.0, 16000.0, 24000.0, 26000.0)
SEAT_X = 2.2
STEP = 0.001


def _record(*, pivot: bool, cleat: bool = True, damping=(3000.0, 3200.0, 4000.0, 4200.0), pitch: bool = True,
            roll: bool = True) -> TractorModel:
    body = Body(TIRES, LOADS, WHEELBASE, pitch=pitch, roll=roll, pivot=pivot, pitch_index=0.8, roll_index=1.2,
                pivot_index=0.05)
    laws = []
    for k, c, w in zip((450e3, 470e3, 520e3, 540e3), damping, LOADS):
        p = dict(EXTENDED_DEFAULTS)
        p.update(stiffness=k, damping=c, static_load=w, footprint_length=0.18 if cleat else 0.0,
                 cleat_height=0.04 if cleat else 0.0, cleat_width=0.1, lug_amplitude=0.002 if cleat else 0.0,
                 lug_pitch=0.3, lug_phase=0.4)
        laws.append(p)
    delay = WHEELBASE / SPEED
    return TractorModel(body=body, laws=tuple(laws), cleat=Cleat(0.04 if cleat else 0.0, 0.1, SPEED),
                        arrivals_s=(0.3, 0.33, 0.3 + delay, 0.33 + delay))


@pytest.fixture(scope="module", params=["rigid", "pivot"])
def system(request, tmp_path_factory):
    record = _record(pivot=request.param == "pivot")
    path = write_tractor_ssp(tmp_path_factory.mktemp("ssp") / "tractor.ssp", record, start_s=0.0, stop_s=2.5,
                             step_s=STEP, seat_x_m=SEAT_X, description="test tractor")
    return record, path


def test_the_ssp_is_valid_ssp_1_0_and_connects_every_tire(system):
    _, path = system
    components, connections, (start, stop) = read_system(path)    # fmpy validates against the SSP 1.0 schema
    assert components == [("body", "resources/body.fmu")] + [(t, f"resources/{t}.fmu") for t in TIRES]
    assert (start, stop) == (0.0, 2.5)
    ends = {(b, cb): (a, ca) for a, ca, b, cb in connections}
    assert len(ends) == len(connections) == 20
    for t in TIRES:
        assert ends[("body", f"force_{t}")] == (t, "force_z")
        for q in ("hub_z", "hub_vz", "hub_x"):
            assert ends[(t, q)] == ("body", f"{q}_{t}")
        assert ends[(t, "hub_vx")] == ("body", "hub_vx")
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
    assert {"SystemStructure.ssd", "resources/body.fmu", *(f"resources/{t}.fmu" for t in TIRES)} <= names


@pytest.mark.parametrize("exchange", ["sequential", "parallel"])
def test_fmpy_runs_the_ssp_like_the_projects_master(system, exchange):
    record, path = system
    got = run_ssp_fmpy(path, step_s=STEP, exchange=exchange)
    ref = master_reference(record, start_s=0.0, step_s=STEP, n=got["time"].size, exchange=exchange,
                           seat_x_m=SEAT_X)
    motion = [f"hub_z_{t}" for t in TIRES] + ["seat_z"]
    assert np.ptp(ref["hub_z_FL"]) > 0.01                     # the cleat moves the hubs by centimetres
    assert relative_deviation(got, ref, motion) < 1e-9
    # accelerations: sequential reads them with the forces of each point; parallel with those it stepped on
    rows = (slice(None), slice(None)) if exchange == "sequential" else (slice(1, None), slice(None, -1))
    for name in [f"hub_az_{t}" for t in TIRES] + ["seat_az"]:
        err = np.max(np.abs(got[name][rows[0]] - ref[name][rows[1]])) / np.ptp(ref[name])
        assert err < 1e-9, name


@pytest.mark.parametrize("pitch, roll", [(True, False), (False, True), (False, False)],
                         ids=["sides", "axles", "corners"])
def test_every_body_of_the_diagnosis_runs_as_an_ssp(tmp_path, pitch, roll):
    record = _record(pivot=False, pitch=pitch, roll=roll)
    path = write_tractor_ssp(tmp_path / "t.ssp", record, start_s=0.0, stop_s=2.0, step_s=STEP, seat_x_m=SEAT_X,
                             seat_y=0.4)
    got = run_ssp_fmpy(path, step_s=STEP)
    ref = master_reference(record, start_s=0.0, step_s=STEP, n=got["time"].size, seat_x_m=SEAT_X, seat_y=0.4)
    names = [f"hub_z_{t}" for t in TIRES] + ["seat_z", "seat_az"]
    assert relative_deviation(got, ref, names) < 1e-9
    # the seat of a body without both couplings: the hubs interpolated bilinearly (0.4 of the half-track left)
    xi = SEAT_X / WHEELBASE
    static = record.static_hub_z(record.inputs(0.0, STEP, 1).hub_x[:, 0])
    u = {t: got[f"hub_z_{t}"] - static[i] for i, t in enumerate(TIRES)}
    bilinear = ((1 - xi) * (0.7 * u["FL"] + 0.3 * u["FR"]) + xi * (0.7 * u["RL"] + 0.3 * u["RR"]))
    assert np.max(np.abs(got["seat_z"] - bilinear)) < 1e-12


def test_libcosim_runs_the_ssp_like_the_projects_master_with_its_exchange(system):
    record, path = system
    got = run_ssp_libcosim(path, step_s=STEP)
    ref = master_reference(record, start_s=0.0, step_s=STEP, n=got["time"].size, exchange="parallel",
                           seat_x_m=SEAT_X)
    assert relative_deviation(got, ref, [f"hub_z_{t}" for t in TIRES] + ["seat_z"], rows=slice(1, None)) < 1e-9
    other = master_reference(record, start_s=0.0, step_s=STEP, n=got["time"].size, exchange="sequential",
                             seat_x_m=SEAT_X)
    # the one-step delay of the exchange is visible, and small at 1 ms
    delay_effect = relative_deviation(other, ref, ["seat_z"])
    assert 1e-6 < delay_effect < 0.05


def test_libcosim_runs_the_ssp_from_the_ssp_alone(system, tmp_path):
    """A libcosim execution created from the SSP with no step given takes the step from its
    osp:FixedStepAlgorithm annotation (without it, libcosim crashed): the same run as with the step given.
    In a child process, so that a crash there fails this test instead of ending the session."""
    import subprocess
    import sys

    record, path = system
    assert ssd_step(path) == STEP
    script = (f"import json, sys; sys.path.insert(0, {str(Path(__file__).resolve().parents[1])!r}); "
              "from identification.fmu.ssp_run import run_ssp_libcosim; "
              f"out = run_ssp_libcosim({str(path)!r}, step_s=None, stop_s=0.5); "
              "print(json.dumps({k: [float(x) for x in v[1:]] for k, v in out.items()}))")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    own = json.loads(proc.stdout)
    given = run_ssp_libcosim(path, step_s=STEP, stop_s=0.5)
    assert len(own["time"]) == 500
    for name in ("time", "seat_z", "hub_z_FL", "hub_z_RR"):
        assert np.array_equal(np.array(own[name]), given[name][1:]), name


def test_a_c_master_without_python_runs_the_ssp(system, tmp_path_factory, tmp_path):
    from build_scripts.kinds import load_kind

    record, path = system
    body, tire = load_kind("tractor_body"), load_kind("extended_tire")   # the host's value references
    assert [body.variable(n).value_reference for n in ("force_FL", "hub_z_FL", "hub_vz_FL", "hub_x_FL", "hub_vx",
                                                       "seat_z", "seat_az")] == [0, 31, 35, 39, 43, 48, 49]
    assert [tire.variable(n).value_reference for n in ("hub_z", "hub_vz", "hub_x", "hub_vx", "force_z")] == \
        [0, 1, 4, 5, 21]
    host = _compile_host(tmp_path_factory, "native_system_host.c")
    root = extract(path, tmp_path / "ssp")
    args = []
    for name, identifier in [("body", "CleatfmuTractorBody")] + [(t, "CleatfmuExtendedTire") for t in TIRES]:
        fmu = root / "resources" / f"{name}.fmu"
        unzipped = extract(fmu, tmp_path / name)
        args += [str(unzipped / "binaries" / "linux64" / f"{identifier}.so"),
                 (unzipped / "resources").as_uri(), guid(fmu)]
    import subprocess
    n = 2000
    done = subprocess.run([str(host), repr(STEP), str(n), *args], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    rows = np.array([[float(x) for x in line.split()] for line in done.stdout.splitlines()])
    assert rows.shape == (n + 1, 7)
    ref = master_reference(record, start_s=0.0, step_s=STEP, n=n + 1, exchange="sequential", seat_x_m=SEAT_X)
    got = {f"hub_z_{t}": rows[:, 1 + i] for i, t in enumerate(TIRES)}
    got.update(seat_z=rows[:, 5], seat_az=rows[:, 6])
    assert relative_deviation(got, ref, [*got]) < 1e-9


def test_the_system_follows_the_exact_linear_response_of_the_tractor(tmp_path):
    """Linear tires, no cleat, released from a displaced, rolled and pitched state: the SSP run (fmpy)
    against python-control's exact response of M q'' + Jᵀ C J q' + Jᵀ K J q = 0."""
    import control

    record = _record(pivot=True, cleat=False)
    J, mass, _ = record.body.matrices()
    q0 = np.array([0.01, 0.004, -0.006, 0.008])          # heave m, pitch rad, roll and axle roll (scaled) m
    path = write_tractor_ssp(tmp_path / "free.ssp", record, start_s=0.0, stop_s=3.0, step_s=STEP,
                             seat_x_m=SEAT_X, initial_q=q0)
    got = run_ssp_fmpy(path, step_s=STEP)
    K = np.diag([p["stiffness"] for p in record.laws])
    C = np.diag([p["damping"] for p in record.laws])
    Minv = np.diag(1.0 / mass)
    n = mass.size
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ J.T @ K @ J, -Minv @ J.T @ C @ J]])
    sys = control.ss(A, np.zeros((2 * n, 1)), np.hstack([J, np.zeros_like(J)]), np.zeros((4, 1)))
    exact = control.initial_response(sys, T=got["time"], X0=np.concatenate([q0, np.zeros(n)]))
    static = record.static_hub_z(np.zeros(4))
    for i, t in enumerate(TIRES):
        motion = got[f"hub_z_{t}"] - static[i]
        err = np.max(np.abs(motion - exact.outputs[i])) / np.max(np.abs(exact.outputs[i]))
        assert err < 2e-3, (t, err)
    # the modes are under-damped: the response rings (it changes sign) and decays
    assert np.sum(np.diff(np.sign(got["hub_z_FL"] - static[0])) != 0) >= 4
    a = WHEELBASE * (LOADS[2] + LOADS[3]) / sum(LOADS)
    assert got["seat_z"][0] == pytest.approx(q0[0] + (a - SEAT_X) * q0[1]
                                             - (LOADS[0] - LOADS[1] + LOADS[2] - LOADS[3]) / sum(LOADS) * q0[2],
                                             abs=1e-15)


def test_the_ride_as_an_ssp_reproduces_the_seat_acceleration_of_ride(tmp_path):
    """body + road profile FMU + four tires on an ISO 8608 road: the seat's acceleration in fmpy (sequential)
    equals ``ride``'s (the compiled stepping) and libcosim's run equals the master with its exchange."""
    from identification.comfort.ride import ride
    from identification.comfort.ride_ssp import write_ride_ssps
    from identification.comfort.road import road_profile
    from identification.fmu.ssp_run import check_ssp

    body = Body(TIRES, LOADS, WHEELBASE, pitch=True, roll=True, pitch_index=0.8, roll_index=0.5)
    road = road_profile("C", SPEED * 9.0 + 1.0, 0.01, 3)
    sets = {"final": ({"FL": 450e3, "FR": 470e3, "RL": 520e3, "RR": 540e3},
                      {"FL": 3000.0, "FR": 3200.0, "RL": 4000.0, "RR": 4200.0})}
    runs = ride(body, sets, road=road, speed_m_s=SPEED, duration_s=8.5, seat_x_m=SEAT_X, seat_y=0.2)
    path = write_ride_ssps(tmp_path, body, sets, road=road, speed_m_s=SPEED, duration_s=8.5, seat_x_m=SEAT_X,
                           seat_y=0.2)["final"]
    components, connections, _ = read_system(path)
    assert [c[0] for c in components] == ["body", "road", *TIRES]
    assert ("road", "road_z_RL", "RL", "road_z") in connections and ("road", "road_vz_FR", "FR", "road_vz") in \
        connections
    got = run_ssp_fmpy(path, step_s=STEP)
    run = runs["final"]
    rows = np.searchsorted(got["time"], run.time_s - 1e-9)
    assert np.allclose(got["time"][rows], run.time_s, atol=1e-9)
    seat = got["seat_az"][rows]
    assert np.std(run.seat_m_s2) > 0.1                     # the road shakes the seat
    assert np.max(np.abs(seat - run.seat_m_s2)) < 1e-9 * np.ptp(run.seat_m_s2)
    from identification.comfort.ride import _point_contact
    from identification.model.ride import ride_model
    laws = [_point_contact(sets["final"][0][t], sets["final"][1][t], w) for t, w in zip(TIRES, LOADS)]
    record = ride_model(body, laws, speed_m_s=SPEED, road_x_m=road.x_m, road_left_m=road.left_m,
                        road_right_m=road.right_m)
    check = check_ssp(path, record, start_s=0.0, step_s=STEP, stop_s=8.5, seat_x_m=SEAT_X, seat_y=0.2)
    assert check["libcosim (parallel exchange)"] < 1e-9 and check["fmpy (parallel exchange)"] < 1e-9
