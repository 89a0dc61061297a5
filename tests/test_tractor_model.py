"""The whole-tractor model record and its stepping: compiled = plain Python, and both = python-control."""

import control
import numpy as np
import pytest

from identification.model import tire_law
from identification.recording.cleat import CleatProfile
from identification.model import Body, Cleat, TractorModel, cleat_inputs
from identification.model.kernels import run_model
from identification.model.stepping import run_model_python
from identification.recording.preprocess import lowpass
from identification.recording import STANDARD_GRAVITY

from tractor_cases import ARRIVALS, C, H, K, L, LOADS, TIRES, V, W  # noqa: F401
BODIES = [dict(), dict(pitch=True), dict(roll=True), dict(pitch=True, roll=True),
          dict(pitch=True, roll=True, pivot=True)]


#: the bevel of the bevelled-cleat cases, m (on the 100 mm cleat)
BEVEL = 0.02


def _record(body_kw, *, options=None, seed=0):
    """The tractor with each tire's law given `options`; with "bevel" the cleat (the road of the point-contact
    tires, the built-in cleat of the footprint ones) is a trapezoid with BEVEL."""
    rng = np.random.default_rng(seed)
    body = Body(TIRES, LOADS, L, pitch_index=0.8, roll_index=0.47, pivot_index=0.06, **body_kw)
    laws = []
    for i, (w, k, c) in enumerate(zip(LOADS, K, C)):
        p = dict(tire_law.EXTENDED_DEFAULTS, stiffness=k, damping=c, static_load=w)
        for opt in options or ():
            if opt == "footprint":
                p.update(footprint_length=rng.uniform(0.2, 0.5), cleat_height=H, cleat_width=W,
                         cleat_bevel=BEVEL if "bevel" in options else 0.0)
            elif opt == "ring":
                p.update(ring_envelope=True)
            elif opt == "unilateral":
                p.update(unilateral=True)
            elif opt == "exponent":
                p.update(stiffness_exponent=rng.uniform(1.2, 1.8))
            elif opt == "friction":
                p.update(friction_force=rng.uniform(100, 400), friction_velocity=0.01)
            elif opt == "lugs":
                p.update(lug_amplitude=1e-3, lug_pitch=rng.uniform(0.15, 0.3), lug_phase=rng.uniform(0, 6))
        laws.append(p)
    height = 0.06 if "unilateral" in (options or ()) else H
    profile = CleatProfile.bevelled(height, W, BEVEL) if "bevel" in (options or ()) else None
    return TractorModel(body, tuple(laws), Cleat(height, W, V, profile), ARRIVALS)


@pytest.mark.parametrize("options", [(), ("footprint",), ("unilateral",), ("exponent",), ("friction",), ("lugs",),
                                     ("bevel",), ("footprint", "bevel"), ("footprint", "ring"),
                                     ("footprint", "unilateral", "exponent", "friction", "lugs"),
                                     ("footprint", "ring", "bevel", "unilateral", "exponent", "friction", "lugs")])
@pytest.mark.parametrize("body", BODIES, ids=lambda b: "+".join(b) or "corners")
def test_compiled_stepping_equals_the_reference(body, options):
    model = _record(body, options=options, seed=len(options))
    grid = model.grid(0.2, 3.0, 1e-3, 1e-3)
    a, b = run_model(model, *grid), run_model_python(model, *grid)
    for name in ("hub_accel_m_s2", "hub_vz_m_s", "force_n"):
        x, y = getattr(a, name), getattr(b, name)
        assert np.max(np.abs(x - y)) <= 1e-12 * np.max(np.abs(y)), name
    flat = [(np.array(x), np.array(y)) for x, y in zip(a.impulses, b.impulses)]
    assert all(x.shape == y.shape and np.allclose(x, y, rtol=1e-12, atol=0) for x, y in flat)


def _geometry(pivot):
    """J and masses of the rigid tractor from geometry (track 1.9 m), independently of the model code."""
    g = STANDARD_GRAVITY
    Wt = np.array(LOADS)
    M = Wt.sum() / g
    a = L * (Wt[2] + Wt[3]) / Wt.sum()
    b = L - a
    half = 0.95
    y = np.array([half, -half, half, -half])
    ycg = (Wt * y).sum() / Wt.sum()
    x = np.array([a, a, -b, -b])
    cols = [np.ones(4), x, y - ycg]
    inertia = [M, 0.8 * M * a * b, 0.47 * M * half ** 2]
    if pivot:
        cols[2] = np.array([-ycg, -ycg, half - ycg, -half - ycg])
        cols.append(np.array([half, -half, 0.0, 0.0]))
        inertia.append(0.06 * (Wt[0] + Wt[1]) / g * half ** 2)
    return np.column_stack(cols), np.diag(inertia)


