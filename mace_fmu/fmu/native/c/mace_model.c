/* The model core of the MACE FMU runtime (see mace_model.h).
 *
 * mace_build follows mace_fmu.iomodel.parametric.ParametricSystem.build step by step:
 * reanalysis of the physical parameters (reanalysis.py), the modal structure block
 * (modal_core.py, with the zero-frequency cluster already reduced in the data), the Pade delay,
 * gain and PD blocks, and the interconnection of all blocks (modelica_like/algebra.py).
 */
#include "mace_model.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "mace_data.h"
#include "mace_resolve.h"
#include "mace_zoh.h"

#define ZERO_HZ 0.01 /* mace_fmu.iomodel.modal_core.ZERO_HZ */
#define TWO_PI (2.0 * 3.14159265358979323846)

enum { BLOCK_STRUCTURE = 0, BLOCK_CONST, BLOCK_DELAY, BLOCK_GAIN, BLOCK_PD };
enum { PARAM_DAMPING = 0, PARAM_DELAY, PARAM_GAIN, PARAM_PHYSICAL, PARAM_FREQUENCY_SCALE };
enum {
    COUNT_IN = 0, COUNT_OUT, COUNT_PAR, COUNT_MODES, COUNT_FLEX, COUNT_BLOCKS, COUNT_PADE, COUNT_STATES,
    COUNT_SO, COUNT_MS, COUNT_PHYS, COUNT_UB, COUNT_YB, COUNT_CORR, COUNT_MASSIVE, N_COUNTS
};
enum { INFO_KIND = 0, INFO_NX, INFO_NU, INFO_NY, INFO_P0, INFO_P1, N_INFO };

/* A sparse matrix in compressed rows (CSR): row i holds val[ptr[i] .. ptr[i + 1]) at columns col[...]. */
typedef struct MaceCsr {
    size_t rows;
    size_t *ptr, *col;
    double *val;
} MaceCsr;

#define MODEL_FORMAT 3 /* mace_fmu.fmu.native.resource.MODEL_FORMAT: 2 added the static corrections, 3 the masses */

static const char STATE_MAGIC[8] = {'M', 'A', 'C', 'E', 'S', 'T', 'A', '1'};
#define STATE_HEADER 7 /* magic, phase, built, coordinates, n_par, n_in, n */

struct MaceModel {
    MaceAlloc al;
    MaceKind kind;
    MaceFile file;
    size_t n_in, n_out, n_par, n_modes, n_flex, n_blocks, pade, n, n_phys;
    size_t n_corr, n_massive; /* static-correction vectors of the reanalysis; the first n_massive carry mass */
    size_t n_structure_inputs, n_structure_outputs; /* the structure block's actuator and sensor rows */
    size_t n_block_inputs, n_block_outputs;         /* all blocks' inputs and outputs, stacked */
    const double *par_nominal, *par_min, *par_max, *freq0, *dk, *wiring, *entry, *exit_, *modal_b, *rows;
    /* the static corrections (mace_fmu/iomodel/stiffness_route.py): W^T K0 W, W^T dK_i W, W^T dK_i Phi0 over the
       flexible modes, their modal inputs and structure output rows; the preload's shape changes per parameter */
    const double *corr_k, *corr_dk, *corr_coupling, *corr_b, *corr_rows, *pre_rows, *pre_b;
    /* the mass parameters' mass changes (zero for a stiffness): Phi0^T dM_i Phi0, W^T dM_i W, W^T dM_i Phi0 */
    const double *dm, *corr_dm, *corr_mass_coupling;
    const int64_t *par_kind, *par_index, *block_info, *flex, *keep_disp, *keep_rate, *row_kind, *me_order;
    /* the state vector's order: model exchange s[i] = x[perm[i]] (me_order of the data: dense-LU friendly),
       pos its inverse; co-simulation: the identity (its stepping coordinates are the zero-order hold's) */
    size_t *perm, *pos;
    const double **blk;   /* 4 per block: A, B, C, D of a constant block */
    const char **names;   /* inputs, outputs, parameters */
    const char *guid;     /* of the FMU the data belong to */
    size_t *damping_of;   /* parameter index of each mode's damping ratio */
    size_t *scale_of;     /* parameter index of each mode's frequency scale (n_par: none) */
    double *params, *built_params, *freq, *u;
    double *rel; /* relative change of each physical parameter in the last reanalysis */
    /* the structure solved again for the physical parameters (mace_resolve.h), when the data carry it: the FE
       data, each structure output's influence row and the actuators' load vectors on every DOF; the last
       re-solve's flexible modes projected on them */
    int resolvable, resolved, rs_cached;
    RsNominalBars rs_nominal; /* the re-solve's bars at the nominal state (mace_resolve.h) */
    RsStructure rs;
    const double *rs_struct_rows, *rs_inputs;
    double *rs_freq, *rs_shapes, *rs_rows, *rs_b;
    double *rs_rel; /* the relative changes the last re-solve was of (rs_cached: its results are in rs_*) */
    int built, y_valid, x_valid;
    int params_changed; /* set since the last build */
    double time;
    double *a, *b, *c, *d; /* the continuous system of the last build */
    MaceZoh *zoh;          /* co-simulation: the step; model exchange: the states' nominal values */
    double *nominal;       /* of the states, for model exchange solvers */
    double *s;             /* co-simulation: stepping coordinates; model exchange: x */
    double *x, *y;
    /* the block diagram of the last build, sparse, for the derivatives and their directional
       derivatives: dx = A_b x + B_b u_b with u_b = W [wiring | entry] [C_b x; u], W = (I - wiring D_b)^-1 */
    MaceCsr ab, bb, cb, wq;
    double *zb;                             /* n_block_outputs + n_in: C_b x, then the inputs */
    double *ub;                             /* n_block_inputs: the blocks' inputs */
    double *dir_x, *dir_u, *dir_dx, *dir_dy; /* directional derivatives: seeds and results */
};

/* struct_row_kind: what a structure output reads (mace_fmu/fmu/native/resource.py) */
#define ROW_DISPLACEMENT 0
#define ROW_RATE 1
#define ROW_ACCELERATION 2

/* ---- sparse matrices ------------------------------------------------------------------------ */

static void csr_free(const MaceAlloc *al, MaceCsr *s) {
    al->free(s->ptr);
    al->free(s->col);
    al->free(s->val);
    memset(s, 0, sizeof(*s));
}

/* s <- the nonzero entries of a (rows x cols, row-major), row i of s being row rp[i] of a and column j
 * column cp[j] (rp, cp: NULL for none); -1 if memory runs out. */
static int csr_from_dense(const MaceAlloc *al, const double *a, size_t rows, size_t cols, const size_t *rp,
                          const size_t *cp, MaceCsr *s) {
    size_t i, j, nnz = 0;
    csr_free(al, s);
    for (i = 0; i < rows * cols; i++) nnz += a[i] != 0.0;
    s->ptr = (size_t *)al->calloc(rows + 1, sizeof(size_t));
    s->col = (size_t *)al->calloc(nnz + 1, sizeof(size_t));
    s->val = (double *)al->calloc(nnz + 1, sizeof(double));
    if (!s->ptr || !s->col || !s->val) {
        csr_free(al, s);
        return -1;
    }
    s->rows = rows;
    nnz = 0;
    for (i = 0; i < rows; i++) {
        const double *row = a + (rp ? rp[i] : i) * cols;
        for (j = 0; j < cols; j++) {
            const double v = row[cp ? cp[j] : j];
            if (v != 0.0) {
                s->col[nnz] = j;
                s->val[nnz++] = v;
            }
        }
        s->ptr[i + 1] = nnz;
    }
    return 0;
}

/* y = s x (accumulate = 0) or y += s x (accumulate = 1). */
static void csr_apply(const MaceCsr *s, const double *x, double *y, int accumulate) {
    size_t i, k;
    for (i = 0; i < s->rows; i++) {
        double acc = accumulate ? y[i] : 0.0;
        for (k = s->ptr[i]; k < s->ptr[i + 1]; k++) acc += s->val[k] * x[s->col[k]];
        y[i] = acc;
    }
}

/* ---- creation -------------------------------------------------------------------------------- */

static const void *entry_1d(MaceModel *m, const char *name, unsigned type, size_t n, char *err) {
    return mace_file_get(&m->file, name, type, 1, &n, err);
}

static const void *entry_2d(MaceModel *m, const char *name, unsigned type, size_t r, size_t c, char *err) {
    size_t dims[2];
    dims[0] = r;
    dims[1] = c;
    return mace_file_get(&m->file, name, type, 2, dims, err);
}

/* The counts of the data file: how many inputs, outputs, parameters, modes, blocks and states. */
static int load_counts(MaceModel *m, const char *resource_dir, char *err) {
    char path[4096];
    size_t k, count_dims = N_COUNTS;
    const int64_t *counts, *version;
    if (mace_resource_read(&m->file, resource_dir, &m->al, path, sizeof(path), err) != 0) return -1;
    if (!(version = (const int64_t *)entry_1d(m, "format_version", MACE_I64, 1, err))) return -1;
    if (version[0] != MODEL_FORMAT) {
        snprintf(err, MACE_ERR_LEN, "%.900s: data format %lld, this runtime reads format %d", path,
                 (long long)version[0], MODEL_FORMAT);
        return -1;
    }
    if (!(counts = (const int64_t *)mace_file_get(&m->file, "counts", MACE_I64, 1, &count_dims, err))) return -1;
    for (k = 0; k < N_COUNTS; k++) {
        if (counts[k] < 0 || counts[k] > 1000000) {
            snprintf(err, MACE_ERR_LEN, "%.900s: count %lu out of range", path, (unsigned long)k);
            return -1;
        }
    }
    m->n_in = (size_t)counts[COUNT_IN];
    m->n_out = (size_t)counts[COUNT_OUT];
    m->n_par = (size_t)counts[COUNT_PAR];
    m->n_modes = (size_t)counts[COUNT_MODES];
    m->n_flex = (size_t)counts[COUNT_FLEX];
    m->n_blocks = (size_t)counts[COUNT_BLOCKS];
    m->pade = (size_t)counts[COUNT_PADE];
    m->n = (size_t)counts[COUNT_STATES];
    m->n_structure_outputs = (size_t)counts[COUNT_SO];
    m->n_structure_inputs = (size_t)counts[COUNT_MS];
    m->n_phys = (size_t)counts[COUNT_PHYS];
    m->n_block_inputs = (size_t)counts[COUNT_UB];
    m->n_block_outputs = (size_t)counts[COUNT_YB];
    m->n_corr = (size_t)counts[COUNT_CORR];
    m->n_massive = (size_t)counts[COUNT_MASSIVE];
    if (m->pade < 1 || m->pade > 10 || m->n_flex > m->n_modes || m->n_massive > m->n_corr) {
        snprintf(err, MACE_ERR_LEN, "%.900s: inconsistent counts", path);
        return -1;
    }
    return 0;
}

