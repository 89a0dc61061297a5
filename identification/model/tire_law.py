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

Extended tire (:func:`extended_tire`, scalar floats; every option's default
reduces it to the point-contact law above):

* **footprint** (``enveloping``): a built-in rectangular cleat (leading edge at
  ``cleat_x``, height H, width w) is averaged over a footprint of length ℓ
  centred on the hub's longitudinal position x - the fixed-footprint model -
  so the tire needs x and ẋ, not the road under its contact point.  The
  average is weighted by the contact pressure along the footprint:

  - uniform (``parabolic_pressure`` false, the default):
    r = H · overlap([x − ℓ/2, x + ℓ/2], [x_c, x_c + w]) / ℓ;
  - parabolic (``parabolic_pressure`` true), pressure ∝ 1 − u², u = 2 ξ / ℓ
    for ξ the distance from the footprint centre, zero at the footprint's ends
    as on a real tire: r = H [P(x_c + w − x) − P(x_c − x)] with the cumulative
    pressure P(ξ) = 1/2 + 3/4 (u − u³/3), u clipped to [−1, 1].

  ṙ = dr/dx · ẋ.  A parabolic footprint of length ℓ spreads the cleat like a
  uniform one of length ≈ 0.77 ℓ (same second moment), but with no kink where
  the footprint's ends pass the cleat's edges;
* **rigid-ring envelope** (``ring_envelope``, with a footprint): the tire as a rigid
  ring of radius R over an elastic bed whose pressure is ∝ sqrt(δ(ξ)), δ(ξ) = δ + z(x + ξ) − ξ²/2R
  the bed's compression at ξ from the hub (small angles): on flat ground its contact is 2 sqrt(2Rδ)
  long, its pressure elliptic and its force linear in δ, so k keeps its meaning; R = ℓ² / (8 δ_W)
  makes ℓ the footprint at the static load (δ_W = n W / k).  The cleat is felt as the equivalent
  height r = [S(δ + H) − S(δ)] / (πR), S(a) = ∫ over the cleat of sqrt(2Ra − ξ²) dξ in closed form
  (:func:`ring_cleat`): H once the cleat holds the whole contact, 0 out of reach; contact starts
  sqrt(2R(δ + H)) ahead of the hub, further than ℓ/2 for a high cleat, and a low cleat is weighed
  towards the contact's ends (an arcsine weight) rather than its centre.  δ is the hub's deflection
  over the road and the lugs; ṙ = ∂r/∂x · ẋ (at that deflection).  A bevelled cleat is taken as the
  rectangle of the same height and area;
* **lugs** (``periodic_disturbance``): road-equivalent lug passing
  A sin(2π x / p + φ);
* **progressive stiffness** (``nonlinear_stiffness``): elastic force
  W sign(δ) |δ/δ_W|ⁿ with δ_W = n W / k, so that k stays the tangent stiffness
  at the static load W;
* **friction** (``friction_damping``): F_c tanh(δ̇ / v_f), a regularised
  Coulomb force;
* **unilateral contact** (``lift_off``): the force is zero unless δ > 0 and the
  sum above is > 0 (the tire never pulls).
