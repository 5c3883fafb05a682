"""A large positive definite matrix factored as two substructures on two cores, joined at their interface.

CHOLMOD's supernodal factorisation runs on one core here: cvxopt's wheels carry a single-threaded
OpenBLAS, and ``cvxopt.cholmod.numeric`` holds the GIL. On a 100k-DOF wide lattice the factorisation
is the largest single step of the eigen-solution (benchmarks/RESULTS.md, "The sparse solver's figures,
by module"). The fill-reducing ordering already cuts the structure in two: nested dissection numbers
one half, then the other, then the separator between them; reverse Cuthill-McKee's band can be cut
anywhere along its length. :func:`bisect` finds where the ordering's frontier (the rows after a cut that touch a row
before it) is narrowest near the middle; those rows are the interface I, the rest the two
substructures 1 and 2, which share no entry.

Each substructure is factored with the interface last, in the ordering's own order, through
CHOLMOD on its own core (mace_fmu.sparse.cholmod.numeric releases the GIL; the wheel's OpenBLAS, although
single-threaded, takes a lock around its buffer allocation, so two threads may call it at once):

    [A_11  A_1I]   [L_11  0   ] [L_11  0   ]^T
    [A_I1  A_II] = [X_1   L_1I] [X_1   L_1I]    with  L_1I L_1I^T = A_II - A_I1 A_11^-1 A_1I,

and the same for 2. The two trailing blocks give the interface's Schur complement without a solve,
S = A_II - A_I1 A_11^-1 A_1I - A_I2 A_22^-1 A_2I = L_1I L_1I^T + L_2I L_2I^T - A_II, a dense matrix of
the interface's size (1,536 rows on the wide lattice), factored by LAPACK. A solve is then a forward
sweep with each substructure's L (on two cores), the interface's dense solve, and a backward sweep
with each L^T (on two cores): the block elimination of the matrix, exact in exact arithmetic. The
substructures' factors together hold what the whole matrix's factor in the same ordering holds (the
interface's dense block twice), so the work is about the same, on two cores instead of one.

Only where it pays: two cores or more, a factor of at least :data:`MIN_FACTOR_ENTRIES` entries in the
ordering chosen (mace_fmu.sparse.ordering, which measures it), an ordering that CHOLMOD did not keep to itself,
an interface of at most :data:`MAX_INTERFACE` rows. Otherwise, and wherever CHOLMOD cannot be reached
through ctypes, mace_fmu.sparse.factor factors the whole matrix. A substructure or a Schur complement that is
not positive definite proves the whole is not (:class:`NotPositiveDefinite`): the caller goes to its LU.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy import linalg as sla
from scipy import sparse
from threadpoolctl import threadpool_limits

from mace_fmu.sparse.cholmod import CholeskySolve, numeric
from mace_fmu.sparse.ordering import Analysis, symbolic_of_lower
from mace_fmu.util.threads import usable_cores

#: The factor size [entries] below which the whole matrix is factored. Below it the factorisation is quick
#: and the substructures' set-up (their symbolic analyses, the interface) and their solves' overhead cost
#: what the second core saves: the 100k-DOF tower's factor, half this size, is slower as substructures, the
#: wide lattice's, twice this size, twice as fast (benchmarks/RESULTS.md, "The sparse solver's figures, by
#: module").
MIN_FACTOR_ENTRIES = 50_000_000
#: The largest interface taken [rows]: its Schur complement is dense, its memory and its factorisation's work
#: growing with the square and the cube of its rows.
MAX_INTERFACE = 6_000
#: Where the cut may fall, as fractions of the rows: two substructures of about equal work.
BALANCE = (0.35, 0.65)


@dataclass(frozen=True)
class Bisection:
    """Two substructures that share no matrix entry, and the interface rows between them."""

    substructures: tuple[np.ndarray, np.ndarray]  #: each one's rows (without the interface), in the ordering's order
    interface: np.ndarray  #: the interface's rows, in the ordering's order


def bisect(matrix: sparse.sparray, permutation: np.ndarray) -> Bisection | None:
    """Cut the ordering ``permutation`` of the symmetric ``matrix`` where its frontier is narrowest near the middle.

    Parameters
    ----------
    matrix : scipy.sparse array
        The symmetric matrix (its pattern is read).
    permutation : numpy.ndarray
        A fill-reducing ordering: row ``permutation[i]`` goes to position i.

    Returns
    -------
    Bisection or None
        None when every cut within :data:`BALANCE` has more than :data:`MAX_INTERFACE` rows on its frontier,
        or the narrowest has none (the matrix falls apart there).
    """
    n = matrix.shape[0]
    position = np.empty(n, dtype=np.int64)
    position[permutation] = np.arange(n)
    pattern = sparse.coo_array(matrix)
    earliest = position.copy()  # the earliest position each row reaches (itself included)
    np.minimum.at(earliest, pattern.row, position[pattern.col])
    # row r is on the frontier of the cut before position c when earliest[r] < c <= position[r]
    reaching = earliest < position
    change = np.zeros(n + 2, dtype=np.int64)
    np.add.at(change, earliest[reaching] + 1, 1)
    np.add.at(change, position[reaching] + 1, -1)
    frontier = np.cumsum(change)[:n + 1]
    low, high = int(BALANCE[0] * n), int(BALANCE[1] * n)
    cut = low + int(np.argmin(frontier[low:high + 1]))
    if not 0 < frontier[cut] <= MAX_INTERFACE:  # no interface: parts not connected, left to the whole factor
        return None
    on_interface = (earliest < cut) & (position >= cut)
    after = permutation[cut:]
    return Bisection(substructures=(permutation[:cut], after[~on_interface[after]]),
                     interface=after[on_interface[after]])


class _Substructure:
    """One substructure with the interface: its factor, and where its rows and the interface lie in it."""

    def __init__(self, matrix: sparse.csr_array, rows: np.ndarray, interface: np.ndarray):
        self.rows = rows
        own = np.concatenate([rows, interface])
        self._block = sparse.csr_array(matrix[own][:, own])
        self.size, self.inner = len(own), len(rows)
        self._y: np.ndarray | None = None  # the sweeps' array and CHOLMOD's workspace, made at the first solve
        self._workspace: np.ndarray | None = None

    def factor(self) -> bool | None:
        """CHOLMOD's analysis in the ordering's own order (the interface last) and its numeric factorisation,
        then L_iI and L_iI L_iI^T (True: done; False: not positive definite; None: CHOLMOD not reachable
        through ctypes). Runs on a thread of its own; neither the analysis nor the factorisation holds Python's
        lock."""
        lower = sparse.csc_array(sparse.tril(self._block))
        lower.sort_indices()
        del self._block
        # through ctypes, Python's lock released: the two substructures' analyses run side by side (cvxopt's held
        # the lock, so one waited for the other)
        self._symbolic = symbolic_of_lower(lower, np.arange(self.size))
        if self._symbolic is None:
            return None
        done = numeric(self._symbolic, lower)
        del lower  # CHOLMOD holds the values now
        if not done:
            return done
        self.solve = CholeskySolve(self._symbolic, self.size)
        if not self.solve.supernodal_ll:
            return None
        order = self.solve.permutation()
        tail = order[self.inner:]
        if np.any(tail < self.inner):  # CHOLMOD's postorder moved an inner row after the interface
            return None
        # so the factor's first ``inner`` positions hold the substructure's rows: these matrix rows
        self.inner_rows = self.rows[order[:self.inner]]
        block = self.solve.trailing_block(self.size - self.inner)
        #: L_iI with its rows in the interface's order, its columns in the factor's
        self.coupling = np.empty_like(block)
        self.coupling[tail - self.inner] = block
        #: L_iI L_iI^T = A_II - A_Ii A_ii^-1 A_iI, in the interface's order: its lower triangle only (BLAS's
        #: symmetric product, half the arithmetic of a general one; the interface's Cholesky reads no other)
        self.condensed = sla.blas.dsyrk(1.0, self.coupling.T, trans=1, lower=1)
        return True

    def forward(self, b: np.ndarray) -> np.ndarray:
        """y = L^-1 [b on the substructure's rows; 0 on the interface] (the factor's order), kept for
        :meth:`backward`, and what the substructure takes off the interface's right-hand side,
        A_Ii A_ii^-1 b_i = X_i y_i = -L_iI w_i (w_i: y's interface part), with its sign turned (the interface's
        order)."""
        y = self._swept(b.shape[1])
        y[:self.inner] = b[self.inner_rows]
        y[self.inner:] = 0.0
        assert self._workspace is not None  # made with y
        self.solve.sweep(y, transpose=False, workspace=self._workspace)
        return self.coupling @ y[self.inner:]

    def backward(self, on_interface: np.ndarray, out: np.ndarray) -> None:
        """L^-T [y's substructure part; L_iI^T x_I]: x_i = A_ii^-1 (b_i - A_iI x_I), written into ``out``'s rows
        of this substructure (``on_interface``: x_I, in the interface's order)."""
        y, workspace = self._y, self._workspace
        assert y is not None and workspace is not None  # forward made them
        y[self.inner:] = self.coupling.T @ on_interface
        self.solve.sweep(y, transpose=True, workspace=workspace)
        out[self.inner_rows] = y[:self.inner]

    def _swept(self, columns: int) -> np.ndarray:
        """The array the sweeps work in, kept from one solve to the next (column-major, as CHOLMOD reads it):
        fresh arrays and CHOLMOD's own copies in and out cost each solve the time of allocating and copying."""
        if self._y is None or self._y.shape[1] != columns:
            self._y = np.empty((self.size, columns), order="F")
            self._workspace = self.solve.sweep_workspace(columns)
        return self._y


class SubstructuredSolve:
    """x = solve(b) for a matrix factored as two substructures and their interface (see the module's text).

    Build it with :func:`substructured_cholesky`.
    """

    def __init__(self, parts: tuple[_Substructure, _Substructure], interface: np.ndarray,
                 schur: tuple[np.ndarray, bool]):
        self._parts, self._interface, self._schur = parts, interface, schur
        self.rows = sum(part.inner for part in parts) + len(interface)
        self._busy = threading.Lock()  # the substructures keep their sweeps' arrays: one solve at a time

    def __call__(self, b: np.ndarray) -> np.ndarray:
        """Solve for ``b`` of shape (rows,) or (rows, k)."""
        b = np.asarray(b, dtype=float)
        columns = b.reshape(self.rows, -1)
        x = np.empty_like(columns)
        # numpy's BLAS threads would wait for the cores the two substructures' sweeps take
        with self._busy, threadpool_limits(limits=1, user_api="blas"), ThreadPoolExecutor(max_workers=2) as threads:
            taken = list(threads.map(lambda part: part.forward(columns), self._parts))
            reduced = columns[self._interface] + taken[0] + taken[1]
            x[self._interface] = on_interface = sla.cho_solve(self._schur, reduced, check_finite=False)
            list(threads.map(lambda part: part.backward(on_interface, x), self._parts))
        return x.reshape(b.shape)


class NotPositiveDefinite(ArithmeticError):
    """The matrix is not positive definite, as a substructure's factorisation shows: each substructure with the
    interface is a principal submatrix and the interface's Schur complement is the Schur complement of one,
    and both are positive definite when the whole matrix is. A Cholesky factorisation of the whole would fail
    too, so the caller goes to its LU at once (at 100k DOFs the whole's factorisation takes seconds)."""


def substructured_cholesky(matrix: sparse.sparray, analysis: Analysis, *,
                           min_factor_entries: int | None = None) -> SubstructuredSolve | None:
    """The positive definite ``matrix`` factored as two substructures on two cores, in ``analysis``'s ordering.

    Parameters
    ----------
    matrix : scipy.sparse array
        Symmetric, expected positive definite.
    analysis : Analysis
        mace_fmu.sparse.ordering's analysis of the matrix: the ordering cut, and its factor's size.
    min_factor_entries : int, optional
        The factor size [entries] from which substructures are taken; :data:`MIN_FACTOR_ENTRIES` when absent.

    Returns
    -------
    SubstructuredSolve or None
        None where substructures do not pay or cannot be had (a small factor, one core, no ordering to cut, a
        wide interface, CHOLMOD not reachable through ctypes): the caller factors the whole matrix.

    Raises
    ------
    NotPositiveDefinite
        A substructure or the interface's Schur complement is not positive definite, so neither is the matrix.
    """
    a = sparse.csr_array(matrix)
    permutation = analysis.permutation
    least = MIN_FACTOR_ENTRIES if min_factor_entries is None else min_factor_entries
    if permutation is None or analysis.choice.factor_entries.get(analysis.choice.method, 0) < least:
        return None
    if usable_cores() < 2:  # one after the other on one core, the two halves cost more than the whole
        return None
    cut = bisect(a, permutation)
    if cut is None:
        return None
    first, second = (_Substructure(a, rows, cut.interface) for rows in cut.substructures)
    parts = (first, second)
    with ThreadPoolExecutor(max_workers=2) as threads:
        factored = list(threads.map(_Substructure.factor, parts))
    if any(done is False for done in factored):
        raise NotPositiveDefinite("a substructure's factorisation met a non-positive pivot")
    if not all(factored):
        return None
    # its lower triangle: the Cholesky below reads no other
    schur = parts[0].condensed + parts[1].condensed - a[cut.interface][:, cut.interface].toarray()
    for part in parts:
        del part.condensed  # in the Schur complement now
    try:
        factor = sla.cho_factor(schur, lower=True)
    except np.linalg.LinAlgError:
        raise NotPositiveDefinite("the interface's Schur complement met a non-positive pivot") from None
    return SubstructuredSolve(parts, cut.interface, factor)
