"""Sparse factorisation of a symmetric FE matrix, reordered first so that its factors stay thin.

A structure's stiffness is as banded as its numbering lets it be; decks number grids as their
authors please. Reverse Cuthill-McKee renumbers the DOFs into a narrow band whatever the deck's
numbering. On a 10k-DOF lattice tower this gives a third fewer nonzeros in the factors than
SuperLU's default column ordering and half its factor time, with the deck's numbering or a random
one alike (benchmarks/RESULTS.md, "FE core at scale").

A positive definite matrix (K - sigma M below every eigenvalue, the modal solution's) is factored
by CHOLMOD's supernodal Cholesky in that order: half the storage of an LU and dense blocks in the
triangular solves. A shift-invert eigen-solution is mostly solves, and at 100k DOFs one takes
41 ms instead of SuperLU's 88 ms, the factorisation 0.5 s instead of 2.7 s. CHOLMOD comes with
cvxopt's wheels. Its own fill-reducing ordering (AMD) was slower on that tower: 14 s to factor,
158 ms a solve.
Any other matrix (a tangent stiffness that is indefinite on the way to a stable state), or one
that turns out not to be positive definite, goes to SuperLU with threshold pivoting.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import reverse_cuthill_mckee
from scipy.sparse.linalg import splu

Solve = Callable[[np.ndarray], np.ndarray]


def factorize(matrix: sparse.sparray | np.ndarray, *, positive_definite: bool = False) -> Solve:
    """A function x = solve(b) for the square symmetric ``matrix``.

    Parameters
    ----------
    matrix : scipy.sparse array or numpy.ndarray
        The symmetric matrix (only its values are used, in any sparse format).
    positive_definite : bool
        Try a sparse Cholesky first (the matrix is expected to be positive definite); it falls back
        to the LU when CHOLMOD is not installed or finds a non-positive pivot.

    Returns
    -------
    callable
        ``solve(b)`` for a vector ``b`` of the matrix's size, or a matrix of such columns.

    Raises
    ------
    RuntimeError
        The matrix is singular (SuperLU's message).
    """
    a = sparse.csr_array(matrix)
    perm = reverse_cuthill_mckee(sparse.csr_matrix(a), symmetric_mode=True)
    if positive_definite:
        solve = _cholesky(a, perm)
        if solve is not None:
            return solve
    # threshold pivoting that prefers the diagonal (keeps the band) but still pivots where a tangent
    # stiffness is indefinite on the way to a stable state (the preload's first Newton steps)
    lu = splu(sparse.csc_array(a[perm][:, perm]), permc_spec="NATURAL", diag_pivot_thresh=0.1,
              options=dict(SymmetricMode=True))
    inverse = np.empty_like(perm)
    inverse[perm] = np.arange(len(perm))

    def solve_lu(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        return lu.solve(b[perm])[inverse]

    return solve_lu


def _cholesky(a: sparse.csr_array, perm: np.ndarray) -> Solve | None:
    """CHOLMOD's L L^T of ``a`` in the order ``perm``; None without cvxopt or for a matrix that is not
    positive definite."""
    try:
        import cvxopt
        import cvxopt.cholmod
    except ImportError:
        return None
    lower = sparse.tril(a).tocoo()
    n = a.shape[0]
    matrix = cvxopt.spmatrix(lower.data, lower.row.astype(int), lower.col.astype(int), (n, n))
    try:
        factor = cvxopt.cholmod.symbolic(matrix, p=cvxopt.matrix(perm.astype(int)), uplo="L")
        cvxopt.cholmod.numeric(matrix, factor)
    except ArithmeticError:  # a non-positive pivot: not positive definite
        return None

    def solve(b: np.ndarray) -> np.ndarray:
        x = cvxopt.matrix(np.ascontiguousarray(np.asarray(b, dtype=float).reshape(n, -1)))  # one or more columns
        cvxopt.cholmod.solve(factor, x)
        return np.asarray(x).reshape(np.shape(b))

    return solve