/* The static corrections and the preload's shape changes (sizes from the counts). */
static int load_corrections(MaceModel *m, char *err) {
    const size_t nc = m->n_corr, nf = m->n_flex, np = m->n_phys, so = m->n_structure_outputs;
    const size_t si = m->n_structure_inputs;
    size_t dims[3];
    dims[0] = np;
    dims[1] = dims[2] = nc;
    if (!(m->corr_dk = (const double *)mace_file_get(&m->file, "correction_dk", MACE_F64, 3, dims, err))) return -1;
    dims[2] = nf;
    if (!(m->corr_coupling = (const double *)mace_file_get(&m->file, "correction_coupling", MACE_F64, 3, dims, err)))
        return -1;
    if (!(m->corr_mass_coupling = (const double *)mace_file_get(&m->file, "correction_mass_coupling", MACE_F64, 3,
                                                                 dims, err)))
        return -1;
    dims[2] = nc;
    if (!(m->corr_dm = (const double *)mace_file_get(&m->file, "correction_dm", MACE_F64, 3, dims, err))) return -1;
    dims[2] = nf;
    dims[1] = so;
    if (!(m->pre_rows = (const double *)mace_file_get(&m->file, "preload_rows", MACE_F64, 3, dims, err))) return -1;
    dims[1] = nf;
    dims[2] = si;
    if (!(m->pre_b = (const double *)mace_file_get(&m->file, "preload_b", MACE_F64, 3, dims, err))) return -1;
    if (!(m->corr_k = (const double *)entry_2d(m, "correction_stiffness", MACE_F64, nc, nc, err)) ||
        !(m->corr_b = (const double *)entry_2d(m, "correction_b", MACE_F64, nc, si, err)) ||
        !(m->corr_rows = (const double *)entry_2d(m, "correction_rows", MACE_F64, so, nc, err)))
        return -1;
    return 0;
}

/* The arrays of the model data (sizes from the counts); every structure row says what it reads. */
static int load_arrays(MaceModel *m, char *err) {
    size_t k, dims[3];
    dims[0] = m->n_phys;
    dims[1] = dims[2] = m->n_flex;
    if (!(m->par_nominal = (const double *)entry_1d(m, "param_nominal", MACE_F64, m->n_par, err)) ||
        !(m->par_min = (const double *)entry_1d(m, "param_min", MACE_F64, m->n_par, err)) ||
        !(m->par_max = (const double *)entry_1d(m, "param_max", MACE_F64, m->n_par, err)) ||
        !(m->par_kind = (const int64_t *)entry_1d(m, "param_kind", MACE_I64, m->n_par, err)) ||
        !(m->par_index = (const int64_t *)entry_1d(m, "param_index", MACE_I64, m->n_par, err)) ||
        !(m->freq0 = (const double *)entry_1d(m, "frequencies_hz", MACE_F64, m->n_modes, err)) ||
        !(m->dk = (const double *)mace_file_get(&m->file, "physical_dk", MACE_F64, 3, dims, err)) ||
        !(m->dm = (const double *)mace_file_get(&m->file, "physical_dm", MACE_F64, 3, dims, err)) ||
        !(m->block_info = (const int64_t *)entry_2d(m, "block_info", MACE_I64, m->n_blocks, N_INFO, err)) ||
        !(m->wiring = (const double *)entry_2d(m, "wiring", MACE_F64, m->n_block_inputs, m->n_block_outputs, err)) ||
        !(m->entry = (const double *)entry_2d(m, "entry", MACE_F64, m->n_block_inputs, m->n_in, err)) ||
        !(m->exit_ = (const double *)entry_2d(m, "exit", MACE_F64, m->n_out, m->n_block_outputs, err)) ||
        !(m->modal_b = (const double *)entry_2d(m, "modal_b", MACE_F64, m->n_modes, m->n_structure_inputs, err)) ||
        !(m->rows = (const double *)entry_2d(m, "struct_rows", MACE_F64, m->n_structure_outputs, m->n_modes, err)) ||
        !(m->row_kind = (const int64_t *)entry_1d(m, "struct_row_kind", MACE_I64, m->n_structure_outputs, err)) ||
        !(m->keep_disp = (const int64_t *)entry_1d(m, "keep_disp", MACE_I64, m->n_modes, err)) ||
        !(m->keep_rate = (const int64_t *)entry_1d(m, "keep_rate", MACE_I64, m->n_modes, err)) ||
        !(m->flex = (const int64_t *)entry_1d(m, "flexible", MACE_I64, m->n_flex, err)) ||
        !(m->me_order = (const int64_t *)entry_1d(m, "me_order", MACE_I64, m->n, err)) ||
        load_corrections(m, err))
        return -1;
    for (k = 0; k < m->n_structure_outputs; k++) {
        if (m->row_kind[k] < ROW_DISPLACEMENT || m->row_kind[k] > ROW_ACCELERATION) {
            snprintf(err, MACE_ERR_LEN, "model data: structure output %lu reads an unknown quantity",
                     (unsigned long)k);
            return -1;
        }
    }
    return 0;
}

/* The optional re-solve data (mace_fmu/fmu/native/resource.py, resolve_*): absent, the reanalysis serves. */
enum {
    RS_LARGE = 0, RS_DOF, RS_GRID, RS_BAR, RS_SPRING, RS_STATIC, RS_MODAL, RS_ZERO, RS_COUNT, RS_MASS_NNZ, RS_DM_NNZ,
    RS_OTHER_NNZ, RS_STATIC_NNZ, RS_MODAL_NNZ, N_RS_COUNTS
};

static int load_triplets(MaceModel *m, const char *key, size_t nnz, RsTriplets *t, char *err) {
    char name[64];
    t->nnz = nnz;
    snprintf(name, sizeof(name), "resolve_%s_rows", key);
    if (!(t->rows = (const int64_t *)entry_1d(m, name, MACE_I64, nnz, err))) return -1;
    snprintf(name, sizeof(name), "resolve_%s_cols", key);
    if (!(t->cols = (const int64_t *)entry_1d(m, name, MACE_I64, nnz, err))) return -1;
    snprintf(name, sizeof(name), "resolve_%s_vals", key);
    if (!(t->vals = (const double *)entry_1d(m, name, MACE_F64, nnz, err))) return -1;
    return 0;
}

/* Every index of the re-solve data inside its bounds, so that a damaged file cannot make the runtime read or
   write outside its arrays. */
static int check_triplets(const RsTriplets *t, size_t rows, size_t cols) {
    size_t e;
    for (e = 0; e < t->nnz; e++)
        if (t->rows[e] < 0 || (size_t)t->rows[e] >= rows || t->cols[e] < 0 || (size_t)t->cols[e] >= cols) return -1;
    return 0;
}

