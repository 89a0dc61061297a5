/* The model of a cleatfmu tire FMU: checks of values and evaluation of the outputs. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cleatfmu_model.h"
#if !MODEL_BODY && !MODEL_ROAD && !MODEL_MAP
#include "cleatfmu_law.h"
#endif

const CleatfmuVariable cleatfmu_variables[N_VARIABLES] = {MODEL_VARIABLES};

int cleatfmu_find_variable(const char *name) {
    int vr;
    for (vr = 0; vr < N_VARIABLES; vr++)
        if (strcmp(cleatfmu_variables[vr].name, name) == 0) return vr;
    return -1;
}

int cleatfmu_value_problem(size_t vr, double value, char *msg, size_t n) {
    const CleatfmuVariable *v;
    if (vr >= N_VARIABLES) {
        snprintf(msg, n, "value reference %u is not a variable", (unsigned)vr);
        return 1;
    }
    v = &cleatfmu_variables[vr];
    switch (v->rule) {
    case RULE_BOOLEAN:
        if (value != 0.0 && value != 1.0) {
            snprintf(msg, n, "%s = %.17g: must be a Boolean", v->name, value);
            return 1;
        }
        return 0;
    case RULE_NONE:
        return 0;
    default:
        break;
    }
    if (!isfinite(value)) {
        snprintf(msg, n, "%s = %.17g %s: must be a finite number", v->name, value, v->unit);
        return 1;
    }
    if (v->rule == RULE_POSITIVE && !(value > 0.0)) {
        snprintf(msg, n, "%s must be > 0 %s, got %.17g %s", v->name, v->unit, value, v->unit);
        return 1;
    }
    if (v->rule == RULE_NONNEGATIVE && !(value >= 0.0)) {
        snprintf(msg, n, "%s must be >= 0 %s, got %.17g %s", v->name, v->unit, value, v->unit);
        return 1;
    }
    return 0;
}

int cleatfmu_set_problem(const double *values, char *msg, size_t n) {
    size_t vr;
    for (vr = 0; vr < N_VARIABLES; vr++)
        if (cleatfmu_variables[vr].causality != VC_OUTPUT && cleatfmu_value_problem(vr, values[vr], msg, n))
            return 1;
#if MODEL_BODY
    if (values[VR_FRONT_AXLE_PIVOT] != 0.0 && !(values[VR_PITCH_COUPLING] != 0.0 && values[VR_ROLL_COUPLING] != 0.0)) {
        snprintf(msg, n, "a pivoting front axle (front_axle_pivot) needs the whole tractor (pitch_coupling and "
                         "roll_coupling)");
        return 1;
    }
#endif
#if MODEL_EXTENDED
    /* the constraints between parameters, in the order of tire_law.extended_parameter_problem */
    if (values[VR_CLEAT_BEVEL] > 0.5 * values[VR_CLEAT_WIDTH]) {
        snprintf(msg, n, "cleat_bevel must be <= cleat_width / 2 (%.17g m), got %.17g m",
                 0.5 * values[VR_CLEAT_WIDTH], values[VR_CLEAT_BEVEL]);
        return 1;
    }
    if (values[VR_RING_ENVELOPE] != 0.0 && values[VR_FOOTPRINT_LENGTH] > 0.0 && values[VR_CLEAT_HEIGHT] != 0.0
        && !(values[VR_STATIC_LOAD] > 0.0)) {
        snprintf(msg, n, "static_load must be > 0 N when ring_envelope (the ring's radius follows from the static "
                         "deflection)");
        return 1;
    }
    if (values[VR_STIFFNESS_EXPONENT] != 1.0 && !(values[VR_STATIC_LOAD] > 0.0)) {
        snprintf(msg, n, "static_load must be > 0 N when stiffness_exponent != 1");
        return 1;
    }
#endif
    return 0;
}

#if MODEL_BODY
#include "cleatfmu_body.h"
#endif
#if MODEL_ROAD
#include "cleatfmu_road.h"
#endif
#if MODEL_MAP
#include "cleatfmu_map.h"
#endif

static int outputs_finite(const double *v, char *msg, size_t n) {
    size_t vr;
    for (vr = 0; vr < N_VARIABLES; vr++) {
        if (cleatfmu_variables[vr].causality == VC_OUTPUT && !isfinite(v[vr])) {
            snprintf(msg, n, "the outputs cannot be evaluated for these inputs and parameters (%s = %.17g)",
                     cleatfmu_variables[vr].name, v[vr]);
            return 1;
        }
    }
    return 0;
}

#if MODEL_ROAD
int cleatfmu_load(const char *resource_location, void **data, char *msg, size_t n) {
    return cleatfmu_road_load(resource_location, (CleatfmuRoad **)data, msg, n);
}

