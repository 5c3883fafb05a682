/* Dense linear algebra for the MACE FMU runtime (see mace_linalg.h). */
#include "mace_linalg.h"

#include <float.h>
#include <math.h>
#include <string.h>

double *ml_zeros(const MaceAlloc *al, size_t n) {
    return (double *)al->calloc(n ? n : 1, sizeof(double));
}

/* ---- kept work arrays ------------------------------------------------------------------------ */

#define WORK_SLOTS 64
#define WORK_MIN_BYTES 65536 /* smaller blocks come from the allocator's own free lists */

struct MaceWork {
    void *block[WORK_SLOTS];
    size_t bytes[WORK_SLOTS];
    unsigned char used[WORK_SLOTS];
};

MaceWork *ml_work_create(const MaceAlloc *al) { return (MaceWork *)al->calloc(1, sizeof(MaceWork)); }

void ml_work_destroy(const MaceAlloc *al, MaceWork *work) {
    size_t k;
    if (!work) return;
    for (k = 0; k < WORK_SLOTS; k++) al->free(work->block[k]);
    al->free(work);
}

double *ml_work(const MaceAlloc *al, size_t n) {
    MaceWork *w = al->work;
    const size_t bytes = (n ? n : 1) * sizeof(double);
    size_t k, slot = WORK_SLOTS;
    double *p;
    if (!w || bytes < WORK_MIN_BYTES) return ml_zeros(al, n);
    for (k = 0; k < WORK_SLOTS; k++) {
        if (w->block[k] && !w->used[k] && w->bytes[k] == bytes) {
            w->used[k] = 1;
            memset(w->block[k], 0, bytes);
            return (double *)w->block[k];
        }
        if (slot == WORK_SLOTS && !w->block[k]) slot = k;
    }
    for (k = 0; slot == WORK_SLOTS && k < WORK_SLOTS; k++) /* all slots taken: give up a free block of another size */
        if (!w->used[k]) {
            al->free(w->block[k]);
            w->block[k] = NULL;
            slot = k;
        }
    p = ml_zeros(al, n);
    if (p && slot < WORK_SLOTS) {
        w->block[slot] = p;
        w->bytes[slot] = bytes;
        w->used[slot] = 1;
    }
    return p;
}

void ml_release(const MaceAlloc *al, void *p) {
    MaceWork *w = al->work;
    size_t k;
    if (!p) return;
    if (w)
        for (k = 0; k < WORK_SLOTS; k++)
            if (w->block[k] == p) {
                w->used[k] = 0;
                return;
            }
    al->free(p);
}

void ml_matmul_acc(size_t r, size_t k, size_t c, const double *a, const double *b, double *out) {
    size_t i, l, j;
    for (i = 0; i < r; i++) {
        double *row = out + i * c;
        for (l = 0; l < k; l++) {
            const double f = a[i * k + l];
            const double *brow = b + l * c;
            if (f == 0.0) continue;
            for (j = 0; j < c; j++) row[j] += f * brow[j];
        }
    }
}

void ml_matmul(size_t r, size_t k, size_t c, const double *a, const double *b, double *out) {
    memset(out, 0, r * c * sizeof(double));
    ml_matmul_acc(r, k, c, a, b, out);
}

int ml_lu(double *a, size_t n, size_t *piv) {
    size_t i, j, k;
    for (k = 0; k < n; k++) {
        size_t p = k;
        double big = fabs(a[k * n + k]);
        for (i = k + 1; i < n; i++) {
            if (fabs(a[i * n + k]) > big) {
                big = fabs(a[i * n + k]);
                p = i;
            }
        }
        piv[k] = p;
        if (big == 0.0) return -1;
        if (p != k) {
            for (j = 0; j < n; j++) {
                double t = a[k * n + j];
                a[k * n + j] = a[p * n + j];
                a[p * n + j] = t;
            }
        }
        for (i = k + 1; i < n; i++) {
            double f = a[i * n + k] / a[k * n + k];
            a[i * n + k] = f;
            if (f == 0.0) continue;
            for (j = k + 1; j < n; j++) a[i * n + j] -= f * a[k * n + j];
        }
    }
    return 0;
}

void ml_lu_solve(const double *lu, size_t n, const size_t *piv, double *b, size_t nrhs) {
    size_t i, j, k;
    for (k = 0; k < n; k++) {
        if (piv[k] != k) {
            for (j = 0; j < nrhs; j++) {
                double t = b[k * nrhs + j];
                b[k * nrhs + j] = b[piv[k] * nrhs + j];
                b[piv[k] * nrhs + j] = t;
            }
        }
    }
    for (i = 1; i < n; i++) {  /* L y = P b, unit lower triangular */
        for (k = 0; k < i; k++) {
            double f = lu[i * n + k];
            if (f == 0.0) continue;
            for (j = 0; j < nrhs; j++) b[i * nrhs + j] -= f * b[k * nrhs + j];
        }
    }
    for (i = n; i-- > 0;) {  /* U x = y */
        for (k = i + 1; k < n; k++) {
            double f = lu[i * n + k];
            if (f == 0.0) continue;
            for (j = 0; j < nrhs; j++) b[i * nrhs + j] -= f * b[k * nrhs + j];
        }
        for (j = 0; j < nrhs; j++) b[i * nrhs + j] /= lu[i * n + i];
    }
}

