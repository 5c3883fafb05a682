/* An FMU instance shared by the FMI 2 and FMI 3 wrappers (see mace_instance.h). */
#include "mace_instance.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static const char *PHASE_NAMES[PH_COUNT] = {"instantiated", "initialization mode", "step mode", "event mode",
                                            "continuous-time mode", "terminated", "error"};

#define SETTABLE_INPUT (MI_IN(PH_INSTANTIATED) | MI_IN(PH_INITIALIZATION) | MI_IN(PH_STEP) | MI_IN(PH_EVENT) | \
                        MI_IN(PH_CONTINUOUS))
#define SETTABLE_PARAMETER (MI_IN(PH_INSTANTIATED) | MI_IN(PH_INITIALIZATION))
/* the largest input magnitude [V] taken (mace_fmu.fmu.native.model_description.INPUT_LIMIT_V, declared as the
   inputs' min and max): 1e308 overflowed model exchange's derivatives */
#define MACE_INPUT_LIMIT_V 1e6
#define GETTABLE (MI_IN(PH_INITIALIZATION) | MI_IN(PH_STEP) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | \
                  MI_IN(PH_TERMINATED) | MI_IN(PH_ERROR))

/* An FMU state: the instance's header (below), then the model's bytes (mace_state_save). The header
 * ties the state to the FMU it came from so that fmi2SetFMUstate / fmi3SetFMUState and the
 * deserialisation can refuse, before anything is applied, a state of another FMU (GUID), of the other
 * FMI version, of the other interface (co-simulation vs model exchange) or one that was edited or
 * damaged (checksum). FMI 2.0.x section 2.1.8 and FMI 3.0 section 2.2.6.4 leave the content of an FMU
 * state to the FMU; section 2.1.8 requires that it "must be possible to set a state of the FMU that
 * was retrieved by the same FMU", so a state from anything else is the caller's error. */
typedef struct MiState {
    size_t size;
    unsigned char bytes[1];
} MiState;

static const char STATE_TAG[8] = {'M', 'I', 'F', 'M', 'U', 'S', 'T', '1'};
enum { HDR_TAG = 0, HDR_API = 8, HDR_KIND = 16, HDR_GUID = 24, HDR_SUM = 32, HDR_SIZE = 40 };

static void emit(MiInstance *inst, MiStatus status, const char *category, const char *fmt, va_list args) {
    if (!inst->message) return;
    vsnprintf(inst->message, 2 * MACE_ERR_LEN, fmt, args);
    inst->log(inst->host, inst->name, status, category, inst->message);
}

MiStatus mi_error(MiInstance *inst, const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    emit(inst, MI_ERROR, "logStatusError", fmt, args);
    va_end(args);
    return MI_ERROR;
}

void mi_debug(MiInstance *inst, const char *fmt, ...) {
    va_list args;
    if (!inst->logging_on) return;
    va_start(args, fmt);
    emit(inst, MI_OK, "logEvents", fmt, args);
    va_end(args);
}

int mi_allowed(MiInstance *inst, const char *function, unsigned mask) {
    if (mask & MI_IN(inst->phase)) return 1;
    mi_error(inst, "%s%s must not be called in %s", inst->api, function, PHASE_NAMES[inst->phase]);
    return 0;
}

int mi_allowed_kind(MiInstance *inst, const char *function, MaceKind kind, unsigned mask) {
    if (inst->kind != kind) {
        mi_error(inst, "%s%s is a %s function and this is a %s instance", inst->api, function,
                 kind == MACE_CO_SIMULATION ? "co-simulation" : "model-exchange",
                 inst->kind == MACE_CO_SIMULATION ? "co-simulation" : "model-exchange");
        return 0;
    }
    return mi_allowed(inst, function, mask);
}

