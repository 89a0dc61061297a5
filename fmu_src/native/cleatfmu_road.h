/* The road of cleatfmu in portable C99: a two-track profile under the four tires, as the ride's model record
 * (identification/comfort/ride.py, RideModel.inputs) makes it, the same operations in the same order.
 *
 * Tire T is at x = start_x + speed t (minus the wheelbase at the rear) and sees its side's track (left: FL,
 * RL), interpolated linearly in the profile's table (np.interp: zero outside it), faded in by a smoothstep
 * over ramp_length from the table's first point: road_z = fade h(x), road_vz = speed (fade h'(x) + fade' h(x)),
 * h' the table's slope column interpolated the same way.
 */
#ifndef CLEATFMU_ROAD_H
#define CLEATFMU_ROAD_H

#include "cleatfmu_names.h"

#include <stddef.h>

#include "cleatfmu_model.h"

/* Name of the profile file in the FMU's resources folder. */
#define CLEATFMU_ROAD_FILE "cleatfmu_road.txt"

#if MODEL_ROAD
/* The profile: n points x (increasing), the left and right heights and their slopes dh/dx. */
typedef struct {
    size_t n;
    double *x, *left, *right, *left_slope, *right_slope;
} CleatfmuRoad;

/* Read resources/cleatfmu_road.txt ("cleatfmu-road 1", "points N", then N lines of five doubles as the
 * 16 hexadecimal digits of their bits: x, left, right, left slope, right slope); returns 0, or 1 with the
 * reason in msg. */
int cleatfmu_road_load(const char *resource_location, CleatfmuRoad **road, char *msg, size_t n);
void cleatfmu_road_free(CleatfmuRoad *road);
/* The road outputs at `time`. */
void cleatfmu_road_outputs(double *v, double time, const CleatfmuRoad *road);
#endif

#endif
