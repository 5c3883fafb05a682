/* Exact zero-order-hold stepping (see mace_zoh.h). */
#include "mace_zoh.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define ZOH_CACHE 4
/* Largest accepted condition number of the decoupling transformation; above it the dense form
 * is used. Measured on the MACE models: 6e4 (1-norm); outputs equal the dense ZOH to 1e-12. */
#define ZOH_MAX_COND 1e6

typedef struct StepCache {
    double h;
    double *phi; /* fast: 4 numbers per block; dense: n x n column-major */
    double *g;   /* m x n: g[k * n + i], the effect of input k on state i */
    int used;
} StepCache;

struct MaceZoh {
    MaceAlloc al;
    size_t n, m, p;
    int fast;
    double condition; /* of the decoupling transformation (1-norm), fast form only */
    size_t nblk;
    size_t *bpos;
    unsigned char *bsize;
    double *bre, *bim; /* block [[re, im], [-im, re]] or the real eigenvalue re */
    double *sx, *sinv; /* fast form: x = sx s, s = sinv x */
    double *a, *b;     /* dense form: the continuous A and B */
    double *bt;        /* n x m input matrix in stepping coordinates */
    double *ct;        /* n x p: ct[i * p + o], output o per unit of state i */
    double *d;         /* p x m */
    double *tmp;
    StepCache cache[ZOH_CACHE];
    size_t next;
};

MaceZoh *zoh_create(const MaceAlloc *al, size_t n, size_t m, size_t p) {
    MaceZoh *z = (MaceZoh *)al->calloc(1, sizeof(MaceZoh));
    size_t k;
    if (!z) return NULL;
    z->al = *al;
    z->n = n;
    z->m = m;
    z->p = p;
    z->bpos = (size_t *)al->calloc(n ? n : 1, sizeof(size_t));
    z->bsize = (unsigned char *)al->calloc(n ? n : 1, 1);
    z->bre = ml_zeros(al, n);
    z->bim = ml_zeros(al, n);
    z->sx = ml_zeros(al, n * n);
    z->sinv = ml_zeros(al, n * n);
    z->a = ml_zeros(al, n * n);
    z->b = ml_zeros(al, n * m);
    z->bt = ml_zeros(al, n * m);
    z->ct = ml_zeros(al, n * p);
    z->d = ml_zeros(al, p * m);
    z->tmp = ml_zeros(al, n);
    for (k = 0; k < ZOH_CACHE; k++) {
        z->cache[k].phi = ml_zeros(al, n * n > 4 * n ? n * n : 4 * n);
        z->cache[k].g = ml_zeros(al, m * n);
        if (!z->cache[k].phi || !z->cache[k].g) break;
    }
    if (k < ZOH_CACHE || !z->bpos || !z->bsize || !z->bre || !z->bim || !z->sx || !z->sinv || !z->a || !z->b ||
        !z->bt || !z->ct || !z->d || !z->tmp) {
        zoh_destroy(z);
        return NULL;
    }
    return z;
}

void zoh_destroy(MaceZoh *z) {
    size_t k;
    if (!z) return;
    for (k = 0; k < ZOH_CACHE; k++) {
        z->al.free(z->cache[k].phi);
        z->al.free(z->cache[k].g);
    }
    z->al.free(z->bpos);
    z->al.free(z->bsize);
    z->al.free(z->bre);
    z->al.free(z->bim);
    z->al.free(z->sx);
    z->al.free(z->sinv);
    z->al.free(z->a);
    z->al.free(z->b);
    z->al.free(z->bt);
    z->al.free(z->ct);
    z->al.free(z->d);
    z->al.free(z->tmp);
    z->al.free(z);
}

int zoh_is_fast(const MaceZoh *z) { return z->fast; }
double zoh_condition(const MaceZoh *z) { return z->fast ? z->condition : 1.0; }

/* ---- strongly connected components (Tarjan, iterative), upstream first --------------------- */

/* comp[v] = component of state v, numbered in topological order of the condensation (a state
 * depends only on states of its own or earlier components); returns the number of components. */
