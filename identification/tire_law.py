"""Point-contact tire force law: spring k parallel to damper c, between hub and road.

This module is the single source of truth for the law.  It is deliberately
free of dependencies (only :mod:`math`) because the FMU build copies this very
file into every point-contact FMU, where it runs without the cleatfmu package.

Sign conventions (absolute vertical coordinates, SI units, z upwards):

* deflection  δ  = r0 − (z_hub − z_road)          m   (positive = compressed)
* rate        δ̇ = ż_road − ż_hub                  m/s (positive = compressing)
* force       F  = k δ + c δ̇                       N   (compressive positive,
  the force the road pushes the hub upwards with)
* contact flag   = δ > 0

The law is linear and bilateral (it also pulls when δ < 0), as in the cleat-test
paper's model.  Every function works element-wise on floats and on numpy
arrays alike (plain arithmetic and comparisons only).

Options (keyword-only, default = the law above) are the extension points: a
new behaviour is added as a new value of an option, never by changing what the
default does.  Today ``contact="bilateral"`` is the only value.
"""

from __future__ import annotations

import math

__all__ = [
    "CONTACT_MODES", "deflection_m", "deflection_rate_m_s", "force_n", "in_contact",
    "point_contact", "parameter_problem", "value_problem",
]

#: Accepted values of the ``contact`` option of :func:`point_contact`.
CONTACT_MODES = ("bilateral",)


def deflection_m(hub_z_m, road_z_m, unloaded_radius_m):
    """Radial tire deflection δ = r0 − (z_hub − z_road), m (positive = compressed).

    Parameters
    ----------
    hub_z_m : float or ndarray
        Hub (wheel centre) height, m.
    road_z_m : float or ndarray
        Road height under the contact point, m.
    unloaded_radius_m : float or ndarray
        Unloaded tire radius r0, m.
    """
    return unloaded_radius_m - (hub_z_m - road_z_m)


def deflection_rate_m_s(hub_vz_m_s, road_vz_m_s):
    """Deflection rate δ̇ = ż_road − ż_hub, m/s (positive = compressing).

    Parameters
    ----------
    hub_vz_m_s : float or ndarray
        Hub vertical velocity, m/s.
    road_vz_m_s : float or ndarray
        Rate of the road height under the contact point, m/s.
    """
    return road_vz_m_s - hub_vz_m_s


def force_n(deflection, deflection_rate, stiffness_n_m, damping_n_s_m):
    """Vertical tire force F = k δ + c δ̇, N (compressive positive, bilateral).

    Parameters
    ----------
    deflection : float or ndarray
        δ, m.
    deflection_rate : float or ndarray
        δ̇, m/s.
    stiffness_n_m : float
        k, N/m.
    damping_n_s_m : float
        c, N·s/m.
    """
    return stiffness_n_m * deflection + damping_n_s_m * deflection_rate


def in_contact(deflection):
    """Contact flag δ > 0 (bool, or bool array for an array δ)."""
    return deflection > 0.0


def point_contact(hub_z_m, hub_vz_m_s, road_z_m, road_vz_m_s, stiffness_n_m, damping_n_s_m,
                  unloaded_radius_m, *, contact="bilateral"):
    """Evaluate the point-contact tire for given hub and road motion.

    Parameters
    ----------
    hub_z_m, hub_vz_m_s : float or ndarray
        Hub height (m) and vertical velocity (m/s).
    road_z_m, road_vz_m_s : float or ndarray
        Road height (m) and its rate (m/s) under the contact point.
    stiffness_n_m : float
        Vertical stiffness k, N/m.
    damping_n_s_m : float
        Vertical damping coefficient c, N·s/m.
    unloaded_radius_m : float
        Unloaded radius r0, m.
    contact : {"bilateral"}, keyword-only
        Contact model.  ``"bilateral"``: the linear law holds for any δ, so the
        force is negative (pulling) when the tire is lifted off.

    Returns
    -------
    force : float or ndarray
        F = k δ + c δ̇, N, compressive positive.
    deflection : float or ndarray
        δ, m.
    deflection_rate : float or ndarray
        δ̇, m/s.
    contact_flag : bool or ndarray of bool
        δ > 0.

    Raises
    ------
    ValueError
        For an unknown ``contact`` value.
    """
    if contact not in CONTACT_MODES:
        raise ValueError(f"contact={contact!r} is not a known contact model (known: {', '.join(CONTACT_MODES)})")
    d = deflection_m(hub_z_m, road_z_m, unloaded_radius_m)
    dd = deflection_rate_m_s(hub_vz_m_s, road_vz_m_s)
    return force_n(d, dd, stiffness_n_m, damping_n_s_m), d, dd, in_contact(d)


def parameter_problem(stiffness_n_m, damping_n_s_m, unloaded_radius_m):
    """Why a scalar parameter set is invalid, or None if it is valid.

    Valid: k finite and > 0 N/m, c finite and ≥ 0 N·s/m, r0 finite and > 0 m.

    Returns
    -------
    str or None
        One-line description of the first problem found.
    """
    for name, unit, value, strictly in (("stiffness k", "N/m", stiffness_n_m, True),
                                        ("damping c", "N*s/m", damping_n_s_m, False),
                                        ("unloaded radius r0", "m", unloaded_radius_m, True)):
        problem = value_problem(name, unit, value, strictly_positive=strictly)
        if problem is not None:
            return problem
    return None


def value_problem(name, unit, value, *, strictly_positive):
    """Why one scalar parameter value is invalid, or None.

    Parameters
    ----------
    name, unit : str
        Used in the message.
    value : object
        The value to check (must be a real number, finite).
    strictly_positive : bool
        Require value > 0 (else value ≥ 0).
    """
    if isinstance(value, (bool, str, bytes)):
        return f"{name} must be a number in {unit}, got {value!r}"
    try:
        value = float(value)
    except (TypeError, ValueError):
        return f"{name} must be a number in {unit}, got {value!r}"
    if not math.isfinite(value):
        return f"{name} must be finite, got {value!r} {unit}"
    if strictly_positive and not value > 0:
        return f"{name} must be > 0 {unit}, got {value!r} {unit}"
    if not strictly_positive and not value >= 0:
        return f"{name} must be >= 0 {unit}, got {value!r} {unit}"
    return None
