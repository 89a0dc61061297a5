/* FMI 2.0 co-simulation interface of a cleatfmu tire FMU: a thin layer over cleatfmu_model.
 *
 * Outputs are direct feedthrough (evaluated from the values set last, when read).
 * A refused value (wrong variable, non-finite, out of its range) makes the call
 * return fmi2Error with the reason logged; the instance keeps its previous values
 * and stays usable.  Parameters that are invalid together make the next read,
 * step or exit from initialization mode fail the same way until they are fixed.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "cleatfmu_model.h"
#include "cleatfmu_resources.h"

typedef enum {
    S_INSTANTIATED = 1, S_INITIALIZATION = 2, S_STEP_COMPLETE = 4, S_TERMINATED = 8
} Mode;

#define ANY_MODE (S_INSTANTIATED | S_INITIALIZATION | S_STEP_COMPLETE | S_TERMINATED)
#define READABLE (S_INITIALIZATION | S_STEP_COMPLETE | S_TERMINATED)
#define SETTABLE (S_INSTANTIATED | S_INITIALIZATION | S_STEP_COMPLETE)

typedef struct {
    fmi2CallbackLogger logger;
    fmi2CallbackFreeMemory free_memory;
    fmi2ComponentEnvironment environment;
    char name[128];
    int log_errors, log_calls;
    Mode mode;
    double time;
    int stale, unchecked;
    double values[N_VARIABLES];
    double start[N_VARIABLES];
    char guid[CLEATFMU_GUID_SIZE];
} Instance;

#define STATE_MAGIC "CLEATFMU"
typedef struct {
    char magic[8];
    double time;
    int unchecked;
    double values[N_VARIABLES];
} Snapshot;
/* Serialized state: magic, kind (32 bytes), number of values (4 bytes LE), time, values. */
#define KIND_BYTES 32
#define SERIALIZED_SIZE (8 + KIND_BYTES + 4 + 8 * (1 + N_VARIABLES))