int ml_inverse(const MaceAlloc *al, const double *a, size_t n, double *out) {
    double *lu = ml_work(al, n * n);
    size_t *piv = (size_t *)al->calloc(n ? n : 1, sizeof(size_t));
    size_t i;
    int status = -1;
    if (lu && piv) {
        memcpy(lu, a, n * n * sizeof(double));
        memset(out, 0, n * n * sizeof(double));
        for (i = 0; i < n; i++) out[i * n + i] = 1.0;
        if (ml_lu(lu, n, piv) == 0) {
            ml_lu_solve(lu, n, piv, out, n);
            status = 0;
        }
    }
    ml_release(al, lu);
    ml_release(al, piv);
    return status;
}

double ml_norm1(const double *a, size_t r, size_t c) {
    double best = 0.0;
    size_t i, j;
    for (j = 0; j < c; j++) {
        double s = 0.0;
        for (i = 0; i < r; i++) s += fabs(a[i * c + j]);
        if (s > best) best = s;
    }
    return best;
}

/* ---- Cholesky ------------------------------------------------------------------------------ */

/* First nonzero column of row i's lower triangle (i if none). */
static size_t envelope_start(const double *a, size_t n, size_t i) {
    size_t j;
    for (j = 0; j < i; j++)
        if (a[i * n + j] != 0.0) return j;
    return i;
}

int ml_cholesky(double *a, size_t n) {
    /* Within each row's envelope (its first nonzero on): a band or a profile ordering (reverse Cuthill-McKee)
       costs its width squared per row instead of n^2. Only exact zeros are skipped, so the result is the dense
       algorithm's to the bit. Row i's envelope start is kept in a[i][i + 1] (upper triangle, zeroed at the end),
       the last row's in a local. */
    size_t i, j, k, last_start;
    if (n == 0) return 0;
    for (i = 0; i + 1 < n; i++) a[i * n + i + 1] = (double)envelope_start(a, n, i);
    last_start = envelope_start(a, n, n - 1);
    for (j = 0; j < n; j++) {
        const size_t fj = j + 1 < n ? (size_t)a[j * n + j + 1] : last_start;
        double d = a[j * n + j];
        for (k = fj; k < j; k++) d -= a[j * n + k] * a[j * n + k];
        if (!(d > 0.0)) return -1;
        d = sqrt(d);
        a[j * n + j] = d;
        for (i = j + 1; i < n; i++) {
            const size_t fi = i + 1 < n ? (size_t)a[i * n + i + 1] : last_start;
            double s;
            if (fi > j) continue; /* outside row i's envelope: stays zero */
            s = a[i * n + j];
            for (k = fi > fj ? fi : fj; k < j; k++) s -= a[i * n + k] * a[j * n + k];
            a[i * n + j] = s / d;
        }
    }
    for (i = 0; i < n; i++)
        for (j = i + 1; j < n; j++) a[i * n + j] = 0.0;
    return 0;
}

void ml_cholesky_solve(const double *l, size_t n, int lower, double *b, size_t nrhs) {
    /* row by row, every right-hand side at once (contiguous in memory); each entry sees the same operations in
       the same order as a column-by-column substitution, so the results are those of one */
    size_t i, k, c;
    if (lower) {
        for (i = 0; i < n; i++) {
            double *row = b + i * nrhs;
            for (k = 0; k < i; k++) {
                const double f = l[i * n + k];
                const double *other = b + k * nrhs;
                if (f == 0.0) continue; /* a band or profile factor: most of the row */
                for (c = 0; c < nrhs; c++) row[c] -= f * other[c];
            }
            for (c = 0; c < nrhs; c++) row[c] /= l[i * n + i];
        }
    } else {
        for (i = n; i-- > 0;) {
            double *row = b + i * nrhs;
            for (k = i + 1; k < n; k++) {
                const double f = l[k * n + i];
                const double *other = b + k * nrhs;
                if (f == 0.0) continue;
                for (c = 0; c < nrhs; c++) row[c] -= f * other[c];
            }
            for (c = 0; c < nrhs; c++) row[c] /= l[i * n + i];
        }
    }
}

/* ---- symmetric eigen-solution ------------------------------------------------------------ */

int ml_jacobi_eigh(double *a, size_t n, double *w, double *v) {
    size_t p, q, r, sweep;
    for (p = 0; p < n; p++)
        for (q = 0; q < n; q++) v[p * n + q] = (p == q) ? 1.0 : 0.0;
    for (sweep = 0; sweep < 100; sweep++) {
        int rotated = 0;
        for (p = 0; p + 1 < n; p++) {
            for (q = p + 1; q < n; q++) {
                double apq = a[p * n + q], app = a[p * n + p], aqq = a[q * n + q];
                double theta, t, c, s, tau;
                /* relative threshold (Demmel and Veselic): keeps small eigenvalues accurate */
                if (apq == 0.0 || fabs(apq) <= DBL_EPSILON * 0.5 * sqrt(fabs(app) * fabs(aqq))) {
                    a[p * n + q] = a[q * n + p] = 0.0;
                    continue;
                }
                rotated = 1;
                theta = 0.5 * (aqq - app) / apq;
                if (fabs(theta) > 1e150) {
                    t = 0.5 / theta;
                } else {
                    t = 1.0 / (fabs(theta) + sqrt(1.0 + theta * theta));
                    if (theta < 0.0) t = -t;
                }
                c = 1.0 / sqrt(1.0 + t * t);
                s = t * c;
                tau = s / (1.0 + c);
                a[p * n + p] = app - t * apq;
                a[q * n + q] = aqq + t * apq;
                a[p * n + q] = a[q * n + p] = 0.0;
                for (r = 0; r < n; r++) {
                    double g, h;
                    if (r != p && r != q) {
                        g = a[r * n + p];
                        h = a[r * n + q];
                        a[r * n + p] = a[p * n + r] = g - s * (h + g * tau);
                        a[r * n + q] = a[q * n + r] = h + s * (g - h * tau);
                    }
                    g = v[r * n + p];
                    h = v[r * n + q];
                    v[r * n + p] = g - s * (h + g * tau);
                    v[r * n + q] = h + s * (g - h * tau);
                }
            }
        }
        if (!rotated) {
            for (p = 0; p < n; p++) w[p] = a[p * n + p];
            return 0;
        }
    }
    return -1;
}

