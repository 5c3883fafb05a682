/* FMI 3.0 co-simulation API of the MACE FMU runtime (see mace_instance.h). Model exchange and
 * scheduled execution are not offered: their instantiation returns NULL with a logged reason. */
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "mace_instance.h"

typedef struct Host3 {
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment env;
} Host3;

typedef struct Fmi3Instance {
    MiInstance *inst;
    Host3 host;
} Fmi3Instance;

static void host_log(void *host, const char *instance, MiStatus status, const char *category, const char *message) {
    const Host3 *h = (const Host3 *)host;
    (void)instance;
    if (h->log) h->log(h->env, (fmi3Status)status, category, message);
}

static const MaceAlloc ALLOC = {calloc, free, NULL};

#define INST(c) (((Fmi3Instance *)(c))->inst)
#define CHECK(c) \
    do {         \
        if (!(c)) return fmi3Error; \
    } while (0)

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    (void)nCategories;
    (void)categories;
    CHECK(c);
    INST(c)->logging_on = loggingOn != fmi3False;
    return fmi3OK;
}

static fmi3Instance unsupported(fmi3String name, fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                const char *what) {
    Host3 host;
    char message[200];
    host.log = log;
    host.env = env;
    strcpy(message, "this FMU offers co-simulation only, not ");
    strcat(message, what);
    host_log(&host, name, MI_ERROR, "logStatusError", message);
    return NULL;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    return unsupported(instanceName, instanceEnvironment, logMessage, "model exchange in FMI 3");
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    return unsupported(instanceName, instanceEnvironment, logMessage, "scheduled execution");
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    Fmi3Instance *w;
    (void)visible;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    if (eventModeUsed) return unsupported(instanceName, instanceEnvironment, logMessage, "event mode");
    w = (Fmi3Instance *)ALLOC.calloc(1, sizeof(Fmi3Instance));
    if (!w) return NULL;
    w->host.log = logMessage;
    w->host.env = instanceEnvironment;
    w->inst = mi_create(instanceName, MACE_CO_SIMULATION, resourcePath, instantiationToken, &ALLOC, host_log,
                        &w->host, loggingOn != fmi3False, "fmi3");
    if (!w->inst) {
        ALLOC.free(w);
        return NULL;
    }
    return w;
}

void fmi3FreeInstance(fmi3Instance c) {
    if (!c) return;
    mi_free(INST(c));
    ALLOC.free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    CHECK(c);
    if (mi_experiment(INST(c), toleranceDefined != fmi3False, tolerance, startTime, stopTimeDefined != fmi3False,
                      stopTime, "EnterInitializationMode") != MI_OK)
        return fmi3Error;
    return (fmi3Status)mi_enter_initialization(INST(c), "EnterInitializationMode");
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    CHECK(c);
    return (fmi3Status)mi_exit_initialization(INST(c), "ExitInitializationMode");
}

fmi3Status fmi3Terminate(fmi3Instance c) {
    CHECK(c);
    return (fmi3Status)mi_terminate(INST(c), "Terminate");
}

fmi3Status fmi3Reset(fmi3Instance c) {
    CHECK(c);
    return (fmi3Status)mi_reset(INST(c), "Reset");
}

static fmi3Status one_value_each(MiInstance *inst, size_t nvr, size_t nvalues, const char *fn) {
    if (nvr == nvalues) return fmi3OK;
    return (fmi3Status)mi_error(inst, "fmi3%s: %lu values for %lu scalar variables", fn, (unsigned long)nvalues,
                                (unsigned long)nvr);
}

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    CHECK(c);
    if (one_value_each(INST(c), nvr, nValues, "GetFloat64") != fmi3OK) return fmi3Error;
    return (fmi3Status)mi_get_reals(INST(c), vr, nvr, values, "GetFloat64");
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[],
                          size_t nValues) {
    CHECK(c);
    if (one_value_each(INST(c), nvr, nValues, "SetFloat64") != fmi3OK) return fmi3Error;
    return (fmi3Status)mi_set_reals(INST(c), vr, nvr, values, "SetFloat64");
}

/* Getters and setters of the types this model has no variables of. */
#define NO_VARIABLES(Type, ctype)                                                                                  \
    fmi3Status fmi3Get##Type(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, ctype values[],            \
                             size_t nValues) {                                                                     \
        (void)vr;                                                                                                  \
        (void)values;                                                                                              \
        (void)nValues;                                                                                             \
        CHECK(c);                                                                                                  \
        return (fmi3Status)mi_no_variables(INST(c), nvr, #Type, "Get" #Type, 0);                                      \
    }                                                                                                              \
    fmi3Status fmi3Set##Type(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const ctype values[],      \
                             size_t nValues) {                                                                     \
        (void)vr;                                                                                                  \
        (void)values;                                                                                              \
        (void)nValues;                                                                                             \
        CHECK(c);                                                                                                  \
        return (fmi3Status)mi_no_variables(INST(c), nvr, #Type, "Set" #Type, 1);                                      \
    }

NO_VARIABLES(Float32, fmi3Float32)
NO_VARIABLES(Int8, fmi3Int8)
NO_VARIABLES(UInt8, fmi3UInt8)
NO_VARIABLES(Int16, fmi3Int16)
NO_VARIABLES(UInt16, fmi3UInt16)
NO_VARIABLES(Int32, fmi3Int32)
NO_VARIABLES(UInt32, fmi3UInt32)
NO_VARIABLES(Int64, fmi3Int64)
NO_VARIABLES(UInt64, fmi3UInt64)
NO_VARIABLES(Boolean, fmi3Boolean)
NO_VARIABLES(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                         fmi3Binary values[], size_t nValues) {
    (void)vr;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Binary", "GetBinary", 0);
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) {
    (void)vr;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Binary", "SetBinary", 1);
}

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
    (void)vr;
    (void)values;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "GetClock", 0);
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[]) {
    (void)vr;
    (void)values;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "SetClock", 1);
}

