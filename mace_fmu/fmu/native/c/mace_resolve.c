/* The structure solved again for new physical parameters (see mace_resolve.h). */
#include "mace_resolve.h"

#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef double complex cx;

#define TWO_PI (2.0 * 3.14159265358979323846)
#define CS_STEP 1e-30          /* complex step (mace_fmu/fe/corotational.py) */
#define FD_RELATIVE_STEP 1e-4  /* central differences of the complex-step derivatives */
#define MAX_LOCAL_ROTATION 0.5 /* rad */
#define WORK_TOLERANCE 1e-14   /* Newton's |du . r| / |u . F| (mace_fmu/iomodel/resolve.py) */
#define MAX_ITERATIONS 30
#define FRESH_TANGENT_WORK 1e-8 /* above this work ratio Newton takes the tangent of the current state */
#define MASSLESS_FRACTION 1e-12

/* q-coordinate a of a bar (translations and spins of A, then of B) is +- reduced coordinate ZMAP[a] */
static const int ZMAP[12] = {0, 1, 2, 3, 4, 5, 0, 1, 2, 6, 7, 8};
static const double ZSIGN[12] = {-1, -1, -1, 1, 1, 1, 1, 1, 1, 1, 1, 1};

/* ---- the corotational bar ---------------------------------------------------------------------- */

/* Rodrigues' formula, complex-safe (a series below 1e-6 rad^2). */
static void rotation_matrix(const cx th[3], cx r[9]) {
    const cx phi2 = th[0] * th[0] + th[1] * th[1] + th[2] * th[2];
    cx a, b;
    int i, j;
    if (cabs(phi2) < 1e-6) {
        a = 1.0 - phi2 / 6.0 + phi2 * phi2 / 120.0;
        b = 0.5 - phi2 / 24.0 + phi2 * phi2 / 720.0;
    } else {
        const cx phi = csqrt(phi2);
        a = csin(phi) / phi;
        b = (1.0 - ccos(phi)) / phi2;
    }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) r[i * 3 + j] = (i == j ? 1.0 - b * phi2 : 0.0) + b * th[i] * th[j];
    r[1] -= a * th[2];
    r[2] += a * th[1];
    r[3] += a * th[2];
    r[5] -= a * th[0];
    r[6] -= a * th[1];
    r[7] += a * th[0];
}

/* Rotation vector of a rotation near the identity; -1 beyond MAX_LOCAL_ROTATION. */
static int rotation_vector_small(const cx r[9], cx w[3]) {
    cx s2, ratio;
    if (creal(r[0] + r[4] + r[8]) < 1.0 + 2.0 * cos(MAX_LOCAL_ROTATION)) return -1;
    w[0] = 0.5 * (r[7] - r[5]);
    w[1] = 0.5 * (r[2] - r[6]);
    w[2] = 0.5 * (r[3] - r[1]);
    s2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    ratio = 1.0 + s2 * (1.0 / 6 + s2 * (3.0 / 40 + s2 * (5.0 / 112 + s2 * (35.0 / 1152 + s2 * 63.0 / 2816))));
    w[0] *= ratio;
    w[1] *= ratio;
    w[2] *= ratio;
    return 0;
}

static void cross(const cx a[3], const cx b[3], cx out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* One bar's natural deformations d (stretch, local end rotations) with its ends at xa (fixed), xb + dz[0:3],
 * rotations R(dz[3:6]) ra and R(dz[6:9]) rb. */
static int deformations(const double *xa, const double *xb, const double *ra, const double *rb, const double *frame0,
                        double length0, const cx dz[9], cx d[7]) {
    cx chord[3], e1[3], e2[3], e3[3], q[3], rot_a[9], rot_b[9], ra1[9], rb1[9], rel[9], th_a[3], th_b[3], norm, length;
    const cx *rows[3];
    int i, j, k, l;
    rotation_matrix(dz + 3, rot_a);
    rotation_matrix(dz + 6, rot_b);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            cx sa = 0.0, sb = 0.0;
            for (k = 0; k < 3; k++) {
                sa += rot_a[i * 3 + k] * ra[k * 3 + j];
                sb += rot_b[i * 3 + k] * rb[k * 3 + j];
            }
            ra1[i * 3 + j] = sa;
            rb1[i * 3 + j] = sb;
        }
    for (i = 0; i < 3; i++) chord[i] = xb[i] + dz[i] - xa[i];
    length = csqrt(chord[0] * chord[0] + chord[1] * chord[1] + chord[2] * chord[2]);
    for (i = 0; i < 3; i++) e1[i] = chord[i] / length;
    for (i = 0; i < 3; i++) { /* the mean of the rotated ends' y axes */
        cx s = 0.0;
        for (k = 0; k < 3; k++) s += (ra1[i * 3 + k] + rb1[i * 3 + k]) * frame0[3 + k];
        q[i] = 0.5 * s;
    }
    cross(e1, q, e3);
    norm = csqrt(e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2]);
    for (i = 0; i < 3; i++) e3[i] /= norm;
    cross(e3, e1, e2);
    rows[0] = e1;
    rows[1] = e2;
    rows[2] = e3;
    for (l = 0; l < 2; l++) { /* rows @ R @ frame0^T for each end */
        const cx *rr = l ? rb1 : ra1;
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) {
                cx s = 0.0;
                for (k = 0; k < 3; k++) {
                    cx t = 0.0;
                    int m;
                    for (m = 0; m < 3; m++) t += rr[k * 3 + m] * frame0[j * 3 + m];
                    s += rows[i][k] * t;
                }
                rel[i * 3 + j] = s;
            }
        if (rotation_vector_small(rel, l ? th_b : th_a) != 0) return -1;
    }
    d[0] = length - length0;
    for (i = 1; i < 3; i++)
        d[0] += length0 / 60.0 * (4.0 * th_a[i] * th_a[i] - 2.0 * th_a[i] * th_b[i] + 4.0 * th_b[i] * th_b[i]);
    for (i = 0; i < 3; i++) {
        d[1 + i] = th_a[i];
        d[4 + i] = th_b[i];
    }
    return 0;
}