static long components(const MaceAlloc *al, const double *a, size_t n, size_t *comp) {
    size_t *index = (size_t *)al->calloc(n + 1, sizeof(size_t)), *low = (size_t *)al->calloc(n + 1, sizeof(size_t));
    size_t *stack = (size_t *)al->calloc(n + 1, sizeof(size_t)), *cs_v = (size_t *)al->calloc(n + 1, sizeof(size_t));
    size_t *cs_next = (size_t *)al->calloc(n + 1, sizeof(size_t));
    char *on = (char *)al->calloc(n + 1, 1);
    size_t counter = 1, sp = 0, csp = 0, ncomp = 0, v0, k;
    long result = -1;
    if (!index || !low || !stack || !cs_v || !cs_next || !on) goto done;
    for (v0 = 0; v0 < n; v0++) {
        if (index[v0]) continue;
        index[v0] = low[v0] = counter++;
        stack[sp++] = v0;
        on[v0] = 1;
        cs_v[csp] = v0;
        cs_next[csp++] = 0;
        while (csp) {
            size_t v = cs_v[csp - 1], i = cs_next[csp - 1];
            while (i < n && (i == v || a[i * n + v] == 0.0)) i++; /* successors: states that read x_v */
            if (i < n) {
                cs_next[csp - 1] = i + 1;
                if (!index[i]) {
                    index[i] = low[i] = counter++;
                    stack[sp++] = i;
                    on[i] = 1;
                    cs_v[csp] = i;
                    cs_next[csp++] = 0;
                } else if (on[i] && index[i] < low[v]) {
                    low[v] = index[i];
                }
            } else {
                csp--;
                if (low[v] == index[v]) {
                    size_t w;
                    do {
                        w = stack[--sp];
                        on[w] = 0;
                        comp[w] = ncomp; /* emitted downstream first */
                    } while (w != v);
                    ncomp++;
                }
                if (csp && low[v] < low[cs_v[csp - 1]]) low[cs_v[csp - 1]] = low[v];
            }
        }
    }
    for (k = 0; k < n; k++) comp[k] = ncomp - 1 - comp[k];
    result = (long)ncomp;
done:
    al->free(index);
    al->free(low);
    al->free(stack);
    al->free(cs_v);
    al->free(cs_next);
    al->free(on);
    return result;
}

/* ---- the decoupled modal form -------------------------------------------------------------- */

static void block_matrix(const MaceZoh *z, size_t k, double l[4]) {
    l[0] = z->bre[k];
    l[1] = z->bim[k];
    l[2] = -z->bim[k];
    l[3] = z->bre[k];
}

/* Solves L_i X - X L_j = -R for X (si x sj), the blocks' own 1x1 or 2x2 matrices. */
static int sylvester(const double li[4], size_t si, const double lj[4], size_t sj, const double *r, double *x) {
    double kmat[16], rhs[4];
    size_t q = si * sj, row, col, t;
    memset(kmat, 0, sizeof(kmat));
    for (col = 0; col < sj; col++) {
        for (row = 0; row < si; row++) {
            size_t eq = row + col * si;
            rhs[eq] = -r[row * sj + col];
            for (t = 0; t < si; t++) kmat[eq * q + (t + col * si)] += li[row * 2 + t];
            for (t = 0; t < sj; t++) kmat[eq * q + (row + t * si)] -= lj[t * 2 + col];
        }
    }
    if (ml_solve_small(kmat, q, rhs) != 0) return -1;
    for (col = 0; col < sj; col++)
        for (row = 0; row < si; row++) x[row * sj + col] = rhs[row + col * si];
    return 0;
}

/* 0: the fast form is ready; 1: no well-conditioned fast form (use the dense one); -1: memory. */
/* x = t^-1 for t (n x n) block lower triangular by component (component c: states start[c] .. start[c + 1] - 1)
 * whose diagonal blocks' inverses are x's diagonal blocks already (x zero elsewhere): block row by block row,
 * x_ij = -x_ii sum_{j <= k < i} t_ik x_kj, t's zeros skipped. work: n x n. Against a dense inverse: the same
 * matrix, at the cost of the couplings between components instead of n^3. */
