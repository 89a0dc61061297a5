/* The tire map (see cleatfmu_map.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cleatfmu_law.h"
#include "cleatfmu_map.h"
#include "cleatfmu_resources.h"

#if MODEL_MAP

/* Largest map file, bytes. */
#define MAX_MAP_FILE (1024UL * 1024UL)

void cleatfmu_map_free(CleatfmuMap *map) {
    if (map == NULL) return;
    free(map->speed);
    free(map);
}

/* n doubles of one line (bits in hex separated by single spaces); 0, or 1 if malformed or NaN. */
static int parse_line(const char *line, double *out, int n) {
    const char *p = line;
    int i;
    for (i = 0; i < n; i++) {
        if (p == NULL || cleatfmu_parse_bits(p, &out[i], &p) || out[i] != out[i]) return 1;
        if (i < n - 1 && *p++ != ' ') return 1;
    }
    return *p != '\0';
}

int cleatfmu_map_load(const char *resource_location, CleatfmuMap **out, char *msg, size_t n) {
    char *buf, *line;
    size_t size, pos = 0, i, nodes = 0;
    double range[2];
    CleatfmuMap *map = NULL;
    *out = NULL;
    if (cleatfmu_read_resource(resource_location, CLEATFMU_MAP_FILE, MAX_MAP_FILE, &buf, &size, msg, n)) return 1;
    line = cleatfmu_next_line(buf, size, &pos);
    if (line == NULL || strcmp(line, "cleatfmu-map 1") != 0) {
        snprintf(msg, n, "%s: not a tire map file", CLEATFMU_MAP_FILE);
        goto fail;
    }
    line = cleatfmu_next_line(buf, size, &pos);
    if (line == NULL || strncmp(line, "tested ", 7) != 0 || parse_line(line + 7, range, 2)
        || !isfinite(range[0]) || !isfinite(range[1]) || !(range[0] <= range[1])) {
        snprintf(msg, n, "%s: no valid 'tested LOW HIGH' line", CLEATFMU_MAP_FILE);
        goto fail;
    }
    line = cleatfmu_next_line(buf, size, &pos);
    if (line == NULL || sscanf(line, "nodes %lu", (unsigned long *)&nodes) != 1 || nodes < 1
        || nodes > MAX_MAP_FILE / 50) {
        snprintf(msg, n, "%s: no valid 'nodes N' line (N >= 1)", CLEATFMU_MAP_FILE);
        goto fail;
    }
    map = (CleatfmuMap *)calloc(1, sizeof *map);
    if (map == NULL || (map->speed = (double *)malloc(3 * nodes * sizeof(double))) == NULL) {
        snprintf(msg, n, "out of memory");
        goto fail;
    }
    map->n = nodes;
    map->tested_low = range[0];
    map->tested_high = range[1];
    map->stiffness = map->speed + nodes;
    map->damping = map->stiffness + nodes;
    for (i = 0; i < nodes; i++) {
        double node[3];
        line = cleatfmu_next_line(buf, size, &pos);
        if (line == NULL || parse_line(line, node, 3) || !isfinite(node[0]) || !isfinite(node[1])
            || !isfinite(node[2]) || !(node[1] > 0.0) || !(node[2] >= 0.0)) {
            snprintf(msg, n, "%s: node %lu is not three finite numbers (speed, k > 0, c >= 0)", CLEATFMU_MAP_FILE,
                     (unsigned long)i + 1);
            goto fail;
        }
        if (i > 0 && !(node[0] > map->speed[i - 1])) {
            snprintf(msg, n, "%s: the speeds must increase (node %lu)", CLEATFMU_MAP_FILE, (unsigned long)i + 1);
            goto fail;
        }
        map->speed[i] = node[0];
        map->stiffness[i] = node[1];
        map->damping[i] = node[2];
    }
    free(buf);
    *out = map;
    return 0;
fail:
    free(buf);
    cleatfmu_map_free(map);
    return 1;
}

/* np.interp(x, xp, fp): fp[0] below xp[0], fp[n - 1] above xp[n - 1]. */
static double interp(double x, const double *xp, const double *fp, size_t n) {
    size_t lo = 0, hi = n - 1;
    double slope;
    if (x <= xp[0]) return fp[0];
    if (x >= xp[n - 1]) return fp[n - 1];
    while (hi - lo > 1) {                 /* xp[lo] <= x < xp[hi] */
        size_t mid = lo + (hi - lo) / 2;
        if (xp[mid] <= x) lo = mid;
        else hi = mid;
    }
    if (x == xp[lo]) return fp[lo];
    slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo]);
    return slope * (x - xp[lo]) + fp[lo];
}

int cleatfmu_map_outputs(double *v, const CleatfmuMap *map, char *msg, size_t n) {
    CleatfmuTireResult r;
    double speed = v[VR_SPEED], k, c, was = v[VR_EXTRAPOLATING];
    k = interp(speed, map->speed, map->stiffness, map->n);
    c = interp(speed, map->speed, map->damping, map->n);
    cleatfmu_point_contact(v[VR_HUB_Z], v[VR_HUB_VZ], v[VR_ROAD_Z], v[VR_ROAD_VZ], k, c, v[VR_UNLOADED_RADIUS], &r);
    v[VR_FORCE_Z] = r.force;
    v[VR_DEFLECTION] = r.deflection;
    v[VR_DEFLECTION_RATE] = r.deflection_rate;
    v[VR_IN_CONTACT] = r.contact ? 1.0 : 0.0;
    v[VR_STIFFNESS] = k;
    v[VR_DAMPING] = c;
    v[VR_EXTRAPOLATING] = (speed < map->tested_low || speed > map->tested_high) ? 1.0 : 0.0;
    if (v[VR_EXTRAPOLATING] != 0.0 && was == 0.0) {
        snprintf(msg, n, "speed %.6g m/s (%.4g km/h) is outside the map's tested range %.6g-%.6g m/s: k = %.6g N/m "
                         "and c = %.6g N.s/m are those of the nearest node (extrapolation)",
                 speed, 3.6 * speed, map->tested_low, map->tested_high, k, c);
        return 1;
    }
    return 0;
}

#endif
