/* FMU kind map_tire: the point-contact tire whose k and c follow the speed through a tire map (a table in
 * the FMU's resources, cleatfmu_map.c).
 * The variable table must match VARIABLES of fmu_src/map_tire (checked by the build). */
#ifndef CLEATFMU_CONFIG_H
#define CLEATFMU_CONFIG_H

#define MODEL_IDENTIFIER CleatfmuMapTire
#define MODEL_KIND "map_tire"
#define MODEL_EXTENDED 0
#define MODEL_MAP 1
#define N_VARIABLES 13

enum {
    VR_HUB_Z, VR_HUB_VZ, VR_ROAD_Z, VR_ROAD_VZ, VR_SPEED, VR_UNLOADED_RADIUS,
    VR_FORCE_Z, VR_DEFLECTION, VR_DEFLECTION_RATE, VR_IN_CONTACT, VR_STIFFNESS, VR_DAMPING, VR_EXTRAPOLATING
};

#define MODEL_VARIABLES \
    {"hub_z", VT_REAL, VC_INPUT, RULE_FINITE, "m"}, \
    {"hub_vz", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"road_z", VT_REAL, VC_INPUT, RULE_FINITE, "m"}, \
    {"road_vz", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"speed", VT_REAL, VC_INPUT, RULE_FINITE, "m/s"}, \
    {"unloaded_radius", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m"}, \
    {"force_z", VT_REAL, VC_OUTPUT, RULE_NONE, "N"}, \
    {"deflection", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"deflection_rate", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"in_contact", VT_BOOLEAN, VC_OUTPUT, RULE_NONE, ""}, \
    {"stiffness", VT_REAL, VC_OUTPUT, RULE_NONE, "N/m"}, \
    {"damping", VT_REAL, VC_OUTPUT, RULE_NONE, "N.s/m"}, \
    {"extrapolating", VT_BOOLEAN, VC_OUTPUT, RULE_NONE, ""}

#endif
