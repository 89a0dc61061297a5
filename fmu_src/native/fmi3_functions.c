/* FMI 3.0 co-simulation interface of a cleatfmu tire FMU: a thin layer over cleatfmu_instance.
 *
 * Float64 and Boolean scalars, direct feedthrough, no event mode, FMU state
 * get/set/serialize.  Refused values give fmi3Error with the reason logged; the
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

static void early_log(fmi3String name, fmi3InstanceEnvironment env, fmi3LogMessageCallback logger, const char *msg) {
    char text[CLEATFMU_MESSAGE_SIZE + 160];
    (void)name;
    if (logger == NULL) return;
    snprintf(text, sizeof text, "%s", msg);
    logger(env, fmi3Error, "logStatusError", text);
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
    (void)visible; (void)loggingOn; (void)earlyReturnAllowed; (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (eventModeUsed) {
        early_log(instanceName, instanceEnvironment, logMessage,
                  "fmi3InstantiateCoSimulation: event mode is not supported (hasEventMode=false)");
        return NULL;
    }
    if (nRequiredIntermediateVariables > 0) {
        early_log(instanceName, instanceEnvironment, logMessage,
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
    s = (CleatfmuInstance *)calloc(1, sizeof *s);
    if (s == NULL) return NULL;
    probe.free_memory = free;
    memcpy(s, &probe, sizeof probe);
    return s;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    early_log(instanceName, instanceEnvironment, logMessage, "the FMU supports co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn; (void)clockUpdate;
    (void)lockPreemption; (void)unlockPreemption;
    early_log(instanceName, instanceEnvironment, logMessage, "the FMU supports co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    if (instance != NULL) S(instance)->free_memory(instance);
}

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

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    if (!ci_allowed(S(instance), "fmi3EnterEventMode", CI_ANY_MODE)) return fmi3Error;
    return STATUS(ci_fail(S(instance), "fmi3EnterEventMode: no event mode (hasEventMode=false)"));
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

/* Types the FMU has no variables of: only empty calls succeed. */
#define NO_VARIABLES(name, modes) \
    (void)valueReferences; (void)values; (void)nValues; \
    if (!ci_allowed(S(instance), name, modes)) return fmi3Error; \
    return nValueReferences ? STATUS(ci_fail(S(instance), name ": the FMU has no variables of this type")) : fmi3OK