static int load_resolve(MaceModel *m, char *err) {
    size_t dims = N_RS_COUNTS, k, n;
    const int64_t *c;
    RsStructure *s = &m->rs;
    if (!mace_file_has(&m->file, "resolve_counts")) return 0;
    if (!(c = (const int64_t *)mace_file_get(&m->file, "resolve_counts", MACE_I64, 1, &dims, err))) return -1;
    for (k = 0; k < N_RS_COUNTS; k++)
        if (c[k] < 0 || c[k] > 100000000) {
            snprintf(err, MACE_ERR_LEN, "model data: re-solve count %lu out of range", (unsigned long)k);
            return -1;
        }
    s->large_preload = c[RS_LARGE] != 0;
    n = s->n_dof = (size_t)c[RS_DOF];
    s->n_grid = (size_t)c[RS_GRID];
    s->n_bar = (size_t)c[RS_BAR];
    s->n_spring = (size_t)c[RS_SPRING];
    s->n_static = (size_t)c[RS_STATIC];
    s->n_modal = (size_t)c[RS_MODAL];
    s->n_zero = (size_t)c[RS_ZERO];
    s->count = (size_t)c[RS_COUNT];
    s->n_flex = m->n_flex;
    s->n_phys = m->n_phys;
    s->zero_hz = ZERO_HZ;
    if (n != 6 * s->n_grid || s->count < s->n_flex + s->n_zero || s->n_static > n || s->n_modal > n) {
        snprintf(err, MACE_ERR_LEN, "model data: inconsistent re-solve counts");
        return -1;
    }
    if (!(s->bar_nodes = (const int64_t *)entry_2d(m, "resolve_bar_nodes", MACE_I64, s->n_bar, 2, err)) ||
        !(s->frames0 = (const double *)entry_2d(m, "resolve_frames0", MACE_F64, s->n_bar, 9, err)) ||
        !(s->lengths0 = (const double *)entry_1d(m, "resolve_lengths0", MACE_F64, s->n_bar, err)) ||
        !(s->k_natural = (const double *)entry_2d(m, "resolve_k_natural", MACE_F64, s->n_bar, 49, err)) ||
        !(s->bar_param = (const int64_t *)entry_1d(m, "resolve_bar_param", MACE_I64, s->n_bar, err)) ||
        !(s->spring_vectors = (const double *)entry_2d(m, "resolve_spring_vectors", MACE_F64, s->n_spring, n, err)) ||
        !(s->spring_k = (const double *)entry_1d(m, "resolve_spring_k", MACE_F64, s->n_spring, err)) ||
        !(s->spring_param = (const int64_t *)entry_1d(m, "resolve_spring_param", MACE_I64, s->n_spring, err)) ||
        load_triplets(m, "mass", (size_t)c[RS_MASS_NNZ], &s->mass, err) ||
        load_triplets(m, "dm", (size_t)c[RS_DM_NNZ], &s->dm, err) ||
        !(s->dm_part = (const int64_t *)entry_1d(m, "resolve_dm_part", MACE_I64, (size_t)c[RS_DM_NNZ], err)) ||
        load_triplets(m, "other", (size_t)c[RS_OTHER_NNZ], &s->other, err) ||
        load_triplets(m, "static_t", (size_t)c[RS_STATIC_NNZ], &s->static_t, err) ||
        load_triplets(m, "modal_t", (size_t)c[RS_MODAL_NNZ], &s->modal_t, err) ||
        !(s->gravity = (const double *)entry_1d(m, "resolve_gravity", MACE_F64, n, err)) ||
        !(s->load = (const double *)entry_1d(m, "resolve_load", MACE_F64, n, err)) ||
        !(s->displacements = (const double *)entry_1d(m, "resolve_displacements", MACE_F64, n, err)) ||
        !(s->positions = (const double *)entry_2d(m, "resolve_positions", MACE_F64, s->n_grid, 3, err)) ||
        !(s->rotations = (const double *)entry_2d(m, "resolve_rotations", MACE_F64, s->n_grid, 9, err)) ||
        !(s->reference = (const double *)entry_2d(m, "resolve_reference", MACE_F64, n, m->n_flex, err)) ||
        !(s->reference_norm = (const double *)entry_1d(m, "resolve_reference_norm", MACE_F64, m->n_flex, err)) ||
        !(m->rs_struct_rows = (const double *)entry_2d(m, "resolve_struct_rows", MACE_F64, m->n_structure_outputs, n,
                                                       err)) ||
        !(m->rs_inputs = (const double *)entry_2d(m, "resolve_inputs", MACE_F64, n, m->n_structure_inputs, err)))
        return -1;
    for (k = 0; k < s->n_bar; k++)
        if (s->bar_nodes[2 * k] < 0 || (size_t)s->bar_nodes[2 * k] >= s->n_grid || s->bar_nodes[2 * k + 1] < 0 ||
            (size_t)s->bar_nodes[2 * k + 1] >= s->n_grid || s->bar_param[k] < -1 || s->bar_param[k] >= (int64_t)m->n_phys)
            goto bad;
    for (k = 0; k < s->n_spring; k++)
        if (s->spring_param[k] < -1 || s->spring_param[k] >= (int64_t)m->n_phys) goto bad;
    for (k = 0; k < s->dm.nnz; k++)
        if (s->dm_part[k] < 0 || s->dm_part[k] >= (int64_t)m->n_phys) goto bad;
    if (check_triplets(&s->mass, n, n) || check_triplets(&s->dm, n, n) || check_triplets(&s->other, n, n) ||
        check_triplets(&s->static_t, n, s->n_static) || check_triplets(&s->modal_t, n, s->n_modal))
        goto bad;
    m->rs_freq = ml_zeros(&m->al, m->n_flex);
    m->rs_shapes = ml_zeros(&m->al, n * m->n_flex);
    m->rs_rows = ml_zeros(&m->al, m->n_structure_outputs * m->n_flex);
    m->rs_b = ml_zeros(&m->al, m->n_flex * m->n_structure_inputs);
    m->rs_rel = ml_zeros(&m->al, m->n_phys);
    m->rs_nominal.bars = ml_zeros(&m->al, s->n_bar * RS_BAR_TERMS);
    s->nominal = &m->rs_nominal;
    if (!m->rs_freq || !m->rs_shapes || !m->rs_rows || !m->rs_b || !m->rs_rel || !m->rs_nominal.bars) {
        snprintf(err, MACE_ERR_LEN, "out of memory loading the re-solve data");
        return -1;
    }
    m->resolvable = 1;
    return 0;
bad:
    snprintf(err, MACE_ERR_LEN, "model data: a re-solve index out of range");
    return -1;
}

/* The state order: model exchange s[i] = x[perm[i]], co-simulation the identity. */
static int load_state_order(MaceModel *m, char *err) {
    size_t k;
    m->perm = (size_t *)m->al.calloc(m->n + 1, sizeof(size_t));
    m->pos = (size_t *)m->al.calloc(m->n + 1, sizeof(size_t));
    if (!m->perm || !m->pos) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        return -1;
    }
    for (k = 0; k < m->n; k++) m->pos[k] = m->n; /* unset */
    for (k = 0; k < m->n; k++) {
        const int64_t q = m->kind == MACE_MODEL_EXCHANGE ? m->me_order[k] : (int64_t)k;
        if (q < 0 || (size_t)q >= m->n || m->pos[q] != m->n) {
            snprintf(err, MACE_ERR_LEN, "model data: the model-exchange state order is not a permutation");
            return -1;
        }
        m->perm[k] = (size_t)q;
        m->pos[q] = k;
    }
    return 0;
}

/* Names, and which parameter is each mode's damping ratio and frequency scale. */
static int load_parameters(MaceModel *m, char *err) {
    size_t k;
    m->names = (const char **)m->al.calloc(m->n_in + m->n_out + m->n_par + 1, sizeof(char *));
    m->blk = (const double **)m->al.calloc(4 * m->n_blocks + 1, sizeof(double *));
    m->damping_of = (size_t *)m->al.calloc(m->n_modes + 1, sizeof(size_t));
    m->scale_of = (size_t *)m->al.calloc(m->n_modes + 1, sizeof(size_t));
    if (!m->names || !m->blk || !m->damping_of || !m->scale_of) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        return -1;
    }
    if (mace_file_strings(&m->file, "guid", 1, &m->guid, err) ||
        mace_file_strings(&m->file, "input_names", m->n_in, m->names, err) ||
        mace_file_strings(&m->file, "output_names", m->n_out, m->names + m->n_in, err) ||
        mace_file_strings(&m->file, "param_names", m->n_par, m->names + m->n_in + m->n_out, err))
        return -1;
    for (k = 0; k < m->n_modes; k++) m->damping_of[k] = m->scale_of[k] = m->n_par;
    for (k = 0; k < m->n_par; k++) {
        const int64_t kind = m->par_kind[k], index = m->par_index[k];
        if (kind == PARAM_DAMPING && index >= 0 && (size_t)index < m->n_modes) {
            m->damping_of[index] = k;
        } else if (kind == PARAM_FREQUENCY_SCALE && index >= 0 && (size_t)index < m->n_modes) {
            m->scale_of[index] = k;
        } else if (kind == PARAM_FREQUENCY_SCALE) {
            snprintf(err, MACE_ERR_LEN, "model data: frequency scale %lu names no mode", (unsigned long)k);
            return -1;
        } else if (kind == PARAM_PHYSICAL && !(index >= 0 && (size_t)index < m->n_phys)) {
            snprintf(err, MACE_ERR_LEN, "model data: physical parameter %lu has no sensitivity", (unsigned long)k);
            return -1;
        } else if (kind < PARAM_DAMPING || kind > PARAM_FREQUENCY_SCALE) {
            snprintf(err, MACE_ERR_LEN, "model data: parameter %lu has the unknown kind %lld", (unsigned long)k,
                     (long long)kind);
            return -1;
        }
    }
    for (k = 0; k < m->n_modes; k++) {
        if (m->damping_of[k] == m->n_par) {
            snprintf(err, MACE_ERR_LEN, "model data: mode %lu has no damping parameter", (unsigned long)(k + 1));
            return -1;
        }
    }
    for (k = 0; k < m->n_flex; k++) {
        if (m->flex[k] < 0 || (size_t)m->flex[k] >= m->n_modes) {
            snprintf(err, MACE_ERR_LEN, "model data: flexible mode index out of range");
            return -1;
        }
    }
    return 0;
}

/* Each block's kind, sizes and parameters (constant blocks: their matrices), and that they add up. */
static int load_blocks(MaceModel *m, char *err) {
    size_t k, sum_x = 0, sum_u = 0, sum_y = 0;
    for (k = 0; k < m->n_blocks; k++) {
        const int64_t *info = m->block_info + k * N_INFO;
        const size_t nx = (size_t)info[INFO_NX], nu = (size_t)info[INFO_NU], ny = (size_t)info[INFO_NY];
        int ok = info[INFO_NX] >= 0 && info[INFO_NU] >= 0 && info[INFO_NY] >= 0;
        switch (info[INFO_KIND]) {
            case BLOCK_STRUCTURE: ok = ok && nu == m->n_structure_inputs && ny == m->n_structure_outputs; break;
            case BLOCK_DELAY: ok = ok && nx == m->pade && nu == 1 && ny == 1 && info[INFO_P0] >= 0; break;
            case BLOCK_GAIN: ok = ok && nx == 0 && nu == 1 && ny == 1 && info[INFO_P0] >= 0; break;
            case BLOCK_PD: ok = ok && nx == 0 && nu == 2 && ny == 1 && info[INFO_P0] >= 0 && info[INFO_P1] >= 0; break;
            case BLOCK_CONST: {
                char name[64];
                const size_t shapes[4][2] = {{nx, nx}, {nx, nu}, {ny, nx}, {ny, nu}};
                int q;
                for (q = 0; q < 4 && ok; q++) {
                    snprintf(name, sizeof(name), "block%lu_%c", (unsigned long)k, "ABCD"[q]);
                    m->blk[4 * k + q] = (const double *)entry_2d(m, name, MACE_F64, shapes[q][0], shapes[q][1], err);
                    if (!m->blk[4 * k + q]) return -1;
                }
                break;
            }
            default: ok = 0;
        }
        if (ok && (info[INFO_P0] >= (int64_t)m->n_par || info[INFO_P1] >= (int64_t)m->n_par)) ok = 0;
        if (!ok) {
            snprintf(err, MACE_ERR_LEN, "model data: block %lu is inconsistent", (unsigned long)k);
            return -1;
        }
        sum_x += nx;
        sum_u += nu;
        sum_y += ny;
    }
    {
        size_t structure_states = 0;
        for (k = 0; k < m->n_modes; k++) structure_states += (size_t)(m->keep_disp[k] != 0) + (m->keep_rate[k] != 0);
        for (k = 0; k < m->n_blocks; k++)
            if (m->block_info[k * N_INFO + INFO_KIND] == BLOCK_STRUCTURE &&
                (size_t)m->block_info[k * N_INFO + INFO_NX] != structure_states)
                sum_x = m->n + 1;
    }
    if (sum_x != m->n || sum_u != m->n_block_inputs || sum_y != m->n_block_outputs) {
        snprintf(err, MACE_ERR_LEN, "model data: block sizes do not add up to the system's");
        return -1;
    }
    return 0;
}