void cleatfmu_unload(void *data) { cleatfmu_road_free((CleatfmuRoad *)data); }
#elif MODEL_MAP
int cleatfmu_load(const char *resource_location, void **data, char *msg, size_t n) {
    return cleatfmu_map_load(resource_location, (CleatfmuMap **)data, msg, n);
}

void cleatfmu_unload(void *data) { cleatfmu_map_free((CleatfmuMap *)data); }
#else
int cleatfmu_load(const char *resource_location, void **data, char *msg, size_t n) {
    (void)resource_location; (void)msg; (void)n;
    *data = NULL;
    return 0;
}

void cleatfmu_unload(void *data) { (void)data; }
#endif

#if MODEL_BODY
int cleatfmu_evaluate(double *v, double time, const void *data, char *msg, size_t n) {
    (void)data;
    cleatfmu_body_outputs(v, time);
    return outputs_finite(v, msg, n);
}

int cleatfmu_step(double *v, double time, double step, char *msg, size_t n) {
    size_t i;
    cleatfmu_body_step(v, step);
    for (i = N_VARIABLES; i < N_VALUES; i++) {
        if (!isfinite(v[i])) {
            snprintf(msg, n, "the body's motion diverged at t = %.17g s (non-finite state)", time + step);
            return 1;
        }
    }
    return 0;
}
#else
int cleatfmu_step(double *v, double time, double step, char *msg, size_t n) {
    (void)v; (void)time; (void)step; (void)msg; (void)n;
    return 0;
}

#if MODEL_ROAD
int cleatfmu_evaluate(double *v, double time, const void *data, char *msg, size_t n) {
    cleatfmu_road_outputs(v, time, (const CleatfmuRoad *)data);
    return outputs_finite(v, msg, n);
}
#elif MODEL_MAP
int cleatfmu_evaluate(double *v, double time, const void *data, char *msg, size_t n) {
    char warning[CLEATFMU_MESSAGE_SIZE];
    int left = cleatfmu_map_outputs(v, (const CleatfmuMap *)data, warning, sizeof warning);
    (void)time;
    if (outputs_finite(v, msg, n)) return 1;
    if (left) {
        snprintf(msg, n, "%s", warning);
        return 2;
    }
    return 0;
}
#else
int cleatfmu_evaluate(double *v, double time, const void *data, char *msg, size_t n) {
    CleatfmuTireResult r;
    (void)time; (void)data;
#if MODEL_EXTENDED
    CleatfmuTireParameters p;
    p.stiffness = v[VR_STIFFNESS];
    p.damping = v[VR_DAMPING];
    p.unloaded_radius = v[VR_UNLOADED_RADIUS];
    p.footprint_length = v[VR_FOOTPRINT_LENGTH];
    p.cleat_x = v[VR_CLEAT_X];
    p.cleat_height = v[VR_CLEAT_HEIGHT];
    p.cleat_width = v[VR_CLEAT_WIDTH];
    p.unilateral = v[VR_UNILATERAL] != 0.0;
    p.stiffness_exponent = v[VR_STIFFNESS_EXPONENT];
    p.static_load = v[VR_STATIC_LOAD];
    p.friction_force = v[VR_FRICTION_FORCE];
    p.friction_velocity = v[VR_FRICTION_VELOCITY];
    p.lug_amplitude = v[VR_LUG_AMPLITUDE];
    p.lug_pitch = v[VR_LUG_PITCH];
    p.lug_phase = v[VR_LUG_PHASE];
    p.parabolic_pressure = v[VR_PARABOLIC_PRESSURE] != 0.0;
    p.cleat_bevel = v[VR_CLEAT_BEVEL];
    p.ring_envelope = v[VR_RING_ENVELOPE] != 0.0;
    cleatfmu_extended_tire(v[VR_HUB_Z], v[VR_HUB_VZ], v[VR_HUB_X], v[VR_HUB_VX], v[VR_ROAD_Z], v[VR_ROAD_VZ],
                           &p, &r);
    v[VR_ROAD_EFFECTIVE_Z] = r.road;
#else
    cleatfmu_point_contact(v[VR_HUB_Z], v[VR_HUB_VZ], v[VR_ROAD_Z], v[VR_ROAD_VZ], v[VR_STIFFNESS], v[VR_DAMPING],
                           v[VR_UNLOADED_RADIUS], &r);
#endif
    v[VR_FORCE_Z] = r.force;
    v[VR_DEFLECTION] = r.deflection;
    v[VR_DEFLECTION_RATE] = r.deflection_rate;
    v[VR_IN_CONTACT] = r.contact ? 1.0 : 0.0;
    return outputs_finite(v, msg, n);
}
#endif
#endif
