"""The independent simulator (``tests/independent``) against closed forms and a reference integrator.

It is the yardstick of the pipeline's accuracy claims, so its own physics is checked here without
the pipeline: the truth experiment on a linear tire, the bristle bed's flat-ground stiffness and its
enveloping of a wide cleat, the cleat's geometry, the analog chain's corner frequencies, the Exudyn
corner against scipy's integrator on the same equation, and the rigid tractor's statics.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

pytest.importorskip("exudyn", reason="the independent simulator needs exudyn (the test extra)")
warnings.filterwarnings("ignore", category=DeprecationWarning, module="exudyn")

from scipy.integrate import quad, solve_ivp  # noqa: E402

from tests.independent.sensor import Chain, acquire  # noqa: E402
from tests.independent.terrain import cleat_polyline, height_at  # noqa: E402
from tests.independent.tires import TireSpec, pack, tire_force  # noqa: E402
from tests.independent.truth import free_decay_truth  # noqa: E402
from tests.independent.vehicle import GRAVITY, WHEELS, Vehicle, cross_cleat  # noqa: E402

FLAT = (np.array([0.0, 1e-3, 2e-3]), np.array([0.0, 0.0, 0.0]))


def test_truth_experiment_returns_a_linear_tires_k_and_c():
    """A point tire k δ + c δ̇ under W/g rings down exactly as that spring and damper: the fit gives them back."""
    spec = TireSpec("point", 0.68, 550e3, 4200.0)
    fd = free_decay_truth(spec, 11460.0)
    assert fd["k"] == pytest.approx(550e3, rel=1e-6)
    assert fd["c"] == pytest.approx(4200.0, rel=1e-5)
    assert fd["mass_kg"] == pytest.approx(11460.0 / GRAVITY)


def test_bristle_bed_flat_stiffness_is_the_ellipse_integral():
    """p = 1/2, ε → 0: F = κ ∫ √(δ - R + √(R² - x²)) dx (scipy's quad), close to the parabola's
    closed form κ π √(2R) δ / 2: nearly linear in δ."""
    r, kappa = 0.68, 3.0e5
    spec = TireSpec("bed", r, kappa, 0.0, eps_m=1e-9, dx_m=0.0005)
    par, xs = pack(spec)
    for delta in (0.01, 0.02, 0.03):
        f, length = tire_force(par, xs, -10.0, r - delta, 0.0, 0.0, 0.0, 0.0, *FLAT)
        half = math.sqrt(2 * r * delta - delta ** 2)
        exact = kappa * quad(lambda x: math.sqrt(max(delta - r + math.sqrt(r * r - x * x), 0.0)), -half, half,
                             limit=200)[0]
        assert f == pytest.approx(exact, rel=1e-3)
        assert f == pytest.approx(kappa * math.pi * math.sqrt(2 * r) * delta / 2, rel=0.01)
        assert length == pytest.approx(2 * math.sqrt(2 * r * delta - delta ** 2), rel=2e-2)


def test_bristle_bed_envelops_a_wide_cleat_as_flat_ground_raised():
    """Centred over a cleat wider than its footprint, the tire carries what it carries on flat ground
    with the hub lower by the cleat's height; half over a leading edge, it carries less than a point
    follower would (the footprint spreads the step)."""
    r, h = 0.68, 0.03
    spec = TireSpec("bed", r, 3.0e5, 0.0)
    par, xs = pack(spec)
    cleat = cleat_polyline(h, 1.2, bevel_m=0.002, round_m=0.0)
    sx, sz = np.ascontiguousarray(cleat[:, 0]), np.ascontiguousarray(cleat[:, 1])
    f_top = tire_force(par, xs, 0.6, r - 0.02 + h, 0.0, 0.0, 0.0, 0.0, sx, sz)[0]
    f_flat = tire_force(par, xs, -10.0, r - 0.02, 0.0, 0.0, 0.0, 0.0, *FLAT)[0]
    assert f_top == pytest.approx(f_flat, rel=1e-6)
    f_edge = tire_force(par, xs, 0.0, r - 0.02, 0.0, 0.0, 0.0, 0.0, sx, sz)[0]
    f_point_over = tire_force(par, xs, -10.0, r - 0.02 - h, 0.0, 0.0, 0.0, 0.0, *FLAT)[0]
    assert f_flat < f_edge < f_point_over


def test_cleat_polyline_geometry():
    """From (0, 0) to (W, 0), top at H, x never decreasing; without rounding its area is H (W - b)."""
    for b, rr in ((0.0, 0.0), (0.004, 0.0), (0.004, 0.003), (0.0, 0.005)):
        pts = cleat_polyline(0.04, 0.1, b, rr)
        assert np.allclose(pts[0], [0, 0]) and np.allclose(pts[-1], [0.1, 0])
        assert pts[:, 1].max() == pytest.approx(0.04)
        assert np.all(np.diff(pts[:, 0]) >= -1e-15)
        area = np.trapezoid(pts[:, 1], pts[:, 0]) if hasattr(np, "trapezoid") else np.trapz(pts[:, 1], pts[:, 0])
        if rr == 0:
            assert area == pytest.approx(0.04 * (0.1 - b), rel=1e-12)
        else:
            assert area < 0.04 * (0.1 - b)
    z, slope = height_at(0.002, *[np.ascontiguousarray(c) for c in cleat_polyline(0.04, 0.1, 0.004).T])
    assert z == pytest.approx(0.02) and slope == pytest.approx(10.0)


@pytest.mark.parametrize("kind", ["butter", "bessel"])
def test_analog_chain_corner_frequencies(kind):
    """A sine at the anti-alias cut-off comes out at -3 dB (Butterworth; a Bessel filter normalised to
    its magnitude, too); at the AC coupling's corner, -3 dB; a constant is removed."""
    rate, m = 1000.0, 20
    t = np.arange(int(6.0 * rate * m)) / (rate * m)
    rng = np.random.default_rng(0)
    chain = Chain(rate_hz=rate, aa_kind=kind, aa_order=4, aa_cutoff_hz=200.0, noise_m_s2=0.0)
    _, y = acquire(t, np.sin(2 * np.pi * 200.0 * t), chain, rng, record_from_s=1.0, duration_s=4.0)
    assert np.sqrt(2 * np.mean(y ** 2)) == pytest.approx(1 / math.sqrt(2), rel=0.01)
    chain = Chain(rate_hz=rate, aa_kind="none", highpass_hz=1.0, noise_m_s2=0.0)
    _, y = acquire(t, np.sin(2 * np.pi * 1.0 * t) + 3.0, chain, rng, record_from_s=3.0, duration_s=3.0)
    assert np.sqrt(2 * np.mean(y ** 2)) == pytest.approx(1 / math.sqrt(2), rel=0.01)


def test_exudyn_corner_matches_scipy_on_the_same_equation():
    """One corner (a point tire, m = W/g) over a bevelled cleat: Exudyn's hub acceleration is scipy's
    DOP853 on m z'' = max(k δ + c δ', 0) - m g, δ = R - z + z_road(v t)."""
    m, k, c, r, v = 1168.0, 550e3, 4200.0, 0.68, 2.0
    spec = TireSpec("point", r, k, c)
    cleat = cleat_polyline(0.04, 0.1, bevel_m=0.01)
    tires = {w: spec for w in WHEELS}
    veh = Vehicle("corners", tires, corner_mass_kg={w: m for w in WHEELS})
    x0 = 0.3
    cr = cross_cleat(veh, speed_m_s=v, cleats={"L": cleat, "R": cleat}, cleat_x_m={"L": x0, "R": x0},
                     step_s=5e-5, duration_s=0.8)
    sx, sz = np.ascontiguousarray(cleat[:, 0]), np.ascontiguousarray(cleat[:, 1])

    def rhs(t, y):
        zr, slope = height_at(v * t - x0, sx, sz)
        d, dd = r - (y[0] - zr), -(y[1] - v * slope)
        return [y[1], (max(k * d + c * dd, 0.0) - m * GRAVITY) / m]
    z_eq = r - m * GRAVITY / k
    t = cr.time_s
    sol = solve_ivp(rhs, (0, t[-1]), [z_eq, 0.0], method="DOP853", t_eval=t, rtol=1e-10, atol=1e-12,
                    max_step=2e-4)
    acc_ref = np.array([rhs(ti, yi)[1] for ti, yi in zip(sol.t, sol.y.T)])
    a = cr.accel_z["FL"]
    assert np.abs(a).max() > 5.0
    # the fixed-step RK44 meets the damper's jump at the bevel's foot with an O(h) error; it shows as a
    # brief lift-off a step away from scipy's, so: the RMS and the hub's path, not the largest sample
    assert np.sqrt(np.mean((a - acc_ref) ** 2)) < 0.01 * np.abs(acc_ref).max()
    assert np.abs(cr.hub_z["FL"] - sol.y[0]).max() < 1e-3


@pytest.mark.parametrize("layout", ["rigid", "pivot"])
def test_rigid_tractor_statics(layout):
    """Settled on flat ground, the tires carry the tractor's weight, and its moments balance about
    both axles' centres (pitch) and the centreline (roll)."""
    spec = TireSpec("bed", 0.68, 2 * 500e3 / (math.pi * math.sqrt(2 * 0.68)), 12e3)
    rear = TireSpec("bed", 0.87, 2 * 420e3 / (math.pi * math.sqrt(2 * 0.87)), 8e3)
    tires = {"FL": spec, "FR": spec, "RL": rear, "RR": rear}
    veh = Vehicle(layout, tires, mass_kg=5500.0, cg_from_front_m=1.6, cg_left_m=0.04, wheelbase_m=2.7, track_m=1.9)
    cleat = cleat_polyline(0.02, 0.1, 0.002)
    cr = cross_cleat(veh, speed_m_s=2.0, cleats={"L": cleat, "R": cleat}, cleat_x_m={"L": 50.0, "R": 50.0},
                     step_s=2e-4, duration_s=0.02)
    f = cr.static_force_z
    weight = 5500.0 * GRAVITY
    assert sum(f.values()) == pytest.approx(weight, rel=1e-5)
    assert (f["RL"] + f["RR"]) * 2.7 == pytest.approx(weight * 1.6, rel=1e-4)
    assert (f["FL"] + f["RL"] - f["FR"] - f["RR"]) * 0.95 == pytest.approx(weight * 0.04, rel=5e-3)
    if layout == "pivot":   # the pivot carries no roll moment: the front axle's loads are equal
        assert f["FL"] == pytest.approx(f["FR"], rel=1e-5)
