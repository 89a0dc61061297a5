/* Every cleatfmu FMU kind linked statically into this one program, each compiled from its FMU's sources/
 * with FMI2_FUNCTION_PREFIX set to its own prefix (pc_, ext_, body_, road_, map_).
 *
 *   native_static_host KIND RESOURCE_URI GUID STEPS STEP_S VR...
 *
 * instantiates KIND (pc, ext, body, road or map) as a co-simulation slave, initializes it at t = 0 with its
 * default values, and prints the outputs VR... after initialization and after each of STEPS steps
 * (one line per point, %.17g).  Exit status 1 on any FMI error. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

#define DECLARE(P)                                                                                            \
    fmi2Component P##fmi2Instantiate(fmi2String, fmi2Type, fmi2String, fmi2String,                           \
                                     const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);                \
    fmi2Status P##fmi2SetupExperiment(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real); \
    fmi2Status P##fmi2EnterInitializationMode(fmi2Component);                                                \
    fmi2Status P##fmi2ExitInitializationMode(fmi2Component);                                                 \
    fmi2Status P##fmi2DoStep(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);                                \
    fmi2Status P##fmi2GetReal(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);                \
    fmi2Status P##fmi2Terminate(fmi2Component);                                                               \
    void P##fmi2FreeInstance(fmi2Component);

DECLARE(pc_)
DECLARE(ext_)
DECLARE(body_)
DECLARE(road_)
DECLARE(map_)

typedef struct {
    const char *name;
    fmi2Component (*instantiate)(fmi2String, fmi2Type, fmi2String, fmi2String, const fmi2CallbackFunctions *,
                                 fmi2Boolean, fmi2Boolean);
    fmi2Status (*setup)(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real);
    fmi2Status (*enter)(fmi2Component);
    fmi2Status (*exit_init)(fmi2Component);
    fmi2Status (*step)(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
    fmi2Status (*get_real)(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
    fmi2Status (*terminate)(fmi2Component);
    void (*free_instance)(fmi2Component);
} Kind;

#define KIND(P, NAME) {NAME, P##fmi2Instantiate, P##fmi2SetupExperiment, P##fmi2EnterInitializationMode, \
                       P##fmi2ExitInitializationMode, P##fmi2DoStep, P##fmi2GetReal, P##fmi2Terminate,     \
                       P##fmi2FreeInstance}

static const Kind KINDS[] = {KIND(pc_, "pc"), KIND(ext_, "ext"), KIND(body_, "body"), KIND(road_, "road"),
                             KIND(map_, "map")};

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    fprintf(stderr, "%s [%d] %s: %s\n", name, (int)status, category, message);
}

static int fail(const char *what) {
    fprintf(stderr, "%s failed\n", what);
    return 1;
}

int main(int argc, char **argv) {
    const Kind *kind = NULL;
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2ValueReference vrs[64];
    fmi2Real values[64];
    fmi2Component c;
    size_t i, n;
    long steps, k;
    double h;
    if (argc < 7 || argc - 6 > 64) {
        fprintf(stderr, "usage: %s KIND RESOURCE_URI GUID STEPS STEP_S VR...\n", argv[0]);
        return 2;
    }
    for (i = 0; i < sizeof KINDS / sizeof KINDS[0]; i++)
        if (strcmp(argv[1], KINDS[i].name) == 0) kind = &KINDS[i];
    if (kind == NULL) return fail("kind");
    steps = strtol(argv[4], NULL, 10);
    h = strtod(argv[5], NULL);
    n = (size_t)(argc - 6);
    for (i = 0; i < n; i++) vrs[i] = (fmi2ValueReference)strtoul(argv[6 + i], NULL, 10);
    c = kind->instantiate(argv[1], fmi2CoSimulation, argv[3], argv[2], &callbacks, fmi2False, fmi2False);
    if (c == NULL) return fail("fmi2Instantiate");
    if (kind->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) > fmi2Warning) return fail("fmi2SetupExperiment");
    if (kind->enter(c) > fmi2Warning || kind->exit_init(c) > fmi2Warning) return fail("initialization");
    for (k = 0; k <= steps; k++) {
        if (k > 0 && kind->step(c, (k - 1) * h, h, fmi2True) > fmi2Warning) return fail("fmi2DoStep");
        if (kind->get_real(c, vrs, n, values) > fmi2Warning) return fail("fmi2GetReal");
        for (i = 0; i < n; i++) printf(i + 1 < n ? "%.17g " : "%.17g\n", values[i]);
    }
    kind->terminate(c);
    kind->free_instance(c);
    return 0;
}
