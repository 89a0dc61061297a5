/* The tire map of cleatfmu in portable C99: the point-contact tire whose k and c follow the speed.
 *
 * The map is a table of nodes (speed, k, c) with the speed range its runs were tested over.  At speed v,
 * k and c are interpolated linearly between the nodes and held at the first or last node outside them
 * (numpy.interp); the force law is cleatfmu_point_contact's.  A speed outside the tested range is an
 * extrapolation: the output `extrapolating` is true, and the evaluation that first finds the speed outside
 * (once per excursion: after a speed inside the range, or at the start) returns a warning.
 */
#ifndef CLEATFMU_MAP_H
#define CLEATFMU_MAP_H

#include "cleatfmu_names.h"

#include <stddef.h>

#include "cleatfmu_model.h"

/* Name of the table in the FMU's resources folder. */
#define CLEATFMU_MAP_FILE "cleatfmu_map.txt"

#if MODEL_MAP
/* The map: n nodes, speeds increasing (m/s), k (N/m) and c (N s/m) at each; the tested speed range. */
typedef struct {
    size_t n;
    double tested_low, tested_high;
    double *speed, *stiffness, *damping;
} CleatfmuMap;

/* Read resources/cleatfmu_map.txt ("cleatfmu-map 1", "tested LOW HIGH", "nodes N", then N lines of three
 * doubles: speed, k, c; every double as the 16 hexadecimal digits of its bits); returns 0, or 1 with the
 * reason in msg. */
int cleatfmu_map_load(const char *resource_location, CleatfmuMap **map, char *msg, size_t n);
void cleatfmu_map_free(CleatfmuMap *map);
/* The outputs (k, c at the speed, the force law, the extrapolation flag); returns 1 with a warning in msg
 * when the speed has just left the tested range, else 0. */
int cleatfmu_map_outputs(double *v, const CleatfmuMap *map, char *msg, size_t n);
#endif

#endif
