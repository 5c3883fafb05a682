/* Exact zero-order-hold stepping of x' = A x + B u, y = C x + D u with the input held over a step.
 *
 * Fast form: the states are balanced, ordered by the strongly connected components of A's
 * graph (upstream first), each component is brought to real modal form (1x1 and 2x2 blocks)
 * and the components are decoupled by small Sylvester equations. The step is then one 2x2
 * rotation per mode plus the input and output products: O(n (m + p)) instead of O(n^2). The
 * identical Bessel filters of the MACE models are separate components that never need
 * decoupling from each other, which keeps the transformation well conditioned.
 * When a component has no well-conditioned modal form (a Jordan block, e.g. an undamped double
 * integrator) or two coupled components share an eigenvalue, the dense exact form
 * expm([[A, B], [0, 0]] h) is used instead: as exact, slower.
 *
 * Step matrices are kept for the last few step sizes; a step size within a few ulps of the
 * current time of a cached one reuses it (hosts compute t[k+1] - t[k]).
 */
#ifndef MACE_ZOH_H
#define MACE_ZOH_H

#include <stddef.h>

#include "mace_linalg.h"

typedef struct MaceZoh MaceZoh;

MaceZoh *zoh_create(const MaceAlloc *al, size_t n, size_t m, size_t p);
void zoh_destroy(MaceZoh *z);
/* Prepares the stepping of (A, B, C, D) (row-major); forget cached steps. */
int zoh_prepare(MaceZoh *z, const double *a, const double *b, const double *c, const double *d, char *err);
int zoh_is_fast(const MaceZoh *z);
/* Condition number (1-norm) of the fast form's transformation to the model's states. */
double zoh_condition(const MaceZoh *z);
/* s <- the state after h seconds from time t with inputs u held; s in stepping coordinates. */
int zoh_step(MaceZoh *z, double *s, const double *u, double t, double h, char *err);
void zoh_output(const MaceZoh *z, const double *s, const double *u, double *y);
/* Typical size of each state x_i: the largest |x_i(t)| of the responses to unit steps on each
 * input, sampled from 0.1 ms to 1 s (fast form only; returns -1 for the dense form). States no
 * input reaches get 1. For solvers' error control (nominal values in model exchange). */
int zoh_state_scales(MaceZoh *z, double *scale);
/* Between stepping coordinates s and the model's states x. */
void zoh_to_x(const MaceZoh *z, const double *s, double *x);
void zoh_from_x(const MaceZoh *z, const double *x, double *s);

#endif
