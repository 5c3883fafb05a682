/* FMI 2.0 co-simulation and model exchange API of the MACE FMU runtime (see mace_instance.h). */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "mace_instance.h"

typedef struct Host2 {
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
} Host2;

typedef struct Fmi2Instance {
    MiInstance *inst; /* first: the wrappers cast between the two */
    Host2 host;
} Fmi2Instance;

static void host_log(void *host, const char *instance, MiStatus status, const char *category, const char *message) {
    const Host2 *h = (const Host2 *)host;
    char escaped[4 * MACE_ERR_LEN];
    size_t o = 0;
    if (!h->logger) return;
    for (; *message && o + 2 < sizeof(escaped); message++) { /* the logger's message is a format string */
        if (*message == '%') escaped[o++] = '%';
        escaped[o++] = *message;
    }
    escaped[o] = '\0';
    h->logger(h->env, instance, (fmi2Status)status, category, escaped);
}

#define INST(c) (((Fmi2Instance *)(c))->inst)
#define CHECK(c)                                         \
    do {                                                 \
        if (!(c)) return fmi2Error; /* no instance to log through */ \
    } while (0)

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    (void)nCategories;
    (void)categories;
    CHECK(c);
    INST(c)->logging_on = loggingOn != fmi2False;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    MaceAlloc al;
    Fmi2Instance *w;
    Host2 host;
    char *path;
    (void)visible;
    al.calloc = (functions && functions->allocateMemory) ? functions->allocateMemory : calloc;
    al.free = (functions && functions->freeMemory) ? functions->freeMemory : free;
    al.work = NULL;
    host.logger = functions ? functions->logger : NULL;
    host.env = functions ? functions->componentEnvironment : NULL;
    if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange) {
        host_log(&host, instanceName, MI_ERROR, "logStatusError", "fmi2Instantiate: unknown FMU type");
        return NULL;
    }
    w = (Fmi2Instance *)al.calloc(1, sizeof(Fmi2Instance));
    if (!w) return NULL;
    w->host = host;
    path = mi_uri_to_path(&al, fmuResourceLocation);
    if (!path) {
        host_log(&host, instanceName, MI_ERROR, "logStatusError",
             "fmi2Instantiate: the resource location is not a file URI");
        al.free(w);
        return NULL;
    }
    w->inst = mi_create(instanceName, fmuType == fmi2CoSimulation ? MACE_CO_SIMULATION : MACE_MODEL_EXCHANGE, path,
                        fmuGUID, &al, host_log, &w->host, loggingOn != fmi2False, "fmi2");
    al.free(path);
    if (!w->inst) {
        al.free(w);
        return NULL;
    }
    return w;
}

