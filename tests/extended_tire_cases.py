"""The extended tire FMU's variables and random valid cases, shared by its test modules."""

from __future__ import annotations

import math

import identification.model.tire_law as law

KIND = "extended_tire"
INPUTS = ["hub_z", "hub_vz", "road_z", "road_vz", "hub_x", "hub_vx"]
BOOL_PARAMS = ["unilateral", "parabolic_pressure", "ring_envelope"]
REAL_PARAMS = [n for n in law.EXTENDED_DEFAULTS if n not in BOOL_PARAMS]
REAL_OUTPUTS = ["force_z", "deflection", "deflection_rate", "road_effective_z"]
OUTPUTS = REAL_OUTPUTS + ["in_contact"]
#: Option sets of the random cases; "footprint" has a uniform contact pressure, "parabolic" a parabolic one;
#: "bevel" makes the built-in cleat a trapezoid (with a uniform footprint unless combined with "parabolic" or
#: "point_cleat"); "ring" sees the cleat through a rigid ring over an elastic bed. The last two sets switch
#: every option on (the ring's envelope, then the footprint parabolic; the cleat bevelled).
OPTION_SETS = [("footprint",), ("point_cleat",), ("unilateral",), ("progressive",), ("friction",), ("lugs",),
               ("parabolic",), ("bevel",), ("bevel", "parabolic"), ("bevel", "point_cleat"),
               ("ring",), ("ring", "bevel"), ("ring", "bevel", "unilateral", "progressive", "friction", "lugs"),
               ("parabolic", "bevel", "unilateral", "progressive", "friction", "lugs")]


def random_parameters(rng, options) -> dict:
    """A valid parameter set with random k, c, r0 and the given options switched on."""
    p = dict(law.EXTENDED_DEFAULTS, stiffness=rng.uniform(1e5, 1.5e6), damping=rng.uniform(0.0, 2e4),
             unloaded_radius=rng.uniform(0.4, 1.0))
    footprint = ("footprint" in options or "parabolic" in options or "ring" in options
                 or ("bevel" in options and "point_cleat" not in options))
    if footprint or "point_cleat" in options:
        p.update(footprint_length=rng.uniform(0.05, 0.5) if footprint else 0.0,
                 cleat_x=rng.uniform(-1.0, 1.0), cleat_height=rng.uniform(0.01, 0.08),
                 cleat_width=rng.uniform(0.02, 0.3))
    if "bevel" in options:  # in (0, w/2]; one case in five a triangle (b = w/2)
        half = 0.5 * p["cleat_width"]
        p["cleat_bevel"] = half if rng.random() < 0.2 else half * (1.0 - rng.random())
    if "parabolic" in options:
        p["parabolic_pressure"] = True
    if "ring" in options:
        p.update(ring_envelope=True, static_load=rng.uniform(5e3, 4e4))
    if "unilateral" in options:
        p["unilateral"] = True
    if "progressive" in options:
        p.update(stiffness_exponent=rng.uniform(0.6, 2.0), static_load=rng.uniform(5e3, 4e4))
    if "friction" in options:
        p.update(friction_force=rng.uniform(10.0, 2000.0), friction_velocity=rng.uniform(0.001, 0.2))
    if "lugs" in options:
        p.update(lug_amplitude=rng.uniform(-0.005, 0.005), lug_pitch=rng.uniform(0.1, 0.5),
                 lug_phase=rng.uniform(-math.pi, math.pi))
    assert law.extended_parameter_problem(p) is None
    return p


def random_inputs(rng, p) -> list[float]:
    """Random inputs in INPUTS order around the unloaded radius and the cleat of parameter set `p`."""
    return [p["unloaded_radius"] + rng.uniform(-0.08, 0.03), rng.uniform(-2.0, 2.0), rng.uniform(-0.02, 0.04),
            rng.uniform(-1.0, 1.0), p["cleat_x"] + rng.uniform(-0.6, 0.9), rng.uniform(-4.0, 4.0)]


def set_parameters(s, vr, p) -> None:
    """Set every parameter of `p` in instance `s`."""
    s.setReal([vr[n] for n in REAL_PARAMS], [float(p[n]) for n in REAL_PARAMS])
    s.setBoolean([vr[n] for n in BOOL_PARAMS], [p[n] for n in BOOL_PARAMS])


def read_outputs(s, vr) -> tuple:
    """The outputs of instance `s` in OUTPUTS order, in_contact as a bool."""
    return (*s.getReal([vr[n] for n in REAL_OUTPUTS]), bool(s.getBoolean([vr["in_contact"]])[0]))


def law_outputs(u, p) -> tuple:
    """tire_law.extended_tire in the FMU's output order."""
    force, deflection, rate, contact, road = law.extended_tire(u[0], u[1], u[4], u[5], u[2], u[3], p)
    return force, deflection, rate, road, contact
