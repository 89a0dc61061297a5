/* FMU kind road_profile: a two-track road profile under the four tires of the tractor (a table in the
 * FMU's resources), the hubs moving at a constant speed.
 * The variable table must match VARIABLES of fmu_src/road_profile (checked by the build). */
#ifndef CLEATFMU_CONFIG_H
#define CLEATFMU_CONFIG_H

#define MODEL_IDENTIFIER CleatfmuRoadProfile
#define MODEL_KIND "road_profile"
#define MODEL_EXTENDED 0
#define MODEL_ROAD 1
/* Parameters are fixed: settable until the end of initialization only. */
#define MODEL_FIXED_PARAMETERS 1
#define N_VARIABLES 12

enum {
    VR_SPEED, VR_START_X, VR_WHEELBASE, VR_RAMP_LENGTH,
    VR_ROAD_Z_FL, VR_ROAD_Z_FR, VR_ROAD_Z_RL, VR_ROAD_Z_RR,
    VR_ROAD_VZ_FL, VR_ROAD_VZ_FR, VR_ROAD_VZ_RL, VR_ROAD_VZ_RR
};

#define MODEL_VARIABLES \
    {"speed", VT_REAL, VC_PARAMETER, RULE_FINITE, "m/s"}, \
    {"start_x", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"wheelbase", VT_REAL, VC_PARAMETER, RULE_NONNEGATIVE, "m"}, \
    {"ramp_length", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m"}, \
    {"road_z_FL", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"road_z_FR", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"road_z_RL", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"road_z_RR", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"road_vz_FL", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"road_vz_FR", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"road_vz_RL", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"road_vz_RR", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}

#endif
