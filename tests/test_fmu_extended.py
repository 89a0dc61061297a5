"""The extended tire FMU: the law it runs, its options, its model description and start values."""

from __future__ import annotations

import math

import numpy as np
import pytest
from extended_tire_cases import (BOOL_PARAMS, INPUTS, KIND, OPTION_SETS, OUTPUTS, REAL_OUTPUTS, REAL_PARAMS,
                                 law_outputs, random_inputs, random_parameters, read_outputs, set_parameters)
from fmu_helpers import (assert_runs_match_the_law, initial_unknowns, kind_fixtures, model_description,
                         output_dependencies)

import identification.model.tire_law as law
from build_scripts import build_fmu, load_kind
from build_scripts.compliance import compliance_problems
from build_scripts.reference import closed_form_outputs, read_reference
from build_scripts.runners import open_fmpy_slave, variable_refs


fmu, vr, slave = kind_fixtures(KIND)


# -- the law ------------------------------------------------------------------------------------

#: The variables in value-reference order: those of the first extended tire FMU, then the appended ones
#: (value references never change, so that importers' connections and saved states keep their meaning).
VALUE_REFERENCES = ["hub_z", "hub_vz", "road_z", "road_vz", "hub_x", "hub_vx", "stiffness", "damping",
                    "unloaded_radius", "footprint_length", "cleat_x", "cleat_height", "cleat_width", "unilateral",
                    "stiffness_exponent", "static_load", "friction_force", "friction_velocity", "lug_amplitude",
                    "lug_pitch", "lug_phase", "force_z", "deflection", "deflection_rate", "in_contact",
                    "road_effective_z",
                    "parabolic_pressure", "cleat_bevel", "ring_envelope"]  # appended, in this order


def test_value_references_of_existing_variables_never_change(fmu, vr):
    assert [v.name for v in load_kind(KIND).variables] == VALUE_REFERENCES
    assert vr == {name: i for i, name in enumerate(VALUE_REFERENCES)}


def test_parameters_are_the_laws_with_its_defaults(fmu):
    kind = load_kind(KIND)
    params = {v.name: v for v in kind.variables if v.causality == "parameter"}
    assert sorted(params) == sorted(law.EXTENDED_DEFAULTS)
    for name, default in law.EXTENDED_DEFAULTS.items():
        assert params[name].start == default and type(params[name].start) is type(default), name
        assert params[name].type == ("Boolean" if isinstance(default, bool) else "Real")
    starts = {}
    for sv in model_description(fmu).iter("ScalarVariable"):
        typed = sv[0]
        if sv.get("causality") == "parameter":
            starts[sv.get("name")] = (typed.get("start") == "true" if typed.tag == "Boolean"
                                      else float(typed.get("start")))
    assert starts == law.EXTENDED_DEFAULTS


@pytest.mark.parametrize("options", OPTION_SETS, ids=["+".join(o) for o in OPTION_SETS])
def test_outputs_are_the_law_for_random_inputs_and_parameters(slave, vr, options):
    s, _ = slave
    rng = np.random.default_rng(OPTION_SETS.index(options))
    seen_contact, active = set(), 0
    for _ in range(6):
        p = random_parameters(rng, options)
        set_parameters(s, vr, p)
        for _ in range(25):
            u = random_inputs(rng, p)
            s.setReal([vr[n] for n in INPUTS], u)
            expected = law_outputs(u, p)
            assert read_outputs(s, vr) == expected  # before doStep: direct feedthrough, bit for bit
            s.doStep(0.0, 1e-3)
            assert read_outputs(s, vr) == expected
            seen_contact.add(expected[-1])
            plain = {**law.EXTENDED_DEFAULTS, **{n: p[n] for n in ("stiffness", "damping", "unloaded_radius")}}
            active += law_outputs(u, plain)[0] != expected[0]
    assert seen_contact == {True, False}
    assert active >= 10  # the options change the force