"""

from __future__ import annotations

import math

__all__ = [
    "CONTACT_MODES", "deflection_m", "deflection_rate_m_s", "force_n", "in_contact",
    "point_contact", "parameter_problem", "value_problem",
    "EXTENDED_DEFAULTS", "footprint_cleat", "bevel_cleat", "ring_cleat", "arc_area", "ring_envelope_on",
    "static_deflection", "lug_road", "elastic_force", "extended_tire",
    "extended_parameter_problem", "extended_force_fn", "LAW_FIELDS", "law_vector", "tire_force",
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
    except OverflowError:  # an integer beyond the float range
        return f"{name} must be finite, got an integer of {len(str(abs(value)))} digits"
    except (TypeError, ValueError):
        return f"{name} must be a number in {unit}, got {value!r}"
    if not math.isfinite(value):
        return f"{name} must be finite, got {value!r} {unit}"
    if strictly_positive and not value > 0:
        return f"{name} must be > 0 {unit}, got {value!r} {unit}"
    if not strictly_positive and not value >= 0:
        return f"{name} must be >= 0 {unit}, got {value!r} {unit}"
    return None


# ----------------------------------------------------------------------------- extended tire

#: Parameters of :func:`extended_tire` and their defaults (SI units); the
#: defaults reduce it to the bilateral point-contact law.
EXTENDED_DEFAULTS = {
    "stiffness": 400000.0,          # k, N/m (tangent at the static load)
    "damping": 2000.0,              # c, N s/m
    "unloaded_radius": 0.75,        # r0, m
    "footprint_length": 0.0,        # ℓ, m (0: the built-in cleat is felt under the contact point)
    "parabolic_pressure": False,    # footprint pressure parabolic (else uniform)
    "cleat_x": 0.0,                 # leading edge of the built-in cleat, m (longitudinal)
    "cleat_height": 0.0,            # H, m (0: no built-in cleat)
    "cleat_width": 0.1,             # w, m
    "cleat_bevel": 0.0,             # b, m (0: vertical edges; else a trapezoid, b <= w / 2)
    "ring_envelope": False,         # the footprint's cleat seen through a rigid ring over an elastic bed
    "unilateral": False,            # contact can only push
    "stiffness_exponent": 1.0,      # n
    "static_load": 0.0,             # W, N (needed when n != 1)
    "friction_force": 0.0,          # F_c, N
    "friction_velocity": 0.01,      # v_f, m/s
    "lug_amplitude": 0.0,           # A, m
    "lug_pitch": 0.25,              # p, m
    "lug_phase": 0.0,               # φ, rad
}


def footprint_cleat(hub_x_m, footprint_m, cleat_x_m, cleat_height_m, cleat_width_m, parabolic=False,
                    bevel_m=0.0):
    """Built-in cleat seen by the tire at longitudinal position x: height (m) and slope dr/dx (-).

    With a footprint ℓ > 0 the cleat height is averaged over [x − ℓ/2, x + ℓ/2],
    weighted by a uniform or (`parabolic`) a parabolic contact pressure; with
    ℓ = 0 it is the height under the contact point, a rectangular pulse whose
    slope is zero except at its edges (where it is a step the importer must
    treat as such).  A `bevel_m` b > 0 makes the cleat a trapezoid rising from
    0 to H over b at the leading edge and falling over b at the trailing edge
    (b ≤ w / 2), see :func:`bevel_cleat`.
    """
    h, w, xc = cleat_height_m, cleat_width_m, cleat_x_m
    if h == 0.0:
        return 0.0, 0.0
    if bevel_m > 0.0:
        return bevel_cleat(hub_x_m, footprint_m, xc, h, w, parabolic, bevel_m)
    if footprint_m <= 0.0:
        return (h if xc <= hub_x_m < xc + w else 0.0), 0.0
    if parabolic:
        u1 = min(1.0, max(-1.0, 2.0 * (xc + w - hub_x_m) / footprint_m))
        u0 = min(1.0, max(-1.0, 2.0 * (xc - hub_x_m) / footprint_m))
        return (0.75 * h * ((u1 - u1 * u1 * u1 / 3.0) - (u0 - u0 * u0 * u0 / 3.0)),
                1.5 * h / footprint_m * (u1 * u1 - u0 * u0))
    lo, hi = hub_x_m - 0.5 * footprint_m, hub_x_m + 0.5 * footprint_m
    left, right = max(lo, xc), min(hi, xc + w)
    if right <= left:
        return 0.0, 0.0
    slope = ((1.0 if hi < xc + w else 0.0) - (1.0 if lo > xc else 0.0)) * h / footprint_m
    return h * (right - left) / footprint_m, slope


def bevel_cleat(x, footprint, xc, h, w, parabolic, bevel):
    """The bevelled (trapezoidal) built-in cleat at x: height (m) and slope dr/dx (-).

    The trapezoid is a sum of four ramps R(s) = max(0, s) with kinks at
    a = x_c, x_c + b, x_c + w − b, x_c + w and weights H/b · (+1, −1, −1, +1).
    Each ramp is averaged over the footprint in closed form:

    * point contact (ℓ = 0): R(x − a), slope 1[x ≥ a];
    * uniform pressure: x − a behind the footprint (a ≤ x − ℓ/2), (x + ℓ/2 − a)² / (2ℓ) inside it, slope
      (x + ℓ/2 − a) / ℓ there;
    * parabolic pressure 3/(2ℓ) (1 − u²): (x − a) P + ℓ/2 Q with u_a = clip(2 (a − x) / ℓ, −1, 1),
      P = 1/2 − 3/4 (u_a − u_a³/3) (the pressure ahead of the kink, the slope) and
      Q = 3/16 − 3/4 (u_a²/2 − u_a⁴/4).
    """
    half = 0.5 * footprint
    if x - half >= xc + w or x + half < xc:
        return 0.0, 0.0
    height, slope = 0.0, 0.0
    for k in range(4):
        a = xc + (0.0, bevel, w - bevel, w)[k]
        s = (1.0, -1.0, -1.0, 1.0)[k] * h / bevel
        if footprint <= 0.0:
            if x >= a:
                height += s * (x - a)
                slope += s
        elif parabolic:
            u = min(1.0, max(-1.0, (a - x) / half))
            p = 0.5 - 0.75 * (u - u * u * u / 3.0)
            height += s * ((x - a) * p + half * (0.1875 - 0.75 * (0.5 * u * u - 0.25 * u * u * u * u)))
            slope += s * p
        elif a <= x - half:
            height += s * (x - a)
            slope += s
        elif a < x + half:
            height += s * (x + half - a) * (x + half - a) / (2.0 * footprint)
            slope += s * (x + half - a) / footprint
    return height, slope


def arc_area(u, s):
    """∫ sqrt(s² − ξ²) dξ from ξ = −s to clip(u, −s, s), m² (0 for s ≤ 0): area under a half circle."""
    if s <= 0.0:
        return 0.0
    v = min(s, max(-s, u))
    return 0.5 * (v * math.sqrt(s * s - v * v) + s * s * math.asin(v / s)) + 0.25 * math.pi * s * s


def ring_cleat(hub_x_m, deflection_m, footprint_m, cleat_x_m, cleat_height_m, cleat_width_m, static_deflection_m,
               bevel_m=0.0):
    """Built-in cleat seen through a rigid ring over an elastic bed: equivalent height (m) and slope dr/dx (-).

    The ring's radius R = ℓ² / (8 δ_W) makes ℓ (`footprint_m`) its flat contact at the static deflection
    δ_W (`static_deflection_m`); `deflection_m` δ is the hub's deflection over the road without the cleat.
    r = [A(u₁, s_H) − A(u₀, s_H) − A(u₁, s₀) + A(u₀, s₀)] / (πR), A = :func:`arc_area`, u₀, u₁ the cleat's
    edges from the hub, s_H = sqrt(2R(δ + H)), s₀ = sqrt(2Rδ) (0 when δ ≤ 0).  A bevel b makes the cleat
    the rectangle of the same height and area (width w − b, from x_c + b/2).
    """
    radius = footprint_m * footprint_m / (8.0 * static_deflection_m)
    u0 = cleat_x_m + 0.5 * bevel_m - hub_x_m
    u1 = u0 + cleat_width_m - bevel_m
    sh = math.sqrt(2.0 * radius * max(deflection_m + cleat_height_m, 0.0))
    s0 = math.sqrt(2.0 * radius * max(deflection_m, 0.0))
    scale = 1.0 / (math.pi * radius)
    height = (arc_area(u1, sh) - arc_area(u0, sh) - arc_area(u1, s0) + arc_area(u0, s0)) * scale
    slope = (math.sqrt(max(0.0, sh * sh - u0 * u0)) - math.sqrt(max(0.0, sh * sh - u1 * u1))
             - math.sqrt(max(0.0, s0 * s0 - u0 * u0)) + math.sqrt(max(0.0, s0 * s0 - u1 * u1))) * scale
    return height, slope


def ring_envelope_on(p) -> bool:
    """Whether parameters `p` (named as in :data:`EXTENDED_DEFAULTS`) see their built-in cleat through the
    rigid ring: ``ring_envelope`` with a footprint and a cleat (else the ring has nothing to envelope)."""
    return bool(p["ring_envelope"]) and p["footprint_length"] > 0.0 and p["cleat_height"] != 0.0


def static_deflection(stiffness_n_m, exponent, static_load_n):
    """Deflection at the static load, m: n W / k (W / k for a linear tire)."""
    return exponent * static_load_n / stiffness_n_m


def lug_road(hub_x_m, amplitude_m, pitch_m, phase_rad):
    """Road-equivalent lug passing A sin(2π x / p + φ): height (m) and slope dr/dx (-)."""
    if amplitude_m == 0.0:
        return 0.0, 0.0
    k = 2.0 * math.pi / pitch_m
    arg = k * hub_x_m + phase_rad
    return amplitude_m * math.sin(arg), amplitude_m * k * math.cos(arg)


def elastic_force(deflection, stiffness_n_m, exponent=1.0, static_load_n=0.0):
    """Elastic tire force, N: k δ, or W sign(δ) |δ/δ_W|ⁿ with δ_W = n W / k (tangent k at W)."""
    if exponent == 1.0:
        return stiffness_n_m * deflection
    ratio = deflection * stiffness_n_m / (exponent * static_load_n)
    return math.copysign(static_load_n * abs(ratio) ** exponent, ratio)


def extended_tire(hub_z_m, hub_vz_m_s, hub_x_m, hub_vx_m_s, road_z_m, road_vz_m_s, p):
    """The extended tire for given hub and road motion (scalars).

    Parameters
    ----------
    hub_z_m, hub_vz_m_s : float
        Hub height (m) and vertical velocity (m/s).
    hub_x_m, hub_vx_m_s : float
        Hub longitudinal position (m) and velocity (m/s), for the built-in cleat and the lugs.
    road_z_m, road_vz_m_s : float
        Road height (m) and rate (m/s) under the contact point, besides the built-in cleat.
    p : mapping
        Parameters named as in :data:`EXTENDED_DEFAULTS`.

    Returns
    -------
    force : float
        Vertical tire force, N, compressive positive.
    deflection, deflection_rate : float
        δ (m) and δ̇ (m/s), including the built-in cleat and the lugs.
    contact : bool
        The tire carries load (unilateral), or δ > 0 (bilateral).
    road_total : float
        Effective road height under the tire, m.
    """
    lug, lug_slope = lug_road(hub_x_m, p["lug_amplitude"], p["lug_pitch"], p["lug_phase"])
    if ring_envelope_on(p):
        cleat, cleat_slope = ring_cleat(hub_x_m, p["unloaded_radius"] - (hub_z_m - (road_z_m + lug)),
                                        p["footprint_length"], p["cleat_x"], p["cleat_height"], p["cleat_width"],
                                        static_deflection(p["stiffness"], p["stiffness_exponent"],
                                                          p["static_load"]), p["cleat_bevel"])
    else:
        cleat, cleat_slope = footprint_cleat(hub_x_m, p["footprint_length"], p["cleat_x"], p["cleat_height"],
                                             p["cleat_width"], p["parabolic_pressure"], p["cleat_bevel"])
    road = road_z_m + cleat + lug
    d = p["unloaded_radius"] - (hub_z_m - road)
    dd = road_vz_m_s + (cleat_slope + lug_slope) * hub_vx_m_s - hub_vz_m_s
    f = elastic_force(d, p["stiffness"], p["stiffness_exponent"], p["static_load"]) + p["damping"] * dd
    if p["friction_force"]:
        f += p["friction_force"] * math.tanh(dd / p["friction_velocity"])
    if p["unilateral"]:
        contact = d > 0.0 and f > 0.0
        if not contact:
            f = 0.0
    else:
        contact = d > 0.0
    return f, d, dd, contact, road


def extended_parameter_problem(p):
    """Why an extended parameter set is invalid, or None."""
    problem = parameter_problem(p["stiffness"], p["damping"], p["unloaded_radius"])
    if problem is not None:
        return problem
    checks = (("footprint_length", "m", False), ("cleat_height", "m", False), ("cleat_width", "m", True),
              ("cleat_bevel", "m", False),
              ("stiffness_exponent", "-", True), ("static_load", "N", False), ("friction_force", "N", False),
              ("friction_velocity", "m/s", True), ("lug_pitch", "m", True))
    for name, unit, strictly in checks:
        problem = value_problem(name, unit, p[name], strictly_positive=strictly)
        if problem is not None:
            return problem
    for name, unit in (("cleat_x", "m"), ("lug_amplitude", "m"), ("lug_phase", "rad")):
        problem = value_problem(name, unit, abs(p[name]) if isinstance(p[name], (int, float)) else p[name],
                                strictly_positive=False)
        if problem is not None:
            return problem
    if p["cleat_bevel"] > 0.5 * p["cleat_width"]:
        return f"cleat_bevel must be <= cleat_width / 2 ({0.5 * p['cleat_width']!r} m), got {p['cleat_bevel']!r} m"
    if ring_envelope_on(p) and not p["static_load"] > 0:
        return "static_load must be > 0 N when ring_envelope (the ring's radius follows from the static deflection)"
    if p["stiffness_exponent"] != 1.0 and not p["static_load"] > 0:
        return "static_load must be > 0 N when stiffness_exponent != 1"
    for name in ("unilateral", "parabolic_pressure", "ring_envelope"):
        if not isinstance(p[name], bool):
            return f"{name} must be a Boolean, got {p[name]!r}"
    return None


def extended_force_fn(p):
    """A fast force-only callback ``f(hub_z, hub_vz, hub_x, hub_vx, road_z, road_vz) -> N`` for `p`.

    The options are resolved once, so each call runs only the code of the
    options in use; every term is computed with the same operations, in the
    same order, as in :func:`extended_tire`, so the results are bit-identical
    (tested).
    """
    k, c, r0 = float(p["stiffness"]), float(p["damping"]), float(p["unloaded_radius"])
    fp, xc, hc, wc = p["footprint_length"], p["cleat_x"], p["cleat_height"], p["cleat_width"]
    parabolic, bevel = bool(p["parabolic_pressure"]), p["cleat_bevel"]
    n, w_load = p["stiffness_exponent"], p["static_load"]
    fc, vf = p["friction_force"], p["friction_velocity"]
    la, lp, lph = p["lug_amplitude"], p["lug_pitch"], p["lug_phase"]
    unilateral = bool(p["unilateral"])
    use_cleat = hc != 0.0
    ring = ring_envelope_on(p)
    sink = static_deflection(k, n, w_load) if ring else 0.0
    use_lug = la != 0.0
    linear = n == 1.0
    tanh = math.tanh

    def force(hub_z, hub_vz, hub_x, hub_vx, road_z, road_vz):
        if use_lug:
            lug, lug_slope = lug_road(hub_x, la, lp, lph)
        else:
            lug, lug_slope = 0.0, 0.0
        if ring:
            cleat, cleat_slope = ring_cleat(hub_x, r0 - (hub_z - (road_z + lug)), fp, xc, hc, wc, sink, bevel)
        elif use_cleat:
            cleat, cleat_slope = footprint_cleat(hub_x, fp, xc, hc, wc, parabolic, bevel)
        else:
            cleat, cleat_slope = 0.0, 0.0
        road = road_z + cleat + lug
        d = r0 - (hub_z - road)
        dd = road_vz + (cleat_slope + lug_slope) * hub_vx - hub_vz
        f = (k * d if linear else elastic_force(d, k, n, w_load)) + c * dd
        if fc:
            f += fc * tanh(dd / vf)
        if unilateral and not (d > 0.0 and f > 0.0):
            return 0.0
        return f

    return force


# ----------------------------------------------------------------------------- the law as one flat function

#: Order of the extended tire's parameters in the flat vector of :func:`tire_force`.
LAW_FIELDS = ("stiffness", "damping", "unloaded_radius", "footprint_length", "cleat_x", "cleat_height",
              "cleat_width", "unilateral", "stiffness_exponent", "static_load", "friction_force",
              "friction_velocity", "lug_amplitude", "lug_pitch", "lug_phase", "parabolic_pressure", "cleat_bevel",
              "ring_envelope")


def law_vector(p) -> list:
    """The parameters `p` (named as in :data:`EXTENDED_DEFAULTS`) as the flat vector of :func:`tire_force`."""
    return [float(p[name]) for name in LAW_FIELDS]


def tire_force(hub_z, hub_vz, hub_x, hub_vx, road_z, road_vz, q):
    """Force of the extended tire (N) with its parameters as a flat vector `q` (see :data:`LAW_FIELDS`).

    The same operations, in the same order, as :func:`extended_tire`, written
    with scalars and :mod:`math` only, so that a JIT compiler (numba) compiles
    this very function (and the :func:`footprint_cleat`, :func:`bevel_cleat`
    and :func:`lug_road` it calls) for the fitting models' compiled stepping while the plain-Python
    stepping and the FMUs run it as it stands.
    """
    k, c, r0 = q[0], q[1], q[2]
    fp, xc, hc, wc = q[3], q[4], q[5], q[6]
    n, w_load, fc, vf = q[8], q[9], q[10], q[11]
    la, lp, lph = q[12], q[13], q[14]
    lug, lug_slope = 0.0, 0.0
    if la != 0.0:
        lug, lug_slope = lug_road(hub_x, la, lp, lph)
    cleat, cleat_slope = 0.0, 0.0
    if hc != 0.0:
        if q[17] != 0.0 and fp > 0.0:
            cleat, cleat_slope = ring_cleat(hub_x, r0 - (hub_z - (road_z + lug)), fp, xc, hc, wc,
                                            static_deflection(k, n, w_load), q[16])
        else:
            cleat, cleat_slope = footprint_cleat(hub_x, fp, xc, hc, wc, q[15] != 0.0, q[16])
    road = road_z + cleat + lug
    d = r0 - (hub_z - road)
    dd = road_vz + (cleat_slope + lug_slope) * hub_vx - hub_vz
    if n == 1.0:
        f = k * d
    else:
        ratio = d * k / (n * w_load)
        f = math.copysign(w_load * abs(ratio) ** n, ratio)
    f = f + c * dd
    if fc != 0.0:
        f += fc * math.tanh(dd / vf)
    if q[7] != 0.0 and not (d > 0.0 and f > 0.0):
        return 0.0
    return f