static void block_lower_inverse(const double *t, size_t n, const size_t *start, size_t ncomp, double *x, double *work) {
    size_t ci, cj, r, q, k, col;
    for (ci = 1; ci < ncomp; ci++) {
        const size_t oi = start[ci], si = start[ci + 1] - oi;
        for (cj = 0; cj < ci; cj++) {
            const size_t oj = start[cj], sj = start[cj + 1] - oj;
            int nonzero = 0;
            for (r = 0; r < si; r++) { /* work (si x sj) = sum_k t_ik x_kj */
                double *wrow = work + r * sj;
                const double *trow = t + (oi + r) * n;
                memset(wrow, 0, sj * sizeof(double));
                for (k = oj; k < oi; k++) {
                    const double f = trow[k];
                    const double *xrow = x + k * n + oj;
                    if (f == 0.0) continue;
                    nonzero = 1;
                    for (col = 0; col < sj; col++) wrow[col] += f * xrow[col];
                }
            }
            if (!nonzero) continue;
            for (r = 0; r < si; r++) {
                double *xrow = x + (oi + r) * n + oj;
                const double *xii = x + (oi + r) * n + oi;
                for (col = 0; col < sj; col++) xrow[col] = 0.0;
                for (q = 0; q < si; q++) {
                    const double f = xii[q];
                    const double *wrow = work + q * sj;
                    if (f == 0.0) continue;
                    for (col = 0; col < sj; col++) xrow[col] -= f * wrow[col];
                }
            }
        }
    }
}