MiInstance *mi_create(const char *name, MaceKind kind, const char *resource_dir, const char *token,
                      const MaceAlloc *al, MiLogger log, void *host, int logging_on, const char *api) {
    MiInstance *inst = (MiInstance *)al->calloc(1, sizeof(MiInstance));
    size_t len = strlen(name ? name : "") + 1;
    if (!inst) return NULL;
    inst->al = *al;
    inst->kind = kind;
    inst->phase = PH_INSTANTIATED;
    inst->logging_on = logging_on;
    inst->api = api;
    inst->log = log;
    inst->host = host;
    inst->name = (char *)al->calloc(len, 1);
    inst->message = (char *)al->calloc(2 * MACE_ERR_LEN, 1);
    if (!inst->name || !inst->message) {
        mi_free(inst);
        return NULL;
    }
    memcpy(inst->name, name ? name : "", len);
    if (!resource_dir) {
        mi_error(inst, "%sInstantiate: no resource location (the model data are in the FMU's resources folder)", api);
        mi_free(inst);
        return NULL;
    }
    inst->model = mace_create(resource_dir, kind, al, inst->err);
    if (!inst->model) {
        mi_error(inst, "%sInstantiate: %s", api, inst->err);
        mi_free(inst);
        return NULL;
    }
    if (!token || strcmp(token, mace_guid(inst->model)) != 0) {
        mi_error(inst, "%sInstantiate: the %s %s does not match the model data (%s)", api,
                 strcmp(api, "fmi2") == 0 ? "GUID" : "instantiation token", token ? token : "(null)",
                 mace_guid(inst->model));
        mi_free(inst);
        return NULL;
    }
    mi_debug(inst, "instantiated from %s (%lu states, %lu inputs, %lu outputs)", resource_dir,
             (unsigned long)mace_n_states(inst->model), (unsigned long)mace_n_inputs(inst->model),
             (unsigned long)mace_n_outputs(inst->model));
    return inst;
}

void mi_free(MiInstance *inst) {
    if (!inst) return;
    mace_destroy(inst->model);
    inst->al.free(inst->name);
    inst->al.free(inst->message);
    inst->al.free(inst);
}

/* ---- values ---------------------------------------------------------------------------------- */

static const char *group_name(MaceGroup g) {
    switch (g) {
        case MACE_VAR_OUTPUT: return "an output";
        case MACE_VAR_FREQUENCY: return "a calculated parameter";
        case MACE_VAR_STATE: return "a continuous state (use SetContinuousStates)";
        case MACE_VAR_DERIVATIVE: return "a state derivative";
        case MACE_VAR_TIME: return "the independent variable (time)";
        default: return "not settable";
    }
}

/* A variable for messages: "output gyro_bus_x", "continuous state 12" (k: its index in its group). */
static void variable_text(const MiInstance *inst, MaceGroup g, size_t k, char *text, size_t size) {
    switch (g) {
        case MACE_VAR_INPUT: snprintf(text, size, "input %s", mace_name(inst->model, g, k)); break;
        case MACE_VAR_OUTPUT: snprintf(text, size, "output %s", mace_name(inst->model, g, k)); break;
        case MACE_VAR_PARAMETER: snprintf(text, size, "parameter %s", mace_name(inst->model, g, k)); break;
        case MACE_VAR_FREQUENCY: snprintf(text, size, "frequency_mode_%lu", (unsigned long)k + 1); break;
        case MACE_VAR_STATE: snprintf(text, size, "continuous state %lu", (unsigned long)k + 1); break;
        case MACE_VAR_DERIVATIVE: snprintf(text, size, "derivative of state %lu", (unsigned long)k + 1); break;
        default: snprintf(text, size, "time"); break;
    }
}

/* Whether a variable group is declared in this FMU's model description (model_description.py):
 * FMI 2 declares no time variable (time is implicit), FMI 3 declares no continuous states or
 * derivatives (co-simulation only). A value reference the FMU's own description does not declare is
 * not a variable of it (FMI 2.0.x section 2.1.7, FMI 3.0 section 2.2.6.2). */
static int declared(const MiInstance *inst, MaceGroup g) {
    if (g == MACE_VAR_UNKNOWN) return 0;
    if (inst->api[3] == '2') return g != MACE_VAR_TIME;
    return g != MACE_VAR_STATE && g != MACE_VAR_DERIVATIVE;
}