/* How a bar's tangent is formed: its material part B^T Kn B only; with the geometric part sum_k g_k d2 d_k / dz2
 * from second derivatives at the state (central differences of complex steps); or with the second derivatives
 * of the nominal state (an approximate tangent for Newton's intermediate iterations: it changes how fast they
 * converge, not where to). */
enum { TANGENT_MATERIAL = 0, TANGENT_EXACT = 1, TANGENT_NOMINAL_CURVATURE = 2 };

/* One bar about the state (positions, rotations): its internal force f_e (12) and tangent k_e (12 x 12, symmetric)
 * as `tangent` says; k_e NULL: the force alone. kn: its natural stiffness. curvature (7 x 9 x 9, d2 d_k / dz_i dz_j):
 * TANGENT_EXACT fills it if not NULL, TANGENT_NOMINAL_CURVATURE takes it. */
static int bar_tangent(const RsStructure *s, size_t bar, const double *positions, const double *rotations,
                       const double *kn, int tangent, double *f_e, double *k_e, double *curvature) {
    const size_t ga = (size_t)s->bar_nodes[2 * bar], gb = (size_t)s->bar_nodes[2 * bar + 1];
    const double *xa = positions + 3 * ga, *xb = positions + 3 * gb, *ra = rotations + 9 * ga, *rb = rotations + 9 * gb;
    const double *frame0 = s->frames0 + 9 * bar, length0 = s->lengths0[bar];
    double d0[7], bz[7][9], g[7], b[7][12], gz[9][9]; /* gz: the geometric part, sum_k g_k d2 d_k / dz2 */
    cx dz[9], d[7];
    int i, j, k, l, a, c;
    for (j = 0; j < 9; j++) { /* dd/dz by complex steps */
        for (i = 0; i < 9; i++) dz[i] = 0.0;
        dz[j] = CS_STEP * I;
        if (deformations(xa, xb, ra, rb, frame0, length0, dz, d) != 0) return -1;
        for (k = 0; k < 7; k++) {
            bz[k][j] = cimag(d[k]) / CS_STEP;
            d0[k] = creal(d[k]);
        }
    }
    for (k = 0; k < 7; k++) {
        g[k] = 0.0;
        for (l = 0; l < 7; l++) g[k] += kn[k * 7 + l] * d0[l];
    }
    for (k = 0; k < 7; k++)
        for (a = 0; a < 12; a++) b[k][a] = bz[k][ZMAP[a]] * ZSIGN[a];
    for (a = 0; a < 12; a++) {
        f_e[a] = 0.0;
        for (k = 0; k < 7; k++) f_e[a] += b[k][a] * g[k];
    }
    if (!k_e) return 0;
    for (a = 0; a < 12; a++)
        for (c = 0; c < 12; c++) {
            double acc = 0.0;
            for (k = 0; k < 7; k++) {
                double t = 0.0;
                for (l = 0; l < 7; l++) t += kn[k * 7 + l] * b[l][c];
                acc += b[k][a] * t;
            }
            k_e[a * 12 + c] = acc;
        }
    if (tangent == TANGENT_EXACT) { /* sum_k g_k d2 d_k / dz2: central differences of complex-step first derivatives */
        for (i = 0; i < 9; i++) {
            const double h = FD_RELATIVE_STEP * (i < 3 ? length0 : 1.0);
            for (j = i; j < 9; j++) {
                double up[7], down[7], acc = 0.0;
                int sign;
                for (sign = 0; sign < 2; sign++) {
                    for (l = 0; l < 9; l++) dz[l] = 0.0;
                    dz[i] = sign ? -h : h;
                    dz[j] += CS_STEP * I;
                    if (deformations(xa, xb, ra, rb, frame0, length0, dz, d) != 0) return -1;
                    for (k = 0; k < 7; k++) (sign ? down : up)[k] = cimag(d[k]);
                }
                for (k = 0; k < 7; k++) {
                    acc += g[k] * (up[k] - down[k]) / (CS_STEP * 2.0 * h);
                    if (curvature)
                        curvature[k * 81 + i * 9 + j] = curvature[k * 81 + j * 9 + i] =
                            (up[k] - down[k]) / (CS_STEP * 2.0 * h);
                }
                gz[i][j] = gz[j][i] = acc;
            }
        }
    } else if (tangent == TANGENT_NOMINAL_CURVATURE) {
        for (i = 0; i < 9; i++)
            for (j = 0; j < 9; j++) {
                double acc = 0.0;
                for (k = 0; k < 7; k++) acc += g[k] * curvature[k * 81 + i * 9 + j];
                gz[i][j] = acc;
            }
    }
    if (tangent != TANGENT_MATERIAL)
        for (a = 0; a < 12; a++)
            for (c = 0; c < 12; c++) k_e[a * 12 + c] += gz[ZMAP[a]][ZMAP[c]] * ZSIGN[a] * ZSIGN[c];
    for (a = 0; a < 12; a++)
        for (c = 0; c < a; c++) k_e[a * 12 + c] = k_e[c * 12 + a] = 0.5 * (k_e[a * 12 + c] + k_e[c * 12 + a]);
    return 0;
}

