/* Dense linear algebra for the MACE FMU runtime: libc and libm only, no LAPACK.
 *
 * Matrices are row-major: a[i * ncols + j] is row i, column j. Functions that need scratch
 * memory take the instance's allocator (FMI 2 hosts provide one) and return -1 when it fails.
 */
#ifndef MACE_LINALG_H
#define MACE_LINALG_H

#include <stddef.h>

/* Size of the error message buffer (char err[MACE_ERR_LEN]) that functions of every layer write into. */
#define MACE_ERR_LEN 1024

typedef struct MaceWork MaceWork;

typedef struct MaceAlloc {
    void *(*calloc)(size_t nobj, size_t size);
    void (*free)(void *obj);
    MaceWork *work; /* large work arrays kept between uses (ml_work), or NULL */
} MaceAlloc;

/* n zeroed doubles from the allocator (NULL if it fails; n == 0 gives a valid 1-element block). */
double *ml_zeros(const MaceAlloc *al, size_t n);

/* Work arrays kept from one use to the next. Every initialisation off nominal allocates the same large
 * temporaries; glibc maps blocks this large afresh and unmaps them when freed, and the kernel's zeroed pages cost
 * a sixth of an initialisation. ml_work: n zeroed doubles, a kept block of exactly that size if one is free
 * (large arrays only, the rest as ml_zeros); ml_release: the end of an ml_work (or ml_zeros) array's use. The
 * kept blocks are freed by ml_work_destroy. One MaceWork serves one thread at a time (an FMU instance's). */
MaceWork *ml_work_create(const MaceAlloc *al);
void ml_work_destroy(const MaceAlloc *al, MaceWork *work);
double *ml_work(const MaceAlloc *al, size_t n);
void ml_release(const MaceAlloc *al, void *p);

/* out (r x c) = a (r x k) b (k x c); out must not alias a or b. Zero entries of a are skipped. */
void ml_matmul(size_t r, size_t k, size_t c, const double *a, const double *b, double *out);
/* out (r x c) += a (r x k) b (k x c). */
void ml_matmul_acc(size_t r, size_t k, size_t c, const double *a, const double *b, double *out);

/* LU factorisation with partial pivoting, in place. Returns 0, or -1 for an exactly singular matrix. */
int ml_lu(double *a, size_t n, size_t *piv);
/* Solves (LU) x = b for nrhs right-hand sides; b is n x nrhs and is overwritten by x. */
void ml_lu_solve(const double *lu, size_t n, const size_t *piv, double *b, size_t nrhs);
/* inverse of a (n x n) into out; -1 if singular. */
int ml_inverse(const MaceAlloc *al, const double *a, size_t n, double *out);
/* 1-norm (largest absolute column sum). */
double ml_norm1(const double *a, size_t r, size_t c);

/* Symmetric eigen-solution by cyclic Jacobi rotations (small relative errors, also for graded
 * matrices): a (n x n, symmetric) is destroyed, w gets the eigenvalues (unsorted), the columns
 * of v the orthonormal eigenvectors. Returns 0, or -1 if 100 sweeps did not converge. */
int ml_jacobi_eigh(double *a, size_t n, double *w, double *v);

/* The k largest eigenvalues of a symmetric a (n x n, read only) and their eigenvectors: Householder
 * tridiagonalisation and implicit QL (EISPACK tred2/tql2, as in the public-domain JAMA package), O(n^3) with a
 * small constant, for the matrices too large for Jacobi rotations. QL's rotations are recorded and applied to
 * the k wanted vectors only, last first (each wanted vector of the tridiagonal is the rotations' product times
 * a unit vector): the same orthogonal transformations as tql2's, a third of its work for k = n / 3. w gets the
 * eigenvalues in descending order, the columns of v (n x k) the orthonormal eigenvectors. Returns 0, or -1
 * (allocation, or QL not converging). */
int ml_sym_eigh_largest(const MaceAlloc *al, const double *a, size_t n, size_t k, double *w, double *v);

/* Cholesky factor of a symmetric positive definite a (n x n): a = L L^T, L lower triangular, in place (the
 * upper triangle is zeroed). Returns 0, or -1 when a pivot is not positive (a not positive definite). */
int ml_cholesky(double *a, size_t n);
/* Solves L x = b (lower = 1) or L^T x = b (lower = 0) for nrhs right-hand sides with the factor of
 * ml_cholesky; b is n x nrhs and is overwritten by x. */
void ml_cholesky_solve(const double *l, size_t n, int lower, double *b, size_t nrhs);

/* One-to-one assignment rows -> columns that maximises the sum of score[i][col[i]] (square,
 * Hungarian algorithm with potentials). Returns 0 or -1 (allocation). */
int ml_assign_max(const MaceAlloc *al, const double *score, size_t n, size_t *col);

/* Diagonal scaling by powers of 2 (LAPACK 3.11+ dgebal, job 'S': 2-norms, no permutation):
 * a <- D^-1 a D in place, scale = diag(D). Returns 0 or -1 for a non-finite entry. */
int ml_balance(double *a, size_t n, double *scale);

/* Real eigen-decomposition of a general matrix (Householder reduction to Hessenberg form and
 * the shifted QR algorithm with eigenvectors, EISPACK orthes/hqr2 by Martin and Wilkinson, as in
 * the public-domain JAMA package): h (n x n) is destroyed; wr, wi get the eigenvalues; v the
 * real eigenvector matrix with a v = v d, d block diagonal with [[wr, wi], [-wi, wr]] (wi > 0)
 * for each complex pair and wr for a real eigenvalue. Returns 0, or -1 if QR did not converge. */
int ml_eig(const MaceAlloc *al, double *h, size_t n, double *wr, double *wi, double *v);

/* Matrix exponential by scaling and squaring with the [13/13] Pade approximant (Higham 2005). */
int ml_expm(const MaceAlloc *al, const double *a, size_t n, double *out);

/* Solves a x = b for a small system (n <= 8) by Gaussian elimination with partial pivoting;
 * a and b are overwritten. Returns -1 when a pivot is below 1e-13 of the largest entry. */
int ml_solve_small(double *a, size_t n, double *b);

#endif