void fmi2FreeInstance(fmi2Component c) {
    MaceAlloc al;
    if (!c) return;
    al = INST(c)->al;
    mi_free(INST(c));
    al.free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    CHECK(c);
    return (fmi2Status)mi_experiment(INST(c), toleranceDefined != fmi2False, tolerance, startTime,
                                     stopTimeDefined != fmi2False, stopTime, "SetupExperiment");
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    CHECK(c);
    return (fmi2Status)mi_enter_initialization(INST(c), "EnterInitializationMode");
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    CHECK(c);
    return (fmi2Status)mi_exit_initialization(INST(c), "ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component c) {
    CHECK(c);
    return (fmi2Status)mi_terminate(INST(c), "Terminate");
}

fmi2Status fmi2Reset(fmi2Component c) {
    CHECK(c);
    return (fmi2Status)mi_reset(INST(c), "Reset");
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    CHECK(c);
    return (fmi2Status)mi_get_reals(INST(c), vr, nvr, value, "GetReal");
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    CHECK(c);
    return (fmi2Status)mi_set_reals(INST(c), vr, nvr, value, "SetReal");
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    (void)vr;
    (void)value;
    CHECK(c);
    return (fmi2Status)mi_no_variables(INST(c), nvr, "Integer", "GetInteger", 0);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    CHECK(c);
    return (fmi2Status)mi_no_variables(INST(c), nvr, "Boolean", "GetBoolean", 0);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr;
    (void)value;
    CHECK(c);
    return (fmi2Status)mi_no_variables(INST(c), nvr, "String", "GetString", 0);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    (void)vr;
    (void)value;
    CHECK(c);
    return (fmi2Status)mi_no_variables(INST(c), nvr, "Integer", "SetInteger", 1);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    CHECK(c);
    return (fmi2Status)mi_no_variables(INST(c), nvr, "Boolean", "SetBoolean", 1);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr;
    (void)value;
    CHECK(c);
    return (fmi2Status)mi_no_variables(INST(c), nvr, "String", "SetString", 1);
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    CHECK(c);
    return (fmi2Status)mi_get_state(INST(c), FMUstate, "GetFMUstate");
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    CHECK(c);
    return (fmi2Status)mi_set_state(INST(c), FMUstate, "SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    CHECK(c);
    return (fmi2Status)mi_free_state(INST(c), FMUstate, "FreeFMUstate");
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    CHECK(c);
    return (fmi2Status)mi_state_size(INST(c), FMUstate, size, "SerializedFMUstateSize");
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    CHECK(c);
    return (fmi2Status)mi_serialize(INST(c), FMUstate, (unsigned char *)serializedState, size, "SerializeFMUstate");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    CHECK(c);
    return (fmi2Status)mi_deserialize(INST(c), (const unsigned char *)serializedState, size, FMUstate,
                                      "DeSerializeFMUstate");
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    CHECK(c);
    return (fmi2Status)mi_directional(INST(c), vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown, dvUnknown,
                                      "GetDirectionalDerivative");
}

/* ---- co-simulation --------------------------------------------------------------------------- */

/* The masks of the FMI 2.0.x section 4.2.4 state table. This FMU's steps never return fmi2Pending
 * or fmi2Discard, so of the table's stepComplete, stepInProgress, stepFailed and stepCanceled
 * states only stepComplete (PH_STEP) is ever reached. */
#define CS_INPUT_DERIVATIVES (MI_IN(PH_INSTANTIATED) | MI_IN(PH_INITIALIZATION) | MI_IN(PH_STEP))
#define CS_OUTPUT_DERIVATIVES (MI_IN(PH_STEP) | MI_IN(PH_TERMINATED) | MI_IN(PH_ERROR))
#define CS_STATUS (MI_IN(PH_STEP) | MI_IN(PH_TERMINATED))

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr;
    (void)order;
    (void)value;
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "SetRealInputDerivatives", MACE_CO_SIMULATION, CS_INPUT_DERIVATIVES))
        return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return (fmi2Status)mi_error(INST(c), "fmi2SetRealInputDerivatives: inputs are held constant over a step "
                                "(canInterpolateInputs is false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)order;
    (void)value;
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "GetRealOutputDerivatives", MACE_CO_SIMULATION, CS_OUTPUT_DERIVATIVES))
        return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return (fmi2Status)mi_error(INST(c), "fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder 0)");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    CHECK(c);
    return (fmi2Status)mi_do_step(INST(c), currentCommunicationPoint, communicationStepSize, "DoStep");
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    CHECK(c);
    /* only in stepInProgress, which a step that never returns fmi2Pending never leaves behind */
    if (!mi_allowed_kind(INST(c), "CancelStep", MACE_CO_SIMULATION, 0)) return fmi2Error;
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    (void)value;
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "GetStatus", MACE_CO_SIMULATION, CS_STATUS)) return fmi2Error;
    /* fmi2DoStepStatus and fmi2PendingStatus have a meaning only after fmi2DoStep returned fmi2Pending */
    return (fmi2Status)mi_error(INST(c), "fmi2GetStatus: no step is ever pending");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "GetRealStatus", MACE_CO_SIMULATION, CS_STATUS)) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return (fmi2Status)mi_error(INST(c), "fmi2GetRealStatus: unknown status kind");
    if (!value) return (fmi2Status)mi_error(INST(c), "fmi2GetRealStatus: NULL value");
    *value = mace_time(INST(c)->model);
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "GetIntegerStatus", MACE_CO_SIMULATION, CS_STATUS)) return fmi2Error;
    return (fmi2Status)mi_error(INST(c), "fmi2GetIntegerStatus: no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "GetBooleanStatus", MACE_CO_SIMULATION, CS_STATUS)) return fmi2Error;
    if (s != fmi2Terminated) return (fmi2Status)mi_error(INST(c), "fmi2GetBooleanStatus: unknown status kind");
    if (!value) return (fmi2Status)mi_error(INST(c), "fmi2GetBooleanStatus: NULL value");
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "GetStringStatus", MACE_CO_SIMULATION, CS_STATUS)) return fmi2Error;
    return (fmi2Status)mi_error(INST(c), "fmi2GetStringStatus: no string status");
}

