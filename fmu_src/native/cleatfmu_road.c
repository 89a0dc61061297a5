/* The road profile (see cleatfmu_road.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cleatfmu_resources.h"
#include "cleatfmu_road.h"

#if MODEL_ROAD

/* Largest profile file, bytes (about 700,000 points). */
#define MAX_ROAD_FILE (64UL * 1024UL * 1024UL)

void cleatfmu_road_free(CleatfmuRoad *road) {
    if (road == NULL) return;
    free(road->x);
    free(road);
}

int cleatfmu_road_load(const char *resource_location, CleatfmuRoad **out, char *msg, size_t n) {
    char *buf, *line;
    size_t size, pos = 0, i, points = 0;
    CleatfmuRoad *road = NULL;
    *out = NULL;
    if (cleatfmu_read_resource(resource_location, CLEATFMU_ROAD_FILE, MAX_ROAD_FILE, &buf, &size, msg, n)) return 1;
    line = cleatfmu_next_line(buf, size, &pos);
    if (line == NULL || strcmp(line, "cleatfmu-road 1") != 0) {
        snprintf(msg, n, "%s: not a road profile file", CLEATFMU_ROAD_FILE);
        goto fail;
    }
    line = cleatfmu_next_line(buf, size, &pos);
    if (line == NULL || sscanf(line, "points %lu", (unsigned long *)&points) != 1 || points < 2
        || points > MAX_ROAD_FILE / 80) {
        snprintf(msg, n, "%s: no valid 'points N' line (N >= 2)", CLEATFMU_ROAD_FILE);
        goto fail;
    }
    road = (CleatfmuRoad *)calloc(1, sizeof *road);
    if (road == NULL || (road->x = (double *)malloc(5 * points * sizeof(double))) == NULL) {
        snprintf(msg, n, "out of memory");
        goto fail;
    }
    road->n = points;
    road->left = road->x + points;
    road->right = road->left + points;
    road->left_slope = road->right + points;
    road->right_slope = road->left_slope + points;
    for (i = 0; i < points; i++) {
        double *columns[5];
        const char *p;
        int c;
        columns[0] = road->x; columns[1] = road->left; columns[2] = road->right;
        columns[3] = road->left_slope; columns[4] = road->right_slope;
        line = cleatfmu_next_line(buf, size, &pos);
        p = line;
        for (c = 0; c < 5; c++) {
            if (p == NULL || cleatfmu_parse_bits(p, &columns[c][i], &p) || (c < 4 && *p++ != ' ')
                || (c == 4 && *p != '\0') || columns[c][i] != columns[c][i]) {
                snprintf(msg, n, "%s: point %lu is not five numbers", CLEATFMU_ROAD_FILE, (unsigned long)i + 1);
                goto fail;
            }
        }
        if (i > 0 && !(road->x[i] > road->x[i - 1])) {
            snprintf(msg, n, "%s: the positions must increase (point %lu)", CLEATFMU_ROAD_FILE, (unsigned long)i + 1);
            goto fail;
        }
    }
    free(buf);
    *out = road;
    return 0;
fail:
    free(buf);
    cleatfmu_road_free(road);
    return 1;
}

/* np.interp(x, xp, fp, left=0, right=0). */
static double interp(double x, const double *xp, const double *fp, size_t n) {
    size_t lo = 0, hi = n - 1;
    double slope;
    if (!(x >= xp[0]) || x > xp[n - 1]) return 0.0;
    if (x == xp[n - 1]) return fp[n - 1];
    while (hi - lo > 1) {                 /* xp[lo] <= x < xp[hi] */
        size_t mid = lo + (hi - lo) / 2;
        if (xp[mid] <= x) lo = mid;
        else hi = mid;
    }
    if (x == xp[lo]) return fp[lo];
    slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo]);
    return slope * (x - xp[lo]) + fp[lo];
}

void cleatfmu_road_outputs(double *v, double time, const CleatfmuRoad *road) {
    static const int left[4] = {1, 0, 1, 0};
    double speed = v[VR_SPEED], ramp = v[VR_RAMP_LENGTH];
    int t;
    for (t = 0; t < 4; t++) {
        double x = v[VR_START_X] + speed * time - (t < 2 ? 0.0 : v[VR_WHEELBASE]);
        const double *h = left[t] ? road->left : road->right, *dh = left[t] ? road->left_slope : road->right_slope;
        double height = interp(x, road->x, h, road->n), slope = interp(x, road->x, dh, road->n);
        double s = (x - road->x[0]) / ramp, fade, dfade;
        s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
        fade = s * s * (3.0 - 2.0 * s);
        dfade = s > 0.0 && s < 1.0 ? 6.0 * s * (1.0 - s) / ramp : 0.0;
        v[VR_ROAD_Z_FL + t] = fade * height;
        v[VR_ROAD_VZ_FL + t] = speed * (fade * slope + dfade * height);
    }
}

#endif