def test_with_every_option_at_its_default_the_force_is_the_point_contact_force(fmu, vr, tmp_path):
    point = build_fmu("point_contact", tmp_path / "point_contact.fmu")
    pvr = {name: ref for name, (ref, _type) in variable_refs(point).items()}
    rng = np.random.default_rng(11)
    a, b = open_fmpy_slave(fmu, instance_name="extended"), open_fmpy_slave(point, instance_name="point")
    try:
        for _ in range(200):
            kcr = [rng.uniform(5e4, 2e6), rng.uniform(0.0, 2e4), rng.uniform(0.3, 1.0)]
            u = random_inputs(rng, {"unloaded_radius": kcr[2], "cleat_x": 0.0})
            for s, refs in ((a, vr), (b, pvr)):
                s.setReal([refs[n] for n in ("stiffness", "damping", "unloaded_radius")], kcr)
                s.setReal([refs[n] for n in INPUTS if n in refs], [x for n, x in zip(INPUTS, u) if n in refs])
            names = ["force_z", "deflection", "deflection_rate"]
            assert a.getReal([vr[n] for n in names]) == b.getReal([pvr[n] for n in names])
            assert a.getBoolean([vr["in_contact"]]) == b.getBoolean([pvr["in_contact"]])
            assert a.getReal([vr["road_effective_z"]]) == [u[2]]
    finally:
        a.freeInstance()
        b.freeInstance()


# Footprint l = 0.3 m centred on hub_x, cleat H = 0.05 m, w = 0.1 m from x_c = 0.5 m: the cleat enters the
# footprint at hub_x = 0.35 m, fills it (plateau H w / l) from 0.45 m to 0.65 m and leaves it at 0.75 m.
CLEAT = {"footprint_length": 0.3, "cleat_x": 0.5, "cleat_height": 0.05, "cleat_width": 0.1}


@pytest.mark.parametrize("hub_x, expected", [  # H s / l with s the length of cleat inside the footprint
    (0.2, 0.0), (0.349, 0.0), (0.36, 0.05 * 0.01 / 0.3), (0.4, 0.05 * 0.05 / 0.3), (0.44, 0.05 * 0.09 / 0.3),
    (0.451, 0.05 * 0.1 / 0.3), (0.55, 0.05 * 0.1 / 0.3), (0.649, 0.05 * 0.1 / 0.3), (0.66, 0.05 * 0.09 / 0.3),
    (0.7, 0.05 * 0.05 / 0.3), (0.74, 0.05 * 0.01 / 0.3), (0.751, 0.0), (1.2, 0.0),
])
def test_enveloped_cleat_is_the_footprint_average_of_the_rectangle(slave, vr, hub_x, expected):
    s, _ = slave
    s.setReal([vr[n] for n in CLEAT], list(CLEAT.values()))
    road_z, speed = 0.012, 2.0
    s.setReal([vr[n] for n in INPUTS], [0.74, 0.0, road_z, 0.0, hub_x, speed])
    road, rate = s.getReal([vr["road_effective_z"], vr["deflection_rate"]])
    assert road - road_z == pytest.approx(expected, rel=1e-12, abs=1e-15)
    ramp = 0.05 / 0.3 * speed  # d(road)/dt on the ramps: (H / l) * hub_vx
    slope = ramp if 0.35 < hub_x < 0.45 else -ramp if 0.65 < hub_x < 0.75 else 0.0
    assert rate == pytest.approx(slope, rel=1e-12, abs=1e-15)


def _parabolic_cleat_by_quadrature(x, length, xc, height, width):
    """The cleat height averaged over the footprint [x - l/2, x + l/2] with the parabolic pressure density
    3/(2 l) (1 - u^2), u = 2 (s - x) / l, integrated numerically over the part of the cleat inside it."""
    from scipy.integrate import quad

    lo, hi = max(x - 0.5 * length, xc), min(x + 0.5 * length, xc + width)
    if hi <= lo:
        return 0.0
    value, _ = quad(lambda s: 1.5 / length * (1.0 - (2.0 * (s - x) / length) ** 2), lo, hi,
                    epsabs=1e-14, epsrel=1e-13)
    return height * value


