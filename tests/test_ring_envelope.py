"""The rigid-ring envelope of the extended tire law against the elastic bed's integral (scipy's quad)."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from identification.model import tire_law


def _bed_height(x, d, footprint, xc, h, w, sink, profile=None):
    """Equivalent cleat height of a rigid ring over a bed whose pressure is ∝ sqrt of its compression,
    integrated numerically: [∫ sqrt((d + z(ξ) − ξ²/2R)₊) − sqrt((d − ξ²/2R)₊) dξ] / (π/2 sqrt(2R)),
    the flat-ground force k d fixing the bed's constant; z the cleat at x + ξ (a rectangle, or `profile`)."""
    radius = footprint ** 2 / (8.0 * sink)
    z = profile or (lambda s: h if xc <= s <= xc + w else 0.0)
    reach = math.sqrt(2.0 * radius * max(d + h, 0.0))
    flat = math.sqrt(2.0 * radius * max(d, 0.0))       # the flat contact's ends: kinks of the integrand
    cuts = sorted({-reach, reach, *(min(reach, max(-reach, e)) for e in (xc - x, xc + w - x, -flat, flat))})

    def integrand(xi):
        flat = d - xi * xi / (2.0 * radius)
        return math.sqrt(max(flat + z(x + xi), 0.0)) - math.sqrt(max(flat, 0.0))

    total = sum(quad(integrand, a, b, limit=200, epsabs=1e-13)[0] for a, b in zip(cuts[:-1], cuts[1:]) if b > a)
    return total / (0.5 * math.pi * math.sqrt(2.0 * radius))


CASES = [(0.3, 0.02, 0.04, 0.1), (0.45, 0.025, 0.03, 0.12), (0.25, 0.012, 0.05, 0.08), (0.35, 0.03, 0.015, 0.3)]


@pytest.mark.parametrize("footprint, sink, h, w", CASES)
def test_equivalent_height_and_slope_are_the_beds_integral(footprint, sink, h, w):
    xc = 0.1
    for d in (-0.01, 0.0, 0.5 * sink, sink, 1.6 * sink):
        reach = math.sqrt(footprint ** 2 / (4.0 * sink) * max(d + h, 0.0))
        for x in np.linspace(xc - reach - 0.05, xc + w + reach + 0.05, 23):
            r, slope = tire_law.ring_cleat(x, d, footprint, xc, h, w, sink)
            assert r == pytest.approx(_bed_height(x, d, footprint, xc, h, w, sink), abs=1e-9), (d, x)
            e = 1e-5
            fd = (_bed_height(x + e, d, footprint, xc, h, w, sink)
                  - _bed_height(x - e, d, footprint, xc, h, w, sink)) / (2 * e)
            assert slope == pytest.approx(fd, rel=5e-3, abs=2e-5), (d, x)   # fd: steep by the contact edges


def test_limits_out_of_reach_over_the_whole_contact_and_the_reach():
    footprint, sink, h, w, d = 0.34, 0.0216, 0.026, 0.12, 0.0216
    radius = footprint ** 2 / (8 * sink)
    reach = math.sqrt(2 * radius * (d + h))            # contact with the cleat's leading edge starts here
    assert reach > 0.5 * footprint * 1.4                # sqrt(1 + H/d) = 1.47 times the half footprint
    assert tire_law.ring_cleat(-reach - 1e-9, d, footprint, 0.0, h, w, sink) == (0.0, 0.0)
    assert tire_law.ring_cleat(-reach + 1e-3, d, footprint, 0.0, h, w, sink)[0] > 0.0
    # a cleat holding the whole contact raises the road by its height
    r, slope = tire_law.ring_cleat(0.0, d, footprint, -2.0, h, 4.0, sink)
    assert r == pytest.approx(h, rel=1e-12) and slope == pytest.approx(0.0, abs=1e-12)
    # a low cleat at the contact's centre weighs far less than the parabolic footprint's average
    low = 0.002
    ring = tire_law.ring_cleat(0.0, d, footprint, -0.5 * w, low, w, sink)[0]
    parabolic = tire_law.footprint_cleat(0.0, footprint, -0.5 * w, low, w, True)[0]
    arcsine = low * 2.0 / math.pi * math.asin(w / footprint)   # the linearised bed's weight ∝ 1/sqrt(1 − u²)
    assert ring == pytest.approx(arcsine, rel=0.03) and ring < 0.6 * parabolic


def test_bevelled_cleat_is_the_rectangle_of_its_area_within_its_error():
    """The law takes a trapezoid as the rectangle of the same height and area; the bed's integral over the
    trapezoid itself differs from it by a small share of H for bevels of the independent cleats' size."""
    footprint, sink, h, w, b, d = 0.34, 0.02, 0.03, 0.1, 0.006, 0.02

    def trapezoid(s):
        t = s
        return h * min(max(min(t, w - t) / b, 0.0), 1.0)

    worst = 0.0
    for x in np.linspace(-0.35, 0.45, 41):
        law = tire_law.ring_cleat(x, d, footprint, 0.0, h, w, sink, b)[0]
        assert law == pytest.approx(tire_law.ring_cleat(x, d, footprint, 0.5 * b, h, w - b, sink)[0], rel=1e-12,
                                    abs=1e-15)
        worst = max(worst, abs(law - _bed_height(x, d, footprint, 0.0, h, w, sink, trapezoid)))
    assert worst < 0.01 * h, worst   # 0.3 % of H measured


def _params(**kw):
    p = dict(tire_law.EXTENDED_DEFAULTS, stiffness=5e5, damping=3000.0, unloaded_radius=0.8, static_load=1e4,
             footprint_length=0.3, cleat_height=0.03, cleat_width=0.1, ring_envelope=True)
    p.update(kw)
    assert tire_law.extended_parameter_problem(p) is None
    return p


def test_flat_ground_keeps_k_and_the_three_forms_of_the_law_agree():
    p = _params()
    plain = dict(p, cleat_height=0.0)
    force = tire_law.extended_force_fn(p)
    q = tire_law.law_vector(p)
    rng = np.random.default_rng(7)
    for _ in range(300):
        z, vz, x, vx = 0.8 - rng.uniform(-0.01, 0.06), rng.normal(0, 0.3), rng.uniform(-1.0, 1.5), 2.0
        full = tire_law.extended_tire(z, vz, x, vx, 0.0, 0.0, p)
        assert force(z, vz, x, vx, 0.0, 0.0) == full[0] == tire_law.tire_force(z, vz, x, vx, 0.0, 0.0, q)
        if x < -0.5:    # out of the ring's reach: the linear tire on flat ground
            assert full[:3] == tire_law.extended_tire(z, vz, x, vx, 0.0, 0.0, plain)[:3]


def test_the_ring_needs_the_static_load():
    p = dict(_params(), static_load=0.0)
    assert "static_load must be > 0 N when ring_envelope" in tire_law.extended_parameter_problem(p)
    assert tire_law.extended_parameter_problem(dict(p, ring_envelope=False)) is None