static int load(MaceModel *m, const char *resource_dir, char *err) {
    if (load_counts(m, resource_dir, err) || load_arrays(m, err) || load_state_order(m, err) ||
        load_parameters(m, err) || load_blocks(m, err) || load_resolve(m, err))
        return -1;
    return 0;
}

MaceModel *mace_create(const char *resource_dir, MaceKind kind, const MaceAlloc *al, char *err) {
    MaceModel *m = (MaceModel *)al->calloc(1, sizeof(MaceModel));
    if (!m) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        return NULL;
    }
    m->al = *al;
    m->al.work = ml_work_create(al);
    m->kind = kind;
    if (load(m, resource_dir, err) != 0) {
        mace_destroy(m);
        return NULL;
    }
    m->params = ml_zeros(al, m->n_par);
    m->built_params = ml_zeros(al, m->n_par);
    m->freq = ml_zeros(al, m->n_modes);
    m->rel = ml_zeros(al, m->n_phys);
    m->u = ml_zeros(al, m->n_in);
    m->a = ml_zeros(al, m->n * m->n);
    m->b = ml_zeros(al, m->n * m->n_in);
    m->c = ml_zeros(al, m->n_out * m->n);
    m->d = ml_zeros(al, m->n_out * m->n_in);
    m->s = ml_zeros(al, m->n);
    m->x = ml_zeros(al, m->n);
    m->y = ml_zeros(al, m->n_out);
    m->nominal = ml_zeros(al, m->n);
    m->zb = ml_zeros(al, m->n_block_outputs + m->n_in);
    m->ub = ml_zeros(al, m->n_block_inputs);
    m->dir_x = ml_zeros(al, m->n);
    m->dir_u = ml_zeros(al, m->n_in);
    m->dir_dx = ml_zeros(al, m->n);
    m->dir_dy = ml_zeros(al, m->n_out);
    m->zoh = zoh_create(&m->al, m->n, m->n_in, m->n_out); /* its work arrays are the model's */
    if (!m->params || !m->built_params || !m->freq || !m->rel || !m->u || !m->a || !m->b || !m->c || !m->d || !m->s || !m->x ||
        !m->y || !m->nominal || !m->zb || !m->ub || !m->dir_x || !m->dir_u || !m->dir_dx || !m->dir_dy || !m->zoh ||
        !m->al.work) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        mace_destroy(m);
        return NULL;
    }
    mace_reset(m);
    return m;
}

void mace_destroy(MaceModel *m) {
    if (!m) return;
    zoh_destroy(m->zoh);
    mace_file_free(&m->file, &m->al);
    m->al.free(m->names);
    m->al.free(m->perm);
    m->al.free(m->pos);
    m->al.free(m->blk);
    m->al.free(m->damping_of);
    m->al.free(m->scale_of);
    m->al.free(m->params);
    m->al.free(m->built_params);
    m->al.free(m->freq);
    m->al.free(m->rel);
    m->al.free(m->rs_freq);
    m->al.free(m->rs_shapes);
    m->al.free(m->rs_rows);
    m->al.free(m->rs_b);
    m->al.free(m->rs_rel);
    m->al.free(m->rs_nominal.bars);
    m->al.free(m->u);
    m->al.free(m->a);
    m->al.free(m->b);
    m->al.free(m->c);
    m->al.free(m->d);
    m->al.free(m->s);
    m->al.free(m->x);
    m->al.free(m->y);
    m->al.free(m->nominal);
    m->al.free(m->zb);
    m->al.free(m->ub);
    m->al.free(m->dir_x);
    m->al.free(m->dir_u);
    m->al.free(m->dir_dx);
    m->al.free(m->dir_dy);
    csr_free(&m->al, &m->ab);
    csr_free(&m->al, &m->bb);
    csr_free(&m->al, &m->cb);
    csr_free(&m->al, &m->wq);
    ml_work_destroy(&m->al, m->al.work);
    m->al.free(m);
}

void mace_reset(MaceModel *m) {
    memcpy(m->params, m->par_nominal, m->n_par * sizeof(double));
    m->params_changed = 1;
    memset(m->u, 0, m->n_in * sizeof(double));
    memset(m->s, 0, m->n * sizeof(double));
    m->time = 0.0;
    m->y_valid = m->x_valid = 0;
}

/* ---- variables ------------------------------------------------------------------------------ */

MaceGroup mace_variable(const MaceModel *m, unsigned long long vr, size_t *index) {
    const size_t sizes[7] = {m->n_in, m->n_out, m->n_par, m->n_modes, m->n, m->n, 1};
    int g;
    for (g = 0; g < 7; g++) {
        if (vr < sizes[g]) {
            *index = (size_t)vr;
            return (MaceGroup)g;
        }
        vr -= sizes[g];
    }
    return MACE_VAR_UNKNOWN;
}

const char *mace_name(const MaceModel *m, MaceGroup group, size_t index) {
    switch (group) {
        case MACE_VAR_INPUT: return index < m->n_in ? m->names[index] : "?";
        case MACE_VAR_OUTPUT: return index < m->n_out ? m->names[m->n_in + index] : "?";
        case MACE_VAR_PARAMETER: return index < m->n_par ? m->names[m->n_in + m->n_out + index] : "?";
        case MACE_VAR_FREQUENCY: return "frequency_mode_<k>";
        case MACE_VAR_STATE: return "a continuous state";
        case MACE_VAR_DERIVATIVE: return "a state derivative";
        case MACE_VAR_TIME: return "time";
        default: return "?";
    }
}

const char *mace_guid(const MaceModel *m) { return m->guid; }
size_t mace_n_states(const MaceModel *m) { return m->n; }
size_t mace_n_inputs(const MaceModel *m) { return m->n_in; }
size_t mace_n_outputs(const MaceModel *m) { return m->n_out; }
double mace_time(const MaceModel *m) { return m->time; }
int mace_fast_form(const MaceModel *m) { return m->zoh ? zoh_is_fast(m->zoh) : 0; }
double mace_fast_form_condition(const MaceModel *m) { return zoh_condition(m->zoh); }

void mace_set_input(MaceModel *m, size_t k, double value) {
    m->u[k] = value;
    m->y_valid = 0;
}

void mace_set_parameter(MaceModel *m, size_t k, double value) {
    m->params[k] = value;
    m->params_changed = 1;
}

/* ---- parameters ----------------------------------------------------------------------------- */

static int check_parameters(const MaceModel *m, char *err) {
    size_t k;
    for (k = 0; k < m->n_par; k++) {
        const double v = m->params[k], lo = m->par_min[k], hi = m->par_max[k];
        const char *name = m->names[m->n_in + m->n_out + k];
        if (!isfinite(v)) {
            snprintf(err, MACE_ERR_LEN, "parameter %s = %g is not a finite number", name, v);
            return -1;
        }
        /* the declared range is the whole check (mace_fmu.parameter_kinds): what the model
           description allows runs, what it does not is refused */
        if (v < lo || v > hi) {
            snprintf(err, MACE_ERR_LEN, "parameter %s = %.17g is outside its declared range [%.15g, %.15g]", name, v,
                     lo, hi);
            return -1;
        }
        if (m->par_kind[k] == PARAM_PHYSICAL && !(m->par_nominal[k] > 0.0)) {
            snprintf(err, MACE_ERR_LEN, "model data: physical parameter %s has no positive nominal value", name);
            return -1;
        }
    }
    return 0;
}

static double signed_omega2(double f) {
    const double w = TWO_PI * f;
    return (f > 0.0 ? 1.0 : (f < 0.0 ? -1.0 : 0.0)) * (w * w);
}

static double signed_frequency_hz(double w2) {
    const double sgn = w2 > 0.0 ? 1.0 : (w2 < 0.0 ? -1.0 : 0.0);
    return sgn * sqrt(fabs(w2)) / TWO_PI;
}

/* The reduced stiffness in the basis [flexible modes, corrections] (mace_fmu/iomodel/reanalysis.py):
 * Omega0^2 + sum p_i Phi0^T dK_i Phi0, the couplings sum p_i W^T dK_i Phi0 and W^T K0 W + sum p_i W^T dK_i W. */
static void reduced_stiffness(const MaceModel *m, double *k) {
    const size_t nf = m->n_flex, nc = m->n_corr, nt = nf + nc;
    size_t i, j, q;
    for (i = 0; i < nf; i++) k[i * nt + i] = signed_omega2(m->freq0[m->flex[i]]);
    for (i = 0; i < nc; i++)
        for (j = 0; j < nc; j++) k[(nf + i) * nt + nf + j] = m->corr_k[i * nc + j];
    for (q = 0; q < m->n_phys; q++) {
        const double r = m->rel[q], *dk = m->dk + q * nf * nf, *dw = m->corr_dk + q * nc * nc;
        const double *cw = m->corr_coupling + q * nc * nf;
        if (r == 0.0) continue;
        for (i = 0; i < nf; i++)
            for (j = 0; j < nf; j++) k[i * nt + j] += r * dk[i * nf + j];
        for (i = 0; i < nc; i++) {
            for (j = 0; j < nf; j++) {
                k[(nf + i) * nt + j] += r * cw[i * nf + j];
                k[j * nt + nf + i] += r * cw[i * nf + j];
            }
            for (j = 0; j < nc; j++) k[(nf + i) * nt + nf + j] += r * dw[i * nc + j];
        }
    }
    for (i = 0; i < nt; i++)
        for (j = 0; j < i; j++) k[i * nt + j] = k[j * nt + i] = 0.5 * (k[i * nt + j] + k[j * nt + i]);
}

