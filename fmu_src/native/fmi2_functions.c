/* FMI 2.0 co-simulation interface of a cleatfmu tire FMU: a thin layer over cleatfmu_instance.
 *
 * Outputs are direct feedthrough (evaluated from the values set last, when read).
 * A refused value (wrong variable, non-finite, out of its range) makes the call
 * return fmi2Error with the reason logged (category logStatusError, when the
 * importer instantiated with loggingOn or enabled it with fmi2SetDebugLogging;
 * instantiation failures are always logged); the instance keeps its previous values
 * and stays usable.  Parameters that are invalid together make the next read,
 * step or exit from initialization mode fail the same way until they are fixed.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "cleatfmu_instance.h"

#if defined(FMI2_FUNCTION_PREFIX)
/* The FMI 2.0 standard header prepends FMI2_FUNCTION_PREFIX to every function name (for static linking of
 * several FMUs); the bundled copy defines fmi2FullName(name) as name.  The definitions below take the
 * prefix as the standard header gives it. */
#undef fmi2FullName
#define fmi2Paste(a, b) a##b
#define fmi2PasteB(a, b) fmi2Paste(a, b)
#define fmi2FullName(name) fmi2PasteB(FMI2_FUNCTION_PREFIX, name)
#endif

#define S(c) ((CleatfmuInstance *)(c))
#define STATUS(x) ((fmi2Status)(x))

/* The FMI 2.0 logger formats its message: '%' is escaped. */
static void log_fmi2(const CleatfmuInstance *s, int status, const char *category, const char *text) {
    char escaped[2 * CLEATFMU_MESSAGE_SIZE + 1];
    size_t i, j = 0;
    fmi2CallbackLogger logger = (fmi2CallbackLogger)s->callback;
    if (logger == NULL) return;
    for (i = 0; text[i] && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    logger((fmi2ComponentEnvironment)s->environment, s->name, STATUS(status), category, escaped);
}

static int get_flag(const void *flags, size_t i) {
    fmi2Boolean b = ((const fmi2Boolean *)flags)[i];
    return b == fmi2True ? 1 : b == fmi2False ? 0 : -1;
}

static void put_flag(void *flags, size_t i, int value) { ((fmi2Boolean *)flags)[i] = value ? fmi2True : fmi2False; }

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    if (!ci_allowed(S(c), "fmi2SetDebugLogging", CI_ANY_MODE)) return fmi2Error;
    return STATUS(ci_set_debug_logging(S(c), loggingOn, nCategories, categories));
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    char msg[CLEATFMU_MESSAGE_SIZE];
    CleatfmuInstance *s, probe;
    (void)visible;
    if (functions == NULL) return NULL;
    memset(&probe, 0, sizeof probe);
    probe.log = log_fmi2;
    probe.callback = (CleatfmuFunction)functions->logger;
    probe.environment = functions->componentEnvironment;
    probe.log_errors = 1;
    strncpy(probe.name, instanceName ? instanceName : "", sizeof probe.name - 1);
    if (fmuType != fmi2CoSimulation) {
        ci_fail(&probe, "fmi2Instantiate: %s supports co-simulation only", MODEL_IDENTIFIER_STRING);
        return NULL;
    }
    if (ci_load(&probe, fmuGUID, fmuResourceLocation, msg, sizeof msg)) {
        ci_fail(&probe, "fmi2Instantiate: %s", msg);
        return NULL;
    }
    probe.log_errors = loggingOn ? 1 : 0; /* nothing is logged unless the importer asks for it */
    probe.log_warnings = MODEL_MAP && loggingOn;
    if (functions->allocateMemory && functions->freeMemory) {
        s = (CleatfmuInstance *)functions->allocateMemory(1, sizeof *s);
        probe.free_memory = functions->freeMemory;
    } else {
        s = (CleatfmuInstance *)calloc(1, sizeof *s);
        probe.free_memory = free;
    }
    if (s == NULL) {
        cleatfmu_unload(probe.data);
        return NULL;
    }
    memcpy(s, &probe, sizeof probe);
    return s;
}

