"""The point-contact tire law (identification.model.tire_law) against exact arithmetic."""

from __future__ import annotations

import ast
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from identification.model import tire_law


def random_cases(n, seed):
    """Random hub/road motion and parameters in physically meaningful ranges (SI units)."""
    rng = np.random.default_rng(seed)
    r0 = rng.uniform(0.3, 1.0, n)
    return dict(hub_z=r0 + rng.uniform(-0.08, 0.03, n), hub_vz=rng.uniform(-2.0, 2.0, n),
                road_z=rng.uniform(-0.02, 0.06, n), road_vz=rng.uniform(-3.0, 3.0, n),
                k=rng.uniform(5e4, 2e6, n), c=rng.uniform(0.0, 2e4, n), r0=r0)


def exact_force(zh, vh, zr, vr, k, c, r0):
    """k (r0 - (zh - zr)) + c (vr - vh), evaluated exactly in rationals."""
    f = [Fraction(float(x)) for x in (zh, vh, zr, vr, k, c, r0)]
    zh, vh, zr, vr, k, c, r0 = f
    return k * (r0 - (zh - zr)) + c * (vr - vh)


def test_force_equals_closed_form_to_1e_12_relative_for_random_inputs():
    cases = random_cases(2000, seed=1)
    worst = 0.0
    for i in range(2000):
        args = [float(cases[key][i]) for key in ("hub_z", "hub_vz", "road_z", "road_vz", "k", "c", "r0")]
        force, *_ = tire_law.point_contact(*args)
        exact = exact_force(*args)
        worst = max(worst, abs(float((Fraction(force) - exact) / exact)))
    assert worst <= 1e-12


def test_arrays_give_the_same_bits_as_floats():
    cases = random_cases(500, seed=2)
    f, d, dd, flag = tire_law.point_contact(cases["hub_z"], cases["hub_vz"], cases["road_z"], cases["road_vz"],
                                            cases["k"], cases["c"], cases["r0"])
    assert isinstance(f, np.ndarray) and flag.dtype == bool
    for i in range(500):
        scalar = tire_law.point_contact(*(float(cases[key][i]) for key in
                                          ("hub_z", "hub_vz", "road_z", "road_vz", "k", "c", "r0")))
        assert (scalar[0], scalar[1], scalar[2], scalar[3]) == (f[i], d[i], dd[i], bool(flag[i]))


def test_signs_and_contact_flag():
    # hub 10 mm below the unloaded radius above a flat road, moving down at 0.5 m/s: compressed and compressing
    f, d, dd, flag = tire_law.point_contact(0.74, -0.5, 0.0, 0.0, 2e5, 1e3, 0.75)
    assert d == pytest.approx(0.01, abs=1e-15) and dd == 0.5 and flag is True
    assert f == pytest.approx(2e5 * 0.01 + 1e3 * 0.5, rel=1e-14)
    # road rising under a hub at rest: the rate is the road's
    assert tire_law.deflection_rate_m_s(0.0, 0.3) == 0.3
    # lifted off by 5 mm: bilateral law pulls, no contact
    f, d, dd, flag = tire_law.point_contact(0.805, 0.0, 0.05, 0.0, 2e5, 1e3, 0.75)
    assert d == pytest.approx(-0.005, abs=1e-15) and f < 0.0 and flag is False
    # exactly touching: no contact, no force
    f, d, _, flag = tire_law.point_contact(0.75, 0.0, 0.0, 0.0, 2e5, 1e3, 0.75)
    assert (f, d, flag) == (0.0, 0.0, False)


def test_unknown_contact_model_is_refused():
    with pytest.raises(ValueError, match="contact"):
        tire_law.point_contact(0.7, 0.0, 0.0, 0.0, 2e5, 1e3, 0.75, contact="unilateral")


@pytest.mark.parametrize("k, c, r0, fragment", [
    (0.0, 1.0, 0.7, "stiffness k must be > 0"), (-1.0, 1.0, 0.7, "stiffness k must be > 0"),
    (math.nan, 1.0, 0.7, "stiffness k must be finite"), (1e5, -1.0, 0.7, "damping c must be >= 0"),
    (1e5, math.inf, 0.7, "damping c must be finite"), (1e5, 1.0, 0.0, "unloaded radius r0 must be > 0"),
    (True, 1.0, 0.7, "must be a number"), ("1e5", 1.0, 0.7, "must be a number"),
])
def test_parameter_problems_are_named(k, c, r0, fragment):
    assert fragment in tire_law.parameter_problem(k, c, r0)


def test_valid_parameters_have_no_problem():
    assert tire_law.parameter_problem(4e5, 0.0, 0.75) is None
    assert tire_law.parameter_problem(np.float64(4e5), 1, 0.75) is None


def test_law_module_imports_only_math():
    tree = ast.parse(Path(tire_law.__file__).read_text(encoding="utf-8"))
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            imported.add(node.module)
    assert imported <= {"math", "__future__"}