MiStatus mi_set_reals(MiInstance *inst, const unsigned int *vr, size_t n, const double *values, const char *fn) {
    size_t i, k;
    if (!mi_allowed(inst, fn, SETTABLE_INPUT)) return MI_ERROR;
    if (n > 0 && (!vr || !values)) return mi_error(inst, "%s%s: NULL value references or values", inst->api, fn);
    /* every value is checked before any is stored: a refused call leaves the instance as it was */
    for (i = 0; i < n; i++) {
        const MaceGroup g = mace_variable(inst->model, vr[i], &k);
        if (!declared(inst, g)) {
            return mi_error(inst, "%s%s: value reference %u is not a variable of this FMU", inst->api, fn, vr[i]);
        } else if (g == MACE_VAR_INPUT || g == MACE_VAR_PARAMETER) {
            if (g == MACE_VAR_PARAMETER && !(MI_IN(inst->phase) & SETTABLE_PARAMETER))
                return mi_error(inst, "%s%s: parameter %s is fixed: set it before %sExitInitializationMode",
                                inst->api, fn, mace_name(inst->model, g, k), inst->api);
            /* refused here, where it is set, so that no variable, output or parameter, ever reads NaN or
               infinite (a parameter outside its declared range is refused by the build, which names it) */
            if (!isfinite(values[i]))
                return mi_error(inst, "%s%s: non-finite value %g for %s %s (expected a finite number); not set",
                                inst->api, fn, values[i], g == MACE_VAR_INPUT ? "input" : "parameter",
                                mace_name(inst->model, g, k));
            if (g == MACE_VAR_INPUT && fabs(values[i]) > MACE_INPUT_LIMIT_V)
                return mi_error(inst, "%s%s: input %s = %g V is outside its declared range [-%g, %g] V; not set",
                                inst->api, fn, mace_name(inst->model, g, k), values[i], MACE_INPUT_LIMIT_V,
                                MACE_INPUT_LIMIT_V);
        } else {
            return mi_error(inst, "%s%s: value reference %u is %s and cannot be set", inst->api, fn, vr[i],
                            group_name(g));
        }
    }
    for (i = 0; i < n; i++) {
        const MaceGroup g = mace_variable(inst->model, vr[i], &k);
        if (g == MACE_VAR_INPUT) mace_set_input(inst->model, k, values[i]);
        else mace_set_parameter(inst->model, k, values[i]);
    }
    return MI_OK;
}

MiStatus mi_get_reals(MiInstance *inst, const unsigned int *vr, size_t n, double *values, const char *fn) {
    size_t i, k;
    if (!mi_allowed(inst, fn, GETTABLE)) return MI_ERROR;
    if (n > 0 && (!vr || !values)) return mi_error(inst, "%s%s: NULL value references or values", inst->api, fn);
    for (i = 0; i < n; i++) {
        const MaceGroup g = mace_variable(inst->model, vr[i], &k);
        if (!declared(inst, g))
            return mi_error(inst, "%s%s: value reference %u is not a variable of this FMU", inst->api, fn, vr[i]);
        if (mace_get(inst->model, g, k, &values[i], inst->err) != 0)
            return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
        /* finite inputs and states can still give an output beyond a double (states of 1e307 set through
           SetContinuousStates): refused as GetDerivatives refuses the same state, never passed on as a
           number with fmiOK */
        if (!isfinite(values[i])) {
            char what[96];
            variable_text(inst, g, k, what, sizeof what);
            if (inst->phase != PH_INITIALIZATION) inst->phase = PH_ERROR;  /* as GetDerivatives */
            return mi_error(inst, "%s%s: %s is %g at t = %g s: the inputs or states are beyond what the model can "
                            "represent", inst->api, fn, what, values[i], mace_time(inst->model));
        }
    }
    return MI_OK;
}

MiStatus mi_no_variables(MiInstance *inst, size_t n, const char *type, const char *fn, int set) {
    if (!mi_allowed(inst, fn, set ? SETTABLE_INPUT : GETTABLE)) return MI_ERROR;
    if (n == 0) return MI_OK;
    return mi_error(inst, "%s%s: this FMU has no %s variables", inst->api, fn, type);
}

/* ---- life cycle ------------------------------------------------------------------------------ */

/* Tolerance of the communication point against the FMU's time, relative to max(1, |t|): hosts
 * compute communication points as t0 + k h or as running sums of step sizes, which differ from
 * the FMU's own sum by a few ulps per step (1e-16 relative each); 1e-9 covers the rounding of
 * millions of steps and is still far below any step a host would make (1 ns at t < 1 s). */
#define TIME_TOLERANCE 1e-9

MiStatus mi_experiment(MiInstance *inst, int tolerance_defined, double tolerance, double start_time,
                       int stop_defined, double stop_time, const char *fn) {
    if (!mi_allowed(inst, fn, MI_IN(PH_INSTANTIATED))) return MI_ERROR;
    /* refused where they are given, so that the time never becomes NaN (FMI 2.0.x section 2.1.6,
       FMI 3.0 section 2.3.2: the start time, and a defined stop time and tolerance, are numbers with
       stopTime >= startTime); values whose "defined" flag is false are not used and not checked */
    if (!isfinite(start_time)) return mi_error(inst, "%s%s: start time %g is not finite", inst->api, fn, start_time);
    if (stop_defined && !(isfinite(stop_time) && stop_time >= start_time))
        return mi_error(inst, "%s%s: stop time %g is not a finite time >= the start time %g", inst->api, fn,
                        stop_time, start_time);
    if (tolerance_defined && !(isfinite(tolerance) && tolerance > 0.0))
        return mi_error(inst, "%s%s: tolerance %g is not a finite number > 0", inst->api, fn, tolerance);
    mace_set_time(inst->model, start_time);
    inst->stop_defined = stop_defined;
    inst->stop_time = stop_time;
    return MI_OK;
}