void fmi2FreeInstance(fmi2Component c) { ci_free(S(c)); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (!ci_allowed(S(c), "fmi2SetupExperiment", CI_INSTANTIATED)) return fmi2Error;
    S(c)->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    if (!ci_allowed(S(c), "fmi2EnterInitializationMode", CI_INSTANTIATED)) return fmi2Error;
    S(c)->mode = CI_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    if (!ci_allowed(S(c), "fmi2ExitInitializationMode", CI_INITIALIZATION)) return fmi2Error;
    if (ci_check_parameters(S(c)) != CI_OK) return fmi2Error;
    S(c)->mode = CI_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    if (!ci_allowed(S(c), "fmi2Terminate", CI_STEP)) return fmi2Error;
    S(c)->mode = CI_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    if (!ci_allowed(S(c), "fmi2Reset", CI_ANY_MODE)) return fmi2Error;
    return STATUS(ci_reset(S(c)));
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    return STATUS(ci_get(S(c), "fmi2GetReal", VT_REAL, vr, nvr, value, NULL, NULL));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    return STATUS(ci_get(S(c), "fmi2GetBoolean", VT_BOOLEAN, vr, nvr, NULL, value, put_flag));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    (void)vr; (void)value;
    if (!ci_allowed(S(c), "fmi2GetInteger", CI_READABLE)) return fmi2Error;
    return nvr ? STATUS(ci_fail(S(c), "fmi2GetInteger: the FMU has no Integer variables")) : fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr; (void)value;
    if (!ci_allowed(S(c), "fmi2GetString", CI_READABLE)) return fmi2Error;
    return nvr ? STATUS(ci_fail(S(c), "fmi2GetString: the FMU has no String variables")) : fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    return STATUS(ci_set(S(c), "fmi2SetReal", VT_REAL, vr, nvr, value, NULL, NULL));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    return STATUS(ci_set(S(c), "fmi2SetBoolean", VT_BOOLEAN, vr, nvr, NULL, value, get_flag));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    (void)vr; (void)value;
    if (!ci_allowed(S(c), "fmi2SetInteger", CI_SETTABLE)) return fmi2Error;
    return nvr ? STATUS(ci_fail(S(c), "fmi2SetInteger: the FMU has no Integer variables")) : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr; (void)value;
    if (!ci_allowed(S(c), "fmi2SetString", CI_SETTABLE)) return fmi2Error;
    return nvr ? STATUS(ci_fail(S(c), "fmi2SetString: the FMU has no String variables")) : fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    return STATUS(ci_get_state(S(c), "fmi2GetFMUstate", FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    return STATUS(ci_set_state(S(c), "fmi2SetFMUstate", FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    return STATUS(ci_free_state(S(c), "fmi2FreeFMUstate", FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    (void)FMUstate;
    if (!ci_allowed(S(c), "fmi2SerializedFMUstateSize", CI_ANY_MODE)) return fmi2Error;
    if (size == NULL) return STATUS(ci_fail(S(c), "fmi2SerializedFMUstateSize: NULL pointer"));
    *size = ci_serialized_size();
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    return STATUS(ci_serialize(S(c), "fmi2SerializeFMUstate", FMUstate, (unsigned char *)serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    return STATUS(ci_deserialize(S(c), "fmi2DeSerializeFMUstate", (const unsigned char *)serializedState, size,
                                 FMUstate));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    if (!ci_allowed(S(c), "fmi2GetDirectionalDerivative", CI_ANY_MODE)) return fmi2Error;
    return STATUS(ci_fail(S(c), "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative=false)"));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)order; (void)value;
    if (!ci_allowed(S(c), "fmi2SetRealInputDerivatives", CI_SETTABLE)) return fmi2Error;
    return nvr ? STATUS(ci_fail(S(c), "fmi2SetRealInputDerivatives: canInterpolateInputs=false")) : fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)order; (void)value;
    if (!ci_allowed(S(c), "fmi2GetRealOutputDerivatives", CI_READABLE)) return fmi2Error;
    return nvr ? STATUS(ci_fail(S(c), "fmi2GetRealOutputDerivatives: maxOutputDerivativeOrder=0")) : fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    return STATUS(ci_do_step(S(c), "fmi2DoStep", currentCommunicationPoint, communicationStepSize));
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    if (!ci_allowed(S(c), "fmi2CancelStep", CI_STEP)) return fmi2Error;
    return STATUS(ci_fail(S(c), "fmi2CancelStep: fmi2DoStep never returns fmi2Pending"));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status *value) {
    (void)kind; (void)value;
    if (!ci_allowed(S(c), "fmi2GetStatus", CI_READABLE)) return fmi2Error;
    return STATUS(ci_fail(S(c), "fmi2GetStatus: fmi2DoStep never returns fmi2Pending"));
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *value) {
    if (!ci_allowed(S(c), "fmi2GetRealStatus", CI_READABLE)) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime || value == NULL)
        return STATUS(ci_fail(S(c), "fmi2GetRealStatus: unsupported status kind"));
    *value = S(c)->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer *value) {
    (void)kind; (void)value;
    if (!ci_allowed(S(c), "fmi2GetIntegerStatus", CI_READABLE)) return fmi2Error;
    return STATUS(ci_fail(S(c), "fmi2GetIntegerStatus: no integer status"));
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *value) {
    if (!ci_allowed(S(c), "fmi2GetBooleanStatus", CI_READABLE)) return fmi2Error;
    if (kind != fmi2Terminated || value == NULL)
        return STATUS(ci_fail(S(c), "fmi2GetBooleanStatus: unsupported status kind"));
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String *value) {
    (void)kind; (void)value;
    if (!ci_allowed(S(c), "fmi2GetStringStatus", CI_READABLE)) return fmi2Error;
    return STATUS(ci_fail(S(c), "fmi2GetStringStatus: no string status"));
}

/* Model-exchange functions: this FMU is co-simulation only. */
#define NOT_MODEL_EXCHANGE(call) \
    if (!ci_allowed(S(c), call, CI_ANY_MODE)) return fmi2Error; \
    return STATUS(ci_fail(S(c), call ": the FMU supports co-simulation only"))

fmi2Status fmi2EnterEventMode(fmi2Component c) { NOT_MODEL_EXCHANGE("fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)info;
    NOT_MODEL_EXCHANGE("fmi2NewDiscreteStates");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { NOT_MODEL_EXCHANGE("fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    NOT_MODEL_EXCHANGE("fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    (void)time;
    NOT_MODEL_EXCHANGE("fmi2SetTime");
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)x; (void)nx;
    NOT_MODEL_EXCHANGE("fmi2SetContinuousStates");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    (void)derivatives; (void)nx;
    NOT_MODEL_EXCHANGE("fmi2GetDerivatives");
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators; (void)ni;
    NOT_MODEL_EXCHANGE("fmi2GetEventIndicators");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)x; (void)nx;
    NOT_MODEL_EXCHANGE("fmi2GetContinuousStates");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)x_nominal; (void)nx;
    NOT_MODEL_EXCHANGE("fmi2GetNominalsOfContinuousStates");
}