def _state_space(pivot):
    """python-control's linear tractor: states (q, q', r1..r4), inputs the road rates, outputs the hub
    velocities J q'."""
    J, Mm = _geometry(pivot)
    nq = J.shape[1]
    k, c = np.diag(K), np.diag(C)
    Minv = np.linalg.inv(Mm)
    A = np.zeros((2 * nq + 4, 2 * nq + 4))
    A[:nq, nq:2 * nq] = np.eye(nq)
    A[nq:2 * nq, :nq] = -Minv @ J.T @ k @ J
    A[nq:2 * nq, nq:2 * nq] = -Minv @ J.T @ c @ J
    A[nq:2 * nq, 2 * nq:] = Minv @ J.T @ k
    B = np.zeros((2 * nq + 4, 4))
    B[nq:2 * nq, :] = Minv @ J.T @ c
    B[2 * nq:, :] = np.eye(4)
    return control.ss(A, B, np.hstack([np.zeros((4, nq)), J, np.zeros((4, 4))]), np.zeros((4, 4)))


def _control_mean_acceleration(pivot, times, ts):
    """Mean hub accelerations over each sample interval from python-control (road-rate impulses at the edges)."""
    sys = _state_space(pivot)
    dt = 2e-5
    grid = np.arange(0.0, times[-1] + 0.5, dt)
    resp = control.impulse_response(sys, grid)
    out = np.zeros((4, times.size))
    for i, t_arr in enumerate(ARRIVALS):
        for edge, sign in ((t_arr, 1.0), (t_arr + W / V, -1.0)):
            for hub in range(4):
                y = np.asarray(resp.outputs[hub, i])

                def vel(t):
                    tau = t - edge
                    return np.where(tau >= 0, sign * H * np.interp(np.clip(tau, 0, None), grid, y), 0.0)
                out[hub] += (vel(times + ts / 2) - vel(times - ts / 2)) / ts
    return out


@pytest.mark.parametrize("pivot", [False, True], ids=["rigid", "pivot"])
def test_tractor_stepping_matches_python_control_and_converges(pivot):
    ts = 1e-3
    times = np.arange(0.3, 3.2, ts)
    ref = np.array([lowpass(r, sample_rate_hz=1 / ts) for r in _control_mean_acceleration(pivot, times, ts)])
    errors = []
    for h in (1e-3, 5e-4, 2.5e-4, 1.25e-4):
        model = _record(dict(pitch=True, roll=True, pivot=pivot))
        traj = run_model(model, *model.grid(0.1, 3.3, h, ts))
        sim = np.array([lowpass(traj.mean_acceleration(i, times, ts), sample_rate_hz=1 / ts) for i in range(4)])
        errors.append(max(float(np.sqrt(np.mean((s - r) ** 2) / np.mean(r ** 2))) for s, r in zip(sim, ref)))
    assert errors[-1] <= 0.005, errors
    assert errors[0] > errors[1] > errors[2] > errors[3], errors


def _control_bevelled_mean_acceleration(times, ts):
    """Mean hub accelerations over each sample interval from python-control's forced response of the rigid
    tractor (pitch, roll) to the bevelled cleat's road rates: +H/b v while a contact point climbs the leading
    bevel, -H/b v on the trailing one, on a 10 us grid."""
    dt = 1e-5
    grid = np.arange(0.0, times[-1] + 0.01, dt)
    rates = np.zeros((4, grid.size))
    mid = grid + dt / 2                                             # the rate held over each interval
    for i, t_arr in enumerate(ARRIVALS):
        s = V * (mid - t_arr)
        rates[i] = np.where((s >= 0) & (s < BEVEL), H / BEVEL * V, 0.0) \
            - np.where((s >= W - BEVEL) & (s < W), H / BEVEL * V, 0.0)
    sysd = control.c2d(_state_space(False), dt, method="zoh")
    vel = np.asarray(control.forced_response(sysd, grid, rates).outputs)
    return np.array([(np.interp(times + ts / 2, grid, v) - np.interp(times - ts / 2, grid, v)) / ts for v in vel])


def test_bevelled_cleat_stepping_matches_python_control():
    """Point contact over a bevelled cleat: the road is the trapezoid, its rate the bevels' slopes times v."""
    ts = 1e-3
    times = np.arange(0.3, 3.2, ts)
    ref = np.array([lowpass(r, sample_rate_hz=1 / ts) for r in _control_bevelled_mean_acceleration(times, ts)])
    model = _record(dict(pitch=True, roll=True), options=("bevel",))
    traj = run_model(model, *model.grid(0.1, 3.3, 1.25e-4, ts))      # first order in h: 1.3 % at 1 ms
    sim = np.array([lowpass(traj.mean_acceleration(i, times, ts), sample_rate_hz=1 / ts) for i in range(4)])
    errors = [float(np.sqrt(np.mean((s - r) ** 2) / np.mean(r ** 2))) for s, r in zip(sim, ref)]
    assert max(errors) <= 0.005, errors
    rect = _record(dict(pitch=True, roll=True))                     # the rectangle is far from it
    sharp = np.array([lowpass(run_model(rect, *rect.grid(0.1, 3.3, 2.5e-4, ts)).mean_acceleration(i, times, ts),
                              sample_rate_hz=1 / ts) for i in range(4)])
    assert min(float(np.sqrt(np.mean((s - r) ** 2) / np.mean(r ** 2))) for s, r in zip(sharp, ref)) > 0.1