/* FMI 2.0.x section 2.1.6 (fmi2SetupExperiment): "if the environment tries to compute past stopTime
   the FMU has to return fmi2Error"; FMI 3.0 section 2.3.2 says the same of a defined stopTime. The
   tolerance is the communication point's: a step that ends at the stop time up to round-off is allowed.
   Checked on co-simulation steps only (see mi_set_time) */
static int past_stop(const MiInstance *inst, double t) {
    return inst->stop_defined && t > inst->stop_time + TIME_TOLERANCE * (fabs(inst->stop_time) > 1.0 ?
                                                                         fabs(inst->stop_time) : 1.0);
}

MiStatus mi_enter_initialization(MiInstance *inst, const char *fn) {
    if (!mi_allowed(inst, fn, MI_IN(PH_INSTANTIATED))) return MI_ERROR;
    inst->phase = PH_INITIALIZATION;
    return MI_OK;
}

MiStatus mi_exit_initialization(MiInstance *inst, const char *fn) {
    if (!mi_allowed(inst, fn, MI_IN(PH_INITIALIZATION))) return MI_ERROR;
    if (mace_build(inst->model, inst->err) != 0) {
        inst->phase = PH_ERROR;
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
    }
    inst->phase = inst->kind == MACE_CO_SIMULATION ? PH_STEP : PH_EVENT;
    if (inst->kind == MACE_CO_SIMULATION)
        mi_debug(inst, "initialised; exact zero-order hold in the %s form (transformation condition %.2g)",
                 mace_fast_form(inst->model) ? "decoupled modal" : "dense matrix-exponential",
                 mace_fast_form_condition(inst->model));
    return MI_OK;
}

MiStatus mi_do_step(MiInstance *inst, double t, double h, const char *fn) {
    const double now = mace_time(inst->model);
    if (!mi_allowed_kind(inst, fn, MACE_CO_SIMULATION, MI_IN(PH_STEP))) return MI_ERROR;
    /* the step must be > 0: FMI 2.0.x sections 4.2.1-4.2.2 define the communication step
       hc_i = tc_{i+1} - tc_i between strictly increasing communication points (the standard's own
       sample FMUs, fmuTemplate.c, refuse communicationStepSize <= 0 with fmi2Error). FMI 3.0
       section 4.2 gives a zero step a meaning only with event mode (event handling at a
       communication point), which this FMU does not offer (hasEventMode false, eventModeUsed
       refused at instantiation): an error there too */
    if (!(isfinite(t) && isfinite(h) && h > 0.0))
        return mi_error(inst, "%s%s: the step from t = %.17g s over %g s needs a finite time and a step > 0", inst->api,
                        fn, t, h);
    /* the step starts where the last one ended: currentCommunicationPoint is tc_i, the end of the
       previous step (or the start time); another point means the importer lost track of the FMU's
       time (a rollback takes fmiSetFMUState). The standard names no status for this; this runtime's
       answer is fmiError, so that a step never silently starts from the wrong state */
    if (!(fabs(t - now) <= TIME_TOLERANCE * (fabs(now) > 1.0 ? fabs(now) : 1.0)))
        return mi_error(inst, "%s%s: currentCommunicationPoint %.17g s is not the FMU's time %.17g s", inst->api,
                        fn, t, now);
    if (past_stop(inst, t + h))
        return mi_error(inst, "%s%s: the step to t = %.17g s passes the stop time %.17g s given at the set-up of the "
                        "experiment", inst->api, fn, t + h, inst->stop_time);
    /* a step the model refuses as an argument (the controller's bound on one call's samples) is refused
       like the checks above: an error that leaves the instance as it was (FMI 3.0 section 2.2.3: illegal
       arguments return fmi3Error; nothing was computed, so nothing needs the error state's reset) */
    if (mace_step_check(inst->model, t, h, inst->err) != 0)
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
    if (mace_do_step(inst->model, t, h, inst->err) != 0) {
        inst->phase = PH_ERROR;
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
    }
    return MI_OK;
}

MiStatus mi_terminate(MiInstance *inst, const char *fn) {
    if (!mi_allowed(inst, fn, MI_IN(PH_STEP) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS))) return MI_ERROR;
    inst->phase = PH_TERMINATED;
    return MI_OK;
}

MiStatus mi_reset(MiInstance *inst, const char *fn) {
    (void)fn;
    mace_reset(inst->model);
    inst->phase = PH_INSTANTIATED;
    inst->stop_defined = 0;  /* as after instantiation: the next setupExperiment says it again */
    return MI_OK;
}

/* ---- FMU state ------------------------------------------------------------------------------- */

