/* An FMU instance: the model core, the FMI state machine and the host's logger, shared by the
 * FMI 2 and FMI 3 wrappers (fmi2_api.c, fmi3_api.c), which only translate types and names.
 *
 * Calls out of order (outside the states the FMI 2.0.x / 3.0 state tables allow them in, or of the
 * other interface) and invalid arguments (a value reference the FMU's own model description does
 * not declare, a non-finite input, a step that does not start at the FMU's time or is not > 0, a
 * step longer than the model takes in one call (the controller's bound), an FMU state of another
 * FMU, interface or FMI version, or a damaged one) return an error with a logged reason and leave
 * the instance as it was; a failure of the model (invalid parameters, derivatives or values beyond
 * what a double holds) logs the reason and puts the instance into the error state, from which only
 * getting values, restoring an FMU state, reset and freeing are possible. Error messages are logged
 * whether debug logging is on or not.
 */
#ifndef MACE_INSTANCE_H
#define MACE_INSTANCE_H

#include "mace_model.h"

typedef enum { MI_OK = 0, MI_WARNING = 1, MI_DISCARD = 2, MI_ERROR = 3, MI_FATAL = 4 } MiStatus;

typedef enum {
    PH_INSTANTIATED = 0,
    PH_INITIALIZATION,
    PH_STEP,        /* co-simulation: step complete */
    PH_EVENT,       /* model exchange */
    PH_CONTINUOUS,  /* model exchange */
    PH_TERMINATED,
    PH_ERROR,
    PH_COUNT
} MiPhase;

#define MI_IN(phase) (1u << (phase))
#define MI_ANY 0xffffu

typedef void (*MiLogger)(void *host, const char *instance, MiStatus status, const char *category,
                         const char *message);

typedef struct MiInstance {
    MaceModel *model;
    MaceAlloc al;
    MaceKind kind;
    MiPhase phase;
    int logging_on;
    char *name;
    const char *api; /* "fmi2" or "fmi3" */
    MiLogger log;
    void *host;
    char err[MACE_ERR_LEN];
    char *message; /* the last message, formatted */
    int stop_defined; /* setupExperiment's stopTimeDefined: no step or time past stop_time [s] */
    double stop_time;
} MiInstance;

/* NULL on failure, after logging the reason through log(host, ...). */
MiInstance *mi_create(const char *name, MaceKind kind, const char *resource_dir, const char *token,
                      const MaceAlloc *al, MiLogger log, void *host, int logging_on, const char *api);
void mi_free(MiInstance *inst);

/* Logs at error level (always) or as debug information (when logging is on). */
MiStatus mi_error(MiInstance *inst, const char *fmt, ...);
void mi_debug(MiInstance *inst, const char *fmt, ...);
/* 1 if `function` may be called now (mask of MI_IN(phase)), else logs why not and returns 0. */
int mi_allowed(MiInstance *inst, const char *function, unsigned mask);
/* The same for a function of one interface only (co-simulation or model exchange). */
int mi_allowed_kind(MiInstance *inst, const char *function, MaceKind kind, unsigned mask);

MiStatus mi_set_reals(MiInstance *inst, const unsigned int *vr, size_t n, const double *values, const char *fn);
MiStatus mi_get_reals(MiInstance *inst, const unsigned int *vr, size_t n, double *values, const char *fn);
/* For the variable types the model has none of. */
MiStatus mi_no_variables(MiInstance *inst, size_t n, const char *type, const char *fn, int set);

/* The experiment (FMI 2 SetupExperiment, FMI 3 EnterInitializationMode's arguments), checked. */
MiStatus mi_experiment(MiInstance *inst, int tolerance_defined, double tolerance, double start_time,
                       int stop_defined, double stop_time, const char *fn);
MiStatus mi_enter_initialization(MiInstance *inst, const char *fn);
MiStatus mi_exit_initialization(MiInstance *inst, const char *fn);
MiStatus mi_do_step(MiInstance *inst, double t, double h, const char *fn);
MiStatus mi_terminate(MiInstance *inst, const char *fn);
MiStatus mi_reset(MiInstance *inst, const char *fn);

/* FMU state: an opaque copy allocated with the instance's allocator. */
MiStatus mi_get_state(MiInstance *inst, void **state, const char *fn);
MiStatus mi_set_state(MiInstance *inst, const void *state, const char *fn);
MiStatus mi_free_state(MiInstance *inst, void **state, const char *fn);
MiStatus mi_state_size(MiInstance *inst, const void *state, size_t *size, const char *fn);
MiStatus mi_serialize(MiInstance *inst, const void *state, unsigned char *bytes, size_t size, const char *fn);
MiStatus mi_deserialize(MiInstance *inst, const unsigned char *bytes, size_t size, void **state, const char *fn);

/* Model exchange. */
MiStatus mi_set_time(MiInstance *inst, double t, const char *fn);
MiStatus mi_set_states(MiInstance *inst, const double *x, size_t n, const char *fn);
MiStatus mi_get_states(MiInstance *inst, double *x, size_t n, const char *fn);
MiStatus mi_get_derivatives(MiInstance *inst, double *dx, size_t n, const char *fn);
MiStatus mi_get_nominals(MiInstance *inst, double *nominal, size_t n, const char *fn);
/* Directional derivatives (model exchange): out[i] = sum_j d unknown[i] / d known[j] seed[j], the unknowns
 * state derivatives or outputs, the knowns states or inputs. */
MiStatus mi_directional(MiInstance *inst, const unsigned int *unknown, size_t n_unknown, const unsigned int *known,
                        size_t n_known, const double *seed, double *out, const char *fn);

/* A path from an FMI 2 resource URI (file:///dir, file:/dir, file://host/dir on Windows,
 * %-escapes decoded); NULL if it is not a file URI. Free with al->free. */
char *mi_uri_to_path(const MaceAlloc *al, const char *uri);

#endif