/* ---- assignment ---------------------------------------------------------------------------- */

int ml_assign_max(const MaceAlloc *al, const double *score, size_t n, size_t *col) {
    /* minimum-cost assignment of cost = -score, shortest augmenting paths with potentials;
       index 0 of the column arrays is a virtual column */
    double *u = ml_work(al, n + 1), *v = ml_work(al, n + 1), *minv = ml_work(al, n + 1);
    size_t *row_of = (size_t *)al->calloc(n + 1, sizeof(size_t));
    size_t *way = (size_t *)al->calloc(n + 1, sizeof(size_t));
    char *used = (char *)al->calloc(n + 1, 1);
    size_t i, j;
    int status = -1;
    if (u && v && minv && row_of && way && used) {
        for (i = 1; i <= n; i++) {
            size_t j0 = 0;
            row_of[0] = i;
            for (j = 0; j <= n; j++) {
                minv[j] = HUGE_VAL;
                used[j] = 0;
            }
            do {
                size_t i0 = row_of[j0], j1 = 0;
                double delta = HUGE_VAL;
                used[j0] = 1;
                for (j = 1; j <= n; j++) {
                    if (!used[j]) {
                        double cur = -score[(i0 - 1) * n + (j - 1)] - u[i0] - v[j];
                        if (cur < minv[j]) {
                            minv[j] = cur;
                            way[j] = j0;
                        }
                        if (minv[j] < delta) {
                            delta = minv[j];
                            j1 = j;
                        }
                    }
                }
                for (j = 0; j <= n; j++) {
                    if (used[j]) {
                        u[row_of[j]] += delta;
                        v[j] -= delta;
                    } else {
                        minv[j] -= delta;
                    }
                }
                j0 = j1;
            } while (row_of[j0] != 0);
            do {
                size_t j1 = way[j0];
                row_of[j0] = row_of[j1];
                j0 = j1;
            } while (j0);
        }
        for (j = 1; j <= n; j++) col[row_of[j] - 1] = j - 1;
        status = 0;
    }
    ml_release(al, u);
    ml_release(al, v);
    ml_release(al, minv);
    ml_release(al, row_of);
    ml_release(al, way);
    ml_release(al, used);
    return status;
}

/* ---- balancing ----------------------------------------------------------------------------- */

int ml_balance(double *a, size_t n, double *scale) {
    const double radix = 2.0, factor = 0.95;
    const double sfmin1 = DBL_MIN / DBL_EPSILON, sfmax1 = 1.0 / sfmin1;
    const double sfmin2 = sfmin1 * radix, sfmax2 = 1.0 / sfmin2;
    size_t i, k;
    int noconv = 1;
    for (i = 0; i < n; i++) scale[i] = 1.0;
    while (noconv) {
        noconv = 0;
        for (i = 0; i < n; i++) {
            double c = 0.0, r = 0.0, ca = 0.0, ra = 0.0, g, f, s;
            for (k = 0; k < n; k++) {
                double x = a[k * n + i], y = a[i * n + k];
                c += x * x;
                r += y * y;
                if (fabs(x) > ca) ca = fabs(x);
                if (fabs(y) > ra) ra = fabs(y);
            }
            c = sqrt(c);
            r = sqrt(r);
            if (c == 0.0 || r == 0.0) continue;
            if (isnan(c + ca + r + ra) || isinf(c + ca + r + ra)) return -1;
            g = r / radix;
            f = 1.0;
            s = c + r;
            while (c < g && fmax(f, fmax(c, ca)) < sfmax2 && fmin(r, fmin(g, ra)) > sfmin2) {
                f *= radix;
                c *= radix;
                ca *= radix;
                r /= radix;
                g /= radix;
                ra /= radix;
            }
            g = c / radix;
            while (g >= r && fmax(r, ra) < sfmax2 && fmin(fmin(f, c), fmin(g, ca)) > sfmin2) {
                f /= radix;
                c /= radix;
                g /= radix;
                ca /= radix;
                r *= radix;
                ra *= radix;
            }
            if (c + r >= factor * s) continue;
            if (f < 1.0 && scale[i] < 1.0 && f * scale[i] <= sfmin1) continue;
            if (f > 1.0 && scale[i] > 1.0 && scale[i] >= sfmax1 / f) continue;
            scale[i] *= f;
            noconv = 1;
            for (k = 0; k < n; k++) a[i * n + k] *= 1.0 / f;
            for (k = 0; k < n; k++) a[k * n + i] *= f;
        }
    }
    return 0;
}

/* ---- general real eigen-decomposition ------------------------------------------------------ */