/* The reduced mass in the same basis when a mass parameter changed (returns 1; 0: M_r = diag(I, I, 0) and mm is
 * untouched): diag(I over the modes and massive corrections, 0 over the massless ones) plus sum p_i of the
 * mass changes Phi0^T dM_i Phi0, W^T dM_i Phi0 and W^T dM_i W (mace_fmu/iomodel/reanalysis.py). */
static int reduced_mass(const MaceModel *m, double *mm) {
    const size_t nf = m->n_flex, nc = m->n_corr, nt = nf + nc, na = nf + m->n_massive;
    size_t i, j, q;
    int changed = 0;
    for (q = 0; q < m->n_phys && !changed; q++) {
        const double *dm = m->dm + q * nf * nf;
        if (m->rel[q] == 0.0) continue;
        for (i = 0; i < nf * nf; i++) changed |= dm[i] != 0.0;
    }
    if (!changed) return 0;
    memset(mm, 0, nt * nt * sizeof(double));
    for (i = 0; i < na; i++) mm[i * nt + i] = 1.0;
    for (q = 0; q < m->n_phys; q++) {
        const double r = m->rel[q], *dm = m->dm + q * nf * nf, *dw = m->corr_dm + q * nc * nc;
        const double *cw = m->corr_mass_coupling + q * nc * nf;
        if (r == 0.0) continue;
        for (i = 0; i < nf; i++)
            for (j = 0; j < nf; j++) mm[i * nt + j] += r * dm[i * nf + j];
        for (i = 0; i < nc; i++) {
            for (j = 0; j < nf; j++) {
                mm[(nf + i) * nt + j] += r * cw[i * nf + j];
                mm[j * nt + nf + i] += r * cw[i * nf + j];
            }
            for (j = 0; j < nc; j++) mm[(nf + i) * nt + nf + j] += r * dw[i * nc + j];
        }
    }
    for (i = 0; i < nt; i++)
        for (j = 0; j < i; j++) mm[i * nt + j] = mm[j * nt + i] = 0.5 * (mm[i * nt + j] + mm[j * nt + i]);
    return 1;
}

/* M_c = T^T M_r T, T = [I; -g] (g = K_zz^-1 K_za, the condensation of the massless corrections), na x na:
 * M_aa - M_az g + g^T h with h = M_zz g - M_za (nz x na, work space), O(nz^2 na + nz na^2). */
static void condensed_mass(const double *mm, const double *g, size_t na, size_t nz, double *h, double *mc) {
    const size_t nt = na + nz;
    size_t i, j, p, q;
    for (p = 0; p < nz; p++)
        for (j = 0; j < na; j++) {
            double acc = -mm[(na + p) * nt + j];
            for (q = 0; q < nz; q++) acc += mm[(na + p) * nt + na + q] * g[q * na + j];
            h[p * na + j] = acc;
        }
    for (i = 0; i < na; i++)
        for (j = 0; j < na; j++) {
            double acc = mm[i * nt + j];
            for (p = 0; p < nz; p++) acc += g[p * na + i] * h[p * na + j] - mm[i * nt + na + p] * g[p * na + j];
            mc[i * na + j] = acc;
        }
    for (i = 0; i < na; i++)
        for (j = 0; j < i; j++) mc[i * na + j] = mc[j * na + i] = 0.5 * (mc[i * na + j] + mc[j * na + i]);
}

/* New frequencies of all modes (m->freq) and the coefficients of the new flexible modes, coef
 * ((n_flex + n_corr) x n_flex, column k: new mode k over the nominal flexible modes and the
 * corrections); *changed = 0 means the identity. The massless corrections are condensed with the
 * changed stiffness; each new mode continues the nominal mode it overlaps most (one-to-one). Each
 * mode's frequency scale multiplies its frequency after the reanalysis (shapes unchanged). A mass change
 * makes it K_c v = omega^2 M_c v: with M_c = L L^T the standard problem L^-1 K_c L^-T y = omega^2 y, v = L^-T y
 * (mass-normalised in the changed mass), the overlaps scored on M_c v, omega^2 the Rayleigh quotient. */
static int reanalyse(MaceModel *m, double *coef, int *changed, char *err) {
    const size_t nf = m->n_flex, nc = m->n_corr, nt = nf + nc, na = nf + m->n_massive, nz = nt - na;
    double *k = NULL, *kc = NULL, *g = NULL, *lu = NULL, *w = NULL, *v = NULL, *score = NULL;
    double *mm = NULL, *mc = NULL, *kc0 = NULL, *h = NULL;
    size_t *col = NULL, *piv = NULL, i, j, q;
    int status = -1, massed = 0;
    *changed = 0;
    for (q = 0; q < m->n_par; q++) {
        if (m->par_kind[q] == PARAM_PHYSICAL) {
            m->rel[m->par_index[q]] = m->params[q] / m->par_nominal[q] - 1.0;
            if (m->rel[m->par_index[q]] != 0.0) *changed = 1;
        }
    }
    for (i = 0; i < m->n_modes; i++) m->freq[i] = signed_frequency_hz(signed_omega2(m->freq0[i]));
    m->resolved = 0;
    if (*changed && m->resolvable) { /* the structure solved again; its modes projected on the instruments */
        const size_t nd = m->rs.n_dof, so = m->n_structure_outputs, si = m->n_structure_inputs;
        int iterations;
        /* the re-solve is a function of the physical parameters alone: the same values (an update's several
           tests, a run repeated after a reset) take the last one's result, which is what solving again gives */
        if (!m->rs_cached || memcmp(m->rs_rel, m->rel, m->n_phys * sizeof(double)) != 0) {
            m->rs_cached = 0;
            if (rs_flexible_modes(&m->al, &m->rs, m->rel, m->rs_freq, m->rs_shapes, &iterations, err) != 0) goto done;
            for (i = 0; i < so; i++)
                for (j = 0; j < nf; j++) {
                    double acc = 0.0;
                    for (q = 0; q < nd; q++) acc += m->rs_struct_rows[i * nd + q] * m->rs_shapes[q * nf + j];
                    m->rs_rows[i * nf + j] = acc;
                }
            for (j = 0; j < nf; j++)
                for (i = 0; i < si; i++) {
                    double acc = 0.0;
                    for (q = 0; q < nd; q++) acc += m->rs_shapes[q * nf + j] * m->rs_inputs[q * si + i];
                    m->rs_b[j * si + i] = acc;
                }
            memcpy(m->rs_rel, m->rel, m->n_phys * sizeof(double));
            m->rs_cached = 1;
        }
        for (i = 0; i < nf; i++) m->freq[m->flex[i]] = m->rs_freq[i];
        m->resolved = 1;
    } else if (*changed) {
        k = ml_work(&m->al, nt * nt);
        kc = ml_work(&m->al, na * na);
        g = ml_work(&m->al, nz * na);
        lu = ml_work(&m->al, nz * nz);
        w = ml_work(&m->al, na);
        v = ml_work(&m->al, na * na);
        score = ml_work(&m->al, na * na);
        col = (size_t *)m->al.calloc(na + 1, sizeof(size_t));
        piv = (size_t *)m->al.calloc(nz + 1, sizeof(size_t));
        mm = ml_work(&m->al, nt * nt);
        mc = ml_work(&m->al, na * na);
        kc0 = ml_work(&m->al, na * na);
        h = ml_work(&m->al, nz * na);
        if (!k || !kc || !g || !lu || !w || !v || !score || !col || !piv || !mm || !mc || !kc0 || !h) goto oom;
        reduced_stiffness(m, k);
        for (i = 0; i < na; i++) memcpy(kc + i * na, k + i * nt, na * sizeof(double));
        if (nz) { /* K_c = K_aa - K_az K_zz^-1 K_za, g = K_zz^-1 K_za */
            for (i = 0; i < nz; i++) {
                memcpy(lu + i * nz, k + (na + i) * nt + na, nz * sizeof(double));
                memcpy(g + i * na, k + (na + i) * nt, na * sizeof(double));
            }
            if (ml_lu(lu, nz, piv) != 0) {
                snprintf(err, MACE_ERR_LEN, "the reanalysis: the massless static corrections' stiffness is singular");
                goto done;
            }
            ml_lu_solve(lu, nz, piv, g, na);
            for (i = 0; i < na; i++)
                for (j = 0; j < na; j++) {
                    double acc = 0.0;
                    for (q = 0; q < nz; q++) acc += k[i * nt + na + q] * g[q * na + j];
                    kc[i * na + j] -= acc;
                }
            for (i = 0; i < na; i++)
                for (j = 0; j < i; j++) kc[i * na + j] = kc[j * na + i] = 0.5 * (kc[i * na + j] + kc[j * na + i]);
        }
        massed = reduced_mass(m, mm);
        if (massed) { /* the standard problem L^-1 K_c L^-T of K_c v = omega^2 M_c v */
            condensed_mass(mm, g, na, nz, h, mc);
            memcpy(kc0, kc, na * na * sizeof(double));
            if (ml_cholesky(mc, na) != 0) {
                snprintf(err, MACE_ERR_LEN, "the reanalysis: the changed mass matrix is not positive definite");
                goto done;
            }
            ml_cholesky_solve(mc, na, 1, kc, na); /* L^-1 K_c */
            for (i = 0; i < na; i++)              /* its transpose, K_c L^-T (K_c symmetric) */
                for (j = 0; j < i; j++) {
                    const double t = kc[i * na + j];
                    kc[i * na + j] = kc[j * na + i];
                    kc[j * na + i] = t;
                }
            ml_cholesky_solve(mc, na, 1, kc, na); /* L^-1 K_c L^-T */
            for (i = 0; i < na; i++)
                for (j = 0; j < i; j++) kc[i * na + j] = kc[j * na + i] = 0.5 * (kc[i * na + j] + kc[j * na + i]);
        }
        if (ml_jacobi_eigh(kc, na, w, v) != 0) {
            snprintf(err, MACE_ERR_LEN, "the reanalysis eigen-solution did not converge");
            goto done;
        }
        if (massed) {
            for (i = 0; i < nf; i++) /* the overlaps M_c v = L L^T v = L y with the nominal modes */
                for (j = 0; j < na; j++) {
                    double acc = 0.0;
                    for (q = 0; q <= i; q++) acc += mc[i * na + q] * v[q * na + j];
                    score[i * na + j] = acc * acc;
                }
            ml_cholesky_solve(mc, na, 0, v, na); /* v = L^-T y */
            for (j = 0; j < na; j++) {           /* omega^2: the Rayleigh quotient (v is M_c-normalised) */
                double acc = 0.0;
                for (i = 0; i < na; i++)
                    for (q = 0; q < na; q++) acc += v[i * na + j] * kc0[i * na + q] * v[q * na + j];
                w[j] = acc;
            }
        } else {
            for (i = 0; i < nf; i++) /* rows of the nominal modes; the corrections' rows score nothing */
                for (j = 0; j < na; j++) score[i * na + j] = v[i * na + j] * v[i * na + j];
        }
        if (ml_assign_max(&m->al, score, na, col) != 0) goto oom;
        for (i = 0; i < nf; i++) { /* new mode i continues nominal mode i */
            m->freq[m->flex[i]] = signed_frequency_hz(w[col[i]]);
            for (j = 0; j < na; j++) coef[j * nf + i] = v[j * na + col[i]];
            for (j = 0; j < nz; j++) {
                double acc = 0.0;
                for (q = 0; q < na; q++) acc += g[j * na + q] * v[q * na + col[i]];
                coef[(na + j) * nf + i] = -acc;
            }
        }
    }
    for (i = 0; i < m->n_modes; i++)
        if (m->scale_of[i] < m->n_par) m->freq[i] *= m->params[m->scale_of[i]];
    for (i = 0; i < nf; i++) {
        const double f = m->freq[m->flex[i]];
        if (fabs(f) < ZERO_HZ) {
            snprintf(err, MACE_ERR_LEN, "after the reanalysis and frequency scales flexible mode %lu is at %g Hz, below the %g Hz of the "
                     "zero-frequency cluster, which a native FMU reduces once at export (the pythonfmu FMU "
                     "re-reduces it)", (unsigned long)(m->flex[i] + 1), f, ZERO_HZ);
            goto done;
        }
    }
    status = 0;
    goto done;
oom:
    snprintf(err, MACE_ERR_LEN, "out of memory in the reanalysis");
done:
    ml_release(&m->al, k);
    ml_release(&m->al, kc);
    ml_release(&m->al, g);
    ml_release(&m->al, lu);
    ml_release(&m->al, w);
    ml_release(&m->al, v);
    ml_release(&m->al, score);
    ml_release(&m->al, col);
    ml_release(&m->al, piv);
    ml_release(&m->al, mm);
    ml_release(&m->al, mc);
    ml_release(&m->al, kc0);
    ml_release(&m->al, h);
    return status;
}

