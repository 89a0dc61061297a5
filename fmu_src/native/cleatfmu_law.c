/* The tire force law (see cleatfmu_law.h and identification/model/tire_law.py). */
#include <math.h>

#include "cleatfmu_law.h"

#define CLEATFMU_PI 3.141592653589793 /* == Python's math.pi */

void cleatfmu_point_contact(double hub_z, double hub_vz, double road_z, double road_vz,
                            double stiffness, double damping, double unloaded_radius,
                            CleatfmuTireResult *out) {
    double d = unloaded_radius - (hub_z - road_z);
    double dd = road_vz - hub_vz;
    out->force = stiffness * d + damping * dd;
    out->deflection = d;
    out->deflection_rate = dd;
    out->contact = d > 0.0;
    out->road = road_z;
}

/* Python's min(1.0, max(-1.0, u)). */
static double clip_unit(double u) {
    u = (u > -1.0) ? u : -1.0;
    return (u < 1.0) ? u : 1.0;
}

/* The bevelled (trapezoidal) built-in cleat at x: height and slope dr/dx (tire_law.bevel_cleat).
 * A sum of four ramps max(0, s) with kinks a = xc, xc + b, xc + w - b, xc + w and weights
 * H / b * (+1, -1, -1, +1), each averaged over the footprint in closed form (point contact,
 * uniform or parabolic pressure); the same operations in the same order as the Python. */
static void bevel_cleat(double x, double footprint, double xc, double h, double w, int parabolic, double bevel,
                        double *height, double *slope) {
    static const double SIGNS[4] = {1.0, -1.0, -1.0, 1.0};
    double half = 0.5 * footprint, offsets[4], a, s, u, p;
    int k;
    *height = 0.0;
    *slope = 0.0;
    if (x - half >= xc + w || x + half < xc) return;
    offsets[0] = 0.0;
    offsets[1] = bevel;
    offsets[2] = w - bevel;
    offsets[3] = w;
    for (k = 0; k < 4; k++) {
        a = xc + offsets[k];
        s = SIGNS[k] * h / bevel;
        if (footprint <= 0.0) {
            if (x >= a) {
                *height += s * (x - a);
                *slope += s;
            }
        } else if (parabolic) {
            u = clip_unit((a - x) / half);
            p = 0.5 - 0.75 * (u - u * u * u / 3.0);
            *height += s * ((x - a) * p + half * (0.1875 - 0.75 * (0.5 * u * u - 0.25 * u * u * u * u)));
            *slope += s * p;
        } else if (a <= x - half) {
            *height += s * (x - a);
            *slope += s;
        } else if (a < x + half) {
            *height += s * (x + half - a) * (x + half - a) / (2.0 * footprint);
            *slope += s * (x + half - a) / footprint;
        }
    }
}

/* Built-in cleat seen at x: height and slope dr/dx (tire_law.footprint_cleat); the
 * footprint's contact pressure is uniform, or parabolic when `parabolic` is nonzero; a
 * bevel > 0 makes the cleat a trapezoid (bevel_cleat). */
static void footprint_cleat(double x, double footprint, double xc, double h, double w, int parabolic,
                            double bevel, double *height, double *slope) {
    double lo, hi, left, right, u0, u1;
    *height = 0.0;
    *slope = 0.0;
    if (h == 0.0) return;
    if (bevel > 0.0) {
        bevel_cleat(x, footprint, xc, h, w, parabolic, bevel, height, slope);
        return;
    }
    if (footprint <= 0.0) {
        *height = (xc <= x && x < xc + w) ? h : 0.0;
        return;
    }
    if (parabolic) {
        u1 = clip_unit(2.0 * (xc + w - x) / footprint);
        u0 = clip_unit(2.0 * (xc - x) / footprint);
        *height = 0.75 * h * ((u1 - u1 * u1 * u1 / 3.0) - (u0 - u0 * u0 * u0 / 3.0));
        *slope = 1.5 * h / footprint * (u1 * u1 - u0 * u0);
        return;
    }
    lo = x - 0.5 * footprint;
    hi = x + 0.5 * footprint;
    left = (xc > lo) ? xc : lo;
    right = (xc + w < hi) ? xc + w : hi;
    if (right <= left) return;
    *slope = (((hi < xc + w) ? 1.0 : 0.0) - ((lo > xc) ? 1.0 : 0.0)) * h / footprint;
    *height = h * (right - left) / footprint;
}