static MiState *new_state(MiInstance *inst, size_t size) {
    MiState *s = (MiState *)inst->al.calloc(1, sizeof(MiState) + size);
    if (s) s->size = size;
    return s;
}

/* FNV-1a, 64 bits: a checksum against edited or damaged states, and the GUID's fingerprint */
static uint64_t fnv1a(uint64_t h, const unsigned char *bytes, size_t n) {
    size_t k;
    for (k = 0; k < n; k++) {
        h ^= bytes[k];
        h *= 1099511628211ULL;
    }
    return h;
}
#define FNV_START 14695981039346656037ULL

static uint64_t state_sum(const unsigned char *bytes, size_t size) {
    const unsigned char zero[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    uint64_t h = fnv1a(FNV_START, bytes, HDR_SUM);
    h = fnv1a(h, zero, 8);
    return fnv1a(h, bytes + HDR_SIZE, size - HDR_SIZE);
}

static uint64_t api_number(const MiInstance *inst) { return inst->api[3] == '2' ? 2u : 3u; }

static uint64_t guid_print(const MiInstance *inst) {
    const char *guid = mace_guid(inst->model);
    return fnv1a(FNV_START, (const unsigned char *)guid, strlen(guid));
}

static size_t full_size(const MiInstance *inst) { return HDR_SIZE + mace_state_size(inst->model); }

/* The phases an instance of this interface can be in (the state machines of FMI 2.0.x sections
 * 3.2.3 and 4.2.4, FMI 3.0 sections 3.2 and 4.2): a co-simulation state is never in Event or
 * Continuous-Time Mode, a model-exchange state never in Step Mode. */
static int phase_possible(const MiInstance *inst, int phase) {
    if (phase < 0 || phase >= PH_COUNT) return 0;
    if (inst->kind == MACE_CO_SIMULATION) return phase != PH_EVENT && phase != PH_CONTINUOUS;
    return phase != PH_STEP;
}

/* The phases in which the model must be built (initialised, with valid parameters). */
#define BUILT_PHASES (MI_IN(PH_STEP) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | MI_IN(PH_TERMINATED))

/* 0 if bytes are an FMU state this instance can take; else logs why not. Nothing is applied. */
static int check_state(MiInstance *inst, const unsigned char *bytes, size_t size, const char *fn) {
    uint64_t api, kind, guid, sum;
    int phase, usable;
    if (!bytes) return mi_error(inst, "%s%s: no FMU state given", inst->api, fn), -1;
    if (size != full_size(inst) || memcmp(bytes + HDR_TAG, STATE_TAG, 8) != 0)
        return mi_error(inst, "%s%s: not an FMU state of this FMU (%lu bytes, %lu expected)", inst->api, fn,
                        (unsigned long)size, (unsigned long)full_size(inst)), -1;
    memcpy(&api, bytes + HDR_API, 8);
    memcpy(&kind, bytes + HDR_KIND, 8);
    memcpy(&guid, bytes + HDR_GUID, 8);
    memcpy(&sum, bytes + HDR_SUM, 8);
    if (sum != state_sum(bytes, size))
        return mi_error(inst, "%s%s: the FMU state is damaged or was edited (its checksum does not match)", inst->api,
                        fn), -1;
    if (api != api_number(inst))
        return mi_error(inst, "%s%s: an FMU state of an FMI %lu instance cannot be set into an FMI %lu instance",
                        inst->api, fn, (unsigned long)api, (unsigned long)api_number(inst)), -1;
    if (guid != guid_print(inst))
        return mi_error(inst, "%s%s: the FMU state belongs to another FMU (GUID %s expected)", inst->api, fn,
                        mace_guid(inst->model)), -1;
    if (kind != (uint64_t)inst->kind)
        return mi_error(inst, "%s%s: a %s FMU state cannot be set into a %s instance", inst->api, fn,
                        kind == MACE_CO_SIMULATION ? "co-simulation" : "model-exchange",
                        inst->kind == MACE_CO_SIMULATION ? "co-simulation" : "model-exchange"), -1;
    if (mace_state_check(inst->model, bytes + HDR_SIZE, size - HDR_SIZE, &phase, &usable, inst->err) != 0)
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err), -1;
    if (!phase_possible(inst, phase))
        return mi_error(inst, "%s%s: the FMU state's state-machine value %d is not a state of this instance",
                        inst->api, fn, phase), -1;
    if ((MI_IN(phase) & BUILT_PHASES) && !usable)
        return mi_error(inst, "%s%s: the FMU state is in %s but its model is not initialised with valid parameters",
                        inst->api, fn, PHASE_NAMES[phase]), -1;
    return 0;
}

