"""Fill-reducing orderings of a symmetric FE matrix, and the one CHOLMOD's own analysis says fills least.

No ordering suits every shape. Reverse Cuthill-McKee keeps the factor inside a band one cross-section
wide: the least fill on a slender tower, where the band is narrow. On a wide structure the band is
wide too, and nested dissection (METIS, through pymetis) fills less: cutting the structure along
small separators, it leaves a factor that grows with the separators' size instead of the
cross-section's. CHOLMOD's approximate minimum degree (AMD) is the third candidate (the analyses run
through ctypes on two threads, beside the nested dissection's ordering). The choice is
made from the matrix, not from its shape: CHOLMOD's symbolic analysis of each candidate (no numbers
factored) gives the size of the factor it would store, and the smallest wins. On 100k-DOF lattices
(benchmarks/RESULTS.md, "Wide structures: the ordering chosen by fill") RCM's factor is the smallest on
a slender tower, nested dissection's on a wide lattice.

Nested dissection orders the graph of the grids, not of the DOFs, when the caller says which DOFs
share a grid: a sixth of the vertices, the same separators, a fraction of the time and no more fill
(benchmarks/RESULTS.md, "The sparse solver's figures, by module"). Without pymetis the candidates are RCM and AMD.
"""

from __future__ import annotations

import functools
import hashlib
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import reverse_cuthill_mckee

from mace_fmu.sparse.cholmod import factor_layout, symbolic_factor
from mace_fmu.sparse.cholmod import load as load_cholmod

#: Names of the orderings, as reports and benchmarks print them.
RCM = "reverse Cuthill-McKee"
NESTED_DISSECTION = "nested dissection (METIS)"
AMD = "approximate minimum degree (CHOLMOD)"


@dataclass(frozen=True)
class OrderingChoice:
    """The ordering a factorisation takes and the factor size each candidate would give."""

    method: str  #: the ordering taken: RCM, NESTED_DISSECTION or AMD
    factor_entries: dict[str, int]  #: entries of CHOLMOD's supernodal factor [-] for each candidate analysed

    def entries_per_row(self, rows: int) -> dict[str, float]:
        """The factor entries of each candidate divided by the matrix's ``rows`` (fill per DOF)."""
        return {name: entries / rows for name, entries in self.factor_entries.items()}