/* Road-equivalent lugs A sin(2 pi x / p + phi): height and slope (tire_law.lug_road). */
static void lug_road(double x, double amplitude, double pitch, double phase, double *height, double *slope) {
    double k, arg;
    *height = 0.0;
    *slope = 0.0;
    if (amplitude == 0.0) return;
    k = 2.0 * CLEATFMU_PI / pitch;
    arg = k * x + phase;
    *height = amplitude * sin(arg);
    *slope = amplitude * k * cos(arg);
}

/* Area under sqrt(s^2 - v^2) from -s to clip(u, -s, s); 0 for s <= 0 (tire_law.arc_area). */
static double arc_area(double u, double s) {
    double v;
    if (s <= 0.0) return 0.0;
    v = fmin(s, fmax(-s, u));
    return 0.5 * (v * sqrt(s * s - v * v) + s * s * asin(v / s)) + 0.25 * CLEATFMU_PI * s * s;
}

/* The built-in cleat seen through a rigid ring over an elastic bed: equivalent height and slope
 * (tire_law.ring_cleat); d is the hub's deflection over the road without the cleat. */
static void ring_cleat(double x, double d, double footprint, double xc, double h, double w, double sink,
                       double bevel, double *height, double *slope) {
    double radius, u0, u1, sh, s0, scale;
    radius = footprint * footprint / (8.0 * sink);
    u0 = xc + 0.5 * bevel - x;
    u1 = u0 + w - bevel;
    sh = sqrt(2.0 * radius * fmax(d + h, 0.0));
    s0 = sqrt(2.0 * radius * fmax(d, 0.0));
    scale = 1.0 / (CLEATFMU_PI * radius);
    *height = (arc_area(u1, sh) - arc_area(u0, sh) - arc_area(u1, s0) + arc_area(u0, s0)) * scale;
    *slope = (sqrt(fmax(0.0, sh * sh - u0 * u0)) - sqrt(fmax(0.0, sh * sh - u1 * u1))
              - sqrt(fmax(0.0, s0 * s0 - u0 * u0)) + sqrt(fmax(0.0, s0 * s0 - u1 * u1))) * scale;
}

/* k d, or W sign(d) |d / d_W|^n with d_W = n W / k (tire_law.elastic_force). */
static double elastic_force(double d, double k, double n, double w) {
    double ratio;
    if (n == 1.0) return k * d;
    ratio = d * k / (n * w);
    return copysign(w * pow(fabs(ratio), n), ratio);
}

void cleatfmu_extended_tire(double hub_z, double hub_vz, double hub_x, double hub_vx,
                            double road_z, double road_vz, const CleatfmuTireParameters *p,
                            CleatfmuTireResult *out) {
    double cleat, cleat_slope, lug, lug_slope, road, d, dd, f;
    int contact;
    lug_road(hub_x, p->lug_amplitude, p->lug_pitch, p->lug_phase, &lug, &lug_slope);
    if (p->ring_envelope && p->footprint_length > 0.0 && p->cleat_height != 0.0)
        ring_cleat(hub_x, p->unloaded_radius - (hub_z - (road_z + lug)), p->footprint_length, p->cleat_x,
                   p->cleat_height, p->cleat_width, p->stiffness_exponent * p->static_load / p->stiffness,
                   p->cleat_bevel, &cleat, &cleat_slope);
    else
        footprint_cleat(hub_x, p->footprint_length, p->cleat_x, p->cleat_height, p->cleat_width,
                        p->parabolic_pressure, p->cleat_bevel, &cleat, &cleat_slope);
    road = road_z + cleat + lug;
    d = p->unloaded_radius - (hub_z - road);
    dd = road_vz + (cleat_slope + lug_slope) * hub_vx - hub_vz;
    f = elastic_force(d, p->stiffness, p->stiffness_exponent, p->static_load) + p->damping * dd;
    if (p->friction_force != 0.0) f += p->friction_force * tanh(dd / p->friction_velocity);
    if (p->unilateral) {
        contact = d > 0.0 && f > 0.0;
        if (!contact) f = 0.0;
    } else {
        contact = d > 0.0;
    }
    out->force = f;
    out->deflection = d;
    out->deflection_rate = dd;
    out->contact = contact;
    out->road = road;
}