static void save_state(MiInstance *inst, unsigned char *bytes) {
    const uint64_t api = api_number(inst), kind = (uint64_t)inst->kind, guid = guid_print(inst);
    const size_t size = full_size(inst);
    uint64_t sum;
    memcpy(bytes + HDR_TAG, STATE_TAG, 8);
    memcpy(bytes + HDR_API, &api, 8);
    memcpy(bytes + HDR_KIND, &kind, 8);
    memcpy(bytes + HDR_GUID, &guid, 8);
    mace_state_save(inst->model, (int)inst->phase, bytes + HDR_SIZE);
    sum = state_sum(bytes, size);
    memcpy(bytes + HDR_SUM, &sum, 8);
}

MiStatus mi_get_state(MiInstance *inst, void **state, const char *fn) {
    const size_t size = full_size(inst);
    MiState *s;
    if (!state) return mi_error(inst, "%s%s: no place for the FMU state given", inst->api, fn);
    s = (MiState *)*state;
    if (!s || s->size != size) { /* FMI 2.0.x 2.1.8: a given state is overwritten; one of another size is not ours */
        s = new_state(inst, size);
        if (!s) return mi_error(inst, "%s%s: out of memory", inst->api, fn);
    }
    save_state(inst, s->bytes);
    *state = s;
    return MI_OK;
}

MiStatus mi_set_state(MiInstance *inst, const void *state, const char *fn) {
    const MiState *s = (const MiState *)state;
    unsigned char *backup;
    int phase;
    if (!s) return mi_error(inst, "%s%s: no FMU state given", inst->api, fn);
    if (check_state(inst, s->bytes, s->size, fn) != 0) return MI_ERROR;
    /* the build in the load can still fail (numerically): then the instance goes back to where it was */
    backup = (unsigned char *)inst->al.calloc(full_size(inst), 1);
    if (!backup) return mi_error(inst, "%s%s: out of memory", inst->api, fn);
    save_state(inst, backup);
    if (mace_state_load(inst->model, s->bytes + HDR_SIZE, s->size - HDR_SIZE, &phase, inst->err) != 0) {
        int old_phase;
        char reason[MACE_ERR_LEN];
        memcpy(reason, inst->err, MACE_ERR_LEN);
        (void)mace_state_load(inst->model, backup + HDR_SIZE, full_size(inst) - HDR_SIZE, &old_phase, inst->err);
        inst->al.free(backup);
        return mi_error(inst, "%s%s: %s; the instance is unchanged", inst->api, fn, reason);
    }
    inst->al.free(backup);
    inst->phase = (MiPhase)phase;
    return MI_OK;
}

MiStatus mi_free_state(MiInstance *inst, void **state, const char *fn) {
    (void)fn;
    if (state) {
        inst->al.free(*state);
        *state = NULL;
    }
    return MI_OK;
}

MiStatus mi_state_size(MiInstance *inst, const void *state, size_t *size, const char *fn) {
    if (!state || !size) return mi_error(inst, "%s%s: no FMU state or size given", inst->api, fn);
    *size = ((const MiState *)state)->size;
    return MI_OK;
}

MiStatus mi_serialize(MiInstance *inst, const void *state, unsigned char *bytes, size_t size, const char *fn) {
    const MiState *s = (const MiState *)state;
    if (!s || !bytes) return mi_error(inst, "%s%s: no FMU state or buffer given", inst->api, fn);
    if (size < s->size) return mi_error(inst, "%s%s: the buffer is smaller than the FMU state", inst->api, fn);
    memcpy(bytes, s->bytes, s->size);
    return MI_OK;
}

MiStatus mi_deserialize(MiInstance *inst, const unsigned char *bytes, size_t size, void **state, const char *fn) {
    MiState *s;
    if (!state) return mi_error(inst, "%s%s: no place for the FMU state given", inst->api, fn);
    /* checked in full here, so that garbage or flipped bits never become a state */
    if (check_state(inst, bytes, size, fn) != 0) return MI_ERROR;
    s = (MiState *)*state;
    if (!s || s->size != size) {
        s = new_state(inst, size);
        if (!s) return mi_error(inst, "%s%s: out of memory", inst->api, fn);
    }
    memcpy(s->bytes, bytes, size);
    *state = s;
    return MI_OK;
}

/* ---- model exchange -------------------------------------------------------------------------- */

static int states_count_ok(MiInstance *inst, size_t n, const char *fn) {
    if (n == mace_n_states(inst->model)) return 1;
    mi_error(inst, "%s%s: %lu states given, the model has %lu", inst->api, fn, (unsigned long)n,
             (unsigned long)mace_n_states(inst->model));
    return 0;
}