def test_track_width_does_not_enter():
    """With the roll coordinate scaled by the half-track, only the roll index enters (two tracks, same J)."""
    body = Body(TIRES, LOADS, L, pitch=True, roll=True, roll_index=0.5)
    J, mass, names = body.matrices()
    for half in (0.8, 1.1):
        Jg, Mg = _geometry(False) if half == 0.95 else (None, None)
        y = np.array([half, -half, half, -half])
        ycg = (np.array(LOADS) * y).sum() / sum(LOADS)
        # physical roll angle phi: hub displacement (y - ycg) phi = (y - ycg)/half * w with w = half phi
        assert np.allclose(J[:, 2], (y - ycg) / half)
    assert names == ("heave", "pitch", "roll")
    assert mass[2] == pytest.approx(0.5 * sum(LOADS) / STANDARD_GRAVITY)


def test_pivot_front_axle_carries_no_roll_moment():
    J, _, _ = Body(TIRES, LOADS, L, pitch=True, roll=True, pivot=True).matrices()
    # equal and opposite front forces: no generalized force on the body's heave, pitch and roll
    f = np.array([100.0, -100.0, 0.0, 0.0])
    gen = J.T @ f
    assert np.allclose(gen[:3], 0.0) and gen[3] == pytest.approx(200.0)
    Jr, _, _ = Body(TIRES, LOADS, L, pitch=True, roll=True).matrices()
    assert abs((Jr.T @ f)[2]) > 100.0           # a rigid front axle rolls the body


@pytest.mark.parametrize("options", [(), ("footprint",)])
def test_inputs_of_all_tires_are_cleat_inputs_per_tire(options):
    model = _record(dict(pitch=True, roll=True), options=options)
    start, h, n = model.grid(0.2, 3.0, 1e-3, 1e-3)
    inputs = model.inputs(start, h, n)
    edges = []
    for j, (p, arrival) in enumerate(zip(model.laws, model.arrivals_s)):
        *rows, e = cleat_inputs(start, h, n, arrival_s=arrival, cleat=model.cleat,
                                external=not model.builtin_cleat(j), x_offset_m=p["cleat_x"])
        for name, row in zip(("road_z", "road_vz", "hub_x", "hub_vx"), rows):
            np.testing.assert_array_equal(getattr(inputs, name)[j], row)
        edges += [(i, j, t_e) for i, t_e in e]
    assert inputs.edges == tuple(sorted(edges)) and (len(edges) == 8) == (not options)


def test_matrices_are_fresh_copies():
    body = Body(TIRES, LOADS, L, pitch=True, roll=True, pitch_index=0.8)
    J, mass, _ = body.matrices()
    J[:] = 0.0
    mass[:] = 0.0
    J2, mass2, _ = Body(TIRES, LOADS, L, pitch=True, roll=True, pitch_index=0.8).matrices()
    assert np.all(mass2 > 0) and np.any(J2 != 0)
    listed = Body(list(TIRES), list(LOADS), L, pitch=True, roll=True, pitch_index=0.8)   # unhashable: not cached
    np.testing.assert_array_equal(listed.matrices()[0], J2)


@pytest.mark.parametrize("J", [np.eye(4), np.ones((4, 3)), np.array([[1.0, 0, 0], [0, 0, 0], [0, 2.0, 3.0], [0, 0, 4.0]]),
                               np.array([[0.0, 1.0, 0.0, 5.0], [0.0, 0.0, 0.0, 0.0]])])
def test_the_compiled_stepping_sums_over_every_non_zero_of_J(J):
    from identification.model.kernels import sparsity

    r0, r1, c0, c1 = sparsity(J)
    for t in range(J.shape[0]):
        inside = np.zeros(J.shape[1], dtype=bool)
        inside[r0[t]:r1[t]] = True
        assert not np.any(J[t, ~inside])
        assert r1[t] - r0[t] <= J.shape[1] and (r1[t] == r0[t]) == (not np.any(J[t]))
    for j in range(J.shape[1]):
        inside = np.zeros(J.shape[0], dtype=bool)
        inside[c0[j]:c1[j]] = True
        assert not np.any(J[~inside, j])
        assert (c1[j] == c0[j]) == (not np.any(J[:, j]))
    assert list(zip(r0, r1))[:1] == [(int(np.flatnonzero(J[0])[0]), int(np.flatnonzero(J[0])[-1]) + 1)]