@pytest.mark.parametrize("length, width", [(0.3, 0.1), (0.08, 0.2), (0.25, 0.25)])
def test_parabolic_footprint_is_the_pressure_weighted_average_of_the_rectangle(length, width):
    """The law's parabolic branch against quadrature (height) and central differences of it (slope)."""
    from scipy.integrate import quad

    xc, height, h, speed = 0.5, 0.05, 1e-6, 2.0
    p = {**law.EXTENDED_DEFAULTS, "footprint_length": length, "cleat_x": xc, "cleat_height": height,
         "cleat_width": width, "parabolic_pressure": True}
    force_fn, q = law.extended_force_fn(p), law.law_vector(p)
    # where an end of the footprint passes an edge of the cleat the height is C1 but not C2: no difference there
    kinks = np.array([xc - 0.5 * length, xc + 0.5 * length, xc + width - 0.5 * length, xc + width + 0.5 * length])
    xs = [x for x in np.linspace(kinks.min() - 0.05, kinks.max() + 0.05, 57) if np.abs(x - kinks).min() > 1e-4]
    bumps = 0
    for x in xs:
        cleat, slope = law.footprint_cleat(x, length, xc, height, width, True)
        assert abs(cleat - _parabolic_cleat_by_quadrature(x, length, xc, height, width)) <= 1e-9, x
        by_difference = (_parabolic_cleat_by_quadrature(x + h, length, xc, height, width)
                         - _parabolic_cleat_by_quadrature(x - h, length, xc, height, width)) / (2.0 * h)
        assert abs(slope - by_difference) <= 1e-9, x
        # the law's three forms (mapping, force callback, flat vector) run the same branch, bit for bit
        f, _, dd, _, road = law.extended_tire(0.74, 0.0, x, speed, 0.0, 0.0, p)
        assert (road, dd) == (cleat, slope * speed)
        assert law.tire_force(0.74, 0.0, x, speed, 0.0, 0.0, q) == f == force_fn(0.74, 0.0, x, speed, 0.0, 0.0)
        bumps += 0.0 < cleat < height and slope != 0.0
    assert bumps >= 20
    # the pressure is normalised: uniform and parabolic footprints spread the same cleat area H w along x
    for parabolic in (False, True):
        area, _ = quad(lambda x: law.footprint_cleat(x, length, xc, height, width, parabolic)[0],
                       kinks.min(), kinks.max(), points=kinks[1:3], epsabs=1e-14, limit=200)
        assert area == pytest.approx(height * width, rel=1e-9), parabolic


def test_parabolic_footprint_in_the_fmu(slave, vr):
    s, _ = slave
    s.setReal([vr[n] for n in CLEAT], list(CLEAT.values()))
    s.setBoolean([vr["parabolic_pressure"]], [True])
    road_z, speed = 0.012, 2.0
    for hub_x in (0.3, 0.36, 0.4, 0.45, 0.5, 0.55, 0.6, 0.7, 0.74, 0.8):
        s.setReal([vr[n] for n in INPUTS], [0.74, 0.0, road_z, 0.0, hub_x, speed])
        road, rate = s.getReal([vr["road_effective_z"], vr["deflection_rate"]])
        expected = _parabolic_cleat_by_quadrature(hub_x, CLEAT["footprint_length"], CLEAT["cleat_x"],
                                                  CLEAT["cleat_height"], CLEAT["cleat_width"])
        assert road - road_z == pytest.approx(expected, rel=1e-9, abs=1e-12)
        cleat, slope = law.footprint_cleat(hub_x, *CLEAT.values(), True)
        assert (road, rate) == (road_z + cleat, slope * speed)
    s.setBoolean([vr["parabolic_pressure"]], [False])  # back to the uniform footprint (plateau H w / l)
    s.setReal([vr["hub_x"]], [0.55])
    assert s.getReal([vr["road_effective_z"]])[0] - road_z == pytest.approx(0.05 * 0.1 / 0.3, rel=1e-12)


def _trapezoid_height(s, xc, height, width, bevel):
    """The bevelled cleat at s: 0 outside [xc, xc + w], rising linearly over the bevel b to H, H on its top."""
    return height * min(1.0, max(0.0, min(s - xc, xc + width - s) / bevel))


