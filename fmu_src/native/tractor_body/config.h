/* FMU kind tractor_body: the body of the whole-tractor model (the rigid tractor: heave, pitch, roll; rigid or
 * pivoting front axle; or half tractors per side or axle, or four corners) on four tire forces,
 * with hub and seat outputs.
 * The variable table must match VARIABLES of fmu_src/tractor_body (checked by the build). */
#ifndef CLEATFMU_CONFIG_H
#define CLEATFMU_CONFIG_H

#define MODEL_IDENTIFIER CleatfmuTractorBody
#define MODEL_KIND "tractor_body"
#define MODEL_EXTENDED 0
#define MODEL_BODY 1
/* Parameters are fixed: settable until the end of initialization only. */
#define MODEL_FIXED_PARAMETERS 1
#define N_VARIABLES 50
/* Hidden state after the variables: coordinates q, predicted rates, rates and accelerations at the
 * last communication point (4 each), the last step size and whether the first step was taken. */
#define N_STATES 18

enum {
    VR_FORCE_FL, VR_FORCE_FR, VR_FORCE_RL, VR_FORCE_RR,
    VR_LOAD_FL, VR_LOAD_FR, VR_LOAD_RL, VR_LOAD_RR,
    VR_STATIC_HUB_Z_FL, VR_STATIC_HUB_Z_FR, VR_STATIC_HUB_Z_RL, VR_STATIC_HUB_Z_RR,
    VR_WHEELBASE, VR_PITCH_INDEX, VR_ROLL_INDEX, VR_PITCH_COUPLING,
    VR_ROLL_COUPLING, VR_FRONT_AXLE_PIVOT, VR_PIVOT_INDEX, VR_SPEED,
    VR_START_X, VR_SEAT_X, VR_SEAT_Y, VR_INITIAL_HUB_DZ_FL,
    VR_INITIAL_HUB_DZ_FR, VR_INITIAL_HUB_DZ_RL, VR_INITIAL_HUB_DZ_RR, VR_INITIAL_HUB_VZ_FL,
    VR_INITIAL_HUB_VZ_FR, VR_INITIAL_HUB_VZ_RL, VR_INITIAL_HUB_VZ_RR, VR_HUB_Z_FL,
    VR_HUB_Z_FR, VR_HUB_Z_RL, VR_HUB_Z_RR, VR_HUB_VZ_FL,
    VR_HUB_VZ_FR, VR_HUB_VZ_RL, VR_HUB_VZ_RR, VR_HUB_X_FL,
    VR_HUB_X_FR, VR_HUB_X_RL, VR_HUB_X_RR, VR_HUB_VX,
    VR_HUB_AZ_FL, VR_HUB_AZ_FR, VR_HUB_AZ_RL, VR_HUB_AZ_RR,
    VR_SEAT_Z, VR_SEAT_AZ
};
enum { ST_Q = N_VARIABLES, ST_DQP = ST_Q + 4, ST_DQ = ST_DQP + 4, ST_DDQ = ST_DQ + 4, ST_LAST_STEP = ST_DDQ + 4,
       ST_STARTED = ST_LAST_STEP + 1 };

#define MODEL_VARIABLES \
    {"force_FL", VT_REAL, VC_INPUT, RULE_FINITE, "N"}, \
    {"force_FR", VT_REAL, VC_INPUT, RULE_FINITE, "N"}, \
    {"force_RL", VT_REAL, VC_INPUT, RULE_FINITE, "N"}, \
    {"force_RR", VT_REAL, VC_INPUT, RULE_FINITE, "N"}, \
    {"load_FL", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "N"}, \
    {"load_FR", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "N"}, \
    {"load_RL", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "N"}, \
    {"load_RR", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "N"}, \
    {"static_hub_z_FL", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"static_hub_z_FR", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"static_hub_z_RL", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"static_hub_z_RR", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"wheelbase", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "m"}, \
    {"pitch_index", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "1"}, \
    {"roll_index", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "1"}, \
    {"pitch_coupling", VT_BOOLEAN, VC_PARAMETER, RULE_BOOLEAN, ""}, \
    {"roll_coupling", VT_BOOLEAN, VC_PARAMETER, RULE_BOOLEAN, ""}, \
    {"front_axle_pivot", VT_BOOLEAN, VC_PARAMETER, RULE_BOOLEAN, ""}, \
    {"pivot_index", VT_REAL, VC_PARAMETER, RULE_POSITIVE, "1"}, \
    {"speed", VT_REAL, VC_PARAMETER, RULE_FINITE, "m/s"}, \
    {"start_x", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"seat_x", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"seat_y", VT_REAL, VC_PARAMETER, RULE_FINITE, "1"}, \
    {"initial_hub_dz_FL", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"initial_hub_dz_FR", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"initial_hub_dz_RL", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"initial_hub_dz_RR", VT_REAL, VC_PARAMETER, RULE_FINITE, "m"}, \
    {"initial_hub_vz_FL", VT_REAL, VC_PARAMETER, RULE_FINITE, "m/s"}, \
    {"initial_hub_vz_FR", VT_REAL, VC_PARAMETER, RULE_FINITE, "m/s"}, \
    {"initial_hub_vz_RL", VT_REAL, VC_PARAMETER, RULE_FINITE, "m/s"}, \
    {"initial_hub_vz_RR", VT_REAL, VC_PARAMETER, RULE_FINITE, "m/s"}, \
    {"hub_z_FL", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_z_FR", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_z_RL", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_z_RR", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_vz_FL", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"hub_vz_FR", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"hub_vz_RL", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"hub_vz_RR", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"hub_x_FL", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_x_FR", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_x_RL", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_x_RR", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"hub_vx", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s"}, \
    {"hub_az_FL", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s2"}, \
    {"hub_az_FR", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s2"}, \
    {"hub_az_RL", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s2"}, \
    {"hub_az_RR", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s2"}, \
    {"seat_z", VT_REAL, VC_OUTPUT, RULE_NONE, "m"}, \
    {"seat_az", VT_REAL, VC_OUTPUT, RULE_NONE, "m/s2"}

#endif
