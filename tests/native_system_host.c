/* A native FMI 2.0 master without Python: the tractor system of an SSP (body + four tire FMUs).
 *
 * usage: native_system_host STEP N BODY_LIB BODY_URI BODY_GUID {TIRE_LIB TIRE_URI TIRE_GUID} x 4
 * Runs N steps of STEP s from t = 0 with the sequential exchange (body first, then each tire with
 * the body's new hub motion; the body's forces are read back after the tires' steps), after
 * initial values propagated in initialization mode.  Prints one line per point (N + 1):
 * "t hub_z_FL hub_z_FR hub_z_RL hub_z_RR seat_z seat_az".
 * Value references: tractor_body force_T 0-3, hub_z_T 31-34, hub_vz_T 35-38, hub_x_T 39-42,
 * hub_vx 43, seat_z 48, seat_az 49 (checked against the kind's table by tests/test_ssp.py); extended_tire hub_z 0, hub_vz 1, hub_x 4, hub_vx 5, force_z 21.
 */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef struct {
    void *lib;
    fmi2Component c;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter_init;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2SetRealTYPE *set_real;
    fmi2GetRealTYPE *get_real;
    fmi2DoStepTYPE *do_step;
    fmi2TerminateTYPE *terminate;
} Fmu;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    fprintf(stderr, "[%s] %d %s: %s\n", name, (int)status, category, message);
}

static void *symbol(void *lib, const char *name) {
    void *p = dlsym(lib, name);
    if (!p) {
        fprintf(stderr, "missing symbol %s\n", name);
        exit(3);
    }
    return p;
}

static void open_fmu(Fmu *f, const char *name, const char *path, const char *uri, const char *guid) {
    static fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2InstantiateTYPE *instantiate;
    f->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!f->lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        exit(3);
    }
    *(void **)&instantiate = symbol(f->lib, "fmi2Instantiate");
    *(void **)&f->free_instance = symbol(f->lib, "fmi2FreeInstance");
    *(void **)&f->setup = symbol(f->lib, "fmi2SetupExperiment");
    *(void **)&f->enter_init = symbol(f->lib, "fmi2EnterInitializationMode");
    *(void **)&f->exit_init = symbol(f->lib, "fmi2ExitInitializationMode");
    *(void **)&f->set_real = symbol(f->lib, "fmi2SetReal");
    *(void **)&f->get_real = symbol(f->lib, "fmi2GetReal");
    *(void **)&f->do_step = symbol(f->lib, "fmi2DoStep");
    *(void **)&f->terminate = symbol(f->lib, "fmi2Terminate");
    f->c = instantiate(name, fmi2CoSimulation, guid, uri, &cb, fmi2False, fmi2True);
    if (!f->c) exit(4);
    if (f->setup(f->c, fmi2False, 0.0, 0.0, fmi2False, 0.0) || f->enter_init(f->c)) exit(5);
}

static void check(fmi2Status status, const char *what) {
    if (status > fmi2Warning) {
        fprintf(stderr, "%s failed (%d)\n", what, (int)status);
        exit(6);
    }
}

static void feed_tire(Fmu *body, Fmu *tire, int t) {
    const fmi2ValueReference from[4] = {31 + t, 35 + t, 39 + t, 43}, to[4] = {0, 1, 4, 5};
    fmi2Real u[4];
    check(body->get_real(body->c, from, 4, u), "body getReal");
    check(tire->set_real(tire->c, to, 4, u), "tire setReal");
}

static void feed_body(Fmu *body, Fmu *tires) {
    const fmi2ValueReference force_vr = 21, to[4] = {0, 1, 2, 3};
    fmi2Real f[4];
    int t;
    for (t = 0; t < 4; t++) check(tires[t].get_real(tires[t].c, &force_vr, 1, &f[t]), "tire getReal");
    check(body->set_real(body->c, to, 4, f), "body setReal");
}

static void print_row(Fmu *body, double t) {
    const fmi2ValueReference vr[6] = {31, 32, 33, 34, 48, 49};
    fmi2Real y[6];
    check(body->get_real(body->c, vr, 6, y), "body getReal");
    printf("%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", t, y[0], y[1], y[2], y[3], y[4], y[5]);
}

int main(int argc, char **argv) {
    Fmu body, tires[4];
    double h;
    long n, i;
    int t, k;
    if (argc != 18) {
        fprintf(stderr, "usage: native_system_host STEP N BODY_LIB BODY_URI BODY_GUID {LIB URI GUID} x 4\n");
        return 2;
    }
    h = atof(argv[1]);
    n = atol(argv[2]);
    open_fmu(&body, "body", argv[3], argv[4], argv[5]);
    for (t = 0; t < 4; t++) open_fmu(&tires[t], "tire", argv[6 + 3 * t], argv[7 + 3 * t], argv[8 + 3 * t]);
    for (k = 0; k < 5; k++) {                 /* initial values: as many passes as components */
        for (t = 0; t < 4; t++) feed_tire(&body, &tires[t], t);
        feed_body(&body, tires);
    }
    check(body.exit_init(body.c), "body exitInitializationMode");
    for (t = 0; t < 4; t++) check(tires[t].exit_init(tires[t].c), "tire exitInitializationMode");
    print_row(&body, 0.0);
    for (i = 0; i < n; i++) {
        double now = (double)i * h;
        check(body.do_step(body.c, now, h, fmi2True), "body doStep");
        for (t = 0; t < 4; t++) {
            feed_tire(&body, &tires[t], t);
            check(tires[t].do_step(tires[t].c, now, h, fmi2True), "tire doStep");
        }
        feed_body(&body, tires);
        print_row(&body, (double)(i + 1) * h);
    }
    body.terminate(body.c);
    body.free_instance(body.c);
    for (t = 0; t < 4; t++) {
        tires[t].terminate(tires[t].c);
        tires[t].free_instance(tires[t].c);
    }
    return 0;
}