def candidate_permutations(matrix: sparse.sparray, *, groups: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Reverse Cuthill-McKee's and (with pymetis installed) nested dissection's permutations of ``matrix``.

    Parameters
    ----------
    matrix : scipy.sparse array
        A square matrix with a symmetric pattern.
    groups : numpy.ndarray, optional
        One label per row (its grid): rows with the same label are kept together, and nested
        dissection orders the graph of the labels, each weighted by its number of rows.

    Returns
    -------
    dict
        Permutation p (row p[i] of ``matrix`` goes to position i) by ordering name.
    """
    pattern = sparse.csr_matrix(matrix)
    found = {RCM: reverse_cuthill_mckee(pattern, symmetric_mode=True).astype(np.int64)}
    dissection = _nested_dissection(pattern, groups)
    if dissection is not None:
        found[NESTED_DISSECTION] = dissection
    return found


def _nested_dissection(pattern: sparse.csr_matrix, groups: np.ndarray | None) -> np.ndarray | None:
    try:
        import pymetis
    except ImportError:
        return None
    n = pattern.shape[0]
    labels, weights, incidence = np.arange(n), None, None
    if groups is not None:
        names, grouped = np.unique(np.asarray(groups), return_inverse=True)
        if len(names) != n:
            labels, weights = grouped, np.bincount(grouped)
            incidence = sparse.csr_matrix((np.ones(n), (np.arange(n), labels)), shape=(n, len(names)))
    magnitude = abs(pattern).astype(float)
    magnitude = magnitude + magnitude.T  # METIS reads a symmetric graph (and crashes on one that is not)
    graph = magnitude if incidence is None else incidence.T @ magnitude @ incidence
    graph = sparse.csr_matrix(sparse.triu(graph, 1) + sparse.tril(graph, -1))  # METIS takes no self-loops
    graph.eliminate_zeros()
    if graph.nnz == 0:  # METIS needs edges; a diagonal matrix fills in no order
        return np.arange(n, dtype=np.int64)
    found, _ = pymetis.nested_dissection(adjacency=pymetis.CSRAdjacency(graph.indptr, graph.indices),
                                         vweights=weights)  # (permutation, its inverse)
    order = np.asarray(found, dtype=np.int64)
    if incidence is None:
        return order
    position = np.empty_like(order)
    position[order] = np.arange(len(order))
    return np.argsort(position[labels], kind="stable").astype(np.int64)  # each group's rows together, in order


@dataclass(frozen=True)
class Analysis:
    """The ordering that fills least, and CHOLMOD's symbolic analysis in it for a numeric factorisation.

    The symbolic factor is the one :func:`analyse` sized the ordering with (a few megabytes at 100k DOFs: the
    pattern, no values); for a choice recalled from an earlier pattern it is made when first asked for."""

    choice: OrderingChoice  #: the ordering taken and every candidate's factor size
    permutation: np.ndarray | None  #: the ordering taken (None for AMD, which CHOLMOD keeps to itself)
    lower_triangle: sparse.csc_array | None  #: the matrix's lower triangle (None without cvxopt)
    analysed: object | None = None  #: the chosen ordering's symbolic factor, as the analysis made it

    @functools.cached_property
    def lower(self) -> object | None:
        """The lower triangle as a cvxopt.spmatrix, for cvxopt's own factorisation (None without cvxopt)."""
        return None if self.lower_triangle is None else _lower_spmatrix(self.lower_triangle)

    @functools.cached_property
    def symbolic(self) -> object | None:
        """CHOLMOD's symbolic factor in the ordering taken (:func:`symbolic_of_lower`; None without cvxopt)."""
        if self.analysed is not None or self.lower_triangle is None:
            return self.analysed
        return symbolic_of_lower(self.lower_triangle, self.permutation)


def analyse(matrix: sparse.sparray, *, groups: np.ndarray | None = None, with_amd: bool = True) -> Analysis:
    """Each candidate ordering of the symmetric ``matrix`` through CHOLMOD's symbolic analysis; the one whose
    factor is smallest. Without cvxopt the choice is reverse Cuthill-McKee, unmeasured.

    Parameters
    ----------
    matrix : scipy.sparse array
        The symmetric matrix (its lower triangle is read).
    groups : numpy.ndarray, optional
        One label per row (its grid), see :func:`candidate_permutations`.
    with_amd : bool
        Analyse CHOLMOD's AMD too (its permutation is not returned: for a Cholesky factor only).

    Returns
    -------
    Analysis
        The ordering taken, every candidate's factor size, and the symbolic factor.
    """
    a = sparse.csr_array(matrix)
    n = a.shape[0]
    key = _pattern_key(a, groups, with_amd)
    known = _CHOSEN.get(key)
    cholmod = load_cholmod()
    if cholmod is None:
        recalled = {known[0].method: known[1]} if known else dict(candidate_permutations(a, groups=groups))
        return Analysis(OrderingChoice(RCM, {}), recalled[RCM], None)
    lower = sparse.csc_array(sparse.tril(a))
    lower.sort_indices()
    if known:  # the choice made for this pattern before
        return Analysis(known[0], known[1], lower)
    # CHOLMOD's analyses through ctypes release Python's lock: AMD's, the longest, runs while the nested
    # dissection orders the grids, then RCM's and nested dissection's side by side
    with ThreadPoolExecutor(max_workers=2) as threads:
        analysing = {AMD: threads.submit(symbolic_factor, lower)} if with_amd else {}
        permutations: dict[str, np.ndarray | None] = dict(candidate_permutations(a, groups=groups))
        analysing.update({name: threads.submit(symbolic_factor, lower, permutation)
                          for name, permutation in permutations.items()})
        factors: dict[str, object | None] = {name: analysis.result() for name, analysis in analysing.items()}
    if with_amd:
        permutations[AMD] = None
    if any(made is None for made in factors.values()):  # CHOLMOD not reachable through ctypes: cvxopt's
        spmatrix = _lower_spmatrix(lower)
        factors = {name: _symbolic(cholmod, spmatrix, permutations[name]) for name in factors}
    counted = {name: _entries(made, n) for name, made in factors.items()}
    entries = {name: size for name, size in counted.items() if size is not None}
    best = min(entries, key=entries.__getitem__) if len(entries) == len(counted) else RCM
    choice = OrderingChoice(best, entries)
    if len(_CHOSEN) >= _CHOSEN_KEPT:
        _CHOSEN.pop(next(iter(_CHOSEN)))
    _CHOSEN[key] = choice, permutations[best]
    # the chosen order's factor is kept for the numeric factorisation, not analysed again
    return Analysis(choice, permutations[best], lower, factors.get(best) if best in entries else None)


def symbolic_of_lower(lower: sparse.csc_array, permutation: np.ndarray | None) -> object | None:
    """CHOLMOD's supernodal symbolic analysis of the matrix whose lower triangle is ``lower``, in the order
    ``permutation`` (None: CHOLMOD's AMD): through ctypes with Python's lock released
    (:func:`mace_fmu.sparse.cholmod.symbolic_factor`, so that the two substructures' analyses run side by side), or
    cvxopt's where CHOLMOD cannot be reached that way. Either factor goes to
    :func:`mace_fmu.sparse.cholmod.numeric` and :class:`mace_fmu.sparse.cholmod.CholeskySolve`.

    Parameters
    ----------
    lower : scipy.sparse.csc_array
        The lower triangle, its row indices sorted within each column.
    permutation : numpy.ndarray or None
        Row ``permutation[i]`` goes to position i.

    Returns
    -------
    object or None
        A :class:`mace_fmu.sparse.cholmod.SymbolicFactor` or cvxopt.cholmod's symbolic factor; None without cvxopt.
    """
    cholmod = load_cholmod()  # first: it readies the BLAS CHOLMOD binds to
    if cholmod is None:
        return None
    return symbolic_factor(lower, permutation) or _symbolic(cholmod, _lower_spmatrix(lower), permutation)


def _lower_spmatrix(a: sparse.sparray) -> object:
    """The lower triangle of ``a`` (already the lower triangle: itself) as a cvxopt.spmatrix."""
    import cvxopt

    lower = sparse.tril(a).tocoo()
    return cvxopt.spmatrix(lower.data, lower.row.astype(int), lower.col.astype(int), a.shape)


#: cvxopt.cholmod reads one options dictionary for the whole process, and an analysis in a given order changes
#: it for the call: two substructures analysed on two threads would otherwise restore each other's change and
#: leave it set (a later AMD analysis then failed, in 2 of 7 runs of the wide lattice)
_OPTIONS = threading.Lock()


def _symbolic(cholmod: Any, spmatrix: object, permutation: np.ndarray | None) -> object:
    """cvxopt.cholmod's symbolic factor of ``spmatrix`` in the order ``permutation`` (None: CHOLMOD's AMD)."""
    import cvxopt

    with _OPTIONS:
        if permutation is None:  # without a permutation CHOLMOD's default is AMD
            return cholmod.symbolic(spmatrix, uplo="L")
        saved = dict(cholmod.options)
        try:
            cholmod.options["nmethods"] = 1  # the given permutation only (0 would let CHOLMOD pick among others)
            return cholmod.symbolic(spmatrix, p=cvxopt.matrix(permutation.astype(int)), uplo="L")
        finally:
            cholmod.options.clear()
            cholmod.options.update(saved)


def least_fill_permutation(matrix: sparse.sparray, *, groups: np.ndarray | None = None) -> np.ndarray:
    """The permutation of RCM or nested dissection, whichever :func:`analyse` finds the smaller factor for
    (the LU's ordering: it needs a permutation, not CHOLMOD's symbolic factor).

    Parameters
    ----------
    matrix : scipy.sparse array
        The matrix, with a symmetric pattern.
    groups : numpy.ndarray, optional
        One label per row (its grid), see :func:`candidate_permutations`.

    Returns
    -------
    numpy.ndarray
        Permutation p: row p[i] of ``matrix`` goes to position i.
    """
    a = sparse.csr_array(matrix)
    for with_amd in (False, True):  # a Cholesky's analysis of the same pattern (then not positive definite) too
        known = _CHOSEN.get(_pattern_key(a, groups, with_amd))
        if known and known[1] is not None:  # AMD's choice has no permutation to give
            return known[1]
    permutation = analyse(a, groups=groups, with_amd=False).permutation
    assert permutation is not None  # only AMD's has none
    return permutation


#: The orderings chosen for the last few patterns: a Newton iteration or a parameter study factors
#: matrices of one pattern again and again, and nested dissection of a 100k-DOF pattern whose grids
#: are not named costs seconds (the choice depends on the pattern only, never on the values).
_CHOSEN: dict[tuple, tuple[OrderingChoice, np.ndarray | None]] = {}
_CHOSEN_KEPT = 4


def _pattern_key(a: sparse.csr_array, groups: np.ndarray | None, with_amd: bool) -> tuple:
    a = a if a.has_sorted_indices else a.sorted_indices()  # a copy: the caller's matrix stays as it was
    digest = hashlib.blake2b(np.ascontiguousarray(a.indptr, dtype=np.int64).tobytes(), digest_size=16)
    digest.update(np.ascontiguousarray(a.indices, dtype=np.int64).tobytes())
    if groups is not None:
        digest.update(np.unique(np.asarray(groups), return_inverse=True)[1].astype(np.int64).tobytes())
    return a.shape, a.nnz, with_amd, digest.hexdigest()


def _entries(symbolic: object, rows: int) -> int | None:
    """The entries of the supernodal factor CHOLMOD's symbolic analysis sized (None: not a factor of ``rows``)."""
    layout = factor_layout(symbolic, rows)
    return None if layout is None else layout.entries