static int fast_form(MaceZoh *z, const double *a_in, const double *b_in, const double *c_in) {
    const MaceAlloc *al = &z->al;
    const size_t n = z->n, m = z->m, p = z->p;
    double *ab = ml_work(al, n * n), *scale = ml_work(al, n), *ap = ml_work(al, n * n);
    double *v = ml_work(al, n * n), *vinv = ml_work(al, n * n), *t = ml_work(al, n * n);
    double *cf = ml_work(al, p * n), *bp = ml_work(al, n * m), *cp = ml_work(al, p * n);
    double *blk = ml_work(al, n * n), *vk = ml_work(al, n * n), *wr = ml_work(al, n), *wi = ml_work(al, n);
    size_t *comp = (size_t *)al->calloc(n + 1, sizeof(size_t)), *perm = (size_t *)al->calloc(n + 1, sizeof(size_t));
    size_t *start = (size_t *)al->calloc(n + 2, sizeof(size_t)), *bcomp = (size_t *)al->calloc(n + 1, sizeof(size_t));
    size_t i, j, k, r, cc, bi, bj, nblk = 0;
    long ncomp;
    int status = 1;
    if (!ab || !scale || !ap || !v || !vinv || !t || !cf || !bp || !cp || !blk || !vk || !wr || !wi || !comp ||
        !perm || !start || !bcomp) {
        status = -1;
        goto done;
    }
    memcpy(ab, a_in, n * n * sizeof(double));
    if (ml_balance(ab, n, scale) != 0) goto done;
    ncomp = components(al, ab, n, comp);
    if (ncomp < 0) {
        status = -1;
        goto done;
    }
    /* order the states by component */
    for (k = 0; k < n; k++) start[comp[k] + 1]++;
    for (k = 0; k < (size_t)ncomp; k++) start[k + 1] += start[k];
    {
        size_t *fill = (size_t *)al->calloc((size_t)ncomp + 1, sizeof(size_t));
        if (!fill) {
            status = -1;
            goto done;
        }
        for (k = 0; k < n; k++) perm[start[comp[k]] + fill[comp[k]]++] = k;
        ml_release(al, fill);
    }
    for (i = 0; i < n; i++) {
        for (j = 0; j < n; j++) ap[i * n + j] = ab[perm[i] * n + perm[j]];
        for (k = 0; k < m; k++) bp[i * m + k] = b_in[perm[i] * m + k] / scale[perm[i]];
        for (k = 0; k < p; k++) cp[k * n + i] = c_in[k * n + perm[i]] * scale[perm[i]];
    }
    /* each component in real modal form: v (block diagonal), vinv, and the 1x1/2x2 blocks */
    for (cc = 0; cc < (size_t)ncomp; cc++) {
        const size_t off = start[cc], sz = start[cc + 1] - start[cc];
        double nv, ni;
        for (i = 0; i < sz; i++)
            for (j = 0; j < sz; j++) blk[i * sz + j] = ap[(off + i) * n + off + j];
        if (ml_eig(al, blk, sz, wr, wi, vk) != 0) goto done;
        for (i = 0; i < sz;) {
            size_t w = (wi[i] == 0.0) ? 1 : 2;
            double norm = 0.0;
            if (w == 2 && !(i + 1 < sz && wi[i] > 0.0 && wi[i + 1] == -wi[i])) goto done;
            for (r = 0; r < sz; r++)
                for (j = i; j < i + w; j++) norm += vk[r * sz + j] * vk[r * sz + j];
            if (!(norm > 0.0) || !isfinite(norm)) goto done;
            norm = 1.0 / sqrt(norm);
            for (r = 0; r < sz; r++)
                for (j = i; j < i + w; j++) vk[r * sz + j] *= norm;
            z->bpos[nblk] = off + i;
            z->bsize[nblk] = (unsigned char)w;
            z->bre[nblk] = wr[i];
            z->bim[nblk] = (w == 2) ? wi[i] : 0.0;
            bcomp[nblk++] = cc;
            i += w;
        }
        if (ml_inverse(al, vk, sz, blk) != 0) goto done;
        nv = ml_norm1(vk, sz, sz);
        ni = ml_norm1(blk, sz, sz);
        if (!(nv * ni <= ZOH_MAX_COND)) goto done;
        for (i = 0; i < sz; i++) {
            for (j = 0; j < sz; j++) {
                v[(off + i) * n + off + j] = vk[i * sz + j];
                vinv[(off + i) * n + off + j] = blk[i * sz + j];
            }
        }
    }
    /* at = vinv ap v (stored in ap), with the diagonal blocks exactly the modal blocks */
    memset(t, 0, n * n * sizeof(double));
    for (cc = 0; cc < (size_t)ncomp; cc++) {
        const size_t off = start[cc], sz = start[cc + 1] - start[cc];
        for (i = 0; i < n; i++)
            for (k = 0; k < sz; k++) {
                const double f = ap[i * n + off + k];
                if (f == 0.0) continue;
                for (j = 0; j < sz; j++) t[i * n + off + j] += f * v[(off + k) * n + off + j];
            }
    }
    memset(ap, 0, n * n * sizeof(double));
    memset(z->bt, 0, n * m * sizeof(double));
    for (cc = 0; cc < (size_t)ncomp; cc++) {
        const size_t off = start[cc], sz = start[cc + 1] - start[cc];
        for (i = 0; i < sz; i++)
            for (k = 0; k < sz; k++) {
                const double f = vinv[(off + i) * n + off + k];
                if (f == 0.0) continue;
                for (j = 0; j < off; j++) ap[(off + i) * n + j] += f * t[(off + k) * n + j];
                for (j = 0; j < m; j++) z->bt[(off + i) * m + j] += f * bp[(off + k) * m + j];
            }
    }
    for (k = 0; k < nblk; k++) {
        double l[4];
        block_matrix(z, k, l);
        for (i = 0; i < z->bsize[k]; i++)
            for (j = 0; j < z->bsize[k]; j++) ap[(z->bpos[k] + i) * n + z->bpos[k] + j] = l[i * 2 + j];
    }
    ml_matmul(p, n, n, cp, v, cf);
    memcpy(t, v, n * n * sizeof(double)); /* t: the transformation, x_balanced_permuted = t s */
    /* decouple the components: block (bi, bj) below the diagonal by x_i -> x_i - X x_j */
    for (bi = 1; bi < nblk; bi++) {
        const size_t pi = z->bpos[bi], si = z->bsize[bi];
        double li[4];
        block_matrix(z, bi, li);
        for (bj = bi; bj-- > 0;) {
            const size_t pj = z->bpos[bj], sj = z->bsize[bj];
            double rr[4], x[4], lj[4];
            int nonzero = 0;
            if (bcomp[bj] == bcomp[bi]) continue;
            for (i = 0; i < si; i++)
                for (j = 0; j < sj; j++) {
                    rr[i * sj + j] = ap[(pi + i) * n + pj + j];
                    nonzero |= rr[i * sj + j] != 0.0;
                }
            if (!nonzero) continue;
            block_matrix(z, bj, lj);
            if (sylvester(li, si, lj, sj, rr, x) != 0) goto done;
            /* rows above block i are decoupled already, so only column block j changes */
            for (r = pi + si; r < n; r++)
                for (j = 0; j < sj; j++)
                    for (k = 0; k < si; k++) ap[r * n + pj + j] += ap[r * n + pi + k] * x[k * sj + j];
            for (i = 0; i < si; i++)
                for (j = 0; j < sj; j++) ap[(pi + i) * n + pj + j] = 0.0;
            /* t's column block i is still v's (pairs before this one changed earlier column blocks only): nonzero
               in its own component's rows alone, so only those change column block j */
            for (r = start[bcomp[bi]]; r < start[bcomp[bi] + 1]; r++)
                for (j = 0; j < sj; j++)
                    for (k = 0; k < si; k++) t[r * n + pj + j] += t[r * n + pi + k] * x[k * sj + j];
            for (i = 0; i < si; i++)
                for (k = 0; k < sj; k++)
                    for (j = 0; j < m; j++) z->bt[(pi + i) * m + j] -= x[i * sj + k] * z->bt[(pj + k) * m + j];
            for (r = 0; r < p; r++)
                for (j = 0; j < sj; j++)
                    for (k = 0; k < si; k++) cf[r * n + pj + j] += cf[r * n + pi + k] * x[k * sj + j];
        }
    }
    block_lower_inverse(t, n, start, (size_t)ncomp, vinv, blk);
    z->condition = ml_norm1(t, n, n) * ml_norm1(vinv, n, n);
    if (!(z->condition <= ZOH_MAX_COND)) goto done;
    /* back to the model's state order and scaling */
    for (i = 0; i < n; i++) {
        const size_t row = perm[i];
        for (j = 0; j < n; j++) {
            z->sx[row * n + j] = scale[row] * t[i * n + j];
            z->sinv[j * n + row] = vinv[j * n + i] / scale[row];
        }
    }
    for (i = 0; i < n; i++)
        for (k = 0; k < p; k++) z->ct[i * p + k] = cf[k * n + i];
    z->nblk = nblk;
    status = 0;
done:
    ml_release(al, ab);
    ml_release(al, scale);
    ml_release(al, ap);
    ml_release(al, v);
    ml_release(al, vinv);
    ml_release(al, t);
    ml_release(al, cf);
    ml_release(al, bp);
    ml_release(al, cp);
    ml_release(al, blk);
    ml_release(al, vk);
    ml_release(al, wr);
    ml_release(al, wi);
    ml_release(al, comp);
    ml_release(al, perm);
    ml_release(al, start);
    ml_release(al, bcomp);
    return status;
}

