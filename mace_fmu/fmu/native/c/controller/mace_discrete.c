/* A sampled-data controller behind the model interface of the runtime (mace_model.h).
 *
 * The data file (written by mace_fmu.fmu.controller) holds a discrete state space
 *     x[k+1] = A x[k] + B u[k],   y[k] = C x[k] + D u[k],
 * its sample time T and its signal names. The FMI layers (fmi2_api.c, fmi3_api.c) and the FMI
 * state machine (mace_instance.c) are the plant FMUs' own; this file replaces mace_model.c and
 * mace_zoh.c in the controller's binary. The controller samples at the instants t0 + k T (t0: the
 * experiment's start time); a communication step from t to t + h runs the samples whose instants lie
 * in (t, t + h] with the inputs held, so any step size works: a step that is a whole number of samples
 * runs that many, a shorter one between two instants none (the outputs hold). One call runs at most
 * MAX_SAMPLES_PER_CALL samples: a longer step is refused before any work, so that the work of a call
 * is bounded. There are no tunable parameters and no continuous states: co-simulation only.
 */
#include "mace_model.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "mace_data.h"

static const char STATE_MAGIC[8] = {'M', 'A', 'C', 'E', 'D', 'S', 'C', '2'};
#define STATE_HEADER 6 /* magic, phase, n_in, n_x, time, origin */
#define STEP_TOLERANCE 1e-9 /* in samples, relative: hosts compute times as sums of steps */
#define MAX_SAMPLES_PER_CALL 1000000.0 /* 2000 s at 2 ms, about a second of work for a 20-state controller */

struct MaceModel {
    MaceAlloc al;
    MaceFile file;
    size_t n_in, n_out, n_x;
    const double *a, *b, *c, *d;
    double sample_time;
    const char **names; /* inputs, outputs */
    const char *guid;
    double *u, *x, *x_next, *y;
    int y_valid;
    double time;
    double origin; /* t0: the sample instants are t0 + k T */
};

static const void *matrix(MaceModel *m, const char *name, size_t r, size_t c, char *err) {
    size_t dims[2];
    dims[0] = r;
    dims[1] = c;
    return mace_file_get(&m->file, name, MACE_F64, 2, dims, err);
}

static int load(MaceModel *m, const char *resource_dir, char *err) {
    char path[4096];
    size_t one = 1, three = 3, k;
    const int64_t *version, *counts;
    const double *sample_time;
    if (mace_resource_read(&m->file, resource_dir, &m->al, path, sizeof(path), err) != 0) return -1;
    if (!(version = (const int64_t *)mace_file_get(&m->file, "controller_format_version", MACE_I64, 1, &one, err)))
        return -1;
    if (version[0] != 1) {
        snprintf(err, MACE_ERR_LEN, "%.900s: controller data format %lld, this runtime reads format 1", path,
                 (long long)version[0]);
        return -1;
    }
    if (!(counts = (const int64_t *)mace_file_get(&m->file, "controller_counts", MACE_I64, 1, &three, err)))
        return -1;
    for (k = 0; k < 3; k++) {
        if (counts[k] < 0 || counts[k] > 100000) {
            snprintf(err, MACE_ERR_LEN, "%.900s: controller size %lu out of range", path, (unsigned long)k);
            return -1;
        }
    }
    m->n_in = (size_t)counts[0];
    m->n_out = (size_t)counts[1];
    m->n_x = (size_t)counts[2];
    if (!(sample_time = (const double *)mace_file_get(&m->file, "sample_time_s", MACE_F64, 1, &one, err)) ||
        !(m->a = (const double *)matrix(m, "A", m->n_x, m->n_x, err)) ||
        !(m->b = (const double *)matrix(m, "B", m->n_x, m->n_in, err)) ||
        !(m->c = (const double *)matrix(m, "C", m->n_out, m->n_x, err)) ||
        !(m->d = (const double *)matrix(m, "D", m->n_out, m->n_in, err)))
        return -1;
    m->sample_time = sample_time[0];
    if (!(isfinite(m->sample_time) && m->sample_time > 0.0)) {
        snprintf(err, MACE_ERR_LEN, "%.900s: sample time %g s, expected a positive number", path, m->sample_time);
        return -1;
    }
    m->names = (const char **)m->al.calloc(m->n_in + m->n_out + 1, sizeof(char *));
    if (!m->names) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        return -1;
    }
    if (mace_file_strings(&m->file, "guid", 1, &m->guid, err) ||
        mace_file_strings(&m->file, "input_names", m->n_in, m->names, err) ||
        mace_file_strings(&m->file, "output_names", m->n_out, m->names + m->n_in, err))
        return -1;
    return 0;
}