/* ---- blocks --------------------------------------------------------------------------------- */

/* The modal structure block into the block-diagonal matrices at state offset ox, input offset
 * ou, output offset oy (eq. 3.5-3.6; states: kept displacements, then kept rates, by mode). */
/* Mode j's signed omega^2 [rad^2/s^2] and 2 zeta omega [rad/s] (zero-frequency modes: 0, 0), as in
 * modal_core.modal_matrices: eta'' = -omega^2 eta - 2 zeta omega eta' + Phi^T b u. */
static void mode_terms(const MaceModel *m, size_t j, double *w2, double *damping) {
    const double f = fabs(m->freq[j]) < ZERO_HZ ? 0.0 : m->freq[j];
    const double w = TWO_PI * fabs(f), zeta = m->params[m->damping_of[j]];
    *w2 = signed_omega2(f);
    *damping = 2.0 * zeta * w;
}

/* The modal structure block (mace_fmu/iomodel/modal_core.py, modal_matrices): A, B and C, and for
 * acceleration outputs C = a [-Omega^2, -2 zeta Omega] and the feedthrough D = a Phi^T b. */
static int structure_block(MaceModel *m, const double *coef, int changed, double *ab, double *bb, double *cb,
                           double *db, size_t N, size_t NU, size_t ox, size_t ou, size_t oy) {
    const size_t nm = m->n_modes, nf = m->n_flex;
    size_t j, k, o, q, nd = 0, pos;
    size_t *dpos = (size_t *)m->al.calloc(nm + 1, sizeof(size_t)), *rpos = (size_t *)m->al.calloc(nm + 1, sizeof(size_t));
    double *mb = ml_zeros(&m->al, nm * m->n_structure_inputs), *rows = ml_zeros(&m->al, m->n_structure_outputs * nm);
    int status = -1;
    if (!dpos || !rpos || !mb || !rows) goto done;
    memcpy(mb, m->modal_b, nm * m->n_structure_inputs * sizeof(double));
    memcpy(rows, m->rows, m->n_structure_outputs * nm * sizeof(double));
    if (changed && m->resolved) { /* the re-solved flexible modes' inputs and rows */
        const size_t ni = m->n_structure_inputs, no = m->n_structure_outputs;
        for (k = 0; k < nf; k++) {
            for (q = 0; q < ni; q++) mb[m->flex[k] * ni + q] = m->rs_b[k * ni + q];
            for (o = 0; o < no; o++) rows[o * nm + m->flex[k]] = m->rs_rows[o * nf + k];
        }
    } else if (changed) { /* the new flexible modes' inputs and rows: coef^T [b + preload; b_W], [rows + preload, rows_W] coef */
        const size_t ni = m->n_structure_inputs, no = m->n_structure_outputs, nc = m->n_corr;
        for (k = 0; k < nf; k++) {
            for (q = 0; q < ni; q++) {
                double acc = 0.0;
                for (j = 0; j < nf; j++) {
                    double b = m->modal_b[m->flex[j] * ni + q];
                    size_t p;
                    for (p = 0; p < m->n_phys; p++) b += m->rel[p] * m->pre_b[(p * nf + j) * ni + q];
                    acc += coef[j * nf + k] * b;
                }
                for (j = 0; j < nc; j++) acc += coef[(nf + j) * nf + k] * m->corr_b[j * ni + q];
                mb[m->flex[k] * ni + q] = acc;
            }
            for (o = 0; o < no; o++) {
                double acc = 0.0;
                for (j = 0; j < nf; j++) {
                    double r = m->rows[o * nm + m->flex[j]];
                    size_t p;
                    for (p = 0; p < m->n_phys; p++) r += m->rel[p] * m->pre_rows[(p * no + o) * nf + j];
                    acc += r * coef[j * nf + k];
                }
                for (j = 0; j < nc; j++) acc += m->corr_rows[o * nc + j] * coef[(nf + j) * nf + k];
                rows[o * nm + m->flex[k]] = acc;
            }
        }
    }
    for (j = 0; j < nm; j++)
        if (m->keep_disp[j]) dpos[j] = nd++;
    pos = nd;
    for (j = 0; j < nm; j++)
        if (m->keep_rate[j]) rpos[j] = pos++;
    for (j = 0; j < nm; j++) {
        double w2, damping;
        mode_terms(m, j, &w2, &damping);
        if (m->keep_disp[j]) {
            ab[(ox + dpos[j]) * N + ox + rpos[j]] = 1.0;
            ab[(ox + rpos[j]) * N + ox + dpos[j]] = -w2;
        }
        if (m->keep_rate[j]) {
            ab[(ox + rpos[j]) * N + ox + rpos[j]] = -damping;
            for (q = 0; q < m->n_structure_inputs; q++)
                bb[(ox + rpos[j]) * NU + ou + q] = mb[j * m->n_structure_inputs + q];
        }
    }
    for (o = 0; o < m->n_structure_outputs; o++) {
        if (m->row_kind[o] == ROW_ACCELERATION) {
            for (j = 0; j < nm; j++) {
                const double a = rows[o * nm + j];
                double w2, damping;
                mode_terms(m, j, &w2, &damping);
                if (m->keep_disp[j]) cb[(oy + o) * N + ox + dpos[j]] = -w2 * a;
                if (m->keep_rate[j]) cb[(oy + o) * N + ox + rpos[j]] = -damping * a;
                for (q = 0; q < m->n_structure_inputs; q++)
                    db[(oy + o) * NU + ou + q] += a * mb[j * m->n_structure_inputs + q];
            }
            continue;
        }
        for (j = 0; j < nm; j++) {
            const int rate = m->row_kind[o] == ROW_RATE;
            if (rate ? m->keep_rate[j] : m->keep_disp[j])
                cb[(oy + o) * N + ox + (rate ? rpos[j] : dpos[j])] = rows[o * nm + j];
        }
    }
    status = 0;
done:
    m->al.free(dpos);
    m->al.free(rpos);
    m->al.free(mb);
    m->al.free(rows);
    return status;
}

/* [order/order] Pade approximation of exp(-s delay), as modelica_like.algebra.pade: companion
 * form in s * delay, divided by the delay, balanced. A delay below PADE_MIN_DELAY_S: unit
 * feedthrough, inert states. */
#define PADE_MIN_DELAY_S 1e-12 /* modelica_like.algebra.PADE_MIN_DELAY_S */
static int pade_block(size_t n, double delay, double *a, double *b, double *c, double *d) {
    double coef[11], den[11], num[11], scale[10], dd;
    size_t k, i;
    memset(a, 0, n * n * sizeof(double));
    memset(b, 0, n * sizeof(double));
    memset(c, 0, n * sizeof(double));
    if (delay < PADE_MIN_DELAY_S) {
        *d = 1.0;
        return 0;
    }
    for (k = 0; k <= n; k++) { /* C(n, k) / ((2n)(2n-1)...(2n-k+1)): exact integers for n <= 10 */
        double binom = 1.0, falling = 1.0;
        for (i = 0; i < k; i++) {
            binom = binom * (double)(n - i) / (double)(i + 1);
            falling *= (double)(2 * n - i);
        }
        coef[k] = binom / falling;
    }
    for (k = 0; k <= n; k++) {
        den[k] = coef[k] / coef[n];
        num[k] = (k % 2 ? -coef[k] : coef[k]) / coef[n];
    }
    dd = num[n];
    for (i = 0; i + 1 < n; i++) a[i * n + i + 1] = 1.0;
    for (k = 0; k < n; k++) a[(n - 1) * n + k] = -den[k];
    b[n - 1] = 1.0;
    for (k = 0; k < n; k++) c[k] = num[k] - dd * den[k];
    for (k = 0; k < n * n; k++) a[k] = a[k] / delay;
    for (k = 0; k < n; k++) b[k] = b[k] / delay;
    if (ml_balance(a, n, scale) != 0) return -1;
    for (k = 0; k < n; k++) {
        b[k] /= scale[k];
        c[k] *= scale[k];
    }
    *d = dd;
    return 0;
}

