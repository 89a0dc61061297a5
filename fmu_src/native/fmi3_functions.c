/* FMI 3.0 co-simulation interface of a cleatfmu tire FMU: a thin layer over cleatfmu_instance.
 *
 * Float64 and Boolean scalars, direct feedthrough, no event mode, FMU state
 * get/set/serialize (the functions for features the FMU does not have are in
 * fmi3_unsupported.c).  Refused values give fmi3Error with the reason logged; the
 * instance keeps its previous values and stays usable.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "cleatfmu_instance.h"

#define S(c) ((CleatfmuInstance *)(c))
#define STATUS(x) ((fmi3Status)(x))

static void log_fmi3(const CleatfmuInstance *s, int status, const char *category, const char *text) {
    fmi3LogMessageCallback logger = (fmi3LogMessageCallback)s->callback;
    if (logger != NULL) logger((fmi3InstanceEnvironment)s->environment, STATUS(status), category, text);
}

static int get_flag(const void *flags, size_t i) { return ((const fmi3Boolean *)flags)[i] ? 1 : 0; }

static void put_flag(void *flags, size_t i, int value) { ((fmi3Boolean *)flags)[i] = value ? fmi3True : fmi3False; }

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    if (!ci_allowed(S(instance), "fmi3SetDebugLogging", CI_ANY_MODE)) return fmi3Error;
    return STATUS(ci_set_debug_logging(S(instance), loggingOn, nCategories, categories));
}

static void early_log(fmi3InstanceEnvironment env, fmi3LogMessageCallback logger, const char *msg) {
    if (logger != NULL) logger(env, fmi3Error, "logStatusError", msg);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    char msg[CLEATFMU_MESSAGE_SIZE];
    CleatfmuInstance *s, probe;
    (void)visible; (void)earlyReturnAllowed; (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (eventModeUsed) {
        early_log(instanceEnvironment, logMessage,
                  "fmi3InstantiateCoSimulation: event mode is not supported (hasEventMode=false)");
        return NULL;
    }
    if (nRequiredIntermediateVariables > 0) {
        early_log(instanceEnvironment, logMessage,
                  "fmi3InstantiateCoSimulation: intermediate updates are not provided");
        return NULL;
    }
    memset(&probe, 0, sizeof probe);
    probe.log = log_fmi3;
    probe.callback = (CleatfmuFunction)logMessage;
    probe.environment = instanceEnvironment;
    probe.log_errors = 1;
    strncpy(probe.name, instanceName ? instanceName : "", sizeof probe.name - 1);
    if (ci_load(&probe, instantiationToken, resourcePath, msg, sizeof msg)) {
        ci_fail(&probe, "fmi3InstantiateCoSimulation: %s", msg);
        return NULL;
    }
    probe.log_errors = loggingOn ? 1 : 0; /* nothing is logged unless the importer asks for it */
    probe.log_warnings = MODEL_MAP && loggingOn;
    s = (CleatfmuInstance *)calloc(1, sizeof *s);
    if (s == NULL) {
        cleatfmu_unload(probe.data);
        return NULL;
    }
    probe.free_memory = free;
    memcpy(s, &probe, sizeof probe);
    return s;
}

void fmi3FreeInstance(fmi3Instance instance) { ci_free(S(instance)); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (!ci_allowed(S(instance), "fmi3EnterInitializationMode", CI_INSTANTIATED)) return fmi3Error;
    S(instance)->time = startTime;
    S(instance)->mode = CI_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    if (!ci_allowed(S(instance), "fmi3ExitInitializationMode", CI_INITIALIZATION)) return fmi3Error;
    if (ci_check_parameters(S(instance)) != CI_OK) return fmi3Error;
    S(instance)->mode = CI_STEP;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    if (!ci_allowed(S(instance), "fmi3Terminate", CI_STEP)) return fmi3Error;
    S(instance)->mode = CI_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    if (!ci_allowed(S(instance), "fmi3Reset", CI_ANY_MODE)) return fmi3Error;
    return STATUS(ci_reset(S(instance)));
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    if (nValues != nValueReferences && ci_allowed(S(instance), "fmi3GetFloat64", CI_ANY_MODE))
        return STATUS(ci_fail(S(instance), "fmi3GetFloat64: %u values for %u scalar variables", (unsigned)nValues,
                              (unsigned)nValueReferences));
    return STATUS(ci_get(S(instance), "fmi3GetFloat64", VT_REAL, valueReferences, nValueReferences, values, NULL,
                         NULL));
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Boolean values[], size_t nValues) {
    if (nValues != nValueReferences && ci_allowed(S(instance), "fmi3GetBoolean", CI_ANY_MODE))
        return STATUS(ci_fail(S(instance), "fmi3GetBoolean: %u values for %u scalar variables", (unsigned)nValues,
                              (unsigned)nValueReferences));
    return STATUS(ci_get(S(instance), "fmi3GetBoolean", VT_BOOLEAN, valueReferences, nValueReferences, NULL, values,
                         put_flag));
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    if (nValues != nValueReferences && ci_allowed(S(instance), "fmi3SetFloat64", CI_ANY_MODE))
        return STATUS(ci_fail(S(instance), "fmi3SetFloat64: %u values for %u scalar variables", (unsigned)nValues,
                              (unsigned)nValueReferences));
    return STATUS(ci_set(S(instance), "fmi3SetFloat64", VT_REAL, valueReferences, nValueReferences, values, NULL,
                         NULL));
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Boolean values[], size_t nValues) {
    if (nValues != nValueReferences && ci_allowed(S(instance), "fmi3SetBoolean", CI_ANY_MODE))
        return STATUS(ci_fail(S(instance), "fmi3SetBoolean: %u values for %u scalar variables", (unsigned)nValues,
                              (unsigned)nValueReferences));
    return STATUS(ci_set(S(instance), "fmi3SetBoolean", VT_BOOLEAN, valueReferences, nValueReferences, NULL, values,
                         get_flag));
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return STATUS(ci_get_state(S(instance), "fmi3GetFMUState", FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    return STATUS(ci_set_state(S(instance), "fmi3SetFMUState", FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return STATUS(ci_free_state(S(instance), "fmi3FreeFMUState", FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    (void)FMUState;
    if (!ci_allowed(S(instance), "fmi3SerializedFMUStateSize", CI_ANY_MODE)) return fmi3Error;
    if (size == NULL) return STATUS(ci_fail(S(instance), "fmi3SerializedFMUStateSize: NULL pointer"));
    *size = ci_serialized_size();
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    return STATUS(ci_serialize(S(instance), "fmi3SerializeFMUState", FMUState, serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    return STATUS(ci_deserialize(S(instance), "fmi3DeserializeFMUState", serializedState, size, FMUState));
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    (void)valueReferences; (void)orders; (void)values; (void)nValues;
    if (!ci_allowed(S(instance), "fmi3GetOutputDerivatives", CI_READABLE)) return fmi3Error;
    return nValueReferences ? STATUS(ci_fail(S(instance), "fmi3GetOutputDerivatives: maxOutputDerivativeOrder=0"))
                            : fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime) {
    int status;
    (void)noSetFMUStatePriorToCurrentPoint;
    status = ci_do_step(S(instance), "fmi3DoStep", currentCommunicationPoint, communicationStepSize);
    if (status != CI_OK) return STATUS(status);
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = S(instance)->time;
    return fmi3OK;
}
