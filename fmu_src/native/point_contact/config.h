/* FMU kind point_contact: spring k parallel to damper c between hub and road.
 * The variable table must match VARIABLES of fmu_src/point_contact (checked by the build). */
#ifndef CLEATFMU_CONFIG_H
#define CLEATFMU_CONFIG_H

#define MODEL_IDENTIFIER CleatfmuPointContact
#define MODEL_KIND "point_contact"
#define MODEL_EXTENDED 0
#define N_VARIABLES 11

enum {
    VR_HUB_Z, VR_HUB_VZ, VR_ROAD_Z, VR_ROAD_VZ, VR_STIFFNESS, VR_DAMPING, VR_UNLOADED_RADIUS,
    VR_FORCE_Z, VR_DEFLECTION, VR_DEFLECTION_RATE, VR_IN_CONTACT
};

#define MODEL_VARIABLES \
    {"hub_z", VT_REAL, VC_INPUT, RULE_FINITE, "m"}, \
    {"hub_vz", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"road_z", VT_REAL, VC_INPUT, RULE_FINITE, "m"}, \
    {"road_vz", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"stiffness", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "N/m"}, \
    {"damping", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "N.s/m"}, \
    {"unloaded_radius", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m"}, \
    {"force_z", VT_REAL, VC_OUTPUT, RULE_NONE, "N"}, \
    {"deflection", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"deflection_rate", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"in_contact", VT_BOOLEAN, VC_OUTPUT, RULE_NONE, ""}

#endif