def _bevelled_cleat_by_quadrature(x, length, xc, height, width, bevel, parabolic):
    """The bevelled cleat averaged over the footprint [x - l/2, x + l/2] under a uniform (1/l) or parabolic
    (3/(2 l) (1 - u^2), u = 2 (s - x) / l) pressure, integrated numerically piece by piece between the
    trapezoid's corners; with l = 0 the trapezoid's height at x."""
    from scipy.integrate import quad

    if length == 0.0:
        return _trapezoid_height(x, xc, height, width, bevel)
    lo, hi = x - 0.5 * length, x + 0.5 * length

    def weighted(s):
        pressure = 1.5 / length * (1.0 - (2.0 * (s - x) / length) ** 2) if parabolic else 1.0 / length
        return _trapezoid_height(s, xc, height, width, bevel) * pressure

    cuts = sorted({lo, hi} | {min(max(xc + k, lo), hi) for k in (0.0, bevel, width - bevel, width)})
    return sum(quad(weighted, a, b, epsabs=1e-15, epsrel=1e-14)[0] for a, b in zip(cuts[:-1], cuts[1:]) if b > a)


#: (footprint l, cleat width w, bevel b, parabolic pressure) of the bevelled cleats checked against quadrature:
#: under the contact point a trapezoid and a triangle (b = w/2); footprints longer and shorter than the cleat,
#: over a triangle, and shorter than the bevel, under both pressures.
BEVELLED = [(0.0, 0.1, 0.02, False), (0.0, 0.1, 0.05, False),
            *((length, width, bevel, parabolic) for parabolic in (False, True)
              for length, width, bevel in ((0.3, 0.1, 0.02), (0.08, 0.2, 0.05), (0.25, 0.25, 0.125),
                                           (0.02, 0.1, 0.03)))]


@pytest.mark.parametrize("length, width, bevel, parabolic", BEVELLED,
                         ids=[f"{'parabolic' if c[3] else 'uniform' if c[0] else 'point'}-l{c[0]}-w{c[1]}-b{c[2]}"
                              for c in BEVELLED])
def test_bevelled_cleat_is_the_pressure_weighted_average_of_the_trapezoid(length, width, bevel, parabolic):
    """The law's bevelled cleat (a sum of four ramps) against quadrature of the trapezoid itself (height, to
    1e-12 m) and central differences of that quadrature (slope); the law's three forms agree bit for bit."""
    from scipy.integrate import quad

    xc, height, h, speed = 0.5, 0.05, 1e-6, 2.0
    p = {**law.EXTENDED_DEFAULTS, "footprint_length": length, "cleat_x": xc, "cleat_height": height,
         "cleat_width": width, "cleat_bevel": bevel, "parabolic_pressure": parabolic}
    assert law.extended_parameter_problem(p) is None
    force_fn, q = law.extended_force_fn(p), law.law_vector(p)
    corners = np.array([xc, xc + bevel, xc + width - bevel, xc + width])
    # where an end of the footprint passes a corner of the trapezoid the slope has a kink: no difference there
    kinks = np.concatenate([corners - 0.5 * length, corners + 0.5 * length])
    xs = [x for x in np.linspace(kinks.min() - 0.05, kinks.max() + 0.05, 121) if np.abs(x - kinks).min() > 1e-4]
    ramps = 0
    for x in xs:
        cleat, slope = law.footprint_cleat(x, length, xc, height, width, parabolic, bevel)
        args = (length, xc, height, width, bevel, parabolic)
        assert abs(cleat - _bevelled_cleat_by_quadrature(x, *args)) <= 1e-12, x
        by_difference = (_bevelled_cleat_by_quadrature(x + h, *args)
                         - _bevelled_cleat_by_quadrature(x - h, *args)) / (2.0 * h)
        assert abs(slope - by_difference) <= 1e-7 * max(1.0, abs(slope)), (x, slope, by_difference)
        f, _, dd, _, road = law.extended_tire(0.74, 0.0, x, speed, 0.0, 0.0, p)
        assert (road, dd) == (cleat, slope * speed)
        assert law.tire_force(0.74, 0.0, x, speed, 0.0, 0.0, q) == f == force_fn(0.74, 0.0, x, speed, 0.0, 0.0)
        ramps += 0.0 < cleat and slope != 0.0
    assert ramps >= 15
    # every pressure spreads the same area, the trapezoid's H (w - b), along x
    area, _ = quad(lambda x: law.footprint_cleat(x, length, xc, height, width, parabolic, bevel)[0],
                   kinks.min(), kinks.max(), points=np.unique(kinks)[1:-1], epsabs=1e-14, limit=200)
    assert area == pytest.approx(height * (width - bevel), rel=1e-9)