static void cdiv(double xr, double xi, double yr, double yi, double *qr, double *qi) {
    double r, d;
    if (fabs(yr) > fabs(yi)) {
        r = yi / yr;
        d = yr + r * yi;
        *qr = (xr + r * xi) / d;
        *qi = (xi - r * xr) / d;
    } else {
        r = yr / yi;
        d = yi + r * yr;
        *qr = (r * xr + xi) / d;
        *qi = (r * xi - xr) / d;
    }
}

/* Householder reduction to upper Hessenberg form, transformations accumulated in v. */
static void orthes(double *H, size_t nn, double *V, double *ort) {
    const long n = (long)nn, high = n - 1;
    long m, i, j;
#define h_(i, j) H[(size_t)(i) * nn + (size_t)(j)]
#define v_(i, j) V[(size_t)(i) * nn + (size_t)(j)]
    for (m = 1; m <= high - 1; m++) {
        double scale = 0.0;
        for (i = m; i <= high; i++) scale += fabs(h_(i, m - 1));
        if (scale != 0.0) {
            double h = 0.0, g;
            for (i = high; i >= m; i--) {
                ort[i] = h_(i, m - 1) / scale;
                h += ort[i] * ort[i];
            }
            g = sqrt(h);
            if (ort[m] > 0) g = -g;
            h -= ort[m] * g;
            ort[m] -= g;
            for (j = m; j < n; j++) {
                double f = 0.0;
                for (i = high; i >= m; i--) f += ort[i] * h_(i, j);
                f /= h;
                for (i = m; i <= high; i++) h_(i, j) -= f * ort[i];
            }
            for (i = 0; i <= high; i++) {
                double f = 0.0;
                for (j = high; j >= m; j--) f += ort[j] * h_(i, j);
                f /= h;
                for (j = m; j <= high; j++) h_(i, j) -= f * ort[j];
            }
            ort[m] *= scale;
            h_(m, m - 1) = scale * g;
        }
    }
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++) v_(i, j) = (i == j) ? 1.0 : 0.0;
    for (m = high - 1; m >= 1; m--) {
        if (h_(m, m - 1) != 0.0) {
            for (i = m + 1; i <= high; i++) ort[i] = h_(i, m - 1);
            for (j = m; j <= high; j++) {
                double g = 0.0;
                for (i = m; i <= high; i++) g += ort[i] * v_(i, j);
                g = (g / ort[m]) / h_(m, m - 1);  /* two divisions avoid underflow */
                for (i = m; i <= high; i++) v_(i, j) += g * ort[i];
            }
        }
    }
}

