"""The independent simulator's tire laws (vertical plane, x forward, z up, SI units).

``point``
    A point follower of the terrain under the hub centre: deflection δ = R0 - (z_hub - z_road(x)),
    force f = k δ (1 + (δ/δ_p)²) + c δ̇ + F_f (2/π) arctan(δ̇ / v_f), never pulling.  δ_p = inf: linear.
``bed``
    A rigid circle over a continuous bed of vertical bristles (within ±``x_max`` of the hub,
    integrated on a grid of ``dx`` refined at the terrain's vertices): each bristle is compressed by the terrain (flat ground or the cleat's polyline) rising above the
    undeformed circle of radius R0 + a_lug cos(n_lug φ_x) (φ_x the material angle under that bristle:
    lugs pass as the wheel rolls).  Per metre of bed, q = κ δ (δ + ε)^(p - 1) + c_b δ̇ +
    F_b (2/π) arctan(δ̇ / v_f), never pulling; F = ∫ q dx.  On flat ground the contact length grows as √δ, so
    p = 1/2 gives a nearly linear tire with an elliptic pressure, p > 1/2 a progressive one.  The
    footprint, and with it the enveloping of a cleat, emerge from the geometry; nothing assumes
    them, and the force is continuous in the hub's position for any continuous terrain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .terrain import height_at

__all__ = ["TireSpec", "tire_force", "pack"]

POINT, BED = 0, 1


@dataclass(frozen=True)
class TireSpec:
    """One tire of the independent simulator.

    ``stiffness`` is k (point, N/m) or κ (bed, N/m^p per m of bed); ``damping`` is c (point, N s/m)
    or c_b (bed, per m); ``friction_N`` is F_f (point, N) or F_b (bed, N per m).
    """

    kind: str                    # "point" | "bed"
    radius_m: float              # R0, unloaded radius
    stiffness: float
    damping: float
    exponent: float = 0.5        # bed: p (1/2: nearly linear tire)
    eps_m: float = 5e-4          # bed: ε, regularises the bristle law's onset
    progressive_m: float = math.inf  # point: δ_p
    friction_N: float = 0.0
    friction_v_m_s: float = 0.01
    lug_amplitude_m: float = 0.0
    lugs: int = 0
    dx_m: float = 0.005
    x_max_m: float = 0.55         # beyond any contact: a 50 mm cleat under the largest tire reaches 0.43 m


def pack(spec: TireSpec) -> tuple[np.ndarray, np.ndarray]:
    """The spec as numba arguments: (parameters, bristle positions relative to the hub)."""
    kind = POINT if spec.kind == "point" else BED
    par = np.array([kind, spec.radius_m, spec.stiffness, spec.damping, spec.exponent, spec.eps_m,
                    spec.progressive_m if math.isfinite(spec.progressive_m) else 0.0, spec.friction_N,
                    spec.friction_v_m_s, spec.lug_amplitude_m, float(spec.lugs)])
    n = int(round(spec.x_max_m / spec.dx_m))
    return par, np.arange(-n, n + 1) * spec.dx_m


@njit(cache=True)
def tire_force(par, xs, x_rel, hz, vx, vz, phi, phi_dot, seg_x, seg_z):
    """Vertical force of the tire on the hub, N, and the contact length, m (point: 1 or 0).

    x_rel : hub's x relative to the cleat's leading edge, m; hz : hub height over the flat ground, m;
    (vx, vz) : hub velocity relative to the terrain, m/s; phi, phi_dot : rolling angle and rate.
    """
    kind, r0, k, c = par[0], par[1], par[2], par[3]
    p, eps, dp, ff, vf, lug_a, lug_n = par[4], par[5], par[6], par[7], par[8], par[9], par[10]
    if kind == 0:
        zr, slope = height_at(x_rel, seg_x, seg_z)
        lug = lug_a * math.cos(lug_n * phi)
        lug_rate = -lug_a * lug_n * math.sin(lug_n * phi) * phi_dot
        d = r0 + lug - (hz - zr)
        if d <= 0.0:
            return 0.0, 0.0
        dd = lug_rate - (vz - vx * slope)
        el = k * d
        if dp > 0.0:
            el *= 1.0 + (d / dp) ** 2
        f = el + c * dd + ff * (2.0 / math.pi) * math.atan(dd / vf)
        return max(f, 0.0), 1.0
    # the bed as a continuum: Gauss-Legendre (2 points) between the grid's points and the terrain's
    # vertices, so that a steep bevel narrower than the grid is integrated as well as the flat ground
    top = seg_z.max()
    x_lo, x_hi = xs[0], xs[xs.shape[0] - 1]
    pts = np.empty(xs.shape[0] + seg_x.shape[0])
    n = 0
    for i in range(xs.shape[0]):
        pts[n] = xs[i]
        n += 1
    for j in range(seg_x.shape[0]):
        v = seg_x[j] - x_rel
        if x_lo < v < x_hi:
            pts[n] = v
            n += 1
    pts = np.sort(pts[:n])
    g = 0.5 / math.sqrt(3.0)
    fz = 0.0
    length = 0.0
    for i in range(n - 1):
        w = pts[i + 1] - pts[i]
        if w <= 0.0:
            continue
        mid = 0.5 * (pts[i] + pts[i + 1])
        for x in (mid - g * w, mid + g * w):
            ang = lug_n * (phi + x / r0)
            ri = r0 + lug_a * math.cos(ang)
            root = math.sqrt(ri * ri - x * x)
            low = hz - root                   # the undeformed circle above this point
            if low >= top and low >= 0.0:
                continue
            zr, slope = height_at(x_rel + x, seg_x, seg_z)
            d = zr - low
            if d <= 0.0:
                continue
            length += 0.5 * w
            ri_dot = -lug_a * lug_n * math.sin(ang) * phi_dot
            dd = vx * slope - vz + ri * ri_dot / root
            q = k * d * (d + eps) ** (p - 1.0) + c * dd + ff * (2.0 / math.pi) * math.atan(dd / vf)
            if q > 0.0:
                fz += 0.5 * w * q
    return fz, length