static fmi3Status not_provided(fmi3Instance c, const char *what) {
    CHECK(c);
    return (fmi3Status)mi_error(INST(c), "fmi3%s: not provided by this FMU", what);
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference;
    (void)nDependencies;
    return not_provided(c, "GetNumberOfVariableDependencies (the model description lists none)");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent, size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[], size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return not_provided(c, "GetVariableDependencies (the model description lists none)");
}

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *FMUState) {
    CHECK(c);
    return (fmi3Status)mi_get_state(INST(c), FMUState, "GetFMUState");
}

fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState FMUState) {
    CHECK(c);
    return (fmi3Status)mi_set_state(INST(c), FMUState, "SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *FMUState) {
    CHECK(c);
    return (fmi3Status)mi_free_state(INST(c), FMUState, "FreeFMUState");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState FMUState, size_t *size) {
    CHECK(c);
    return (fmi3Status)mi_state_size(INST(c), FMUState, size, "SerializedFMUStateSize");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    CHECK(c);
    return (fmi3Status)mi_serialize(INST(c), FMUState, (unsigned char *)serializedState, size, "SerializeFMUState");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    CHECK(c);
    return (fmi3Status)mi_deserialize(INST(c), (const unsigned char *)serializedState, size, FMUState,
                                      "DeserializeFMUState");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return not_provided(c, "GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return not_provided(c, "GetAdjointDerivative");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) { return not_provided(c, "EnterConfigurationMode"); }
fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) { return not_provided(c, "ExitConfigurationMode"); }

fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    (void)vr;
    (void)intervals;
    (void)qualifiers;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "GetIntervalDecimal", 0);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 counters[],
                                   fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "GetIntervalFraction", 0);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 shifts[]) {
    (void)vr;
    (void)shifts;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "GetShiftDecimal", 0);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "GetShiftFraction", 0);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[]) {
    (void)vr;
    (void)intervals;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "SetIntervalDecimal", 1);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "SetIntervalFraction", 1);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 shifts[]) {
    (void)vr;
    (void)shifts;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "SetShiftDecimal", 1);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    CHECK(c);
    return (fmi3Status)mi_no_variables(INST(c), nvr, "Clock", "SetShiftFraction", 1);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) { return not_provided(c, "EvaluateDiscreteStates"); }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    (void)discreteStatesNeedUpdate;
    (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined;
    (void)nextEventTime;
    return not_provided(c, "UpdateDiscreteStates (no event mode)");
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) { return not_provided(c, "EnterEventMode (no event mode)"); }
fmi3Status fmi3EnterStepMode(fmi3Instance c) { return not_provided(c, "EnterStepMode (no event mode)"); }
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { return not_provided(c, "EnterContinuousTimeMode"); }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return not_provided(c, "CompletedIntegratorStep");
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time) {
    (void)time;
    return not_provided(c, "SetTime");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return not_provided(c, "SetContinuousStates");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 derivatives[], size_t nContinuousStates) {
    (void)derivatives;
    (void)nContinuousStates;
    return not_provided(c, "GetContinuousStateDerivatives");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    (void)eventIndicators;
    (void)nEventIndicators;
    return not_provided(c, "GetEventIndicators");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return not_provided(c, "GetContinuousStates");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[], size_t nContinuousStates) {
    (void)nominals;
    (void)nContinuousStates;
    return not_provided(c, "GetNominalsOfContinuousStates");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *nEventIndicators) {
    CHECK(c);
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *nContinuousStates) {
    CHECK(c);
    *nContinuousStates = 0; /* co-simulation: no states are exposed */
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues) {
    (void)vr;
    (void)orders;
    (void)values;
    (void)nValues;
    CHECK(c);
    if (!mi_allowed(INST(c), "GetOutputDerivatives", MI_IN(PH_STEP) | MI_IN(PH_TERMINATED) | MI_IN(PH_ERROR)))
        return fmi3Error;
    if (nvr == 0) return fmi3OK;
    return not_provided(c, "GetOutputDerivatives (maxOutputDerivativeOrder 0)");
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    fmi3Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    CHECK(c);
    status = (fmi3Status)mi_do_step(INST(c), currentCommunicationPoint, communicationStepSize, "DoStep");
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = mace_time(INST(c)->model);
    return status;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clockReference, fmi3Float64 activationTime) {
    (void)clockReference;
    (void)activationTime;
    return not_provided(c, "ActivateModelPartition (no scheduled execution)");
}