/* Shifted QR on the Hessenberg matrix, then eigenvectors by back-substitution. */
static int hqr2(double *H, size_t nn_, double *d, double *e, double *V) {
    const long nn = (long)nn_, low = 0, high = nn - 1;
    const double eps = DBL_EPSILON;
    long n = nn - 1, iter = 0, total = 0, i, j, k, l, m;
    double exshift = 0.0, p = 0, q = 0, r = 0, s = 0, z = 0, t, w, x, y, norm = 0.0;

    for (i = 0; i < nn; i++)
        for (j = (i > 0 ? i - 1 : 0); j < nn; j++) norm += fabs(h_(i, j));

    while (n >= low) {
        l = n;
        while (l > low) {  /* a single small sub-diagonal element */
            s = fabs(h_(l - 1, l - 1)) + fabs(h_(l, l));
            if (s == 0.0) s = norm;
            if (fabs(h_(l, l - 1)) < eps * s) break;
            l--;
        }
        if (l == n) {  /* one root */
            h_(n, n) += exshift;
            d[n] = h_(n, n);
            e[n] = 0.0;
            n--;
            iter = 0;
        } else if (l == n - 1) {  /* two roots */
            w = h_(n, n - 1) * h_(n - 1, n);
            p = (h_(n - 1, n - 1) - h_(n, n)) / 2.0;
            q = p * p + w;
            z = sqrt(fabs(q));
            h_(n, n) += exshift;
            h_(n - 1, n - 1) += exshift;
            x = h_(n, n);
            if (q >= 0) {  /* real pair */
                z = (p >= 0) ? p + z : p - z;
                d[n - 1] = x + z;
                d[n] = d[n - 1];
                if (z != 0.0) d[n] = x - w / z;
                e[n - 1] = 0.0;
                e[n] = 0.0;
                x = h_(n, n - 1);
                s = fabs(x) + fabs(z);
                p = x / s;
                q = z / s;
                r = sqrt(p * p + q * q);
                p /= r;
                q /= r;
                for (j = n - 1; j < nn; j++) {
                    z = h_(n - 1, j);
                    h_(n - 1, j) = q * z + p * h_(n, j);
                    h_(n, j) = q * h_(n, j) - p * z;
                }
                for (i = 0; i <= n; i++) {
                    z = h_(i, n - 1);
                    h_(i, n - 1) = q * z + p * h_(i, n);
                    h_(i, n) = q * h_(i, n) - p * z;
                }
                for (i = low; i <= high; i++) {
                    z = v_(i, n - 1);
                    v_(i, n - 1) = q * z + p * v_(i, n);
                    v_(i, n) = q * v_(i, n) - p * z;
                }
            } else {  /* complex pair */
                d[n - 1] = x + p;
                d[n] = x + p;
                e[n - 1] = z;
                e[n] = -z;
            }
            n -= 2;
            iter = 0;
        } else {  /* no convergence yet: a double QR step */
            if (++total > 100 * nn) return -1;
            x = h_(n, n);
            y = 0.0;
            w = 0.0;
            if (l < n) {
                y = h_(n - 1, n - 1);
                w = h_(n, n - 1) * h_(n - 1, n);
            }
            if (iter == 10) {  /* Wilkinson's exceptional shift */
                exshift += x;
                for (i = low; i <= n; i++) h_(i, i) -= x;
                s = fabs(h_(n, n - 1)) + fabs(h_(n - 1, n - 2));
                x = y = 0.75 * s;
                w = -0.4375 * s * s;
            }
            if (iter == 30) {  /* a second exceptional shift */
                s = (y - x) / 2.0;
                s = s * s + w;
                if (s > 0) {
                    s = sqrt(s);
                    if (y < x) s = -s;
                    s = x - w / ((y - x) / 2.0 + s);
                    for (i = low; i <= n; i++) h_(i, i) -= s;
                    exshift += s;
                    x = y = w = 0.964;
                }
            }
            iter++;
            m = n - 2;  /* two consecutive small sub-diagonal elements */
            while (m >= l) {
                z = h_(m, m);
                r = x - z;
                s = y - z;
                p = (r * s - w) / h_(m + 1, m) + h_(m, m + 1);
                q = h_(m + 1, m + 1) - z - r - s;
                r = h_(m + 2, m + 1);
                s = fabs(p) + fabs(q) + fabs(r);
                p /= s;
                q /= s;
                r /= s;
                if (m == l) break;
                if (fabs(h_(m, m - 1)) * (fabs(q) + fabs(r)) <
                    eps * (fabs(p) * (fabs(h_(m - 1, m - 1)) + fabs(z) + fabs(h_(m + 1, m + 1)))))
                    break;
                m--;
            }
            for (i = m + 2; i <= n; i++) {
                h_(i, i - 2) = 0.0;
                if (i > m + 2) h_(i, i - 3) = 0.0;
            }
            for (k = m; k <= n - 1; k++) {
                int notlast = (k != n - 1);
                if (k != m) {
                    p = h_(k, k - 1);
                    q = h_(k + 1, k - 1);
                    r = notlast ? h_(k + 2, k - 1) : 0.0;
                    x = fabs(p) + fabs(q) + fabs(r);
                    if (x != 0.0) {
                        p /= x;
                        q /= x;
                        r /= x;
                    }
                }
                if (x == 0.0) break;
                s = sqrt(p * p + q * q + r * r);
                if (p < 0) s = -s;
                if (s != 0) {
                    if (k != m) {
                        h_(k, k - 1) = -s * x;
                    } else if (l != m) {
                        h_(k, k - 1) = -h_(k, k - 1);
                    }
                    p += s;
                    x = p / s;
                    y = q / s;
                    z = r / s;
                    q /= p;
                    r /= p;
                    for (j = k; j < nn; j++) {
                        p = h_(k, j) + q * h_(k + 1, j);
                        if (notlast) {
                            p += r * h_(k + 2, j);
                            h_(k + 2, j) -= p * z;
                        }
                        h_(k, j) -= p * x;
                        h_(k + 1, j) -= p * y;
                    }
                    for (i = 0; i <= (n < k + 3 ? n : k + 3); i++) {
                        p = x * h_(i, k) + y * h_(i, k + 1);
                        if (notlast) {
                            p += z * h_(i, k + 2);
                            h_(i, k + 2) -= p * r;
                        }
                        h_(i, k) -= p;
                        h_(i, k + 1) -= p * q;
                    }
                    for (i = low; i <= high; i++) {
                        p = x * v_(i, k) + y * v_(i, k + 1);
                        if (notlast) {
                            p += z * v_(i, k + 2);
                            v_(i, k + 2) -= p * r;
                        }
                        v_(i, k) -= p;
                        v_(i, k + 1) -= p * q;
                    }
                }
            }
        }
    }

    if (norm == 0.0) return 0;
    for (n = nn - 1; n >= 0; n--) {  /* back-substitution on the quasi-triangular form */
        p = d[n];
        q = e[n];
        if (q == 0) {  /* real vector */
            l = n;
            h_(n, n) = 1.0;
            for (i = n - 1; i >= 0; i--) {
                w = h_(i, i) - p;
                r = 0.0;
                for (j = l; j <= n; j++) r += h_(i, j) * h_(j, n);
                if (e[i] < 0.0) {
                    z = w;
                    s = r;
                } else {
                    l = i;
                    if (e[i] == 0.0) {
                        h_(i, n) = (w != 0.0) ? -r / w : -r / (eps * norm);
                    } else {
                        x = h_(i, i + 1);
                        y = h_(i + 1, i);
                        q = (d[i] - p) * (d[i] - p) + e[i] * e[i];
                        t = (x * s - z * r) / q;
                        h_(i, n) = t;
                        h_(i + 1, n) = (fabs(x) > fabs(z)) ? (-r - w * t) / x : (-s - y * t) / z;
                    }
                    t = fabs(h_(i, n));
                    if ((eps * t) * t > 1)
                        for (j = i; j <= n; j++) h_(j, n) /= t;
                }
            }
        } else if (q < 0) {  /* complex vector (the second of the pair) */
            l = n - 1;
            if (fabs(h_(n, n - 1)) > fabs(h_(n - 1, n))) {
                h_(n - 1, n - 1) = q / h_(n, n - 1);
                h_(n - 1, n) = -(h_(n, n) - p) / h_(n, n - 1);
            } else {
                cdiv(0.0, -h_(n - 1, n), h_(n - 1, n - 1) - p, q, &h_(n - 1, n - 1), &h_(n - 1, n));
            }
            h_(n, n - 1) = 0.0;
            h_(n, n) = 1.0;
            for (i = n - 2; i >= 0; i--) {
                double ra = 0.0, sa = 0.0, vr, vi;
                for (j = l; j <= n; j++) {
                    ra += h_(i, j) * h_(j, n - 1);
                    sa += h_(i, j) * h_(j, n);
                }
                w = h_(i, i) - p;
                if (e[i] < 0.0) {
                    z = w;
                    r = ra;
                    s = sa;
                } else {
                    l = i;
                    if (e[i] == 0) {
                        cdiv(-ra, -sa, w, q, &h_(i, n - 1), &h_(i, n));
                    } else {
                        x = h_(i, i + 1);
                        y = h_(i + 1, i);
                        vr = (d[i] - p) * (d[i] - p) + e[i] * e[i] - q * q;
                        vi = (d[i] - p) * 2.0 * q;
                        if (vr == 0.0 && vi == 0.0)
                            vr = eps * norm * (fabs(w) + fabs(q) + fabs(x) + fabs(y) + fabs(z));
                        cdiv(x * r - z * ra + q * sa, x * s - z * sa - q * ra, vr, vi, &h_(i, n - 1), &h_(i, n));
                        if (fabs(x) > (fabs(z) + fabs(q))) {
                            h_(i + 1, n - 1) = (-ra - w * h_(i, n - 1) + q * h_(i, n)) / x;
                            h_(i + 1, n) = (-sa - w * h_(i, n) - q * h_(i, n - 1)) / x;
                        } else {
                            cdiv(-r - y * h_(i, n - 1), -s - y * h_(i, n), z, q, &h_(i + 1, n - 1), &h_(i + 1, n));
                        }
                    }
                    t = fmax(fabs(h_(i, n - 1)), fabs(h_(i, n)));
                    if ((eps * t) * t > 1) {
                        for (j = i; j <= n; j++) {
                            h_(j, n - 1) /= t;
                            h_(j, n) /= t;
                        }
                    }
                }
            }
        }
    }
    for (j = nn - 1; j >= low; j--) {  /* back to the eigenvectors of the original matrix */
        for (i = low; i <= high; i++) {
            z = 0.0;
            for (k = low; k <= (j < high ? j : high); k++) z += v_(i, k) * h_(k, j);
            v_(i, j) = z;
        }
    }
    return 0;
#undef h_
#undef v_
}

