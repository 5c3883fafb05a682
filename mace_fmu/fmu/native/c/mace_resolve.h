/* The structure solved again for new physical parameters (mace_fmu/iomodel/resolve.py, step by step): the
 * bars' natural stiffness, the springs and the masses scaled; 1-g: Newton iterations of the corotational bars
 * (mace_fmu/fe/corotational.py) from the nominal equilibrium to the new one and the tangent there; the modes of
 * the modal constraints' reduced problem (massless DOFs condensed, shift and invert, Householder and QL); each
 * flexible nominal mode continued by the new mode of the largest mass-weighted MAC (Hungarian assignment).
 *
 * Numerics layer: plain arrays in, plain arrays out; the arrays are borrowed from the model's data file.
 */
#ifndef MACE_RESOLVE_H
#define MACE_RESOLVE_H

#include <stddef.h>
#include <stdint.h>

#include "mace_linalg.h"

/* A sparse matrix as (row, column, value) triplets; duplicates add up. */
typedef struct RsTriplets {
    size_t nnz;
    const int64_t *rows, *cols;
    const double *vals;
} RsTriplets;

#define RS_BAR_TERMS 723 /* a bar's internal force (12), tangent (12 x 12) and curvature (7 x 9 x 9) */

/* Each bar's internal force, tangent and the second derivatives of its natural deformations (d2 d_k / dz_i dz_j)
 * at the nominal state with its nominal natural stiffness (n_bar x RS_BAR_TERMS), filled by the first re-solve
 * that needs them (ready: 0; 1, the material tangent; 2, the whole tangent and the curvature). */
typedef struct RsNominalBars {
    int ready;
    double *bars;
} RsNominalBars;

typedef struct RsStructure {
    int large_preload;        /* 1: 1-g, the large-displacement gravity preload; 0: no preload (0-g) */
    size_t n_dof, n_grid, n_bar, n_spring, n_static, n_modal, n_flex, n_zero, n_phys, count;
    const int64_t *bar_nodes; /* n_bar x 2: grid rows of the ends A and B */
    const double *frames0;    /* n_bar x 9: undeformed element axes, rows x, y, z in basic */
    const double *lengths0;   /* n_bar: undeformed lengths [m] */
    const double *k_natural;  /* n_bar x 49: natural stiffness (mace_fmu/fe/beam.py) */
    const int64_t *bar_param; /* n_bar: the physical parameter scaling the bar's stiffness, or -1 */
    const double *spring_vectors; /* n_spring x n_dof */
    const double *spring_k;       /* n_spring [N/m] */
    const int64_t *spring_param;  /* n_spring: parameter or -1 */
    RsTriplets mass;              /* nominal mass [kg, kg m^2] */
    RsTriplets dm;                /* the mass parameters' mass matrices, ... */
    const int64_t *dm_part;       /* ... each entry's parameter */
    RsTriplets other;             /* stiffness no parameter scales (0-g: the elements other than bars, springs) */
    RsTriplets static_t, modal_t; /* the static and the modal constraints' T (n_dof x n_static, n_dof x n_modal) */
    const double *gravity, *load, *displacements; /* n_dof: field [m/s^2], nominal load [N], equilibrium [m, rad] */
    const double *positions, *rotations;          /* the nominal equilibrium: n_grid x 3 [m], n_grid x 9 */
    const double *reference;      /* n_dof x n_flex: M0 phi0 of the nominal flexible modes */
    const double *reference_norm; /* n_flex: phi0^T M0 phi0 */
    double zero_hz;               /* modes below this [Hz] form the zero-frequency cluster */
    RsNominalBars *nominal;       /* the model's own (mutable) cache of the bars at the nominal state */
} RsStructure;

/* The n_flex flexible modes continuing the nominal ones, the physical parameters at (1 + rel[p]) times nominal:
 * freq_hz (n_flex) and mass-normalised shapes (n_dof x n_flex, row-major). *iterations: Newton's. 0, or -1 with
 * the reason in err. */
int rs_flexible_modes(const MaceAlloc *al, const RsStructure *s, const double *rel, double *freq_hz,
                      double *shapes, int *iterations, char *err);

#endif
