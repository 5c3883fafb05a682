/* An FMU instance shared by the FMI 2 and FMI 3 wrappers (see mace_instance.h). */
#include "mace_instance.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static const char *PHASE_NAMES[PH_COUNT] = {"instantiated", "initialization mode", "step mode", "event mode",
                                            "continuous-time mode", "terminated", "error"};

#define SETTABLE_INPUT (MI_IN(PH_INSTANTIATED) | MI_IN(PH_INITIALIZATION) | MI_IN(PH_STEP) | MI_IN(PH_EVENT) | \
                        MI_IN(PH_CONTINUOUS))
#define SETTABLE_PARAMETER (MI_IN(PH_INSTANTIATED) | MI_IN(PH_INITIALIZATION))
#define GETTABLE (MI_IN(PH_INITIALIZATION) | MI_IN(PH_STEP) | MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS) | \
                  MI_IN(PH_TERMINATED) | MI_IN(PH_ERROR))

typedef struct MiState {
    size_t size;
    unsigned char bytes[1];
} MiState;

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

MiStatus mi_set_reals(MiInstance *inst, const unsigned int *vr, size_t n, const double *values, const char *fn) {
    size_t i, k;
    if (!mi_allowed(inst, fn, SETTABLE_INPUT)) return MI_ERROR;
    for (i = 0; i < n; i++) {
        const MaceGroup g = mace_variable(inst->model, vr[i], &k);
        if (g == MACE_VAR_INPUT) {
            mace_set_input(inst->model, k, values[i]);
        } else if (g == MACE_VAR_PARAMETER) {
            if (!(MI_IN(inst->phase) & SETTABLE_PARAMETER))
                return mi_error(inst, "%s%s: parameter %s is fixed: set it before %sExitInitializationMode",
                                inst->api, fn, mace_name(inst->model, g, k), inst->api);
            mace_set_parameter(inst->model, k, values[i]);
        } else if (g == MACE_VAR_UNKNOWN) {
            return mi_error(inst, "%s%s: value reference %u is not a variable of this FMU", inst->api, fn, vr[i]);
        } else {
            return mi_error(inst, "%s%s: value reference %u is %s and cannot be set", inst->api, fn, vr[i],
                            group_name(g));
        }
    }
    return MI_OK;
}

MiStatus mi_get_reals(MiInstance *inst, const unsigned int *vr, size_t n, double *values, const char *fn) {
    size_t i, k;
    if (!mi_allowed(inst, fn, GETTABLE)) return MI_ERROR;
    for (i = 0; i < n; i++) {
        const MaceGroup g = mace_variable(inst->model, vr[i], &k);
        if (g == MACE_VAR_UNKNOWN)
            return mi_error(inst, "%s%s: value reference %u is not a variable of this FMU", inst->api, fn, vr[i]);
        if (mace_get(inst->model, g, k, &values[i], inst->err) != 0)
            return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
    }
    return MI_OK;
}

MiStatus mi_no_variables(MiInstance *inst, size_t n, const char *type, const char *fn) {
    if (n == 0) return MI_OK;
    return mi_error(inst, "%s%s: this FMU has no %s variables", inst->api, fn, type);
}

/* ---- life cycle ------------------------------------------------------------------------------ */

MiStatus mi_enter_initialization(MiInstance *inst, double start_time, const char *fn) {
    if (!mi_allowed(inst, fn, MI_IN(PH_INSTANTIATED))) return MI_ERROR;
    if (!isfinite(start_time)) return mi_error(inst, "%s%s: start time %g is not finite", inst->api, fn, start_time);
    mace_set_time(inst->model, start_time);
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
    if (!mi_allowed(inst, fn, MI_IN(PH_STEP))) return MI_ERROR;
    if (!(isfinite(t) && isfinite(h) && h >= 0.0))
        return mi_error(inst, "%s%s: the step from t = %g s over %g s needs a finite time and a step >= 0", inst->api,
                        fn, t, h);
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
    return MI_OK;
}

/* ---- FMU state ------------------------------------------------------------------------------- */

static MiState *new_state(MiInstance *inst, size_t size) {
    MiState *s = (MiState *)inst->al.calloc(1, sizeof(MiState) + size);
    if (s) s->size = size;
    return s;
}

MiStatus mi_get_state(MiInstance *inst, void **state, const char *fn) {
    const size_t size = mace_state_size(inst->model);
    MiState *s = (MiState *)*state;
    if (!s || s->size != size) {
        s = new_state(inst, size);
        if (!s) return mi_error(inst, "%s%s: out of memory", inst->api, fn);
    }
    mace_state_save(inst->model, (int)inst->phase, s->bytes);
    *state = s;
    return MI_OK;
}

MiStatus mi_set_state(MiInstance *inst, const void *state, const char *fn) {
    const MiState *s = (const MiState *)state;
    int phase;
    if (!s) return mi_error(inst, "%s%s: no FMU state given", inst->api, fn);
    if (mace_state_load(inst->model, s->bytes, s->size, &phase, inst->err) != 0 || phase < 0 || phase >= PH_COUNT)
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
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
    if (!state) return mi_error(inst, "%s%s: no FMU state given", inst->api, fn);
    *size = ((const MiState *)state)->size;
    return MI_OK;
}

MiStatus mi_serialize(MiInstance *inst, const void *state, unsigned char *bytes, size_t size, const char *fn) {
    const MiState *s = (const MiState *)state;
    if (!s || size < s->size) return mi_error(inst, "%s%s: the buffer is smaller than the FMU state", inst->api, fn);
    memcpy(bytes, s->bytes, s->size);
    return MI_OK;
}

MiStatus mi_deserialize(MiInstance *inst, const unsigned char *bytes, size_t size, void **state, const char *fn) {
    MiState *s;
    if (size != mace_state_size(inst->model))
        return mi_error(inst, "%s%s: %lu bytes are not an FMU state of this model (%lu expected)", inst->api, fn,
                        (unsigned long)size, (unsigned long)mace_state_size(inst->model));
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

MiStatus mi_set_time(MiInstance *inst, double t, const char *fn) {
    if (!mi_allowed(inst, fn, MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS))) return MI_ERROR;
    mace_set_time(inst->model, t);
    return MI_OK;
}

MiStatus mi_set_states(MiInstance *inst, const double *x, size_t n, const char *fn) {
    if (!mi_allowed(inst, fn, MI_IN(PH_EVENT) | MI_IN(PH_CONTINUOUS)) || !states_count_ok(inst, n, fn)) return MI_ERROR;
    mace_set_states(inst->model, x);
    return MI_OK;
}

MiStatus mi_get_states(MiInstance *inst, double *x, size_t n, const char *fn) {
    if (!mi_allowed(inst, fn, GETTABLE) || !states_count_ok(inst, n, fn)) return MI_ERROR;
    mace_get_states(inst->model, x);
    return MI_OK;
}

MiStatus mi_get_derivatives(MiInstance *inst, double *dx, size_t n, const char *fn) {
    if (!mi_allowed(inst, fn, GETTABLE) || !states_count_ok(inst, n, fn)) return MI_ERROR;
    if (mace_get_derivatives(inst->model, dx, inst->err) != 0) {
        if (inst->phase != PH_INITIALIZATION) inst->phase = PH_ERROR;
        return mi_error(inst, "%s%s: %s", inst->api, fn, inst->err);
    }
    return MI_OK;
}

MiStatus mi_get_nominals(MiInstance *inst, double *nominal, size_t n, const char *fn) {
    if (!states_count_ok(inst, n, fn)) return MI_ERROR;
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
