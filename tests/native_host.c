/* A native FMI 2.0 host without Python: dlopens a cleatfmu tire FMU's linux binary.
 *
 * usage: native_host LIB RESOURCE_URI GUID MODE [ARGS]
 *   equilibrium                 print force_z with the FMU's start values
 *   step MASS STEP_M N H        quarter car of MASS kg on the tire, road step STEP_M at 0.1 s;
 *                               N steps of H s; prints "t z v force" per step
 *   leak N                      N instantiate/free cycles; prints the RSS growth in bytes
 *   bench N                     N setReal/doStep/getReal steps; prints steps per second
 * Value references are those of the point_contact kind (hub_z 0, hub_vz 1, road_z 2,
 * road_vz 3, force_z 7).
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static fmi2InstantiateTYPE *instantiate;
static fmi2FreeInstanceTYPE *free_instance;
static fmi2SetupExperimentTYPE *setup;
static fmi2EnterInitializationModeTYPE *enter_init;
static fmi2ExitInitializationModeTYPE *exit_init;
static fmi2SetRealTYPE *set_real;
static fmi2GetRealTYPE *get_real;
static fmi2DoStepTYPE *do_step;
static fmi2TerminateTYPE *terminate;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    fprintf(stderr, "[%s] %d %s: %s\n", name, (int)status, category, message);
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

int main(int argc, char **argv) {
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    const fmi2ValueReference in_vr[4] = {0, 1, 2, 3}, force_vr = 7;
    const char *uri, *guid, *mode;
    fmi2Component c;
    void *lib;
    double force;
    if (argc < 5) {
        fprintf(stderr, "usage: native_host LIB RESOURCE_URI GUID MODE [ARGS]\n");
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 3;
    }
    uri = argv[2];
    guid = argv[3];
    mode = argv[4];
    *(void **)&instantiate = symbol(lib, "fmi2Instantiate");
    *(void **)&free_instance = symbol(lib, "fmi2FreeInstance");
    *(void **)&setup = symbol(lib, "fmi2SetupExperiment");
    *(void **)&enter_init = symbol(lib, "fmi2EnterInitializationMode");
    *(void **)&exit_init = symbol(lib, "fmi2ExitInitializationMode");
    *(void **)&set_real = symbol(lib, "fmi2SetReal");
    *(void **)&get_real = symbol(lib, "fmi2GetReal");
    *(void **)&do_step = symbol(lib, "fmi2DoStep");
    *(void **)&terminate = symbol(lib, "fmi2Terminate");

    if (strcmp(mode, "leak") == 0) {
        long n = atol(argv[5]), i, before = 0;
        for (i = 0; i < n + 200; i++) {
            if (i == 200) before = rss_bytes();
            c = instantiate("leak", fmi2CoSimulation, guid, uri, &cb, fmi2False, fmi2False);
            if (!c) return 4;
            free_instance(c);
        }
        printf("%ld\n", rss_bytes() - before);
        return 0;
    }
    c = instantiate("host", fmi2CoSimulation, guid, uri, &cb, fmi2False, fmi2False);
    if (!c) return 4;
    if (setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) || enter_init(c) || exit_init(c)) return 5;
    if (strcmp(mode, "equilibrium") == 0) {
        if (get_real(c, &force_vr, 1, &force)) return 6;
        printf("%.17g\n", force);
    } else if (strcmp(mode, "step") == 0) {
        const double g = 9.80665, mass = atof(argv[5]), height = atof(argv[6]), h = atof(argv[8]);
        long n = atol(argv[7]), i;
        const fmi2ValueReference z_vr = 0;
        double z, v = 0.0, t = 0.0, u[4];
        if (get_real(c, &z_vr, 1, &z)) return 6;
        for (i = 0; i < n; i++) {
            u[0] = z; u[1] = v; u[2] = t >= 0.1 ? height : 0.0; u[3] = 0.0;
            if (set_real(c, in_vr, 4, u) || do_step(c, t, h, fmi2True) || get_real(c, &force_vr, 1, &force)) return 7;
            v += h * (force / mass - g);
            z += h * v;
            t = (i + 1) * h;
            printf("%.17g %.17g %.17g %.17g\n", t, z, v, force);
        }
    } else if (strcmp(mode, "bench") == 0) {
        long n = atol(argv[5]), i;
        double u[4] = {0.7, 0.0, 0.0, 0.0}, sum = 0.0, seconds;
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        for (i = 0; i < n; i++) {
            u[0] = 0.7 + 1e-9 * (double)(i & 1023);
            set_real(c, in_vr, 4, u);
            do_step(c, (double)i * 1e-3, 1e-3, fmi2True);
            get_real(c, &force_vr, 1, &force);
            sum += force;
        }
        clock_gettime(CLOCK_MONOTONIC, &t1);
        seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        printf("%.6g %.17g\n", (double)n / seconds, sum);
    } else {
        fprintf(stderr, "unknown mode %s\n", mode);
        return 2;
    }
    terminate(c);
    free_instance(c);
    dlclose(lib);
    return 0;
}