MaceModel *mace_create(const char *resource_dir, MaceKind kind, const MaceAlloc *al, char *err) {
    MaceModel *m;
    if (kind != MACE_CO_SIMULATION) {
        snprintf(err, MACE_ERR_LEN, "a sampled-data controller has no model-exchange interface: instantiate it for "
                 "co-simulation");
        return NULL;
    }
    m = (MaceModel *)al->calloc(1, sizeof(MaceModel));
    if (!m) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        return NULL;
    }
    m->al = *al;
    if (load(m, resource_dir, err) != 0) {
        mace_destroy(m);
        return NULL;
    }
    m->u = ml_zeros(al, m->n_in);
    m->x = ml_zeros(al, m->n_x);
    m->x_next = ml_zeros(al, m->n_x);
    m->y = ml_zeros(al, m->n_out);
    if (!m->u || !m->x || !m->x_next || !m->y) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        mace_destroy(m);
        return NULL;
    }
    mace_reset(m);
    return m;
}

void mace_destroy(MaceModel *m) {
    if (!m) return;
    mace_file_free(&m->file, &m->al);
    m->al.free(m->names);
    m->al.free(m->u);
    m->al.free(m->x);
    m->al.free(m->x_next);
    m->al.free(m->y);
    m->al.free(m);
}

void mace_reset(MaceModel *m) {
    memset(m->u, 0, m->n_in * sizeof(double));
    memset(m->x, 0, m->n_x * sizeof(double));
    m->time = m->origin = 0.0;
    m->y_valid = 0;
}

/* Value references: inputs, outputs, then FMI 3's time (no parameters, frequencies or states). */
MaceGroup mace_variable(const MaceModel *m, unsigned long long vr, size_t *index) {
    if (vr < m->n_in) {
        *index = (size_t)vr;
        return MACE_VAR_INPUT;
    }
    vr -= m->n_in;
    if (vr < m->n_out) {
        *index = (size_t)vr;
        return MACE_VAR_OUTPUT;
    }
    if (vr == m->n_out) {
        *index = 0;
        return MACE_VAR_TIME;
    }
    return MACE_VAR_UNKNOWN;
}

const char *mace_name(const MaceModel *m, MaceGroup group, size_t index) {
    switch (group) {
        case MACE_VAR_INPUT: return index < m->n_in ? m->names[index] : "?";
        case MACE_VAR_OUTPUT: return index < m->n_out ? m->names[m->n_in + index] : "?";
        case MACE_VAR_TIME: return "time";
        default: return "?";
    }
}

const char *mace_guid(const MaceModel *m) { return m->guid; }
size_t mace_n_states(const MaceModel *m) { (void)m; return 0; }
size_t mace_n_inputs(const MaceModel *m) { return m->n_in; }
size_t mace_n_outputs(const MaceModel *m) { return m->n_out; }
double mace_time(const MaceModel *m) { return m->time; }
int mace_fast_form(const MaceModel *m) { (void)m; return 0; }
double mace_fast_form_condition(const MaceModel *m) { (void)m; return 1.0; }

void mace_set_input(MaceModel *m, size_t k, double value) {
    m->u[k] = value;
    m->y_valid = 0;
}

void mace_set_parameter(MaceModel *m, size_t k, double value) { (void)m; (void)k; (void)value; }

int mace_build(MaceModel *m, char *err) { (void)m; (void)err; return 0; }

static const double *outputs(MaceModel *m) {
    size_t i, k;
    if (m->y_valid) return m->y;
    for (i = 0; i < m->n_out; i++) {
        double acc = 0.0;
        for (k = 0; k < m->n_x; k++) acc += m->c[i * m->n_x + k] * m->x[k];
        for (k = 0; k < m->n_in; k++) acc += m->d[i * m->n_in + k] * m->u[k];
        m->y[i] = acc;
    }
    m->y_valid = 1;
    return m->y;
}

int mace_get(MaceModel *m, MaceGroup group, size_t k, double *value, char *err) {
    switch (group) {
        case MACE_VAR_INPUT: *value = m->u[k]; return 0;
        case MACE_VAR_OUTPUT: *value = outputs(m)[k]; return 0;
        case MACE_VAR_TIME: *value = m->time; return 0;
        default: snprintf(err, MACE_ERR_LEN, "unknown variable"); return -1;
    }
}

/* Sample instants t0 + k T passed by time t (k counted with a relative tolerance: hosts sum their steps). */
static double samples_by(const MaceModel *m, double t) {
    const double k = (t - m->origin) / m->sample_time;
    return floor(k + STEP_TOLERANCE * (fabs(k) > 1.0 ? fabs(k) : 1.0));
}

/* A step too long for one call is an invalid argument, checked before any work (mace_model.h): the
 * instance refuses it and stays usable, as it does a step of 0 s; it was refused inside mace_do_step,
 * which left the instance in its error state, usable only after a reset. */
int mace_step_check(const MaceModel *m, double t, double h, char *err) {
    double samples;
    if (!(isfinite(t) && isfinite(h) && h >= 0.0)) {
        snprintf(err, MACE_ERR_LEN, "step from t = %g s over %g s: need a finite time and a step >= 0", t, h);
        return -1;
    }
    samples = samples_by(m, t + h) - samples_by(m, t);
    if (!(samples <= MAX_SAMPLES_PER_CALL)) {
        snprintf(err, MACE_ERR_LEN, "a step of %.17g s holds %.17g samples of %.17g s, more than the %.0f one call "
                 "runs (the work of a call is bounded): take shorter steps", h, samples, m->sample_time,
                 MAX_SAMPLES_PER_CALL);
        return -1;
    }
    return 0;
}