/* ---- model exchange -------------------------------------------------------------------------- */

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "EnterEventMode", MACE_MODEL_EXCHANGE, MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS)))
        return fmi2Error;
    INST(c)->phase = PH_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "NewDiscreteStates", MACE_MODEL_EXCHANGE, MI_IN(PH_EVENT))) return fmi2Error;
    if (!eventInfo) return (fmi2Status)mi_error(INST(c), "fmi2NewDiscreteStates: NULL eventInfo");
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "EnterContinuousTimeMode", MACE_MODEL_EXCHANGE, MI_IN(PH_EVENT))) return fmi2Error;
    INST(c)->phase = PH_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "CompletedIntegratorStep", MACE_MODEL_EXCHANGE, MI_IN(PH_CONTINUOUS)))
        return fmi2Error;
    if (!enterEventMode || !terminateSimulation)
        return (fmi2Status)mi_error(INST(c), "fmi2CompletedIntegratorStep: NULL enterEventMode or terminateSimulation");
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    CHECK(c);
    return (fmi2Status)mi_set_time(INST(c), time, "SetTime");
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    CHECK(c);
    return (fmi2Status)mi_set_states(INST(c), x, nx, "SetContinuousStates");
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    CHECK(c);
    return (fmi2Status)mi_get_derivatives(INST(c), derivatives, nx, "GetDerivatives");
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators;
    CHECK(c);
    if (!mi_allowed_kind(INST(c), "GetEventIndicators", MACE_MODEL_EXCHANGE,
                         MI_IN(PH_INITIALIZATION) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | MI_IN(PH_TERMINATED) |
                             MI_IN(PH_ERROR)))
        return fmi2Error;
    if (ni == 0) return fmi2OK;
    return (fmi2Status)mi_error(INST(c), "fmi2GetEventIndicators: this model has no event indicators");
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    CHECK(c);
    return (fmi2Status)mi_get_states(INST(c), x, nx, "GetContinuousStates");
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    CHECK(c);
    return (fmi2Status)mi_get_nominals(INST(c), x_nominal, nx, "GetNominalsOfContinuousStates");
}

/* Not part of FMI: a whole co-simulation record in one call, for a host that knows this runtime
 * (mace-fmu's updating engine, which runs thousands of records). For k = 0 .. n_steps - 1 it makes
 * the calls an FMI host makes, through the same state machine and checks:
 *     fmi2SetReal(vr_in, u + k n_in); fmi2GetReal(vr_out, y + k n_out);
 *     and, for k < n_steps - 1, fmi2DoStep(t0 + k h, h),
 * so the outputs equal the FMI route's bit for bit; only the host's per-call overhead is gone.
 * u is row-major (n_steps x n_in), y row-major (n_steps x n_out). Stops at the first call that returns
 * worse than fmi2Warning and returns its status; *steps_done (if not NULL) is the number of rows of y
 * written. */
FMI2_Export fmi2Status maceRunRecord(fmi2Component c, const fmi2ValueReference vr_in[], size_t n_in,
                                     const fmi2ValueReference vr_out[], size_t n_out, size_t n_steps, fmi2Real t0,
                                     fmi2Real h, const fmi2Real u[], fmi2Real y[], size_t *steps_done) {
    size_t k;
    MiStatus s = MI_OK, worst = MI_OK;
    if (steps_done) *steps_done = 0;
    CHECK(c);
    if ((n_in && (!vr_in || !u)) || (n_out && (!vr_out || !y)))
        return (fmi2Status)mi_error(INST(c), "maceRunRecord: NULL arrays for %zu inputs and %zu outputs", n_in, n_out);
#define MACE_RUN(call)                   \
    do {                                 \
        s = (call);                      \
        if (s > MI_WARNING) return (fmi2Status)s; \
        if (s > worst) worst = s;        \
    } while (0)
    for (k = 0; k < n_steps; k++) {
        if (n_in) MACE_RUN(mi_set_reals(INST(c), vr_in, n_in, u + k * n_in, "SetReal"));
        MACE_RUN(mi_get_reals(INST(c), vr_out, n_out, y + k * n_out, "GetReal"));
        if (steps_done) *steps_done = k + 1;
        if (k + 1 < n_steps) MACE_RUN(mi_do_step(INST(c), t0 + (double)k * h, h, "DoStep"));
    }
#undef MACE_RUN
    return (fmi2Status)worst;
}