int zoh_prepare(MaceZoh *z, const double *a, const double *b, const double *c, const double *d, char *err) {
    const size_t n = z->n, m = z->m, p = z->p;
    size_t i, k;
    int status;
    for (k = 0; k < ZOH_CACHE; k++) z->cache[k].used = 0;
    z->next = 0;
    memcpy(z->d, d, p * m * sizeof(double));
    status = fast_form(z, a, b, c);
    if (status < 0) {
        snprintf(err, MACE_ERR_LEN, "out of memory preparing the step");
        return -1;
    }
    z->fast = (status == 0);
    if (!z->fast) {
        memcpy(z->a, a, n * n * sizeof(double));
        memcpy(z->b, b, n * m * sizeof(double));
        memcpy(z->bt, b, n * m * sizeof(double));
        for (i = 0; i < n; i++)
            for (k = 0; k < p; k++) z->ct[i * p + k] = c[k * n + i];
    }
    return 0;
}

/* ---- step matrices ------------------------------------------------------------------------- */

static void fast_matrices(const MaceZoh *z, double h, double *phi, double *g) {
    const size_t n = z->n, m = z->m;
    size_t k, i, j, q;
    memset(g, 0, m * n * sizeof(double));
    for (k = 0; k < z->nblk; k++) {
        const size_t pos = z->bpos[k];
        double gam[4];
        if (z->bsize[k] == 1) {
            const double lam = z->bre[k];
            phi[4 * k] = exp(lam * h);
            gam[0] = (lam == 0.0) ? h : expm1(lam * h) / lam;
            for (q = 0; q < m; q++) g[q * n + pos] = gam[0] * z->bt[pos * m + q];
        } else {
            /* the block acts as multiplication by mu = re - i im on s[pos] + i s[pos + 1] */
            const double re = z->bre[k], im = z->bim[k];
            const double e = exp(re * h), cs = cos(im * h), sn = sin(im * h), half = sin(0.5 * im * h);
            const double num_re = expm1(re * h) * cs - 2.0 * half * half, num_im = -e * sn;
            double den = re * re + im * im, g_re, g_im; /* (e^{mu h} - 1) / mu */
            g_re = (num_re * re - num_im * im) / den;
            g_im = (num_im * re + num_re * im) / den;
            phi[4 * k] = e * cs;
            phi[4 * k + 1] = e * sn;
            phi[4 * k + 2] = -e * sn;
            phi[4 * k + 3] = e * cs;
            gam[0] = g_re;
            gam[1] = -g_im;
            gam[2] = g_im;
            gam[3] = g_re;
            for (q = 0; q < m; q++)
                for (i = 0; i < 2; i++)
                    for (j = 0; j < 2; j++) g[q * n + pos + i] += gam[i * 2 + j] * z->bt[(pos + j) * m + q];
        }
    }
}