int mace_do_step(MaceModel *m, double t, double h, char *err) {
    double samples;
    size_t n, s, i, k;
    if (mace_step_check(m, t, h, err) != 0) return -1; /* for callers that did not ask first */
    samples = samples_by(m, t + h) - samples_by(m, t);
    for (k = 0; k < m->n_in; k++) {
        if (!isfinite(m->u[k])) {
            snprintf(err, MACE_ERR_LEN, "non-finite input %s = %g at t = %g s", m->names[k], m->u[k], t);
            return -1;
        }
    }
    n = samples > 0.0 ? (size_t)samples : 0;
    for (s = 0; s < n; s++) {
        for (i = 0; i < m->n_x; i++) {
            double acc = 0.0;
            for (k = 0; k < m->n_x; k++) acc += m->a[i * m->n_x + k] * m->x[k];
            for (k = 0; k < m->n_in; k++) acc += m->b[i * m->n_in + k] * m->u[k];
            m->x_next[i] = acc;
        }
        memcpy(m->x, m->x_next, m->n_x * sizeof(double));
    }
    m->time = t + h;
    m->y_valid = 0;
    return 0;
}

/* No continuous states: the model-exchange entry points have nothing to do (never reached, since
 * mace_create refuses model exchange). */
void mace_set_time(MaceModel *m, double t) { m->time = m->origin = t; } /* the experiment's start */
void mace_set_states(MaceModel *m, const double *x) { (void)m; (void)x; }
void mace_get_states(MaceModel *m, double *x) { (void)m; (void)x; }
void mace_get_nominals(MaceModel *m, double *nominal) { (void)m; (void)nominal; }
int mace_get_derivatives(MaceModel *m, double *dx, char *err) { (void)m; (void)dx; (void)err; return 0; }
/* co-simulation only: the instance layer refuses directional derivatives before it gets here */
int mace_directional(MaceModel *m, const double *vx, const double *vu, double *dx, double *dy, char *err) {
    (void)m;
    (void)vx;
    (void)vu;
    (void)dx;
    (void)dy;
    snprintf(err, MACE_ERR_LEN, "no directional derivatives in a sampled-data controller");
    return -1;
}
size_t mace_state_position(const MaceModel *m, size_t k) {
    (void)m;
    return k;
}
double *mace_directional_buffer(MaceModel *m, MaceGroup group) {
    (void)m;
    (void)group;
    return NULL;
}

size_t mace_state_size(const MaceModel *m) { return 8 * (STATE_HEADER + m->n_in + m->n_x); }

void mace_state_save(MaceModel *m, int phase, unsigned char *buffer) {
    uint64_t header[3];
    header[0] = (uint64_t)phase;
    header[1] = m->n_in;
    header[2] = m->n_x;
    memcpy(buffer, STATE_MAGIC, 8);
    memcpy(buffer + 8, header, sizeof(header));
    memcpy(buffer + 32, &m->time, 8);
    memcpy(buffer + 40, &m->origin, 8);
    memcpy(buffer + 48, m->u, 8 * m->n_in);
    memcpy(buffer + 48 + 8 * m->n_in, m->x, 8 * m->n_x);
}

int mace_state_check(MaceModel *m, const unsigned char *buffer, size_t size, int *phase, int *usable, char *err) {
    uint64_t header[3];
    double v;
    size_t k;
    if (size != mace_state_size(m) || memcmp(buffer, STATE_MAGIC, 8) != 0) {
        snprintf(err, MACE_ERR_LEN, "not an FMU state of this controller (%lu bytes)", (unsigned long)size);
        return -1;
    }
    memcpy(header, buffer + 8, sizeof(header));
    if (header[1] != m->n_in || header[2] != m->n_x || header[0] > 255) {
        snprintf(err, MACE_ERR_LEN, "not an FMU state of this controller (other dimensions or a damaged header)");
        return -1;
    }
    for (k = 0; k < 2 + m->n_in + m->n_x; k++) { /* time, origin, inputs, states: all finite */
        memcpy(&v, buffer + 32 + 8 * k, 8);
        if (!isfinite(v)) {
            snprintf(err, MACE_ERR_LEN, "a damaged FMU state (a non-finite time, input or state)");
            return -1;
        }
    }
    *phase = (int)header[0];
    *usable = 1; /* nothing to build */
    return 0;
}

int mace_state_load(MaceModel *m, const unsigned char *buffer, size_t size, int *phase, char *err) {
    int usable;
    if (mace_state_check(m, buffer, size, phase, &usable, err) != 0) return -1;
    memcpy(&m->time, buffer + 32, 8);
    memcpy(&m->origin, buffer + 40, 8);
    memcpy(m->u, buffer + 48, 8 * m->n_in);
    memcpy(m->x, buffer + 48 + 8 * m->n_in, 8 * m->n_x);
    m->y_valid = 0;
    return 0;
}