#: Bevels of the fmpy runs: under the contact point, uniform and parabolic footprint pressures.
BEVEL_RUNS = {"point contact": {"footprint_length": 0.0}, "uniform": {}, "parabolic": {"parabolic_pressure": True}}


@pytest.mark.parametrize("run", list(BEVEL_RUNS))
def test_bevelled_cleat_stepped_in_fmpy_gives_the_independent_closed_form_in_both_backends(fmu, tmp_path, run):
    """The reference experiment (every option on) over a cleat with 30 mm bevels, stepped by fmpy: the
    pythonfmu FMU (built with the bevel, or switched to it before initialization) and the native FMU give
    the Python law's outputs for the inputs held over each step, and build_scripts/reference.py's
    independent closed form of the trapezoid's footprint average."""
    kind = load_kind(KIND)
    starts = {**kind.reference_start_values, "cleat_bevel": 0.03, **BEVEL_RUNS[run]}
    p = {**law.EXTENDED_DEFAULTS, **starts}
    assert law.extended_parameter_problem(p) is None
    ref = read_reference(KIND)
    signals = {n: ref[n] for n in ["time", *INPUTS]}
    held = {n: np.concatenate([signals[n][:1], signals[n][:-1]]) for n in INPUTS}  # fmpy's alignment
    rows = [law.extended_tire(*(float(held[n][k]) for n in ("hub_z", "hub_vz", "hub_x", "hub_vx", "road_z",
                                                            "road_vz")), p) for k in range(ref["time"].size)]
    expected = {name: np.array([row[j] for row in rows]) for j, name in
                enumerate(("force_z", "deflection", "deflection_rate", "in_contact", "road_effective_z"))}
    closed = closed_form_outputs(KIND, signals, p)
    # the bevel matters in this run: another road under the tire than over the rectangle, on the bevels' ramps
    square = closed_form_outputs(KIND, signals, {**p, "cleat_bevel": 0.0})
    assert np.abs(closed["road_effective_z"] - square["road_effective_z"]).max() > 1e-3
    if run == "point contact":  # the bevels' slope is felt: H / b * hub_vx
        assert np.isclose(np.abs(closed["deflection_rate"] - square["deflection_rate"]),
                          0.05 / 0.03 * 7.0 / 3.6, rtol=1e-9).sum() >= 20
    runs = {"pythonfmu built with the bevel": (build_fmu(KIND, tmp_path / "py.fmu", start_values=starts), None),
            "pythonfmu switched before initialization": (fmu, starts),
            "native built with the bevel": (build_fmu(KIND, tmp_path / "native.fmu", backend="native",
                                                      start_values=starts, platforms=["linux64"]), None)}
    assert_runs_match_the_law(runs, signals, OUTPUTS, expected, closed, kind)


def test_a_bevel_beyond_half_the_cleat_width_is_refused_naming_cleat_bevel(slave, vr, tmp_path):
    """b <= w/2 is a constraint between parameters: a bevel set before the width that allows it is accepted,
    but reading an output, stepping and leaving initialization fail, naming cleat_bevel, until it holds; a
    negative or non-finite bevel is refused as it is set; a build with such a bevel is refused."""
    from fmpy.fmi1 import FMICallException

    s, messages = slave
    s.setReal([vr["cleat_height"], vr["cleat_x"]], [0.04, 0.0])
    s.setReal([vr["cleat_bevel"]], [0.08])  # the width is still 0.1 m
    for call in (lambda: s.getReal([vr["road_effective_z"]]), lambda: s.getBoolean([vr["in_contact"]]),
                 lambda: s.doStep(0.0, 1e-3)):
        with pytest.raises(FMICallException):
            call()
    reason = "cleat_bevel must be <= cleat_width / 2 (0.05 m), got 0.08 m"
    assert sum(status == 3 and reason in m for status, m in messages) == 3, messages
    s.setReal([vr["cleat_width"]], [0.2])  # now b = 0.08 m <= 0.1 m
    s.setReal([vr["hub_x"], vr["hub_vx"]], [0.04, 2.0])  # on the leading bevel, half way up
    road, rate = s.getReal([vr["road_effective_z"], vr["deflection_rate"]])
    assert road == pytest.approx(0.04 * 0.04 / 0.08, rel=1e-12) and rate == pytest.approx(0.04 / 0.08 * 2.0)
    s.doStep(0.0, 1e-3)
    for value, words in ((-0.01, "cleat_bevel must be >= 0 m"), (math.inf, "cleat_bevel")):
        count = len(messages)
        with pytest.raises(FMICallException):
            s.setReal([vr["cleat_bevel"]], [value])
        assert any(status == 3 and words in m for status, m in messages[count:]), messages[count:]
        assert s.getReal([vr["cleat_bevel"]]) == [0.08]
    s.reset()
    s.setupExperiment(startTime=0.0)
    s.setReal([vr["cleat_bevel"]], [0.06])  # the start width 0.1 m allows 0.05 m
    s.enterInitializationMode()
    count = len(messages)
    with pytest.raises(FMICallException):
        s.exitInitializationMode()
    assert any(status == 3 and "cleat_bevel must be <= cleat_width / 2" in m for status, m in messages[count:])
    for backend in ("pythonfmu", "native"):
        with pytest.raises(ValueError, match=r"cleat_bevel must be <= cleat_width / 2 \(0.05 m\), got 0.06 m"):
            build_fmu(KIND, tmp_path / f"{backend}.fmu", start_values={"cleat_bevel": 0.06}, backend=backend,
                      platforms=["linux64"] if backend == "native" else None)
    assert list(tmp_path.iterdir()) == []