static int dense_matrices(const MaceZoh *z, double h, double *phi, double *g) {
    const size_t n = z->n, m = z->m, nm = n + m;
    double *aug = ml_zeros(&z->al, nm * nm), *e = ml_zeros(&z->al, nm * nm);
    size_t i, j;
    int status = -1;
    if (aug && e) {
        for (i = 0; i < n; i++) {
            for (j = 0; j < n; j++) aug[i * nm + j] = z->a[i * n + j] * h;
            for (j = 0; j < m; j++) aug[i * nm + n + j] = z->b[i * m + j] * h;
        }
        if (ml_expm(&z->al, aug, nm, e) == 0) {
            for (i = 0; i < n; i++) {
                for (j = 0; j < n; j++) phi[j * n + i] = e[i * nm + j];
                for (j = 0; j < m; j++) g[j * n + i] = e[i * nm + n + j];
            }
            status = 0;
        }
    }
    z->al.free(aug);
    z->al.free(e);
    return status;
}

static StepCache *matrices_for(MaceZoh *z, double t, double h, char *err) {
    const double tol = 4.0 * DBL_EPSILON * (fabs(t) + fabs(h));
    StepCache *c;
    size_t k;
    for (k = 0; k < ZOH_CACHE; k++)
        if (z->cache[k].used && fabs(z->cache[k].h - h) <= tol) return &z->cache[k];
    c = &z->cache[z->next];
    z->next = (z->next + 1) % ZOH_CACHE;
    c->used = 0;
    if (z->fast) {
        fast_matrices(z, h, c->phi, c->g);
    } else if (dense_matrices(z, h, c->phi, c->g) != 0) {
        snprintf(err, MACE_ERR_LEN, "the matrix exponential of the %g s step failed", h);
        return NULL;
    }
    c->h = h;
    c->used = 1;
    return c;
}