/* Model exchange: the masks of the FMI 2.0.x section 3.2.3 state table. */
#define ME_GET_STATES (MI_IN(PH_INITIALIZATION) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | MI_IN(PH_TERMINATED) | \
                       MI_IN(PH_ERROR))
#define ME_GET_DERIVATIVES (MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | MI_IN(PH_TERMINATED) | MI_IN(PH_ERROR))
#define ME_GET_NOMINALS (MI_IN(PH_INSTANTIATED) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | MI_IN(PH_TERMINATED) | \
                         MI_IN(PH_ERROR))

static int all_finite(const double *x, size_t n) {
    size_t k;
    for (k = 0; k < n; k++)
        if (!isfinite(x[k])) return 0;
    return 1;
}

MiStatus mi_set_time(MiInstance *inst, double t, const char *fn) {
    if (!mi_allowed_kind(inst, fn, MACE_MODEL_EXCHANGE, MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS))) return MI_ERROR;
    if (!isfinite(t)) return mi_error(inst, "%s%s: time %g is not finite", inst->api, fn, t);
    /* no stop-time check here: an importer's integrator evaluates the derivatives beyond its output
       time and interpolates back (fmpy's CVode sets times past stopTime on a run that ends at it), so
       refusing them would break the integrators the standard's rule does not aim at */
    mace_set_time(inst->model, t);
    return MI_OK;
}

MiStatus mi_set_states(MiInstance *inst, const double *x, size_t n, const char *fn) {
    /* Continuous-Time Mode only (FMI 2.0.x section 3.2.3 table: fmi2SetContinuousStates) */
    if (!mi_allowed_kind(inst, fn, MACE_MODEL_EXCHANGE, MI_IN(PH_CONTINUOUS)) || !states_count_ok(inst, n, fn))
        return MI_ERROR;
    if (n > 0 && !x) return mi_error(inst, "%s%s: NULL states", inst->api, fn);
    if (!all_finite(x, n)) return mi_error(inst, "%s%s: a non-finite state value; not set", inst->api, fn);
    mace_set_states(inst->model, x);
    return MI_OK;
}

MiStatus mi_get_states(MiInstance *inst, double *x, size_t n, const char *fn) {
    if (!mi_allowed_kind(inst, fn, MACE_MODEL_EXCHANGE, ME_GET_STATES) || !states_count_ok(inst, n, fn))
        return MI_ERROR;
    if (n > 0 && !x) return mi_error(inst, "%s%s: NULL states", inst->api, fn);
    mace_get_states(inst->model, x);
    return MI_OK;
}

MiStatus mi_get_derivatives(MiInstance *inst, double *dx, size_t n, const char *fn) {
    if (!mi_allowed_kind(inst, fn, MACE_MODEL_EXCHANGE, ME_GET_DERIVATIVES) || !states_count_ok(inst, n, fn))
        return MI_ERROR;
    if (n > 0 && !dx) return mi_error(inst, "%s%s: NULL derivatives", inst->api, fn);
    if (mace_get_derivatives(inst->model, dx, inst->err) != 0) {
        if (inst->phase != PH_INITIALIZATION) inst->phase = PH_ERROR;
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
    }
    return MI_OK;
}

/* Directional derivatives (FMI 2.0.x section 2.1.9), model exchange: the unknowns are state derivatives
 * and outputs, the knowns states and inputs (the model is linear: the result is its Jacobian times the
 * seed). Allowed where fmi2GetReal is (the FMI 2.0.x state tables), except Instantiated. */
#define ME_DIRECTIONAL (MI_IN(PH_INITIALIZATION) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | MI_IN(PH_TERMINATED) | \
                        MI_IN(PH_ERROR))