/* ---- the system ----------------------------------------------------------------------------- */

static int assemble(MaceModel *m, const double *coef, int changed, char *err) {
    const size_t N = m->n, NU = m->n_block_inputs, NY = m->n_block_outputs, ni = m->n_in, no = m->n_out;
    double *ab = ml_work(&m->al, N * N), *bb = ml_work(&m->al, N * NU), *cb = ml_work(&m->al, NY * N);
    double *db = ml_work(&m->al, NY * NU), *w = ml_work(&m->al, NU * NU), *rhs = ml_work(&m->al, NU * (N + ni));
    double *t = ml_work(&m->al, (NY > NU ? NY : NU) * (N + ni)), *wq = ml_work(&m->al, NU * (NY + ni));
    size_t *piv = (size_t *)m->al.calloc(NU + 1, sizeof(size_t));
    size_t k, i, j, ox = 0, ou = 0, oy = 0;
    int status = -1;
    if (!ab || !bb || !cb || !db || !w || !rhs || !t || !wq || !piv) {
        snprintf(err, MACE_ERR_LEN, "out of memory building the system");
        goto done;
    }
    for (k = 0; k < m->n_blocks; k++) {
        const int64_t *info = m->block_info + k * N_INFO;
        const size_t nx = (size_t)info[INFO_NX], nu = (size_t)info[INFO_NU], ny = (size_t)info[INFO_NY];
        switch (info[INFO_KIND]) {
            case BLOCK_STRUCTURE:
                if (structure_block(m, coef, changed, ab, bb, cb, db, N, NU, ox, ou, oy) != 0) {
                    snprintf(err, MACE_ERR_LEN, "out of memory building the structure block");
                    goto done;
                }
                break;
            case BLOCK_DELAY: {
                double pa[100], pb[10], pc[10], pd;
                if (pade_block(nx, m->params[info[INFO_P0]], pa, pb, pc, &pd) != 0) {
                    snprintf(err, MACE_ERR_LEN, "the Pade realisation of %s failed", mace_name(m, MACE_VAR_PARAMETER,
                             (size_t)info[INFO_P0]));
                    goto done;
                }
                for (i = 0; i < nx; i++) {
                    for (j = 0; j < nx; j++) ab[(ox + i) * N + ox + j] = pa[i * nx + j];
                    bb[(ox + i) * NU + ou] = pb[i];
                    cb[oy * N + ox + i] = pc[i];
                }
                db[oy * NU + ou] = pd;
                break;
            }
            case BLOCK_GAIN: db[oy * NU + ou] = m->params[info[INFO_P0]]; break;
            case BLOCK_PD:
                db[oy * NU + ou] = m->params[info[INFO_P0]];
                db[oy * NU + ou + 1] = m->params[info[INFO_P1]];
                break;
            default: { /* constant block */
                const double *a = m->blk[4 * k], *b = m->blk[4 * k + 1], *c = m->blk[4 * k + 2], *d = m->blk[4 * k + 3];
                for (i = 0; i < nx; i++) {
                    for (j = 0; j < nx; j++) ab[(ox + i) * N + ox + j] = a[i * nx + j];
                    for (j = 0; j < nu; j++) bb[(ox + i) * NU + ou + j] = b[i * nu + j];
                }
                for (i = 0; i < ny; i++) {
                    for (j = 0; j < nx; j++) cb[(oy + i) * N + ox + j] = c[i * nx + j];
                    for (j = 0; j < nu; j++) db[(oy + i) * NU + ou + j] = d[i * nu + j];
                }
            }
        }
        ox += nx;
        ou += nu;
        oy += ny;
    }
    /* u_b = wiring y_b + entry r: with W = (I - wiring D_b)^-1, A = A_b + B_b W wiring C_b,
       B = B_b W entry, C = exit (C_b + D_b W wiring C_b), D = exit D_b W entry */
    ml_matmul(NU, NY, NU, m->wiring, db, w);
    for (i = 0; i < NU * NU; i++) w[i] = -w[i];
    for (i = 0; i < NU; i++) w[i * NU + i] += 1.0;
    ml_matmul(NU, NY, N, m->wiring, cb, t); /* t: NU x N, scratch */
    for (i = 0; i < NU; i++) {
        memcpy(rhs + i * (N + ni), t + i * N, N * sizeof(double));
        memcpy(rhs + i * (N + ni) + N, m->entry + i * ni, ni * sizeof(double));
    }
    if (ml_lu(w, NU, piv) != 0) {
        snprintf(err, MACE_ERR_LEN, "the block diagram has an algebraic loop (I - wiring D is singular)");
        goto done;
    }
    ml_lu_solve(w, NU, piv, rhs, N + ni); /* rhs = W [wiring C_b | entry] */
    for (i = 0; i < NU; i++) {
        memcpy(wq + i * (NY + ni), m->wiring + i * NY, NY * sizeof(double));
        memcpy(wq + i * (NY + ni) + NY, m->entry + i * ni, ni * sizeof(double));
    }
    ml_lu_solve(w, NU, piv, wq, NY + ni); /* wq = W [wiring | entry] */
    if (csr_from_dense(&m->al, ab, N, N, m->perm, m->perm, &m->ab) != 0 ||
        csr_from_dense(&m->al, bb, N, NU, m->perm, NULL, &m->bb) != 0 ||
        csr_from_dense(&m->al, cb, NY, N, NULL, m->perm, &m->cb) != 0 ||
        csr_from_dense(&m->al, wq, NU, NY + ni, NULL, NULL, &m->wq) != 0) {
        snprintf(err, MACE_ERR_LEN, "out of memory building the system");
        goto done;
    }
    memcpy(m->a, ab, N * N * sizeof(double));
    memset(m->b, 0, N * ni * sizeof(double));
    for (i = 0; i < N; i++) {
        for (k = 0; k < NU; k++) {
            const double f = bb[i * NU + k];
            const double *row = rhs + k * (N + ni);
            if (f == 0.0) continue;
            for (j = 0; j < N; j++) m->a[i * N + j] += f * row[j];
            for (j = 0; j < ni; j++) m->b[i * ni + j] += f * row[N + j];
        }
    }
    ml_matmul(NY, NU, N + ni, db, rhs, t); /* D_b W [wiring C_b | entry] */
    for (i = 0; i < NY; i++)
        for (j = 0; j < N; j++) t[i * (N + ni) + j] += cb[i * N + j];
    memset(m->c, 0, no * N * sizeof(double));
    memset(m->d, 0, no * ni * sizeof(double));
    for (i = 0; i < no; i++) {
        for (k = 0; k < NY; k++) {
            const double f = m->exit_[i * NY + k];
            if (f == 0.0) continue;
            for (j = 0; j < N; j++) m->c[i * N + j] += f * t[k * (N + ni) + j];
            for (j = 0; j < ni; j++) m->d[i * ni + j] += f * t[k * (N + ni) + N + j];
        }
    }
    status = 0;
done:
    ml_release(&m->al, ab);
    ml_release(&m->al, bb);
    ml_release(&m->al, cb);
    ml_release(&m->al, db);
    ml_release(&m->al, w);
    ml_release(&m->al, rhs);
    ml_release(&m->al, t);
    ml_release(&m->al, wq);
    ml_release(&m->al, piv);
    return status;
}

int mace_build(MaceModel *m, char *err) {
    double *coef;
    int changed, status = -1;
    if (m->built && !m->params_changed) return 0;
    if (check_parameters(m, err) != 0) return -1;
    m->params_changed = 0;
    if (m->built && memcmp(m->params, m->built_params, m->n_par * sizeof(double)) == 0) return 0;
    m->built = 0;
    coef = ml_work(&m->al, (m->n_flex + m->n_corr) * m->n_flex);
    if (!coef) {
        snprintf(err, MACE_ERR_LEN, "out of memory");
        return -1;
    }
    if (reanalyse(m, coef, &changed, err) == 0 && assemble(m, coef, changed, err) == 0 &&
        zoh_prepare(m->zoh, m->a, m->b, m->c, m->d, err) == 0) {
        size_t i;
        if (m->kind == MACE_MODEL_EXCHANGE) {
            if (zoh_state_scales(m->zoh, m->dir_dx) != 0)
                for (i = 0; i < m->n; i++) m->dir_dx[i] = 1.0;
            for (i = 0; i < m->n; i++) m->nominal[i] = m->dir_dx[m->perm[i]];
        }
        memcpy(m->built_params, m->params, m->n_par * sizeof(double));
        memset(m->s, 0, m->n * sizeof(double));
        m->built = 1;
        m->y_valid = m->x_valid = 0;
        status = 0;
    }
    ml_release(&m->al, coef);
    return status;
}

/* ---- values --------------------------------------------------------------------------------- */

static const double *model_states(MaceModel *m) {
    if (m->kind == MACE_MODEL_EXCHANGE) return m->s;
    if (!m->x_valid) {
        zoh_to_x(m->zoh, m->s, m->x);
        m->x_valid = 1;
    }
    return m->x;
}

static const double *outputs(MaceModel *m) {
    size_t i, k;
    if (m->y_valid) return m->y;
    if (m->kind == MACE_CO_SIMULATION) {
        zoh_output(m->zoh, m->s, m->u, m->y);
    } else {
        for (i = 0; i < m->n_out; i++) {
            double acc = 0.0;
            for (k = 0; k < m->n; k++) acc += m->c[i * m->n + m->perm[k]] * m->s[k];
            for (k = 0; k < m->n_in; k++) acc += m->d[i * m->n_in + k] * m->u[k];
            m->y[i] = acc;
        }
    }
    m->y_valid = 1;
    return m->y;
}

/* dx = A x + B u through the sparse block diagram of the last build: about 4,000 multiplications for
 * the 1-g model's 297 states against 91,000 for the dense A and B (which stay for the zero-order hold). */