/* Send a message to the importer's logger; '%' is escaped as the logger formats it. */
static void send(fmi2CallbackLogger logger, fmi2ComponentEnvironment env, const char *name, fmi2Status status,
                 const char *category, const char *text) {
    char escaped[2 * CLEATFMU_MESSAGE_SIZE + 1];
    size_t i, j = 0;
    if (logger == NULL) return;
    for (i = 0; text[i] && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    logger(env, name, status, category, escaped);
}

static fmi2Status fail(Instance *s, const char *fmt, ...) {
    char text[CLEATFMU_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (s->log_errors) send(s->logger, s->environment, s->name, fmi2Error, "logStatusError", text);
    return fmi2Error;
}

/* Check that `c` is an instance and the call is allowed in its mode. */
static int allowed(fmi2Component c, const char *function, int modes) {
    Instance *s = (Instance *)c;
    if (s == NULL) return 0;
    if (!(s->mode & modes)) {
        fail(s, "%s: not allowed in this state (call sequence)", function);
        return 0;
    }
    if (s->log_calls) send(s->logger, s->environment, s->name, fmi2OK, "logCalls", function);
    return 1;
}

static int arrays_ok(Instance *s, const char *function, const void *vr, size_t nvr, const void *value) {
    if (nvr > 0 && (vr == NULL || value == NULL)) {
        fail(s, "%s: NULL array", function);
        return 0;
    }
    return 1;
}

static fmi2Status check_parameters(Instance *s) {
    char msg[CLEATFMU_MESSAGE_SIZE];
    if (s->unchecked) {
        if (cleatfmu_set_problem(s->values, msg, sizeof msg)) return fail(s, "parameters rejected: %s", msg);
        s->unchecked = 0;
    }
    return fmi2OK;
}

static fmi2Status update(Instance *s) {
    char msg[CLEATFMU_MESSAGE_SIZE];
    if (!s->stale) return fmi2OK;
    if (check_parameters(s) != fmi2OK) return fmi2Error;
    if (cleatfmu_evaluate(s->values, msg, sizeof msg)) return fail(s, "%s", msg);
    s->stale = 0;
    return fmi2OK;
}

/* ---------------------------------------------------------------- common functions */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Instance *s = (Instance *)c;
    size_t i;
    if (!allowed(c, "fmi2SetDebugLogging", ANY_MODE)) return fmi2Error;
    if (nCategories == 0) {
        s->log_errors = s->log_calls = loggingOn ? 1 : 0;
        return fmi2OK;
    }
    if (categories == NULL) return fail(s, "fmi2SetDebugLogging: NULL categories");
    for (i = 0; i < nCategories; i++) {
        if (categories[i] && strcmp(categories[i], "logStatusError") == 0) s->log_errors = loggingOn ? 1 : 0;
        else if (categories[i] && strcmp(categories[i], "logCalls") == 0) s->log_calls = loggingOn ? 1 : 0;
        else return fail(s, "fmi2SetDebugLogging: unknown log category %s", categories[i] ? categories[i] : "NULL");
    }
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    char msg[CLEATFMU_MESSAGE_SIZE], guid[CLEATFMU_GUID_SIZE];
    double values[N_VARIABLES];
    const char *name = instanceName ? instanceName : "";
    Instance *s;
    (void)visible;
    (void)loggingOn;
    if (functions == NULL) return NULL;
    memset(values, 0, sizeof values);
    if (fmuType != fmi2CoSimulation) {
        send(functions->logger, functions->componentEnvironment, name, fmi2Error, "logStatusError",
             "fmi2Instantiate: " MODEL_IDENTIFIER_STRING " supports co-simulation only");
        return NULL;
    }
    if (cleatfmu_read_start_file(fmuResourceLocation, guid, values, msg, sizeof msg)) {
        send(functions->logger, functions->componentEnvironment, name, fmi2Error, "logStatusError", msg);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, guid) != 0) {
        snprintf(msg, sizeof msg, "fmi2Instantiate: GUID %.80s does not match the FMU's %s",
                 fmuGUID ? fmuGUID : "NULL", guid);
        send(functions->logger, functions->componentEnvironment, name, fmi2Error, "logStatusError", msg);
        return NULL;
    }
    if (cleatfmu_set_problem(values, msg, sizeof msg)) {
        send(functions->logger, functions->componentEnvironment, name, fmi2Error, "logStatusError", msg);
        return NULL;
    }
    s = functions->allocateMemory ? (Instance *)functions->allocateMemory(1, sizeof *s)
                                  : (Instance *)calloc(1, sizeof *s);
    if (s == NULL) return NULL;
    memset(s, 0, sizeof *s);
    s->logger = functions->logger;
    s->free_memory = functions->allocateMemory ? functions->freeMemory : NULL;
    s->environment = functions->componentEnvironment;
    strncpy(s->name, name, sizeof s->name - 1);
    s->log_errors = 1;
    s->log_calls = 0;
    s->mode = S_INSTANTIATED;
    memcpy(s->values, values, sizeof values);
    memcpy(s->start, values, sizeof values);
    memcpy(s->guid, guid, sizeof guid);
    s->stale = 1;
    return s;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *s = (Instance *)c;
    if (s == NULL) return;
    if (s->free_memory) s->free_memory(s);
    else free(s);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance *s = (Instance *)c;
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (!allowed(c, "fmi2SetupExperiment", S_INSTANTIATED)) return fmi2Error;
    s->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    if (!allowed(c, "fmi2EnterInitializationMode", S_INSTANTIATED)) return fmi2Error;
    ((Instance *)c)->mode = S_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *s = (Instance *)c;
    if (!allowed(c, "fmi2ExitInitializationMode", S_INITIALIZATION)) return fmi2Error;
    if (check_parameters(s) != fmi2OK) return fmi2Error;
    s->mode = S_STEP_COMPLETE;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    if (!allowed(c, "fmi2Terminate", S_STEP_COMPLETE)) return fmi2Error;
    ((Instance *)c)->mode = S_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Instance *s = (Instance *)c;
    if (!allowed(c, "fmi2Reset", ANY_MODE)) return fmi2Error;
    memcpy(s->values, s->start, sizeof s->values);
    s->mode = S_INSTANTIATED;
    s->time = 0.0;
    s->stale = 1;
    s->unchecked = 0;
    return fmi2OK;
}

/* ---------------------------------------------------------------- getters and setters */