MiStatus mi_directional(MiInstance *inst, const unsigned int *unknown, size_t n_unknown, const unsigned int *known,
                        size_t n_known, const double *seed, double *out, const char *fn) {
    MaceModel *m = inst->model;
    double *vx = mace_directional_buffer(m, MACE_VAR_STATE), *vu = mace_directional_buffer(m, MACE_VAR_INPUT);
    double *dx = mace_directional_buffer(m, MACE_VAR_DERIVATIVE), *dy = mace_directional_buffer(m, MACE_VAR_OUTPUT);
    int want_dx = 0, want_dy = 0;
    size_t i, k;
    if (inst->kind != MACE_MODEL_EXCHANGE)
        return mi_error(inst, "%s%s: provided for model exchange only (providesDirectionalDerivative of the "
                        "ModelExchange element); this is a co-simulation instance", inst->api, fn);
    if (!mi_allowed(inst, fn, ME_DIRECTIONAL)) return MI_ERROR;
    if ((n_unknown > 0 && (!unknown || !out)) || (n_known > 0 && (!known || !seed)))
        return mi_error(inst, "%s%s: NULL value references or values", inst->api, fn);
    /* everything is checked before anything is computed */
    for (i = 0; i < n_known; i++) {
        const MaceGroup g = mace_variable(m, known[i], &k);
        if (!declared(inst, g)) return mi_error(inst, "%s%s: value reference %u is not a variable of this FMU",
                                               inst->api, fn, known[i]);
        if (g != MACE_VAR_STATE && g != MACE_VAR_INPUT)
            return mi_error(inst, "%s%s: known value reference %u is neither a continuous state nor an input "
                            "(the directional derivatives are those of the derivatives and outputs with respect to "
                            "the states and inputs)", inst->api, fn, known[i]);
        if (!isfinite(seed[i]))
            return mi_error(inst, "%s%s: the seed of value reference %u is not finite", inst->api, fn, known[i]);
    }
    for (i = 0; i < n_unknown; i++) {
        const MaceGroup g = mace_variable(m, unknown[i], &k);
        if (!declared(inst, g)) return mi_error(inst, "%s%s: value reference %u is not a variable of this FMU",
                                               inst->api, fn, unknown[i]);
        if (g == MACE_VAR_DERIVATIVE) {
            want_dx = 1;
        } else if (g == MACE_VAR_OUTPUT) {
            want_dy = 1;
        } else {
            return mi_error(inst, "%s%s: unknown value reference %u is neither a state derivative nor an output",
                            inst->api, fn, unknown[i]);
        }
    }
    memset(vx, 0, mace_n_states(m) * sizeof(double));
    memset(vu, 0, mace_n_inputs(m) * sizeof(double));
    for (i = 0; i < n_known; i++) {
        const MaceGroup g = mace_variable(m, known[i], &k);
        if (g == MACE_VAR_STATE) {
            vx[mace_state_position(m, k)] += seed[i];
        } else {
            vu[k] += seed[i];
        }
    }
    if (mace_directional(m, vx, vu, want_dx ? dx : NULL, want_dy ? dy : NULL, inst->err) != 0)
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
    for (i = 0; i < n_unknown; i++) {
        const MaceGroup g = mace_variable(m, unknown[i], &k);
        out[i] = g == MACE_VAR_DERIVATIVE ? dx[mace_state_position(m, k)] : dy[k];
    }
    return MI_OK;
}

MiStatus mi_get_nominals(MiInstance *inst, double *nominal, size_t n, const char *fn) {
    if (!mi_allowed_kind(inst, fn, MACE_MODEL_EXCHANGE, ME_GET_NOMINALS) || !states_count_ok(inst, n, fn))
        return MI_ERROR;
    if (n > 0 && !nominal) return mi_error(inst, "%s%s: NULL nominals", inst->api, fn);
    mace_get_nominals(inst->model, nominal);
    return MI_OK;
}

/* ---- resource URI ---------------------------------------------------------------------------- */

static int hex(int c) {
    if (c >= '0' && c <= '9') return c - '0';
    c = tolower(c);
    return (c >= 'a' && c <= 'f') ? c - 'a' + 10 : -1;
}

char *mi_uri_to_path(const MaceAlloc *al, const char *uri) {
    const char *p;
    char *out, *o;
    if (!uri || strlen(uri) < 5) return NULL;
    if (!(tolower((unsigned char)uri[0]) == 'f' && tolower((unsigned char)uri[1]) == 'i' &&
          tolower((unsigned char)uri[2]) == 'l' && tolower((unsigned char)uri[3]) == 'e' && uri[4] == ':'))
        return NULL;
    p = uri + 5;
    if (strncmp(p, "///", 3) == 0) {
        p += 2;
    } else if (strncmp(p, "//localhost/", 12) == 0) {
        p += 11;
    } else if (strncmp(p, "//", 2) == 0) { /* a host: keep //host/share (a Windows UNC path) */
    }
    /* /C:/dir on Windows is C:/dir */
    if (p[0] == '/' && isalpha((unsigned char)p[1]) && p[2] == ':') p++;
    out = (char *)al->calloc(strlen(p) + 1, 1);
    if (!out) return NULL;
    for (o = out; *p; p++) {
        if (p[0] == '%' && hex((unsigned char)p[1]) >= 0 && hex((unsigned char)p[2]) >= 0) {
            *o++ = (char)(hex((unsigned char)p[1]) * 16 + hex((unsigned char)p[2]));
            p += 2;
        } else {
            *o++ = *p;
        }
    }
    *o = '\0';
    return out;
}