static void rhs(MaceModel *m, const double *x, const double *u, double *dx) {
    csr_apply(&m->cb, x, m->zb, 0);
    memcpy(m->zb + m->n_block_outputs, u, m->n_in * sizeof(double));
    csr_apply(&m->wq, m->zb, m->ub, 0);
    csr_apply(&m->ab, x, dx, 0);
    csr_apply(&m->bb, m->ub, dx, 1);
}

int mace_get(MaceModel *m, MaceGroup group, size_t k, double *value, char *err) {
    if (group == MACE_VAR_INPUT) {
        *value = m->u[k];
        return 0;
    }
    if (group == MACE_VAR_PARAMETER) {
        *value = m->params[k];
        return 0;
    }
    if (group == MACE_VAR_TIME) {
        *value = m->time;
        return 0;
    }
    if (mace_build(m, err) != 0) return -1;
    switch (group) {
        case MACE_VAR_OUTPUT: *value = outputs(m)[k]; break;
        case MACE_VAR_FREQUENCY: *value = m->freq[k]; break;
        case MACE_VAR_STATE: *value = model_states(m)[m->pos[k]]; break;
        case MACE_VAR_DERIVATIVE:
            rhs(m, model_states(m), m->u, m->dir_dx);
            *value = m->dir_dx[m->pos[k]];
            break;
        default: snprintf(err, MACE_ERR_LEN, "unknown variable"); return -1;
    }
    return 0;
}

static int inputs_finite(const MaceModel *m, double t, char *err) {
    size_t k, used;
    int bad = 0;
    for (k = 0; k < m->n_in; k++)
        if (!isfinite(m->u[k])) bad = 1;
    if (!bad) return 0;
    used = (size_t)snprintf(err, MACE_ERR_LEN, "non-finite input value(s) at t = %g s:", t);
    for (k = 0; k < m->n_in && used < MACE_ERR_LEN; k++)
        if (!isfinite(m->u[k]))
            used += (size_t)snprintf(err + used, MACE_ERR_LEN - used, " %s = %g", m->names[k], m->u[k]);
    return -1;
}

int mace_step_check(const MaceModel *m, double t, double h, char *err) {
    /* the zero-order hold takes any finite step: its cost does not grow with h (one matrix exponential) */
    (void)m; (void)t; (void)h; (void)err;
    return 0;
}

int mace_do_step(MaceModel *m, double t, double h, char *err) {
    if (!m->built) {
        snprintf(err, MACE_ERR_LEN, "the model is not initialised");
        return -1;
    }
    if (!(isfinite(t) && isfinite(h) && h >= 0.0)) {
        snprintf(err, MACE_ERR_LEN, "step from t = %g s over %g s: need a finite time and a step >= 0", t, h);
        return -1;
    }
    if (inputs_finite(m, t, err) != 0) return -1;
    if (h > 0.0 && zoh_step(m->zoh, m->s, m->u, t, h, err) != 0) return -1;
    m->time = t + h;
    m->y_valid = m->x_valid = 0;
    return 0;
}

void mace_set_time(MaceModel *m, double t) { m->time = t; }

void mace_set_states(MaceModel *m, const double *x) {
    memcpy(m->s, x, m->n * sizeof(double));
    m->y_valid = 0;
}

void mace_get_states(MaceModel *m, double *x) { memcpy(x, m->s, m->n * sizeof(double)); }

void mace_get_nominals(MaceModel *m, double *nominal) {
    size_t i;
    for (i = 0; i < m->n; i++) nominal[i] = m->built ? m->nominal[i] : 1.0;
}

int mace_get_derivatives(MaceModel *m, double *dx, char *err) {
    size_t i;
    if (mace_build(m, err) != 0) return -1;
    if (inputs_finite(m, m->time, err) != 0) return -1;
    rhs(m, m->s, m->u, dx);
    for (i = 0; i < m->n; i++) { /* finite inputs and states can still overflow (inputs of 1e308) */
        if (!isfinite(dx[i])) {
            snprintf(err, MACE_ERR_LEN, "the derivative of state %lu is %g at t = %g s: the inputs or states are "
                     "beyond what the model can represent", (unsigned long)i, dx[i], m->time);
            return -1;
        }
    }
    return 0;
}

int mace_directional(MaceModel *m, const double *vx, const double *vu, double *dx, double *dy, char *err) {
    size_t i, k;
    if (mace_build(m, err) != 0) return -1;
    if (dx) rhs(m, vx, vu, dx);
    if (dy) {
        for (i = 0; i < m->n_out; i++) {
            double acc = 0.0;
            for (k = 0; k < m->n; k++) acc += m->c[i * m->n + m->perm[k]] * vx[k];
            for (k = 0; k < m->n_in; k++) acc += m->d[i * m->n_in + k] * vu[k];
            dy[i] = acc;
        }
    }
    return 0;
}

size_t mace_state_position(const MaceModel *m, size_t k) { return m->pos[k]; }

double *mace_directional_buffer(MaceModel *m, MaceGroup group) {
    switch (group) {
        case MACE_VAR_STATE: return m->dir_x;
        case MACE_VAR_INPUT: return m->dir_u;
        case MACE_VAR_DERIVATIVE: return m->dir_dx;
        case MACE_VAR_OUTPUT: return m->dir_dy;
        default: return NULL;
    }
}

/* ---- FMU state ------------------------------------------------------------------------------ */

static int coordinates(const MaceModel *m) { /* 0: model states x; 1: the fast form's */
    return m->kind == MACE_CO_SIMULATION && m->built && zoh_is_fast(m->zoh);
}

size_t mace_state_size(const MaceModel *m) {
    return 8 * (STATE_HEADER + 1 + m->n_par + m->n_in + 2 * m->n);
}

static void put(unsigned char *buf, size_t *pos, const void *src, size_t bytes) {
    memcpy(buf + *pos, src, bytes);
    *pos += bytes;
}

void mace_state_save(MaceModel *m, int phase, unsigned char *buffer) {
    uint64_t header[STATE_HEADER - 1];
    size_t pos = 0;
    header[0] = (uint64_t)phase;
    header[1] = (uint64_t)m->built;
    header[2] = (uint64_t)coordinates(m);
    header[3] = m->n_par;
    header[4] = m->n_in;
    header[5] = m->n;
    put(buffer, &pos, STATE_MAGIC, 8);
    put(buffer, &pos, header, sizeof(header));
    put(buffer, &pos, &m->time, 8);
    put(buffer, &pos, m->params, 8 * m->n_par);
    put(buffer, &pos, m->u, 8 * m->n_in);
    put(buffer, &pos, m->s, 8 * m->n);
    put(buffer, &pos, m->built ? model_states(m) : m->s, 8 * m->n);
}

static int all_finite(const unsigned char *bytes, size_t n) {
    size_t k;
    for (k = 0; k < n; k++) {
        double v;
        memcpy(&v, bytes + 8 * k, 8);
        if (!isfinite(v)) return 0;
    }
    return 1;
}

int mace_state_check(MaceModel *m, const unsigned char *buffer, size_t size, int *phase, int *usable, char *err) {
    uint64_t header[STATE_HEADER - 1];
    const size_t pos = 8 + sizeof(header);
    double *saved;
    if (size != mace_state_size(m) || memcmp(buffer, STATE_MAGIC, 8) != 0) {
        snprintf(err, MACE_ERR_LEN, "not an FMU state of this model (%lu bytes)", (unsigned long)size);
        return -1;
    }
    memcpy(header, buffer + 8, sizeof(header));
    if (header[3] != m->n_par || header[4] != m->n_in || header[5] != m->n) {
        snprintf(err, MACE_ERR_LEN, "not an FMU state of this model (other dimensions)");
        return -1;
    }
    if (header[0] > 255 || header[1] > 1 || header[2] > 1) {
        snprintf(err, MACE_ERR_LEN, "a damaged FMU state (header flags out of range)");
        return -1;
    }
    /* time, inputs and states: the setters refuse non-finite values, so a state with one is damaged
       (parameters may be anything before initialisation: the build refuses them) */
    if (!all_finite(buffer + pos, 1) || !all_finite(buffer + pos + 8 * (1 + m->n_par), m->n_in + 2 * m->n)) {
        snprintf(err, MACE_ERR_LEN, "a damaged FMU state (a non-finite time, input or state)");
        return -1;
    }
    *phase = (int)header[0];
    /* usable: built and with parameters the build accepts (checked on a copy, nothing applied) */
    *usable = 0;
    if (header[1]) {
        saved = m->params;
        m->params = (double *)m->al.calloc(m->n_par + 1, sizeof(double));
        if (!m->params) {
            m->params = saved;
            snprintf(err, MACE_ERR_LEN, "out of memory");
            return -1;
        }
        memcpy(m->params, buffer + pos + 8, 8 * m->n_par);
        *usable = check_parameters(m, err) == 0;
        m->al.free(m->params);
        m->params = saved;
    }
    return 0;
}

int mace_state_load(MaceModel *m, const unsigned char *buffer, size_t size, int *phase, char *err) {
    uint64_t header[STATE_HEADER - 1];
    size_t pos = 8 + sizeof(header);
    const unsigned char *vec;
    int usable;
    if (mace_state_check(m, buffer, size, phase, &usable, err) != 0) return -1;
    memcpy(header, buffer + 8, sizeof(header));
    memcpy(&m->time, buffer + pos, 8);
    pos += 8;
    memcpy(m->params, buffer + pos, 8 * m->n_par);
    m->params_changed = 1;
    pos += 8 * m->n_par;
    memcpy(m->u, buffer + pos, 8 * m->n_in);
    pos += 8 * m->n_in;
    vec = buffer + pos;
    m->y_valid = m->x_valid = 0;
    if (usable) {
        if (mace_build(m, err) != 0) return -1;
        if ((int)header[2] == coordinates(m)) {
            memcpy(m->s, vec, 8 * m->n);
        } else {
            memcpy(m->x, vec + 8 * m->n, 8 * m->n);
            if (m->kind == MACE_CO_SIMULATION) {
                zoh_from_x(m->zoh, m->x, m->s);
            } else {
                memcpy(m->s, m->x, 8 * m->n);
            }
        }
    } else {
        memset(m->s, 0, 8 * m->n);
    }
    return 0;
}