static fmi2Status get_values(fmi2Component c, const char *function, CleatfmuVarType type,
                             const fmi2ValueReference vr[], size_t nvr, double *reals, fmi2Boolean *booleans) {
    Instance *s = (Instance *)c;
    size_t i;
    if (!allowed(c, function, READABLE)) return fmi2Error;
    if (!arrays_ok(s, function, vr, nvr, type == VT_REAL ? (void *)reals : (void *)booleans)) return fmi2Error;
    for (i = 0; i < nvr; i++)
        if (vr[i] >= N_VARIABLES || cleatfmu_variables[vr[i]].type != type)
            return fail(s, "%s: value reference %u is not a %s variable", function, (unsigned)vr[i],
                        type == VT_REAL ? "Real" : "Boolean");
    if (nvr > 0 && update(s) != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (type == VT_REAL) reals[i] = s->values[vr[i]];
        else booleans[i] = s->values[vr[i]] != 0.0 ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    return get_values(c, "fmi2GetReal", VT_REAL, vr, nvr, value, NULL);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    return get_values(c, "fmi2GetBoolean", VT_BOOLEAN, vr, nvr, NULL, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    (void)vr; (void)value;
    if (!allowed(c, "fmi2GetInteger", READABLE)) return fmi2Error;
    return nvr ? fail((Instance *)c, "fmi2GetInteger: the FMU has no Integer variables") : fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr; (void)value;
    if (!allowed(c, "fmi2GetString", READABLE)) return fmi2Error;
    return nvr ? fail((Instance *)c, "fmi2GetString: the FMU has no String variables") : fmi2OK;
}

static fmi2Status set_values(fmi2Component c, const char *function, CleatfmuVarType type,
                             const fmi2ValueReference vr[], size_t nvr, const double *reals,
                             const fmi2Boolean *booleans) {
    Instance *s = (Instance *)c;
    char msg[CLEATFMU_MESSAGE_SIZE];
    size_t i;
    int parameters = 0;
    if (!allowed(c, function, SETTABLE)) return fmi2Error;
    if (!arrays_ok(s, function, vr, nvr, type == VT_REAL ? (const void *)reals : (const void *)booleans))
        return fmi2Error;
    for (i = 0; i < nvr; i++) {
        double value;
        if (vr[i] >= N_VARIABLES || cleatfmu_variables[vr[i]].type != type
            || cleatfmu_variables[vr[i]].causality == VC_OUTPUT)
            return fail(s, "%s: value reference %u is not a %s input or parameter", function, (unsigned)vr[i],
                        type == VT_REAL ? "Real" : "Boolean");
        if (type == VT_BOOLEAN && booleans[i] != fmi2True && booleans[i] != fmi2False)
            return fail(s, "%s: %s = %d: must be a Boolean: rejected", function,
                        cleatfmu_variables[vr[i]].name, (int)booleans[i]);
        value = type == VT_REAL ? reals[i] : (booleans[i] ? 1.0 : 0.0);
        if (cleatfmu_value_problem(vr[i], value, msg, sizeof msg)) {
            return fail(s, "%s: %s: rejected", function, msg);
        }
        if (cleatfmu_variables[vr[i]].causality == VC_PARAMETER) parameters = 1;
    }
    for (i = 0; i < nvr; i++) s->values[vr[i]] = type == VT_REAL ? reals[i] : (booleans[i] ? 1.0 : 0.0);
    if (nvr > 0) s->stale = 1;
    if (parameters) s->unchecked = 1;
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    return set_values(c, "fmi2SetReal", VT_REAL, vr, nvr, value, NULL);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    return set_values(c, "fmi2SetBoolean", VT_BOOLEAN, vr, nvr, NULL, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    (void)vr; (void)value;
    if (!allowed(c, "fmi2SetInteger", SETTABLE)) return fmi2Error;
    return nvr ? fail((Instance *)c, "fmi2SetInteger: the FMU has no Integer variables") : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr; (void)value;
    if (!allowed(c, "fmi2SetString", SETTABLE)) return fmi2Error;
    return nvr ? fail((Instance *)c, "fmi2SetString: the FMU has no String variables") : fmi2OK;
}

/* ---------------------------------------------------------------- FMU state */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    Instance *s = (Instance *)c;
    Snapshot *snap;
    if (!allowed(c, "fmi2GetFMUstate", ANY_MODE)) return fmi2Error;
    if (FMUstate == NULL) return fail(s, "fmi2GetFMUstate: NULL pointer");
    snap = (Snapshot *)*FMUstate;
    if (snap == NULL) {
        snap = (Snapshot *)calloc(1, sizeof *snap);
        if (snap == NULL) return fail(s, "fmi2GetFMUstate: out of memory");
    } else if (memcmp(snap->magic, STATE_MAGIC, 8) != 0) {
        return fail(s, "fmi2GetFMUstate: not an FMU state of this FMU");
    }
    memcpy(snap->magic, STATE_MAGIC, 8);
    snap->time = s->time;
    snap->unchecked = s->unchecked;
    memcpy(snap->values, s->values, sizeof s->values);
    *FMUstate = snap;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    Instance *s = (Instance *)c;
    const Snapshot *snap = (const Snapshot *)FMUstate;
    if (!allowed(c, "fmi2SetFMUstate", ANY_MODE)) return fmi2Error;
    if (snap == NULL || memcmp(snap->magic, STATE_MAGIC, 8) != 0)
        return fail(s, "fmi2SetFMUstate: not an FMU state of this FMU");
    memcpy(s->values, snap->values, sizeof s->values);
    s->time = snap->time;
    s->unchecked = snap->unchecked;
    s->stale = 1;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    if (!allowed(c, "fmi2FreeFMUstate", ANY_MODE)) return fmi2Error;
    if (FMUstate && *FMUstate) {
        memset(*FMUstate, 0, 8);
        free(*FMUstate);
        *FMUstate = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    (void)FMUstate;
    if (!allowed(c, "fmi2SerializedFMUstateSize", ANY_MODE)) return fmi2Error;
    if (size == NULL) return fail((Instance *)c, "fmi2SerializedFMUstateSize: NULL pointer");
    *size = SERIALIZED_SIZE;
    return fmi2OK;
}

static void put_u32(fmi2Byte *p, unsigned long v) {
    int i;
    for (i = 0; i < 4; i++) p[i] = (fmi2Byte)((v >> (8 * i)) & 0xff);
}

static unsigned long get_u32(const fmi2Byte *p) {
    unsigned long v = 0;
    int i;
    for (i = 3; i >= 0; i--) v = (v << 8) | (unsigned char)p[i];
    return v;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    Instance *s = (Instance *)c;
    const Snapshot *snap = (const Snapshot *)FMUstate;
    char kind[KIND_BYTES];
    if (!allowed(c, "fmi2SerializeFMUstate", ANY_MODE)) return fmi2Error;
    if (snap == NULL || memcmp(snap->magic, STATE_MAGIC, 8) != 0)
        return fail(s, "fmi2SerializeFMUstate: not an FMU state of this FMU");
    if (serializedState == NULL || size < SERIALIZED_SIZE)
        return fail(s, "fmi2SerializeFMUstate: buffer of %u bytes, %u needed", (unsigned)size,
                    (unsigned)SERIALIZED_SIZE);
    memset(kind, 0, sizeof kind);
    strncpy(kind, MODEL_KIND, sizeof kind - 1);
    memcpy(serializedState, STATE_MAGIC, 8);
    memcpy(serializedState + 8, kind, KIND_BYTES);
    put_u32(serializedState + 8 + KIND_BYTES, (unsigned long)N_VARIABLES + (snap->unchecked ? 0x10000UL : 0UL));
    memcpy(serializedState + 12 + KIND_BYTES, &snap->time, 8);
    memcpy(serializedState + 20 + KIND_BYTES, snap->values, 8 * N_VARIABLES);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    Instance *s = (Instance *)c;
    char kind[KIND_BYTES], msg[CLEATFMU_MESSAGE_SIZE];
    unsigned long header;
    Snapshot *snap;
    size_t vr;
    if (!allowed(c, "fmi2DeSerializeFMUstate", ANY_MODE)) return fmi2Error;
    if (serializedState == NULL || FMUstate == NULL || size != SERIALIZED_SIZE)
        return fail(s, "fmi2DeSerializeFMUstate: not a serialized state of FMU kind %s", MODEL_KIND);
    memset(kind, 0, sizeof kind);
    strncpy(kind, MODEL_KIND, sizeof kind - 1);
    header = get_u32(serializedState + 8 + KIND_BYTES);
    if (memcmp(serializedState, STATE_MAGIC, 8) != 0 || memcmp(serializedState + 8, kind, KIND_BYTES) != 0
        || (header & 0xffffUL) != N_VARIABLES)
        return fail(s, "fmi2DeSerializeFMUstate: not a serialized state of FMU kind %s", MODEL_KIND);
    snap = (Snapshot *)*FMUstate;
    if (snap == NULL) snap = (Snapshot *)calloc(1, sizeof *snap);
    if (snap == NULL) return fail(s, "fmi2DeSerializeFMUstate: out of memory");
    memcpy(snap->magic, STATE_MAGIC, 8);
    snap->unchecked = (header & 0x10000UL) != 0;
    memcpy(&snap->time, serializedState + 12 + KIND_BYTES, 8);
    memcpy(snap->values, serializedState + 20 + KIND_BYTES, 8 * N_VARIABLES);
    for (vr = 0; vr < N_VARIABLES; vr++) {
        if (cleatfmu_variables[vr].causality != VC_OUTPUT && cleatfmu_value_problem(vr, snap->values[vr], msg, sizeof msg)) {
            if (*FMUstate == NULL) free(snap);
            return fail(s, "fmi2DeSerializeFMUstate: %s", msg);
        }
    }
    *FMUstate = snap;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    if (!allowed(c, "fmi2GetDirectionalDerivative", ANY_MODE)) return fmi2Error;
    return fail((Instance *)c, "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative=false)");
}

/* ---------------------------------------------------------------- co-simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)order; (void)value;
    if (!allowed(c, "fmi2SetRealInputDerivatives", SETTABLE)) return fmi2Error;
    return nvr ? fail((Instance *)c, "fmi2SetRealInputDerivatives: canInterpolateInputs=false") : fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)order; (void)value;
    if (!allowed(c, "fmi2GetRealOutputDerivatives", READABLE)) return fmi2Error;
    return nvr ? fail((Instance *)c, "fmi2GetRealOutputDerivatives: maxOutputDerivativeOrder=0") : fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance *s = (Instance *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(c, "fmi2DoStep", S_STEP_COMPLETE)) return fmi2Error;
    if (!(communicationStepSize >= 0.0) || !isfinite(currentCommunicationPoint))
        return fail(s, "fmi2DoStep: invalid communication point %.17g or step size %.17g", currentCommunicationPoint,
                    communicationStepSize);
    if (check_parameters(s) != fmi2OK) return fmi2Error;
    s->time = currentCommunicationPoint + communicationStepSize;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    if (!allowed(c, "fmi2CancelStep", S_STEP_COMPLETE)) return fmi2Error;
    return fail((Instance *)c, "fmi2CancelStep: fmi2DoStep never returns fmi2Pending");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status *value) {
    (void)kind; (void)value;
    if (!allowed(c, "fmi2GetStatus", READABLE)) return fmi2Error;
    return fail((Instance *)c, "fmi2GetStatus: fmi2DoStep never returns fmi2Pending");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *value) {
    Instance *s = (Instance *)c;
    if (!allowed(c, "fmi2GetRealStatus", READABLE)) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime || value == NULL) return fail(s, "fmi2GetRealStatus: unsupported status kind");
    *value = s->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer *value) {
    (void)kind; (void)value;
    if (!allowed(c, "fmi2GetIntegerStatus", READABLE)) return fmi2Error;
    return fail((Instance *)c, "fmi2GetIntegerStatus: no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *value) {
    if (!allowed(c, "fmi2GetBooleanStatus", READABLE)) return fmi2Error;
    if (kind != fmi2Terminated || value == NULL) return fail((Instance *)c, "fmi2GetBooleanStatus: unsupported status kind");
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String *value) {
    (void)kind; (void)value;
    if (!allowed(c, "fmi2GetStringStatus", READABLE)) return fmi2Error;
    return fail((Instance *)c, "fmi2GetStringStatus: no string status");
}

/* Model-exchange functions: this FMU is co-simulation only. */
#define NOT_MODEL_EXCHANGE(call) \
    if (!allowed(c, call, ANY_MODE)) return fmi2Error; \
    return fail((Instance *)c, call ": the FMU supports co-simulation only")

fmi2Status fmi2EnterEventMode(fmi2Component c) { NOT_MODEL_EXCHANGE("fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) { (void)info; NOT_MODEL_EXCHANGE("fmi2NewDiscreteStates"); }
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { NOT_MODEL_EXCHANGE("fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    NOT_MODEL_EXCHANGE("fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) { (void)time; NOT_MODEL_EXCHANGE("fmi2SetTime"); }
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) { (void)x; (void)nx; NOT_MODEL_EXCHANGE("fmi2SetContinuousStates"); }
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) { (void)derivatives; (void)nx; NOT_MODEL_EXCHANGE("fmi2GetDerivatives"); }
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) { (void)eventIndicators; (void)ni; NOT_MODEL_EXCHANGE("fmi2GetEventIndicators"); }
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) { (void)x; (void)nx; NOT_MODEL_EXCHANGE("fmi2GetContinuousStates"); }
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) { (void)x_nominal; (void)nx; NOT_MODEL_EXCHANGE("fmi2GetNominalsOfContinuousStates"); }