#define GETTER(fn, type) \
    fmi3Status fn(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                  type values[], size_t nValues) { NO_VARIABLES(#fn, CI_READABLE); }
#define SETTER(fn, type) \
    fmi3Status fn(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, \
                  const type values[], size_t nValues) { NO_VARIABLES(#fn, CI_SETTABLE); }

GETTER(fmi3GetFloat32, fmi3Float32)
GETTER(fmi3GetInt8, fmi3Int8)
GETTER(fmi3GetUInt8, fmi3UInt8)
GETTER(fmi3GetInt16, fmi3Int16)
GETTER(fmi3GetUInt16, fmi3UInt16)
GETTER(fmi3GetInt32, fmi3Int32)
GETTER(fmi3GetUInt32, fmi3UInt32)
GETTER(fmi3GetInt64, fmi3Int64)
GETTER(fmi3GetUInt64, fmi3UInt64)
GETTER(fmi3GetString, fmi3String)
SETTER(fmi3SetFloat32, fmi3Float32)
SETTER(fmi3SetInt8, fmi3Int8)
SETTER(fmi3SetUInt8, fmi3UInt8)
SETTER(fmi3SetInt16, fmi3Int16)
SETTER(fmi3SetUInt16, fmi3UInt16)
SETTER(fmi3SetInt32, fmi3Int32)
SETTER(fmi3SetUInt32, fmi3UInt32)
SETTER(fmi3SetInt64, fmi3Int64)
SETTER(fmi3SetUInt64, fmi3UInt64)
SETTER(fmi3SetString, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueSizes;
    NO_VARIABLES("fmi3GetBinary", CI_READABLE);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueSizes;
    NO_VARIABLES("fmi3SetBinary", CI_SETTABLE);
}

/* Calls about features the FMU does not have (clocks, event mode, model exchange, derivatives). */
#define UNSUPPORTED(name, why) \
    if (!ci_allowed(S(instance), name, CI_ANY_MODE)) return fmi3Error; \
    return STATUS(ci_fail(S(instance), name ": " why))

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[]) {
    (void)valueReferences; (void)nValueReferences; (void)values;
    UNSUPPORTED("fmi3GetClock", "the FMU has no clocks");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[]) {
    (void)valueReferences; (void)nValueReferences; (void)values;
    UNSUPPORTED("fmi3SetClock", "the FMU has no clocks");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference; (void)nDependencies;
    UNSUPPORTED("fmi3GetNumberOfVariableDependencies", "the dependencies are in modelDescription.xml");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent; (void)elementIndicesOfDependent; (void)independents; (void)elementIndicesOfIndependents;
    (void)dependencyKinds; (void)nDependencies;
    UNSUPPORTED("fmi3GetVariableDependencies", "the dependencies are in modelDescription.xml");
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

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity;
    (void)nSensitivity;
    UNSUPPORTED("fmi3GetDirectionalDerivative", "not provided (providesDirectionalDerivatives=false)");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity;
    (void)nSensitivity;
    UNSUPPORTED("fmi3GetAdjointDerivative", "not provided (providesAdjointDerivatives=false)");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    UNSUPPORTED("fmi3EnterConfigurationMode", "the FMU has no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    UNSUPPORTED("fmi3ExitConfigurationMode", "the FMU has no structural parameters");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences; (void)nValueReferences; (void)intervals; (void)qualifiers;
    UNSUPPORTED("fmi3GetIntervalDecimal", "the FMU has no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; (void)qualifiers;
    UNSUPPORTED("fmi3GetIntervalFraction", "the FMU has no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    UNSUPPORTED("fmi3GetShiftDecimal", "the FMU has no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    UNSUPPORTED("fmi3GetShiftFraction", "the FMU has no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences; (void)nValueReferences; (void)intervals;
    UNSUPPORTED("fmi3SetIntervalDecimal", "the FMU has no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    UNSUPPORTED("fmi3SetIntervalFraction", "the FMU has no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    UNSUPPORTED("fmi3SetShiftDecimal", "the FMU has no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    UNSUPPORTED("fmi3SetShiftFraction", "the FMU has no clocks");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    UNSUPPORTED("fmi3EvaluateDiscreteStates", "no event mode (hasEventMode=false)");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    (void)discreteStatesNeedUpdate; (void)terminateSimulation; (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged; (void)nextEventTimeDefined; (void)nextEventTime;
    UNSUPPORTED("fmi3UpdateDiscreteStates", "no event mode (hasEventMode=false)");
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    UNSUPPORTED("fmi3EnterContinuousTimeMode", "the FMU supports co-simulation only");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    UNSUPPORTED("fmi3CompletedIntegratorStep", "the FMU supports co-simulation only");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    UNSUPPORTED("fmi3SetTime", "the FMU supports co-simulation only");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    (void)continuousStates; (void)nContinuousStates;
    UNSUPPORTED("fmi3SetContinuousStates", "the FMU supports co-simulation only");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    (void)derivatives; (void)nContinuousStates;
    UNSUPPORTED("fmi3GetContinuousStateDerivatives", "the FMU supports co-simulation only");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    (void)eventIndicators; (void)nEventIndicators;
    UNSUPPORTED("fmi3GetEventIndicators", "the FMU supports co-simulation only");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates; (void)nContinuousStates;
    UNSUPPORTED("fmi3GetContinuousStates", "the FMU supports co-simulation only");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    (void)nominals; (void)nContinuousStates;
    UNSUPPORTED("fmi3GetNominalsOfContinuousStates", "the FMU supports co-simulation only");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    if (!ci_allowed(S(instance), "fmi3GetNumberOfEventIndicators", CI_ANY_MODE)) return fmi3Error;
    if (nEventIndicators == NULL) return STATUS(ci_fail(S(instance), "fmi3GetNumberOfEventIndicators: NULL pointer"));
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    if (!ci_allowed(S(instance), "fmi3GetNumberOfContinuousStates", CI_ANY_MODE)) return fmi3Error;
    if (nContinuousStates == NULL)
        return STATUS(ci_fail(S(instance), "fmi3GetNumberOfContinuousStates: NULL pointer"));
    *nContinuousStates = 0;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    UNSUPPORTED("fmi3EnterStepMode", "no event mode (hasEventMode=false): the FMU is in step mode after "
                                     "fmi3ExitInitializationMode");
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

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference; (void)activationTime;
    UNSUPPORTED("fmi3ActivateModelPartition", "the FMU supports co-simulation only");
}