/* ---- assembly ----------------------------------------------------------------------------------- */

/* The bars' forces, tangents (`tangent`: TANGENT_MATERIAL or TANGENT_EXACT) and curvatures at the nominal state
 * with their nominal natural stiffness, computed once per model: at a given state a bar's force and tangent are
 * linear in its natural stiffness (f = B^T Kn d, k = B^T Kn B + sum (Kn d)_k d2 d_k / dz2), so Newton's first
 * iteration and the 0-g re-solve scale these instead. */
static int nominal_bars(const RsStructure *s, int tangent) {
    RsNominalBars *c = s->nominal;
    size_t bar;
    if (c->ready == 1 + tangent) return 0;
    c->ready = 0;
    for (bar = 0; bar < s->n_bar; bar++) {
        double *terms = c->bars + bar * RS_BAR_TERMS;
        if (bar_tangent(s, bar, s->positions, s->rotations, s->k_natural + bar * 49, tangent, terms, terms + 12,
                        tangent == TANGENT_EXACT ? terms + 156 : NULL) != 0)
            return -1;
    }
    c->ready = 1 + tangent;
    return 0;
}

/* k (n x n) = the bars' tangent (as `tangent` says) + springs + other; f: the bars' internal force; k NULL: the
 * force alone (first derivatives only). at_nominal: positions and rotations are the nominal state's. */
static int assemble(const RsStructure *s, const double *factor, const double *positions, const double *rotations,
                    int at_nominal, int tangent, const double *k_springs, double *k, double *f) {
    const size_t n = s->n_dof;
    size_t bar, i, a, c;
    double kn[49], f_e[12], k_e[144];
    if ((at_nominal || tangent == TANGENT_NOMINAL_CURVATURE) &&
        nominal_bars(s, tangent == TANGENT_MATERIAL ? TANGENT_MATERIAL : TANGENT_EXACT) != 0)
        return -1;
    memset(f, 0, n * sizeof(double));
    if (k) {
        memcpy(k, k_springs, n * n * sizeof(double));
        for (i = 0; i < s->other.nnz; i++) k[s->other.rows[i] * n + s->other.cols[i]] += s->other.vals[i];
    }
    for (bar = 0; bar < s->n_bar; bar++) {
        const double scale = s->bar_param[bar] >= 0 ? factor[s->bar_param[bar]] : 1.0;
        double *terms = s->nominal->bars + bar * RS_BAR_TERMS;
        size_t dof[12];
        if (at_nominal) {
            for (i = 0; i < 12; i++) f_e[i] = scale * terms[i];
            if (k)
                for (i = 0; i < 144; i++) k_e[i] = scale * terms[12 + i];
        } else {
            for (i = 0; i < 49; i++) kn[i] = scale * s->k_natural[bar * 49 + i];
            if (bar_tangent(s, bar, positions, rotations, kn, tangent, f_e, k ? k_e : NULL,
                            tangent == TANGENT_NOMINAL_CURVATURE ? terms + 156 : NULL) != 0)
                return -1;
        }
        for (a = 0; a < 12; a++) dof[a] = 6 * (size_t)s->bar_nodes[2 * bar + (a < 6 ? 0 : 1)] + a % 6;
        for (a = 0; a < 12; a++) {
            f[dof[a]] += f_e[a];
            if (k)
                for (c = 0; c < 12; c++) k[dof[a] * n + dof[c]] += k_e[a * 12 + c];
        }
    }
    return 0;
}