def test_without_footprint_the_cleat_is_felt_under_the_contact_point_only(slave, vr):
    s, _ = slave
    s.setReal([vr[n] for n in CLEAT], [0.0, *list(CLEAT.values())[1:]])
    for hub_x, height in ((0.499, 0.0), (0.5, 0.05), (0.55, 0.05), (0.6, 0.0)):
        s.setReal([vr["hub_x"], vr["hub_vx"]], [hub_x, 2.0])
        assert s.getReal([vr["road_effective_z"], vr["deflection_rate"]]) == [height, 0.0]


def test_unilateral_contact_never_pulls(slave, vr):
    s, _ = slave
    k, c, r0 = s.getReal([vr[n] for n in ("stiffness", "damping", "unloaded_radius")])
    cases = [  # (hub_z, hub_vz, sign of δ, sign of the bilateral force, in contact when unilateral)
        (r0 + 0.01, 0.0, -1, -1, False),  # lifted off
        (r0 + 0.01, -3.0, -1, 1, False),  # lifted off, even while the damper pushes
        (r0, -0.5, 0, 1, False),  # δ = 0
        (r0 - 0.01, 3.0, 1, -1, False),  # δ > 0 but the damper pulls harder than the spring pushes
        (r0 - 0.01, 1.0, 1, 1, True),  # δ > 0, pushing
    ]
    for hub_z, hub_vz, deflection_sign, force_sign, contact in cases:
        s.setReal([vr["hub_z"], vr["hub_vz"]], [hub_z, hub_vz])
        s.setBoolean([vr["unilateral"]], [False])
        bilateral, deflection = s.getReal([vr["force_z"], vr["deflection"]])
        assert bilateral == k * (r0 - hub_z) + c * (-hub_vz)
        assert (np.sign(deflection), np.sign(bilateral)) == (deflection_sign, force_sign)
        s.setBoolean([vr["unilateral"]], [True])
        force, (flag,) = s.getReal([vr["force_z"]])[0], s.getBoolean([vr["in_contact"]])
        assert bool(flag) is contact
        assert force == (bilateral if contact else 0.0)


