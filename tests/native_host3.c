/* A native FMI 3.0 co-simulation host without Python: dlopens a cleatfmu tire FMU's x86_64-linux binary.
 *
 * usage: native_host3 LIB RESOURCE_PATH INSTANTIATION_TOKEN MODE [ARGS]
 *   equilibrium [FORCE_VR]      print force_z (value reference FORCE_VR, default 7) with the start values
 *   step MASS STEP_M N H        quarter car of MASS kg on the tire, road step STEP_M at 0.1 s;
 *                               N steps of H s; prints "t z v force time" per step, where time is the
 *                               FMU's independent variable (value reference 11) after the step
 *   leak N                      N instantiate/free cycles; prints the RSS growth in bytes
 * Value references of step are those of the point_contact kind (hub_z 0, hub_vz 1, road_z 2,
 * road_vz 3, force_z 7, time 11).
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

static fmi3InstantiateCoSimulationTYPE *instantiate;
static fmi3FreeInstanceTYPE *free_instance;
static fmi3EnterInitializationModeTYPE *enter_init;
static fmi3ExitInitializationModeTYPE *exit_init;
static fmi3SetFloat64TYPE *set_float64;
static fmi3GetFloat64TYPE *get_float64;
static fmi3DoStepTYPE *do_step;
static fmi3TerminateTYPE *terminate;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    fprintf(stderr, "[%s] %d %s: %s\n", env ? (const char *)env : "?", (int)status, category, message);
}

static long rss_bytes(void) {
    char line[256];
    long kb = -1;
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return -1;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "VmRSS:", 6) == 0) kb = atol(line + 6);
    fclose(f);
    return kb * 1024;
}

static void *symbol(void *lib, const char *name) {
    void *p = dlsym(lib, name);
    if (!p) {
        fprintf(stderr, "missing symbol %s\n", name);
        exit(3);
    }
    return p;
}

static fmi3Instance make(const char *name, const char *token, const char *path) {
    return instantiate(name, token, path, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, (void *)name,
                       logger, NULL);
}

int main(int argc, char **argv) {
    const fmi3ValueReference in_vr[4] = {0, 1, 2, 3}, z_vr = 0, time_vr = 11;
    fmi3ValueReference force_vr = 7;
    const char *path, *token, *mode;
    fmi3Instance c;
    void *lib;
    double force;
    if (argc < 5) {
        fprintf(stderr, "usage: native_host3 LIB RESOURCE_PATH INSTANTIATION_TOKEN MODE [ARGS]\n");
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 3;
    }
    path = argv[2];
    token = argv[3];
    mode = argv[4];
    *(void **)&instantiate = symbol(lib, "fmi3InstantiateCoSimulation");
    *(void **)&free_instance = symbol(lib, "fmi3FreeInstance");
    *(void **)&enter_init = symbol(lib, "fmi3EnterInitializationMode");
    *(void **)&exit_init = symbol(lib, "fmi3ExitInitializationMode");
    *(void **)&set_float64 = symbol(lib, "fmi3SetFloat64");
    *(void **)&get_float64 = symbol(lib, "fmi3GetFloat64");
    *(void **)&do_step = symbol(lib, "fmi3DoStep");
    *(void **)&terminate = symbol(lib, "fmi3Terminate");

    if (strcmp(mode, "leak") == 0) {
        long n = argc > 5 ? atol(argv[5]) : 0, i, before = 0;
        for (i = 0; i < n + 200; i++) {
            if (i == 200) before = rss_bytes();
            c = make("leak", token, path);
            if (!c) return 4;
            free_instance(c);
        }
        printf("%ld\n", rss_bytes() - before);
        return 0;
    }
    c = make("host", token, path);
    if (!c) return 4;
    if (enter_init(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) || exit_init(c)) return 5;
    if (strcmp(mode, "equilibrium") == 0) {
        if (argc > 5) force_vr = (fmi3ValueReference)atol(argv[5]);
        if (get_float64(c, &force_vr, 1, &force, 1)) return 6;
        printf("%.17g\n", force);
    } else if (strcmp(mode, "step") == 0 && argc > 8) {
        const double g = 9.80665, mass = atof(argv[5]), height = atof(argv[6]), h = atof(argv[8]);
        long n = atol(argv[7]), i;
        double z, v = 0.0, t = 0.0, u[4], fmu_time;
        fmi3Boolean event, stop, early;
        fmi3Float64 last;
        if (get_float64(c, &z_vr, 1, &z, 1)) return 6;
        for (i = 0; i < n; i++) {
            u[0] = z; u[1] = v; u[2] = t >= 0.1 ? height : 0.0; u[3] = 0.0;
            if (set_float64(c, in_vr, 4, u, 4) || do_step(c, t, h, fmi3True, &event, &stop, &early, &last) ||
                get_float64(c, &force_vr, 1, &force, 1) || get_float64(c, &time_vr, 1, &fmu_time, 1))
                return 7;
            if (event || stop || early) return 8;
            v += h * (force / mass - g);
            z += h * v;
            t = (i + 1) * h;
            printf("%.17g %.17g %.17g %.17g %.17g\n", t, z, v, force, fmu_time);
        }
    } else {
        fprintf(stderr, "unknown mode or missing arguments: %s\n", mode);
        return 2;
    }
    if (terminate(c)) return 9;
    free_instance(c);
    dlclose(lib);
    return 0;
}