int ml_eig(const MaceAlloc *al, double *h, size_t n, double *wr, double *wi, double *v) {
    double *ort = ml_work(al, n);
    int status = -1;
    if (ort) {
        if (n == 1) {
            wr[0] = h[0];
            wi[0] = 0.0;
            v[0] = 1.0;
            status = 0;
        } else {
            orthes(h, n, v, ort);
            status = hqr2(h, n, wr, wi, v);
        }
    }
    ml_release(al, ort);
    return status;
}

/* ---- matrix exponential -------------------------------------------------------------------- */

int ml_expm(const MaceAlloc *al, const double *a_in, size_t n, double *out) {
    static const double b[14] = {64764752532480000.0, 32382376266240000.0, 7771770303897600.0,
                                 1187353796428800.0,  129060195264000.0,   10559470521600.0,
                                 670442572800.0,      33522128640.0,       1323241920.0,
                                 40840800.0,          960960.0,            16380.0,
                                 182.0,               1.0};
    const size_t nn = n * n;
    double *a = ml_zeros(al, nn), *a2 = ml_zeros(al, nn), *a4 = ml_zeros(al, nn), *a6 = ml_zeros(al, nn);
    double *t = ml_zeros(al, nn), *u = ml_zeros(al, nn), *v = ml_zeros(al, nn);
    size_t *piv = (size_t *)al->calloc(n ? n : 1, sizeof(size_t));
    int status = -1, squarings = 0, k;
    size_t i;
    if (!(a && a2 && a4 && a6 && t && u && v && piv)) goto done;
    {
        double norm = ml_norm1(a_in, n, n), f = 1.0;
        if (!isfinite(norm)) goto done;
        if (norm > 5.371920351148152) squarings = (int)ceil(log2(norm / 5.371920351148152));
        if (squarings < 0) squarings = 0;
        f = ldexp(1.0, -squarings);
        for (i = 0; i < nn; i++) a[i] = a_in[i] * f;
    }
    ml_matmul(n, n, n, a, a, a2);
    ml_matmul(n, n, n, a2, a2, a4);
    ml_matmul(n, n, n, a4, a2, a6);
    for (i = 0; i < nn; i++) t[i] = b[13] * a6[i] + b[11] * a4[i] + b[9] * a2[i];
    ml_matmul(n, n, n, a6, t, u);  /* u = A6 (b13 A6 + b11 A4 + b9 A2) + b7 A6 + b5 A4 + b3 A2 + b1 I */
    for (i = 0; i < nn; i++) u[i] += b[7] * a6[i] + b[5] * a4[i] + b[3] * a2[i];
    for (i = 0; i < n; i++) u[i * n + i] += b[1];
    ml_matmul(n, n, n, a, u, t);  /* t = U */
    for (i = 0; i < nn; i++) u[i] = b[12] * a6[i] + b[10] * a4[i] + b[8] * a2[i];
    ml_matmul(n, n, n, a6, u, v);  /* v = V */
    for (i = 0; i < nn; i++) v[i] += b[6] * a6[i] + b[4] * a4[i] + b[2] * a2[i];
    for (i = 0; i < n; i++) v[i * n + i] += b[0];
    for (i = 0; i < nn; i++) {
        double p = v[i] + t[i], q = v[i] - t[i];
        out[i] = p;
        a[i] = q;
    }
    if (ml_lu(a, n, piv) != 0) goto done;
    ml_lu_solve(a, n, piv, out, n);  /* (V - U) X = V + U */
    for (k = 0; k < squarings; k++) {
        ml_matmul(n, n, n, out, out, t);
        memcpy(out, t, nn * sizeof(double));
    }
    status = 0;
done:
    al->free(a);
    al->free(a2);
    al->free(a4);
    al->free(a6);
    al->free(t);
    al->free(u);
    al->free(v);
    al->free(piv);
    return status;
}

