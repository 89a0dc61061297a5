/* FMU kind extended_tire: point contact plus enveloped built-in cleat (rectangular or bevelled;
 * uniform or parabolic footprint pressure, or a rigid ring over an elastic bed), lugs, progressive stiffness, friction and unilateral contact.
 * The variable table must match VARIABLES of fmu_src/extended_tire (checked by the build);
 * new variables are appended, so that the value references of the others never change. */
#ifndef CLEATFMU_CONFIG_H
#define CLEATFMU_CONFIG_H

#define MODEL_IDENTIFIER CleatfmuExtendedTire
#define MODEL_KIND "extended_tire"
#define MODEL_EXTENDED 1
#define N_VARIABLES 29

enum {
    VR_HUB_Z, VR_HUB_VZ, VR_ROAD_Z, VR_ROAD_VZ, VR_HUB_X, VR_HUB_VX,
    VR_STIFFNESS, VR_DAMPING, VR_UNLOADED_RADIUS, VR_FOOTPRINT_LENGTH, VR_CLEAT_X, VR_CLEAT_HEIGHT,
    VR_CLEAT_WIDTH, VR_UNILATERAL, VR_STIFFNESS_EXPONENT, VR_STATIC_LOAD, VR_FRICTION_FORCE,
    VR_FRICTION_VELOCITY, VR_LUG_AMPLITUDE, VR_LUG_PITCH, VR_LUG_PHASE,
    VR_FORCE_Z, VR_DEFLECTION, VR_DEFLECTION_RATE, VR_IN_CONTACT, VR_ROAD_EFFECTIVE_Z,
    VR_PARABOLIC_PRESSURE, VR_CLEAT_BEVEL, VR_RING_ENVELOPE
};

#define MODEL_VARIABLES \
    {"hub_z", VT_REAL, VC_INPUT, RULE_FINITE, "m"}, \
    {"hub_vz", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"road_z", VT_REAL, VC_INPUT, RULE_FINITE, "m"}, \
    {"road_vz", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"hub_x", VT_REAL, VC_INPUT, RULE_FINITE, "m"}, \
    {"hub_vx", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"stiffness", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "N/m"}, \
    {"damping", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "N.s/m"}, \
    {"unloaded_radius", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m"}, \
    {"footprint_length", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "m"}, \
    {"cleat_x", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"cleat_height", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "m"}, \
    {"cleat_width", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m"}, \
    {"unilateral", VT_BOOLEAN, VC_PARAMETER, RULE_BOOLEAN, ""}, \
    {"stiffness_exponent", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "1"}, \
    {"static_load", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "N"}, \
    {"friction_force", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "N"}, \
    {"friction_velocity", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m/s"}, \
    {"lug_amplitude", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"lug_pitch", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m"}, \
    {"lug_phase", VT_REAL, VC_PARAMETER, RULE_FINITE, "rad"}, \
    {"force_z", VT_REAL, VC_OUTPUT, RULE_NONE, "N"}, \
    {"deflection", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"deflection_rate", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"in_contact", VT_BOOLEAN, VC_OUTPUT, RULE_NONE, ""}, \
    {"road_effective_z", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"parabolic_pressure", VT_BOOLEAN, VC_PARAMETER, RULE_BOOLEAN, ""}, \
    {"cleat_bevel", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "m"}, \
    {"ring_envelope", VT_BOOLEAN, VC_PARAMETER, RULE_BOOLEAN, ""}

#endif