int zoh_step(MaceZoh *z, double *s, const double *u, double t, double h, char *err) {
    const size_t n = z->n, m = z->m;
    const StepCache *c = matrices_for(z, t, h, err);
    size_t i, j, k;
    if (!c) return -1;
    memcpy(z->tmp, s, n * sizeof(double));
    if (z->fast) {
        for (k = 0; k < z->nblk; k++) {
            const size_t pos = z->bpos[k];
            const double *f = c->phi + 4 * k;
            if (z->bsize[k] == 1) {
                s[pos] = f[0] * z->tmp[pos];
            } else {
                s[pos] = f[0] * z->tmp[pos] + f[1] * z->tmp[pos + 1];
                s[pos + 1] = f[2] * z->tmp[pos] + f[3] * z->tmp[pos + 1];
            }
        }
    } else {
        memset(s, 0, n * sizeof(double));
        for (j = 0; j < n; j++) {
            const double xj = z->tmp[j];
            const double *col = c->phi + j * n;
            if (xj == 0.0) continue;
            for (i = 0; i < n; i++) s[i] += col[i] * xj;
        }
    }
    for (k = 0; k < m; k++) {
        const double uk = u[k];
        const double *col = c->g + k * n;
        if (uk == 0.0) continue;
        for (i = 0; i < n; i++) s[i] += col[i] * uk;
    }
    for (i = 0; i < n; i++) {
        if (!isfinite(s[i])) {
            snprintf(err, MACE_ERR_LEN, "the state overflowed at t = %g s (an unstable model run too long?)", t + h);
            return -1;
        }
    }
    return 0;
}

void zoh_output(const MaceZoh *z, const double *s, const double *u, double *y) {
    const size_t n = z->n, m = z->m, p = z->p;
    size_t i, k;
    for (k = 0; k < p; k++) {
        double acc = 0.0;
        for (i = 0; i < m; i++) acc += z->d[k * m + i] * u[i];
        y[k] = acc;
    }
    for (i = 0; i < n; i++) {
        const double si = s[i];
        const double *row = z->ct + i * p;
        if (si == 0.0) continue;
        for (k = 0; k < p; k++) y[k] += row[k] * si;
    }
}

int zoh_state_scales(MaceZoh *z, double *scale) {
    const size_t n = z->n, m = z->m;
    double *phi = ml_zeros(&z->al, 4 * n), *g = ml_zeros(&z->al, m * n), *x = ml_zeros(&z->al, n);
    size_t i, k;
    int step, status = -1;
    if (z->fast && phi && g && x) {
        for (i = 0; i < n; i++) scale[i] = 0.0;
        for (step = 0; step <= 12; step++) {
            fast_matrices(z, pow(10.0, -4.0 + step / 3.0), phi, g);
            for (k = 0; k < m; k++) {
                zoh_to_x(z, g + k * n, x);
                for (i = 0; i < n; i++)
                    if (fabs(x[i]) > scale[i]) scale[i] = fabs(x[i]);
            }
        }
        for (i = 0; i < n; i++)
            if (!(scale[i] > 0.0) || !isfinite(scale[i])) scale[i] = 1.0;
        status = 0;
    }
    z->al.free(phi);
    z->al.free(g);
    z->al.free(x);
    return status;
}

void zoh_to_x(const MaceZoh *z, const double *s, double *x) {
    if (z->fast) {
        ml_matmul(z->n, z->n, 1, z->sx, s, x);
    } else {
        memcpy(x, s, z->n * sizeof(double));
    }
}

void zoh_from_x(const MaceZoh *z, const double *x, double *s) {
    if (z->fast) {
        ml_matmul(z->n, z->n, 1, z->sinv, x, s);
    } else {
        memcpy(s, x, z->n * sizeof(double));
    }
}