/* T's entries grouped by `keys` (its rows or its columns, n of them): group g's are order[start[g]] ..
 * order[start[g + 1] - 1] (start: n + 1 entries, order: t->nnz). */
static void group_entries(const RsTriplets *t, const int64_t *keys, size_t n, size_t *start, size_t *order) {
    size_t e, g;
    memset(start, 0, (n + 1) * sizeof(size_t));
    for (e = 0; e < t->nnz; e++) start[keys[e] + 1]++;
    for (g = 0; g < n; g++) start[g + 1] += start[g];
    for (e = 0; e < t->nnz; e++) order[start[keys[e]]++] = e;
    for (g = n; g > 0; g--) start[g] = start[g - 1];
    start[0] = 0;
}

/* out (nt x nt) = T^T a T for a dense a (n x n) and T as triplets (n x nt) grouped by column (group_entries):
 * row c of out is the sum over T's entries (r, c, v) of v T^T a[r]; T selects and combines a few DOFs per column,
 * so this reads only the rows of a that T touches, each once. */
static void reduce(const double *a, size_t n, const RsTriplets *t, size_t nt, const size_t *col_start,
                   const size_t *col_order, double *out) {
    size_t c, x, e;
    memset(out, 0, nt * nt * sizeof(double));
    for (c = 0; c < nt; c++) {
        double *orow = out + c * nt;
        for (x = col_start[c]; x < col_start[c + 1]; x++) {
            const double v = t->vals[col_order[x]], *arow = a + (size_t)t->rows[col_order[x]] * n;
            for (e = 0; e < t->nnz; e++) orow[t->cols[e]] += v * (t->vals[e] * arow[t->rows[e]]);
        }
    }
}

/* y (n x m) = T x (x: nt x m) */
static void expand(const RsTriplets *t, const double *x, size_t m, double *y, size_t n) {
    size_t e, j;
    memset(y, 0, n * m * sizeof(double));
    for (e = 0; e < t->nnz; e++)
        for (j = 0; j < m; j++) y[t->rows[e] * m + j] += t->vals[e] * x[t->cols[e] * m + j];
}

/* x (nt) = T^T y (y: n) */
static void restrict_vector(const RsTriplets *t, const double *y, double *x, size_t nt) {
    size_t e;
    memset(x, 0, nt * sizeof(double));
    for (e = 0; e < t->nnz; e++) x[t->cols[e]] += t->vals[e] * y[t->rows[e]];
}

/* out (nt x nt) += v T[r, :]^T T[c, :] for each entry (r, c, v) of a sparse matrix (scale[e] times, if scale):
 * T^T M T without M dense (a mass is nearly diagonal; T grouped by row: group_entries). */
static void reduce_sparse(const RsTriplets *m, const double *scale, const RsTriplets *t, const size_t *start,
                          const size_t *order, size_t nt, double *out) {
    size_t e, a, b;
    for (e = 0; e < m->nnz; e++) {
        const size_t r = (size_t)m->rows[e], c = (size_t)m->cols[e];
        const double v = scale ? scale[e] * m->vals[e] : m->vals[e];
        if (v == 0.0) continue;
        for (a = start[r]; a < start[r + 1]; a++) {
            const double va = v * t->vals[order[a]];
            double *row = out + (size_t)t->cols[order[a]] * nt;
            for (b = start[c]; b < start[c + 1]; b++) row[t->cols[order[b]]] += va * t->vals[order[b]];
        }
    }
}

static void advance(size_t n_grid, const double *delta, double *positions, double *rotations) {
    size_t g;
    int i, j, k;
    for (g = 0; g < n_grid; g++) {
        cx th[3], r[9];
        double old[9];
        for (i = 0; i < 3; i++) {
            positions[3 * g + i] += delta[6 * g + i];
            th[i] = delta[6 * g + 3 + i];
        }
        rotation_matrix(th, r);
        memcpy(old, rotations + 9 * g, sizeof(old));
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) {
                double acc = 0.0;
                for (k = 0; k < 3; k++) acc += creal(r[i * 3 + k]) * old[k * 3 + j];
                rotations[9 * g + i * 3 + j] = acc;
            }
    }
}

/* ---- the preload -------------------------------------------------------------------------------- */