def test_reference_run_exercises_every_option_and_obeys_the_closed_form():
    kind = load_kind(KIND)
    ref = read_reference(KIND)
    p = {**law.EXTENDED_DEFAULTS, **kind.reference_start_values}
    assert p["footprint_length"] > p["cleat_width"] and p["cleat_height"] > 0 and p["unilateral"]
    assert p["stiffness_exponent"] != 1 and p["friction_force"] > 0 and p["lug_amplitude"] != 0
    expected = closed_form_outputs(KIND, {n: ref[n] for n in ["time", *INPUTS]}, p)
    for name in REAL_OUTPUTS:
        np.testing.assert_allclose(ref[name], expected[name], rtol=kind.reference_rtol, atol=kind.reference_atol)
    assert np.array_equal(ref["in_contact"], expected["in_contact"])
    held_x = np.concatenate([ref["hub_x"][:1], ref["hub_x"][:-1]])  # fmpy's alignment (see runners)
    held_road = np.concatenate([ref["road_z"][:1], ref["road_z"][:-1]])
    lug = p["lug_amplitude"] * np.sin(2 * np.pi * held_x / p["lug_pitch"] + p["lug_phase"])
    cleat = ref["road_effective_z"] - held_road - lug
    plateau = p["cleat_height"] * p["cleat_width"] / p["footprint_length"]
    assert np.isclose(cleat, plateau, rtol=1e-9).sum() > 50 and np.isclose(cleat, 0.0, atol=1e-12).sum() > 50
    assert ((cleat > 1e-4) & (cleat < plateau - 1e-4)).sum() > 50  # both ramps
    lifted, pulled = ref["deflection"] <= 0, (ref["deflection"] > 0) & ~ref["in_contact"]
    assert lifted.sum() > 50 and pulled.sum() > 5 and ref["in_contact"].sum() > 50
    assert np.all(ref["force_z"][~ref["in_contact"]] == 0.0) and np.all(ref["force_z"][ref["in_contact"]] > 0)
    assert np.abs(ref["deflection_rate"]).max() > 10 * p["friction_velocity"]  # friction saturates
    linear = closed_form_outputs(KIND, {n: ref[n] for n in ["time", *INPUTS]}, {**p, "stiffness_exponent": 1.0})
    assert np.abs(linear["force_z"] - ref["force_z"]).max() > 1000.0  # the progressive spring matters


# -- model description --------------------------------------------------------------------------

EXPECTED_UNITS = {"hub_z": "m", "hub_vz": "m/s", "road_z": "m", "road_vz": "m/s", "hub_x": "m", "hub_vx": "m/s",
                  "stiffness": "N/m", "damping": "N.s/m", "unloaded_radius": "m", "footprint_length": "m",
                  "cleat_x": "m", "cleat_height": "m", "cleat_width": "m", "stiffness_exponent": "1",
                  "static_load": "N", "friction_force": "N", "friction_velocity": "m/s", "lug_amplitude": "m",
                  "lug_pitch": "m", "lug_phase": "rad", "force_z": "N", "deflection": "m", "deflection_rate": "m/s",
                  "road_effective_z": "m", "cleat_bevel": "m"}
EXPECTED_INPUT_DEPENDENCIES = {"force_z": set(INPUTS), "in_contact": set(INPUTS),
                               "deflection": {"hub_z", "road_z", "hub_x"},
                               # the ring's equivalent cleat depends on the hub's deflection over the road
                               "deflection_rate": {"hub_z", "hub_vz", "road_z", "road_vz", "hub_x", "hub_vx"},
                               "road_effective_z": {"hub_z", "road_z", "hub_x"}}


def test_compliance_units_descriptions_and_experiment(fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu)) == []
    assert compliance_problems(fmu) == []
    root = model_description(fmu)
    units = {u.get("name") for u in root.find("UnitDefinitions")}
    variables = {sv.get("name"): sv for sv in root.iter("ScalarVariable")}
    assert set(variables) == set(EXPECTED_UNITS) | {"unilateral", "parabolic_pressure", "ring_envelope", "in_contact"}
    for name, sv in variables.items():
        assert sv.get("description"), name
        if name in EXPECTED_UNITS:
            assert sv.find("Real").get("unit") == EXPECTED_UNITS[name] and EXPECTED_UNITS[name] in units
    for name in BOOL_PARAMS:
        flag = variables[name]
        assert (flag.get("causality"), flag.get("variability"), flag.find("Boolean").get("start")) \
            == ("parameter", "tunable", "false"), name
    de = root.find("DefaultExperiment")
    assert (float(de.get("startTime")), float(de.get("stopTime")), float(de.get("stepSize"))) == (0.0, 0.6, 0.001)
    cs = root.find("CoSimulation")
    assert cs.get("modelIdentifier") == "CleatfmuExtendedTire"
    assert (cs.get("canGetAndSetFMUstate"), cs.get("canSerializeFMUstate")) == ("true", "true")


def test_model_structure_lists_exactly_the_inputs_each_output_depends_on(fmu):
    root = model_description(fmu)
    declared = {out: names for out, (names, _kinds) in output_dependencies(root).items()}
    assert declared == EXPECTED_INPUT_DEPENDENCIES
    assert initial_unknowns(root) == set(OUTPUTS)


