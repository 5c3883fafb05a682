"""Sparse factorisation of a symmetric FE matrix, reordered first so that its factors stay thin.

A structure's stiffness is as banded as its numbering lets it be; decks number grids as their
authors please. The DOFs are renumbered first, in the ordering that fills least for this matrix
(mace_fmu.sparse.ordering): reverse Cuthill-McKee on a slender structure, nested dissection on a wide
one, each measured by CHOLMOD's symbolic analysis before any number is factored. Either fills less
than SuperLU's default column ordering, with the deck's numbering or a random one alike, and on a wide
structure nested dissection less than RCM.

A positive definite matrix (K - sigma M below every eigenvalue, the modal solution's) is factored
by CHOLMOD's supernodal Cholesky in that order: half the storage of an LU and dense blocks in the
triangular solves, which a shift-invert eigen-solution is mostly made of. CHOLMOD comes with cvxopt's
wheels (mace_fmu.sparse.cholmod loads it on OpenBLAS and solves many right-hand sides in one pass over
the factor). From a factor of 50 million entries up it is factored as two substructures joined at
their interface, one on each core (mace_fmu.sparse.substructures). The figures are in
benchmarks/RESULTS.md, "The sparse solver's figures, by module".
Any other matrix (a tangent stiffness that is indefinite on the way to a stable state), or one
that turns out not to be positive definite, goes to SuperLU with threshold pivoting, in the
ordering chosen the same way (AMD excepted: CHOLMOD keeps its permutation to itself).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from mace_fmu.sparse.cholmod import CholeskySolve, SymbolicFactor, numeric
from mace_fmu.sparse.cholmod import load as load_cholmod
from mace_fmu.sparse.ordering import Analysis, analyse, least_fill_permutation
from mace_fmu.sparse.substructures import NotPositiveDefinite, substructured_cholesky

Solve = Callable[[np.ndarray], np.ndarray]


def factorize(matrix: sparse.sparray | np.ndarray, *, positive_definite: bool = False,
              groups: np.ndarray | None = None) -> Solve:
    """A function x = solve(b) for the square symmetric ``matrix``.

    Parameters
    ----------
    matrix : scipy.sparse array or numpy.ndarray
        The symmetric matrix (only its values are used, in any sparse format).
    positive_definite : bool
        Try a sparse Cholesky first (the matrix is expected to be positive definite); it falls back
        to the LU when CHOLMOD is not installed or finds a non-positive pivot.
    groups : numpy.ndarray, optional
        One label per row, the grid of each DOF: nested dissection then orders the grids (faster,
        the same fill), each grid's DOFs together.

    Returns
    -------
    callable
        ``solve(b)`` for a vector ``b`` of the matrix's size, or a matrix of such columns (solved
        together: one pass over the factor for all of them).

    Raises
    ------
    RuntimeError
        The matrix is singular (SuperLU's message).
    """
    a = sparse.csr_array(matrix)
    if positive_definite:
        analysis = analyse(a, groups=groups)
        # two substructures on two cores where the matrix is large (mace_fmu.sparse.substructures), else the whole
        try:
            solve = substructured_cholesky(a, analysis) or _cholesky(analysis, a.shape[0])
        except NotPositiveDefinite:  # the whole would fail as well: to the LU at once
            solve = None
        if solve is not None:
            return solve
    # RCM or nested dissection (AMD's permutation stays inside CHOLMOD); a pattern factored before
    # (Newton iterations) reuses its choice
    perm = least_fill_permutation(a, groups=groups)
    # threshold pivoting that prefers the diagonal (keeps the ordering's fill) but still pivots where a
    # tangent stiffness is indefinite on the way to a stable state (the preload's first Newton steps)
    lu = splu(sparse.csc_array(a[perm][:, perm]), permc_spec="NATURAL", diag_pivot_thresh=0.1,
              options={"SymmetricMode": True})
    inverse = np.empty_like(perm)
    inverse[perm] = np.arange(len(perm))

    def solve_lu(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        return lu.solve(b[perm])[inverse]

    return solve_lu


def _cholesky(analysis: Analysis, n: int) -> Solve | None:
    """CHOLMOD's L L^T in the analysed ordering; None without cvxopt or for a matrix that is not positive
    definite."""
    symbolic = analysis.symbolic
    if symbolic is None:
        return None
    done = numeric(symbolic, analysis.lower_triangle)  # False: a non-positive pivot, not positive definite
    if done is None and not isinstance(symbolic, SymbolicFactor):  # a cvxopt factor ctypes cannot take: cvxopt's
        try:
            cholmod = load_cholmod()
            assert cholmod is not None  # a cvxopt factor: cvxopt is there
            cholmod.numeric(analysis.lower, symbolic)
            done = True
        except ArithmeticError:
            done = False
    return CholeskySolve(symbolic, n) if done else None