/* Newton iterations from the nominal equilibrium; k: the tangent at the new one. Modified Newton: the tangent
 * of the current state until the work ratio falls below FRESH_TANGENT_WORK, then kept while each iteration's work
 * falls below a quarter of the last one's (as the preload's own iterations do, mace_fmu/fe/preload.py). The
 * first iteration's tangent is the nominal state's, scaled bar by bar; the later ones take the nominal
 * curvatures with the current forces (TANGENT_NOMINAL_CURVATURE: as fast as exact tangents here, three
 * iterations); the tangent of the equilibrium reached, the modes' stiffness, is exact. */
static int equilibrium(const MaceAlloc *al, const RsStructure *s, const double *factor, const double *k_springs,
                       const double *load, double *k, int *iterations, char *err) {
    const size_t n = s->n_dof, ns = s->n_static;
    double *pos = ml_work(al, s->n_grid * 3), *rot = ml_work(al, s->n_grid * 9), *u = ml_work(al, n);
    double *f = ml_work(al, n), *r = ml_work(al, n), *rs = ml_work(al, ns), *kr = ml_work(al, ns * ns);
    double *delta = ml_work(al, n), *tr = ml_work(al, n);
    size_t *col_start = (size_t *)al->calloc(ns + 1, sizeof(size_t));
    size_t *col_order = (size_t *)al->calloc(s->static_t.nnz + 1, sizeof(size_t));
    double previous = HUGE_VAL;
    size_t i, j;
    int it, factored = 0, status = -1;
    if (!pos || !rot || !u || !f || !r || !rs || !kr || !delta || !tr || !col_start || !col_order) {
        snprintf(err, MACE_ERR_LEN, "out of memory in the preload's re-solve");
        goto done;
    }
    group_entries(&s->static_t, s->static_t.cols, ns, col_start, col_order);
    memcpy(pos, s->positions, s->n_grid * 3 * sizeof(double));
    memcpy(rot, s->rotations, s->n_grid * 9 * sizeof(double));
    memcpy(u, s->displacements, n * sizeof(double));
    for (it = 1; it <= MAX_ITERATIONS; it++) {
        double work_done = 0.0, scale = 0.0, ratio;
        /* the first iteration is at the nominal state */
        if (assemble(s, factor, pos, rot, it == 1, it == 1 ? TANGENT_EXACT : TANGENT_NOMINAL_CURVATURE, k_springs,
                     factored ? NULL : k, f) != 0)
            goto rotation;
        for (i = 0; i < n; i++) {
            double spring = 0.0;
            for (j = 0; j < n; j++) spring += k_springs[i * n + j] * u[j];
            r[i] = load[i] - f[i] - spring;
        }
        restrict_vector(&s->static_t, r, rs, ns);
        if (!factored) {
            reduce(k, n, &s->static_t, ns, col_start, col_order, kr);
            if (ml_cholesky(kr, ns) != 0) {
                snprintf(err, MACE_ERR_LEN, "the gravity preload's tangent stiffness is not positive definite for "
                         "these parameters (the structure buckles or hangs unstably)");
                goto done;
            }
            factored = 1;
        }
        memcpy(delta, rs, ns * sizeof(double));
        ml_cholesky_solve(kr, ns, 1, delta, 1);
        ml_cholesky_solve(kr, ns, 0, delta, 1);
        expand(&s->static_t, delta, 1, tr, n); /* tr = T x, then delta = T x and tr = T r */
        memcpy(delta, tr, n * sizeof(double));
        expand(&s->static_t, rs, 1, tr, n);
        advance(s->n_grid, delta, pos, rot);
        for (i = 0; i < n; i++) {
            u[i] += delta[i];
            work_done += delta[i] * tr[i];
            scale += u[i] * load[i];
        }
        ratio = fabs(work_done) / fmax(fabs(scale), 1e-300);
        if (ratio <= WORK_TOLERANCE) {
            *iterations = it;
            if (assemble(s, factor, pos, rot, 0, TANGENT_EXACT, k_springs, k, f) != 0) goto rotation;
            status = 0;
            goto done;
        }
        /* a fresh tangent until the work is small (a first step with a stale one diverged: the cables' geometric
           stiffness moves with their forces) and whenever an iteration stops contracting */
        if (ratio > FRESH_TANGENT_WORK || ratio > 0.25 * previous) factored = 0;
        previous = ratio;
    }
    snprintf(err, MACE_ERR_LEN, "the gravity preload did not converge in %d Newton iterations from the nominal "
             "equilibrium: the parameters are too far from nominal for this structure", MAX_ITERATIONS);
    goto done;
rotation:
    snprintf(err, MACE_ERR_LEN, "a bar's local rotation exceeds %g rad in the preload's re-solve: the structure "
             "deforms beyond small-strain beam theory for these parameters", MAX_LOCAL_ROTATION);
done:
    ml_release(al, pos);
    ml_release(al, rot);
    ml_release(al, u);
    ml_release(al, f);
    ml_release(al, r);
    ml_release(al, rs);
    ml_release(al, kr);
    ml_release(al, col_start);
    ml_release(al, col_order);
    ml_release(al, delta);
    ml_release(al, tr);
    return status;
}