def test_declared_dependencies_hold_numerically(slave, vr):
    """Perturbing an input changes only outputs that declare it; a "constant" kind has coefficient +-1."""
    s, _ = slave
    kinds = {v.name: v.depends for v in load_kind(KIND).variables if v.causality == "output"}
    rng = np.random.default_rng(5)
    changed = {(out, i): False for out in OUTPUTS for i in EXPECTED_INPUT_DEPENDENCIES[out]}
    for draw in range(80):   # every option on, the footprint parabolic or the ring's
        p = random_parameters(rng, OPTION_SETS[-1 - draw % 2])
        set_parameters(s, vr, p)
        u = random_inputs(rng, p)
        s.setReal([vr[n] for n in INPUTS], u)
        base = dict(zip(OUTPUTS, read_outputs(s, vr)))
        for j, name in enumerate(INPUTS):
            h = 1e-6
            s.setReal([vr[name]], [u[j] + h])
            moved = dict(zip(OUTPUTS, read_outputs(s, vr)))
            s.setReal([vr[name]], [u[j]])
            for out in OUTPUTS:
                if name not in EXPECTED_INPUT_DEPENDENCIES[out]:
                    assert moved[out] == base[out], (out, name)
                    continue
                changed[out, name] |= moved[out] != base[out]
                if kinds[out][name] == "constant":
                    assert abs(moved[out] - base[out]) == pytest.approx(h, rel=1e-6), (out, name)
    assert all(changed[out, i] for out in REAL_OUTPUTS for i in EXPECTED_INPUT_DEPENDENCIES[out])


def test_build_writes_every_start_value_including_the_boolean_and_the_description(tmp_path, vr):
    starts = {"stiffness": 312345.6789012345, "damping": 1234.5, "unloaded_radius": 0.8, "footprint_length": 0.25,
              "cleat_x": -0.3, "cleat_height": 0.04, "cleat_width": 0.08, "unilateral": True,
              "stiffness_exponent": 1.25, "static_load": 12000.0, "friction_force": 300.0,
              "friction_velocity": 0.02, "lug_amplitude": 0.003, "lug_pitch": 0.3, "lug_phase": 0.7,
              "parabolic_pressure": True, "cleat_bevel": 0.015}
    fmu = build_fmu(KIND, tmp_path / "FL.fmu", start_values=starts, description="front left, test day 3")
    root = model_description(fmu)
    assert root.get("description") == "front left, test day 3"
    written = {}
    for sv in root.iter("ScalarVariable"):
        typed = sv[0]
        if sv.get("name") in starts:
            start = typed.get("start")
            written[sv.get("name")] = start == "true" if typed.tag == "Boolean" else float(start)
    assert written == starts
    s = open_fmpy_slave(fmu)
    try:
        assert s.getReal([vr[n] for n in REAL_PARAMS]) == [starts[n] for n in REAL_PARAMS]
        assert s.getBoolean([vr[n] for n in BOOL_PARAMS]) == [1, 1, 0]
        assert s.getReal([vr["hub_z"]]) == [0.8]
    finally:
        s.freeInstance()


@pytest.mark.parametrize("starts, match", [
    ({"unilateral": 1}, "True or False"), ({"parabolic_pressure": 0.0}, "True or False"),
    ({"stiffness_exponent": True}, "finite number"),
    ({"lug_phase": math.nan}, "finite"), ({"stiffness_exponent": 1.4}, "static_load must be > 0"),
    ({"cleat_width": 0.0}, "cleat_width must be > 0"),
    ({"cleat_bevel": -0.001}, "cleat_bevel must be >= 0 m"),
    ({"cleat_bevel": 0.06}, r"cleat_bevel must be <= cleat_width / 2 \(0.05 m\), got 0.06 m"),
    ({"cleat_bevel": 0.03, "cleat_width": 0.05}, "cleat_bevel must be <= cleat_width / 2"),
])
def test_build_rejects_invalid_start_values(tmp_path, starts, match):
    with pytest.raises(ValueError, match=match):
        build_fmu(KIND, tmp_path / "bad.fmu", start_values=starts)
    assert list(tmp_path.iterdir()) == []