int ml_solve_small(double *a, size_t n, double *b) {
    size_t i, j, k;
    double big = 0.0;
    for (i = 0; i < n * n; i++)
        if (fabs(a[i]) > big) big = fabs(a[i]);
    for (k = 0; k < n; k++) {
        size_t p = k;
        for (i = k + 1; i < n; i++)
            if (fabs(a[i * n + k]) > fabs(a[p * n + k])) p = i;
        if (!(fabs(a[p * n + k]) > 1e-13 * big)) return -1;
        if (p != k) {
            double tb = b[k];
            b[k] = b[p];
            b[p] = tb;
            for (j = 0; j < n; j++) {
                double t = a[k * n + j];
                a[k * n + j] = a[p * n + j];
                a[p * n + j] = t;
            }
        }
        for (i = k + 1; i < n; i++) {
            double f = a[i * n + k] / a[k * n + k];
            for (j = k; j < n; j++) a[i * n + j] -= f * a[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (i = n; i-- > 0;) {
        for (j = i + 1; j < n; j++) b[i] -= a[i * n + j] * b[j];
        b[i] /= a[i * n + i];
    }
    return 0;
}

/* Householder tridiagonalisation (EISPACK tred2's reduction, as in the public-domain JAMA package) of a symmetric
 * matrix in v: d gets the diagonal, e the subdiagonal in e[1..n-1], and v and hs the reflectors, A = P_n-1 ... P_1
 * T P_1 ... P_n-1 with P_s = I - u u^T / hs[s], u the first s entries of row s of v (hs[s] = 0: P_s = I). JAMA's
 * algorithm with every v[r][c] read as v[c][r] (the same operations in the same order), its inner loops along
 * memory instead of across it; the transformation is not accumulated (ml_sym_eigh_largest applies it to the wanted
 * vectors only, a third of the work when they are a third). */
static void tridiagonalise(double *v, size_t n, double *d, double *e, double *hs) {
    size_t i, j, k;
    for (j = 0; j < n; j++) d[j] = v[j * n + n - 1];
    for (i = n - 1; i > 0; i--) {
        double scale = 0.0, h = 0.0;
        for (k = 0; k < i; k++) scale += fabs(d[k]);
        if (scale == 0.0) {
            e[i] = d[i - 1];
            for (j = 0; j < i; j++) {
                d[j] = v[j * n + i - 1];
                v[j * n + i] = 0.0;
                v[i * n + j] = 0.0;
            }
        } else {
            double f, g, hh;
            for (k = 0; k < i; k++) {
                d[k] /= scale;
                h += d[k] * d[k];
            }
            f = d[i - 1];
            g = sqrt(h);
            if (f > 0) g = -g;
            e[i] = scale * g;
            h -= f * g;
            d[i - 1] = f - g;
            for (j = 0; j < i; j++) e[j] = 0.0;
            for (j = 0; j < i; j++) {
                f = d[j];
                v[i * n + j] = f;
                g = e[j] + v[j * n + j] * f;
                for (k = j + 1; k <= i - 1; k++) {
                    g += v[j * n + k] * d[k];
                    e[k] += v[j * n + k] * f;
                }
                e[j] = g;
            }
            f = 0.0;
            for (j = 0; j < i; j++) {
                e[j] /= h;
                f += e[j] * d[j];
            }
            hh = f / (h + h);
            for (j = 0; j < i; j++) e[j] -= hh * d[j];
            for (j = 0; j < i; j++) {
                f = d[j];
                g = e[j];
                for (k = j; k <= i - 1; k++) v[j * n + k] -= (f * e[k] + g * d[k]);
                d[j] = v[j * n + i - 1];
                v[j * n + i] = 0.0;
            }
        }
        d[i] = h;
    }
    for (i = 0; i < n; i++) { /* the reflectors' h, then the diagonal */
        hs[i] = i ? d[i] : 0.0;
        d[i] = v[i * n + i];
    }
    e[0] = 0.0;
}

/* QL's plane rotations, in the order made: rotation t mixes rows i[t] and i[t] + 1 of the vectors by (c, s). */
typedef struct Rotations {
    const MaceAlloc *al;
    size_t count, capacity;
    size_t *i;
    double *c, *s;
} Rotations;

static int rotations_add(Rotations *r, size_t i, double c, double s) {
    if (r->count == r->capacity) {
        const size_t capacity = r->capacity ? 2 * r->capacity : 1024;
        size_t *ni = (size_t *)r->al->calloc(capacity, sizeof(size_t));
        double *nc = ml_work(r->al, capacity), *ns = ml_work(r->al, capacity);
        if (!ni || !nc || !ns) {
            ml_release(r->al, ni);
            ml_release(r->al, nc);
            ml_release(r->al, ns);
            return -1;
        }
        if (r->count) {
            memcpy(ni, r->i, r->count * sizeof(size_t));
            memcpy(nc, r->c, r->count * sizeof(double));
            memcpy(ns, r->s, r->count * sizeof(double));
        }
        ml_release(r->al, r->i);
        ml_release(r->al, r->c);
        ml_release(r->al, r->s);
        r->i = ni;
        r->c = nc;
        r->s = ns;
        r->capacity = capacity;
    }
    r->i[r->count] = i;
    r->c[r->count] = c;
    r->s[r->count++] = s;
    return 0;
}

/* Implicit QL iterations of the tridiagonal (d, e) (EISPACK tql2, JAMA): d gets the eigenvalues (unordered) and
 * rot every rotation that tql2 applies to the rows of its vectors (row i' = c row i - s row i+1, row i+1' = s row
 * i + c row i+1), in order. -1 if one eigenvalue takes more than 60 iterations or memory runs out. */
static int tridiagonal_ql(Rotations *rot, size_t n, double *d, double *e) {
    size_t i, l, m;
    double f = 0.0, tst1 = 0.0;
    const double eps = DBL_EPSILON;
    for (i = 1; i < n; i++) e[i - 1] = e[i];
    e[n - 1] = 0.0;
    for (l = 0; l < n; l++) {
        int iterations = 0;
        tst1 = fmax(tst1, fabs(d[l]) + fabs(e[l]));
        m = l;
        while (m < n - 1 && fabs(e[m]) > eps * tst1) m++;
        if (m > l) {
            do {
                double g = d[l], p = (d[l + 1] - g) / (2.0 * e[l]), r = hypot(p, 1.0), dl1, h, c, c2, c3, el1, s, s2;
                if (++iterations > 60) return -1;
                if (p < 0) r = -r;
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                dl1 = d[l + 1];
                h = g - d[l];
                for (i = l + 2; i < n; i++) d[i] -= h;
                f += h;
                p = d[m];
                c = 1.0;
                c2 = c3 = c;
                el1 = e[l + 1];
                s = s2 = 0.0;
                for (i = m; i-- > l;) {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    g = c * e[i];
                    h = c * p;
                    r = hypot(p, e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    if (rotations_add(rot, i, c, s) != 0) return -1;
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
            } while (fabs(e[l]) > eps * tst1);
        }
        d[l] += f;
        e[l] = 0.0;
    }
    return 0;
}

int ml_sym_eigh_largest(const MaceAlloc *al, const double *a, size_t n, size_t k, double *w, double *v) {
    double *d = ml_work(al, n), *e = ml_work(al, n), *hs = ml_work(al, n), *q = ml_work(al, n * n);
    double *uv = ml_work(al, k);
    unsigned char *taken = (unsigned char *)al->calloc(n + 1, 1);
    Rotations rot = {0};
    size_t i, j, t;
    int status = -1;
    rot.al = al;
    if (!d || !e || !hs || !q || !uv || !taken || k > n) goto done;
    if (k == 0) {
        status = 0;
        goto done;
    }
    memcpy(q, a, n * n * sizeof(double));
    tridiagonalise(q, n, d, e, hs);
    if (tridiagonal_ql(&rot, n, d, e) != 0) goto done;
    memset(v, 0, n * k * sizeof(double));
    for (j = 0; j < k; j++) { /* the k largest, by selection (ties: the lower index first) */
        size_t best = n;
        for (i = 0; i < n; i++)
            if (!taken[i] && (best == n || d[i] > d[best])) best = i;
        taken[best] = 1;
        w[j] = d[best];
        v[best * k + j] = 1.0;
    }
    /* vector j of the tridiagonal: the transposed rotations applied to its unit vector, last first; v's row i
       holds component i of every wanted vector, so each rotation runs along two rows */
    for (t = rot.count; t-- > 0;) {
        const double c = rot.c[t], s = rot.s[t];
        double *vi = v + rot.i[t] * k, *vi1 = vi + k;
        for (j = 0; j < k; j++) {
            const double h = vi1[j];
            vi1[j] = c * h - s * vi[j];
            vi[j] = c * vi[j] + s * h;
        }
    }
    for (t = 1; t < n; t++) { /* then v = P_n-1 ... P_1 v: P_1 first */
        const double *u = q + t * n;
        if (hs[t] == 0.0) continue;
        memset(uv, 0, k * sizeof(double)); /* u^T v, every wanted vector at once */
        for (i = 0; i < t; i++)
            for (j = 0; j < k; j++) uv[j] += u[i] * v[i * k + j];
        for (i = 0; i < t; i++) {
            const double f = u[i] / hs[t];
            for (j = 0; j < k; j++) v[i * k + j] -= f * uv[j];
        }
    }
    status = 0;
done:
    ml_release(al, d);
    ml_release(al, e);
    ml_release(al, hs);
    ml_release(al, q);
    ml_release(al, uv);
    ml_release(al, taken);
    ml_release(al, rot.i);
    ml_release(al, rot.c);
    ml_release(al, rot.s);
    return status;
}