/* ---- the modes ---------------------------------------------------------------------------------- */

static int compare_doubles(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median of the positive entries of the diagonal of a (n x n); 1 if there are none. */
static double positive_diagonal_median(const MaceAlloc *al, const double *a, size_t n) {
    double *v = ml_zeros(al, n), out = 1.0;
    size_t i, count = 0;
    if (!v) return 1.0;
    for (i = 0; i < n; i++)
        if (a[i * n + i] > 0.0) v[count++] = a[i * n + i];
    if (count) {
        qsort(v, count, sizeof(double), compare_doubles);
        out = count % 2 ? v[count / 2] : 0.5 * (v[count / 2 - 1] + v[count / 2]);
    }
    al->free(v);
    return out;
}

/* The `count` lowest modes of (k, m) on the modal DOFs (n x n each): eigenvalues [rad^2/s^2] ascending in
 * w2 and M-normalised vectors in x (n x count), the massless DOFs condensed statically, then shift and invert
 * (mace_fmu/iomodel/resolve.py: the low modes to round-off relative to themselves). */
static int lowest_modes(const MaceAlloc *al, const double *k, const double *m, size_t n, size_t count, double *w2,
                        double *x, char *err) {
    size_t *a_idx = (size_t *)al->calloc(n + 1, sizeof(size_t)), *o_idx = (size_t *)al->calloc(n + 1, sizeof(size_t));
    size_t na = 0, no = 0, i, j, q;
    double biggest = 0.0, sigma;
    double *koo = NULL, *g = NULL, *kc = NULL, *mc = NULL, *c = NULL, *mu = NULL, *y = NULL;
    int status = -1;
    if (!a_idx || !o_idx) goto oom;
    for (i = 0; i < n; i++) biggest = fmax(biggest, m[i * n + i]);
    for (i = 0; i < n; i++) {
        if (m[i * n + i] <= MASSLESS_FRACTION * biggest)
            o_idx[no++] = i;
        else
            a_idx[na++] = i;
    }
    if (count > na) count = na;
    koo = ml_work(al, no * no);
    g = ml_work(al, no * na);
    kc = ml_work(al, na * na);
    mc = ml_work(al, na * na);
    c = ml_work(al, na * na);
    mu = ml_work(al, na);
    y = ml_work(al, na * count);
    if (!koo || !g || !kc || !mc || !c || !mu || !y) goto oom;
    for (i = 0; i < no; i++) {
        for (j = 0; j < no; j++) koo[i * no + j] = k[o_idx[i] * n + o_idx[j]];
        for (j = 0; j < na; j++) g[i * na + j] = k[o_idx[i] * n + a_idx[j]];
    }
    if (no && ml_cholesky(koo, no) != 0) {
        snprintf(err, MACE_ERR_LEN, "the re-solve: the massless DOFs' stiffness is not positive definite");
        goto done;
    }
    if (no) { /* g = K_oo^-1 K_oa */
        ml_cholesky_solve(koo, no, 1, g, na);
        ml_cholesky_solve(koo, no, 0, g, na);
    }
    for (i = 0; i < na; i++) { /* K_c = K_aa - K_ao g, K_ao's zeros skipped (a band: most of it) */
        for (j = 0; j < na; j++) {
            kc[i * na + j] = k[a_idx[i] * n + a_idx[j]];
            mc[i * na + j] = m[a_idx[i] * n + a_idx[j]];
        }
        for (q = 0; q < no; q++) {
            const double f = k[a_idx[i] * n + o_idx[q]];
            if (f == 0.0) continue;
            for (j = 0; j < na; j++) kc[i * na + j] -= f * g[q * na + j];
        }
    }
    for (i = 0; i < na; i++)
        for (j = 0; j < i; j++) {
            kc[i * na + j] = kc[j * na + i] = 0.5 * (kc[i * na + j] + kc[j * na + i]);
            mc[i * na + j] = mc[j * na + i] = 0.5 * (mc[i * na + j] + mc[j * na + i]);
        }
    sigma = -1e-6 * positive_diagonal_median(al, kc, na) / positive_diagonal_median(al, mc, na);
    for (i = 0; i < na * na; i++) kc[i] -= sigma * mc[i];
    if (ml_cholesky(kc, na) != 0) {
        snprintf(err, MACE_ERR_LEN, "the re-solve: the stiffness is not positive definite (an unstable structure)");
        goto done;
    }
    memcpy(c, mc, na * na * sizeof(double)); /* L^-1 M, its transpose M L^-T, then L^-1 M L^-T */
    ml_cholesky_solve(kc, na, 1, c, na);
    for (i = 0; i < na; i++)
        for (j = 0; j < i; j++) {
            const double t = c[i * na + j];
            c[i * na + j] = c[j * na + i];
            c[j * na + i] = t;
        }
    ml_cholesky_solve(kc, na, 1, c, na);
    for (i = 0; i < na; i++)
        for (j = 0; j < i; j++) c[i * na + j] = c[j * na + i] = 0.5 * (c[i * na + j] + c[j * na + i]);
    if (ml_sym_eigh_largest(al, c, na, count, mu, y) != 0) { /* the largest mu first: the lowest modes */
        snprintf(err, MACE_ERR_LEN, "the re-solve's eigen-solution did not converge");
        goto done;
    }
    for (j = 0; j < count; j++) w2[j] = sigma + 1.0 / mu[j];
    ml_cholesky_solve(kc, na, 0, y, count); /* x_a = L^-T y */
    memset(mu, 0, count * sizeof(double)); /* x^T M x of each vector, M's zeros skipped (it is nearly diagonal) */
    for (i = 0; i < na; i++)
        for (q = 0; q < na; q++) {
            const double f = mc[i * na + q];
            if (f == 0.0) continue;
            for (j = 0; j < count; j++) mu[j] += y[i * count + j] * f * y[q * count + j];
        }
    for (j = 0; j < count; j++) mu[j] = 1.0 / sqrt(mu[j]);
    for (i = 0; i < na; i++)
        for (j = 0; j < count; j++) y[i * count + j] *= mu[j];
    memset(x, 0, n * count * sizeof(double));
    for (i = 0; i < na; i++) memcpy(x + a_idx[i] * count, y + i * count, count * sizeof(double));
    for (i = 0; i < no; i++) { /* x_o = -g x_a, along the rows of x_a */
        double *row = x + o_idx[i] * count;
        for (q = 0; q < na; q++) {
            const double f = g[i * na + q];
            if (f == 0.0) continue;
            for (j = 0; j < count; j++) row[j] -= f * y[q * count + j];
        }
    }
    status = 0;
    goto done;
oom:
    snprintf(err, MACE_ERR_LEN, "out of memory in the re-solve's eigen-solution");
done:
    ml_release(al, a_idx);
    ml_release(al, o_idx);
    ml_release(al, koo);
    ml_release(al, g);
    ml_release(al, kc);
    ml_release(al, mc);
    ml_release(al, c);
    ml_release(al, mu);
    ml_release(al, y);
    return status;
}

/* ---- the whole re-solve ------------------------------------------------------------------------- */

int rs_flexible_modes(const MaceAlloc *al, const RsStructure *s, const double *rel, double *freq_hz,
                      double *shapes, int *iterations, char *err) {
    const size_t n = s->n_dof, nm = s->n_modal, count = s->count;
    double *factor = ml_work(al, s->n_phys), *ks = ml_work(al, n * n), *k = ml_work(al, n * n);
    double *change = ml_work(al, s->dm.nnz), *load = ml_work(al, n), *f = ml_work(al, n);
    double *km = ml_work(al, nm * nm), *mm = ml_work(al, nm * nm);
    double *w2 = ml_work(al, count), *xm = ml_work(al, nm * count), *x = ml_work(al, n * count);
    double *freq = ml_work(al, count), *score = NULL, *overlap = NULL, *norm = ml_work(al, count);
    size_t *flex_new = (size_t *)al->calloc(count + 1, sizeof(size_t)), *col = NULL;
    size_t *row_start = (size_t *)al->calloc(n + 1, sizeof(size_t));
    size_t *col_start = (size_t *)al->calloc(nm + 1, sizeof(size_t));
    size_t *row_order = (size_t *)al->calloc(s->modal_t.nnz + 1, sizeof(size_t));
    size_t *col_order = (size_t *)al->calloc(s->modal_t.nnz + 1, sizeof(size_t));
    size_t i, j, e, p, n_new = 0, zeros = 0, square;
    int status = -1;
    *iterations = 0;
    if (!factor || !ks || !k || !change || !load || !f || !km || !mm || !w2 || !xm || !x || !freq || !norm ||
        !flex_new || !row_start || !col_start || !row_order || !col_order)
        goto oom;
    for (p = 0; p < s->n_phys; p++) factor[p] = 1.0 + rel[p];
    for (i = 0; i < s->n_spring; i++) { /* K_s = sum k e e^T */
        const double kk = s->spring_k[i] * (s->spring_param[i] >= 0 ? factor[s->spring_param[i]] : 1.0);
        const double *vec = s->spring_vectors + i * n;
        for (j = 0; j < n; j++) {
            if (vec[j] == 0.0) continue;
            for (e = 0; e < n; e++) ks[j * n + e] += kk * vec[j] * vec[e];
        }
    }
    memcpy(load, s->load, n * sizeof(double));
    for (e = 0; e < s->dm.nnz; e++) {
        change[e] = factor[s->dm_part[e]] - 1.0;
        load[s->dm.rows[e]] += change[e] * s->dm.vals[e] * s->gravity[s->dm.cols[e]];
    }
    if (s->large_preload) {
        if (equilibrium(al, s, factor, ks, load, k, iterations, err) != 0) goto done;
    } else if (assemble(s, factor, s->positions, s->rotations, 1, TANGENT_MATERIAL, ks, k, f) != 0) {
        snprintf(err, MACE_ERR_LEN, "the re-solve: a bar's local rotation exceeds %g rad", MAX_LOCAL_ROTATION);
        goto done;
    }
    group_entries(&s->modal_t, s->modal_t.rows, n, row_start, row_order);
    group_entries(&s->modal_t, s->modal_t.cols, nm, col_start, col_order);
    reduce(k, n, &s->modal_t, nm, col_start, col_order, km);
    reduce_sparse(&s->mass, NULL, &s->modal_t, row_start, row_order, nm, mm); /* mm: zeroed by ml_work */
    reduce_sparse(&s->dm, change, &s->modal_t, row_start, row_order, nm, mm);
    if (lowest_modes(al, km, mm, nm, count, w2, xm, err) != 0) goto done;
    expand(&s->modal_t, xm, count, x, n);
    for (j = 0; j < count; j++) {
        freq[j] = (w2[j] < 0 ? -1.0 : 1.0) * sqrt(fabs(w2[j])) / TWO_PI;
        if (fabs(freq[j]) < s->zero_hz)
            zeros++;
        else
            flex_new[n_new++] = j;
    }
    if (zeros != s->n_zero || n_new < s->n_flex) {
        snprintf(err, MACE_ERR_LEN, "the re-solve has %lu zero-frequency and %lu flexible modes, the nominal "
                 "structure %lu and %lu: a parameter value that frees or holds a rigid-body motion or a mechanism",
                 (unsigned long)zeros, (unsigned long)n_new, (unsigned long)s->n_zero, (unsigned long)s->n_flex);
        goto done;
    }
    square = n_new;
    score = ml_work(al, square * square);
    overlap = ml_work(al, s->n_flex * count);
    col = (size_t *)al->calloc(square + 1, sizeof(size_t));
    if (!score || !overlap || !col) goto oom;
    for (j = 0; j < n_new; j++) { /* x^T M0 x of each new mode, the nominal mass weighting the MAC */
        const size_t c = flex_new[j];
        double acc = 0.0;
        for (e = 0; e < s->mass.nnz; e++) acc += x[s->mass.rows[e] * count + c] * s->mass.vals[e] *
                                                 x[s->mass.cols[e] * count + c];
        norm[j] = acc;
    }
    for (e = 0; e < n; e++) /* overlap[i][c]: reference mode i (mass-weighted) times new mode c, along the rows */
        for (i = 0; i < s->n_flex; i++) {
            const double weight = s->reference[e * s->n_flex + i];
            double *row = overlap + i * count;
            const double *xe = x + e * count;
            if (weight == 0.0) continue;
            for (j = 0; j < count; j++) row[j] += weight * xe[j];
        }
    for (i = 0; i < s->n_flex; i++)
        for (j = 0; j < n_new; j++) {
            const double cross_mass = overlap[i * count + flex_new[j]];
            score[i * square + j] = cross_mass * cross_mass / (s->reference_norm[i] * norm[j]);
        }
    if (ml_assign_max(al, score, square, col) != 0) goto oom;
    for (i = 0; i < s->n_flex; i++) {
        const size_t c = flex_new[col[i]];
        freq_hz[i] = freq[c];
        for (e = 0; e < n; e++) shapes[e * s->n_flex + i] = x[e * count + c];
    }
    status = 0;
    goto done;
oom:
    snprintf(err, MACE_ERR_LEN, "out of memory in the structure's re-solve");
done:
    ml_release(al, factor);
    ml_release(al, ks);
    ml_release(al, k);
    ml_release(al, change);
    ml_release(al, row_start);
    ml_release(al, col_start);
    ml_release(al, row_order);
    ml_release(al, col_order);
    ml_release(al, load);
    ml_release(al, f);
    ml_release(al, km);
    ml_release(al, mm);
    ml_release(al, w2);
    ml_release(al, xm);
    ml_release(al, x);
    ml_release(al, freq);
    ml_release(al, score);
    ml_release(al, overlap);
    ml_release(al, norm);
    ml_release(al, flex_new);
    ml_release(al, col);
    return status;
}
