/* The model core of the MACE FMU runtime, independent of the FMI version.
 *
 * A model is the data file resources/mace_model.bin written by mace_fmu.fmu.native.resource:
 * the blocks and wiring of a volts-volts block diagram, the retained modes and their stiffness
 * sensitivities. mace_build turns the parameter vector into (A, B, C, D) as
 * mace_fmu.iomodel.parametric.ParametricSystem does, then prepares the exact zero-order-hold
 * step (co-simulation) or the derivatives (model exchange).
 *
 * Functions that can fail return 0 or -1 and write a one-line reason into err (MACE_ERR_LEN).
 */
#ifndef MACE_MODEL_H
#define MACE_MODEL_H

#include <stddef.h>

#include "mace_linalg.h"

#define MACE_RUNTIME_VERSION "1.0"
#define MACE_DATA_FILE "mace_model.bin"

typedef enum { MACE_CO_SIMULATION = 0, MACE_MODEL_EXCHANGE = 1 } MaceKind;

/* Variables by value reference: inputs, outputs, parameters, calculated frequencies,
 * continuous states, their derivatives and the time (FMI 3's independent variable), in that order. */
typedef enum {
    MACE_VAR_UNKNOWN = -1,
    MACE_VAR_INPUT = 0,
    MACE_VAR_OUTPUT,
    MACE_VAR_PARAMETER,
    MACE_VAR_FREQUENCY,
    MACE_VAR_STATE,
    MACE_VAR_DERIVATIVE,
    MACE_VAR_TIME
} MaceGroup;

typedef struct MaceModel MaceModel;

MaceModel *mace_create(const char *resource_dir, MaceKind kind, const MaceAlloc *al, char *err);
void mace_destroy(MaceModel *m);
/* Back to the state after mace_create: nominal parameters, zero inputs and state, time 0. */
void mace_reset(MaceModel *m);

MaceGroup mace_variable(const MaceModel *m, unsigned long long vr, size_t *index);
const char *mace_name(const MaceModel *m, MaceGroup group, size_t index);
/* The GUID (FMI 2) or instantiation token (FMI 3) of the FMU the data were written for. */
const char *mace_guid(const MaceModel *m);
size_t mace_n_states(const MaceModel *m);
size_t mace_n_inputs(const MaceModel *m);
size_t mace_n_outputs(const MaceModel *m);

void mace_set_input(MaceModel *m, size_t k, double value);
void mace_set_parameter(MaceModel *m, size_t k, double value);
/* Value of a variable; builds the system first if the parameters changed since the last build. */
int mace_get(MaceModel *m, MaceGroup group, size_t k, double *value, char *err);

/* Checks the parameters and rebuilds the system if they changed since the last build. */
int mace_build(MaceModel *m, char *err);
/* 1 if the stepping uses the decoupled modal form, 0 for the dense matrix exponential. */
int mace_fast_form(const MaceModel *m);
/* Condition number of the decoupled modal form's transformation (1 for the dense form). */
double mace_fast_form_condition(const MaceModel *m);

/* Co-simulation: whether the model takes a step from t over h seconds (t and h finite, h > 0: the
 * instance layer's checks). 0 if it does; -1 and the reason in err for a step it refuses as an invalid
 * argument (the controller's bound on the samples of one call), which leaves everything as it was: the
 * instance refuses the call and stays usable, as for a step of 0 s. */
int mace_step_check(const MaceModel *m, double t, double h, char *err);
/* Co-simulation: the exact zero-order-hold step from t over h seconds with the held inputs. */
int mace_do_step(MaceModel *m, double t, double h, char *err);
double mace_time(const MaceModel *m);

/* Model exchange. */
void mace_set_time(MaceModel *m, double t);
void mace_set_states(MaceModel *m, const double *x);
void mace_get_states(MaceModel *m, double *x);
int mace_get_derivatives(MaceModel *m, double *dx, char *err);
/* Position of model state k (value-reference order) in the state vector: model exchange orders its states
 * for dense-LU integrators (the data's me_order: delays, filters, displacements, rates), co-simulation keeps k. */
size_t mace_state_position(const MaceModel *m, size_t k);
/* Directional derivatives of the linear model (its Jacobian times a seed): dx = A vx + B vu and
 * dy = C vx + D vu for the current parameters (either result may be NULL), vx and dx in the state
 * vector's order (mace_state_position). */
int mace_directional(MaceModel *m, const double *vx, const double *vu, double *dx, double *dy, char *err);
/* The model's scratch vectors for mace_directional: seeds (MACE_VAR_STATE: n, MACE_VAR_INPUT: n_in)
 * and results (MACE_VAR_DERIVATIVE: n, MACE_VAR_OUTPUT: n_out); NULL for other groups. */
double *mace_directional_buffer(MaceModel *m, MaceGroup group);
/* Nominal values of the states (their typical size; 1 before the first build). */
void mace_get_nominals(MaceModel *m, double *nominal);

/* FMU state as a byte string: the caller's phase (its state machine), time, parameters,
 * inputs and the state vector (in stepping and in model coordinates). */
size_t mace_state_size(const MaceModel *m);
void mace_state_save(MaceModel *m, int phase, unsigned char *buffer);
/* 0 if buffer is an FMU state of this model (size, magic, dimensions, finite time, inputs and
 * states), with nothing applied; *phase: the caller's phase stored in it; *usable: 1 if it was saved
 * from a built model and its parameters pass the build's checks (the states in it then apply). */
int mace_state_check(MaceModel *m, const unsigned char *buffer, size_t size, int *phase, int *usable, char *err);
/* Applies a state mace_state_check accepts; -1 (err) if it is refused or the build fails. */
int mace_state_load(MaceModel *m, const unsigned char *buffer, size_t size, int *phase, char *err);

#endif
