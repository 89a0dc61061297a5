/* The tire force law of cleatfmu in portable C99 (libm only).
 *
 * A transcription of identification/model/tire_law.py (point_contact, extended_tire):
 * the same operations in the same order, so that both agree to round-off
 * (compile with -ffp-contract=off: no fused multiply-add).  SI units, z up:
 * deflection d = r0 - (hub_z - road), rate dd = d(road)/dt - hub_vz,
 * force compressive positive.
 */
#ifndef CLEATFMU_LAW_H
#define CLEATFMU_LAW_H

#include "cleatfmu_names.h"

/* Parameters of the extended tire; the defaults of each option switch it off. */
typedef struct {
    double stiffness;          /* k, N/m (> 0; tangent at static_load when the exponent != 1) */
    double damping;            /* c, N s/m (>= 0) */
    double unloaded_radius;    /* r0, m (> 0) */
    double footprint_length;   /* l, m (>= 0) */
    double cleat_x;            /* leading edge of the built-in cleat, m */
    double cleat_height;       /* H, m (>= 0) */
    double cleat_width;        /* w, m (> 0) */
    int unilateral;            /* the tire never pulls */
    double stiffness_exponent; /* n (> 0) */
    double static_load;        /* W, N (> 0 when n != 1) */
    double friction_force;     /* F_c, N (>= 0) */
    double friction_velocity;  /* v_f, m/s (> 0) */
    double lug_amplitude;      /* A, m */
    double lug_pitch;          /* p, m (> 0) */
    double lug_phase;          /* phi, rad */
    int parabolic_pressure;    /* footprint contact pressure parabolic (else uniform) */
    double cleat_bevel;        /* b, m (0 <= b <= w / 2; 0: rectangular cleat, else a trapezoid) */
    int ring_envelope;         /* the footprint's cleat seen through a rigid ring over an elastic bed */
} CleatfmuTireParameters;

/* Outputs of the law. */
typedef struct {
    double force;           /* N, compressive positive */
    double deflection;      /* m */
    double deflection_rate; /* m/s */
    int contact;            /* carries load (unilateral) or deflection > 0 */
    double road;            /* effective road height, m */
} CleatfmuTireResult;

/* Point contact: F = k d + c dd, d = r0 - (hub_z - road_z), dd = road_vz - hub_vz (bilateral). */
void cleatfmu_point_contact(double hub_z, double hub_vz, double road_z, double road_vz,
                            double stiffness, double damping, double unloaded_radius,
                            CleatfmuTireResult *out);

/* Extended tire: built-in cleat (rectangular, or bevelled: a trapezoid) averaged over
 * the footprint (uniform or parabolic contact pressure) or seen through a rigid ring over
 * an elastic bed (ring_envelope), lugs, progressive stiffness,
 * regularised Coulomb friction, unilateral contact. */
void cleatfmu_extended_tire(double hub_z, double hub_vz, double hub_x, double hub_vx,
                            double road_z, double road_vz, const CleatfmuTireParameters *p,
                            CleatfmuTireResult *out);

#endif
