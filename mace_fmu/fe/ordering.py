"""Fill-reducing orderings of a symmetric FE matrix, and the one CHOLMOD's own analysis says fills least.

No ordering suits every shape. Reverse Cuthill-McKee keeps the factor inside a band one cross-section
wide: the least fill on a slender tower, where the band is narrow. On a wide structure the band is
wide too, and nested dissection (METIS, through pymetis) fills less: cutting the structure along
small separators, it leaves a factor that grows with the separators' size instead of the
cross-section's. CHOLMOD's approximate minimum degree (AMD) is the third candidate (its analysis, the
longest, runs through ctypes on a thread of its own, beside the other two). The choice is
made from the matrix, not from its shape: CHOLMOD's symbolic analysis of each candidate (a fraction
of a second at 100k DOFs, no numbers factored) gives the size of the factor it would store, and the
smallest wins. Measured on 100k-DOF lattices (benchmarks/RESULTS.md, "Wide structures: the ordering
chosen by fill"): on a 6 x 6-grid tower RCM's factor is the smallest (263 entries per DOF; nested
dissection 346, AMD 843); on a 20 x 20-grid one nested dissection's (1242 against RCM's 2072).

Nested dissection orders the graph of the grids, not of the DOFs, when the caller says which DOFs
share a grid: a sixth of the vertices, the same separators, ten times faster (0.3 s against 3.6 s
at 100k DOFs) and no more fill. Without pymetis the candidates are RCM and AMD.
"""

from __future__ import annotations

import hashlib
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import reverse_cuthill_mckee

from mace_fmu.fe.cholmod import factor_layout, own_analysis_entries
from mace_fmu.fe.cholmod import load as load_cholmod

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
    names, labels = np.unique(np.asarray(groups), return_inverse=True) if groups is not None else (None, None)
    if groups is None or len(names) == n:
        labels, weights, incidence = np.arange(n), None, None
    else:
        incidence = sparse.csr_matrix((np.ones(n), (np.arange(n), labels)), shape=(n, len(names)))
        weights = np.bincount(labels)
    magnitude = abs(pattern).astype(float)
    magnitude = magnitude + magnitude.T  # METIS reads a symmetric graph (and crashes on one that is not)
    graph = magnitude if incidence is None else incidence.T @ magnitude @ incidence
    graph = sparse.csr_matrix(sparse.triu(graph, 1) + sparse.tril(graph, -1))  # METIS takes no self-loops
    graph.eliminate_zeros()
    if graph.nnz == 0:  # METIS needs edges; a diagonal matrix fills in no order
        return np.arange(n, dtype=np.int64)
    order, _ = pymetis.nested_dissection(adjacency=pymetis.CSRAdjacency(graph.indptr, graph.indices),
                                         vweights=weights)  # (permutation, its inverse)
    order = np.asarray(order, dtype=np.int64)
    if incidence is None:
        return order
    position = np.empty_like(order)
    position[order] = np.arange(len(order))
    return np.argsort(position[labels], kind="stable").astype(np.int64)  # each group's rows together, in order


@dataclass(frozen=True)
class Analysis:
    """CHOLMOD's symbolic analysis in the ordering that fills least, ready for its numeric factorisation."""

    choice: OrderingChoice  #: the ordering taken and every candidate's factor size
    permutation: np.ndarray | None  #: the ordering taken (None for AMD, which CHOLMOD keeps to itself)
    symbolic: object | None  #: cvxopt.cholmod's symbolic factor in that ordering (None without cvxopt)
    lower: object | None  #: the matrix's lower triangle as the cvxopt.spmatrix it was analysed as


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
        permutations = {known[0].method: known[1]} if known else candidate_permutations(a, groups=groups)
        return Analysis(OrderingChoice(RCM, {}), permutations[RCM], None, None)
    lower = sparse.csc_array(sparse.tril(a))
    lower.sort_indices()
    spmatrix = _lower_spmatrix(lower)
    if known and known[1] is None:  # AMD, CHOLMOD's default
        return Analysis(known[0], None, _symbolic(cholmod, spmatrix, None), spmatrix)
    if known:  # a known choice needs its own analysis only
        return Analysis(known[0], known[1], _symbolic(cholmod, spmatrix, known[1]), spmatrix)
    # CHOLMOD's own (AMD) analysis releases Python's lock through ctypes: it runs while the other candidates
    # are ordered and analysed, which hold it (the wide lattice's analyses: 0.66-0.83 s against 0.79-0.89 s)
    with ThreadPoolExecutor(max_workers=1) as thread:
        own = thread.submit(own_analysis_entries, lower) if with_amd else None
        permutations: dict[str, np.ndarray | None] = dict(candidate_permutations(a, groups=groups))
        analysed = {name: _analysed(cholmod, spmatrix, permutation, n) for name, permutation in permutations.items()}
        own_entries = None if own is None else own.result()
    if with_amd:
        permutations[AMD] = None
        # without ctypes, cvxopt's analysis: the symbolic factor at once
        analysed[AMD] = (None, own_entries) if own_entries is not None else _analysed(cholmod, spmatrix, None, n)
    entries = {name: size for name, (_, size) in analysed.items() if size is not None}
    best = min(entries, key=entries.__getitem__) if len(entries) == len(analysed) else RCM
    symbolic = analysed[best][0]
    if symbolic is None:  # AMD counted through ctypes: its symbolic factor, for the factorisation
        symbolic = _symbolic(cholmod, spmatrix, None)
    choice = OrderingChoice(best, entries)
    if len(_CHOSEN) >= _CHOSEN_KEPT:
        _CHOSEN.pop(next(iter(_CHOSEN)))
    _CHOSEN[key] = choice, permutations[best]
    return Analysis(choice, permutations[best], symbolic, spmatrix)


def _analysed(cholmod: object, spmatrix: object, permutation: np.ndarray | None,
              rows: int) -> tuple[object, int | None]:
    """The symbolic factor in the order ``permutation`` (None: CHOLMOD's AMD) and its entries."""
    symbolic = _symbolic(cholmod, spmatrix, permutation)
    return symbolic, _entries(symbolic, rows)


def symbolic_in_order(matrix: sparse.sparray, permutation: np.ndarray) -> object | None:
    """CHOLMOD's symbolic analysis of the symmetric ``matrix`` in the order ``permutation``, as it is given.

    Parameters
    ----------
    matrix : scipy.sparse array
        The symmetric matrix (its lower triangle is read).
    permutation : numpy.ndarray
        Row ``permutation[i]`` goes to position i.

    Returns
    -------
    object or None
        cvxopt.cholmod's symbolic factor; None without cvxopt.
    """
    cholmod = load_cholmod()
    if cholmod is None:
        return None
    return _symbolic(cholmod, _lower_spmatrix(sparse.csr_array(matrix)), permutation)


def _lower_spmatrix(a: sparse.sparray) -> object:
    """The lower triangle of ``a`` (already the lower triangle: itself) as a cvxopt.spmatrix."""
    import cvxopt

    lower = sparse.tril(a).tocoo()
    return cvxopt.spmatrix(lower.data, lower.row.astype(int), lower.col.astype(int), a.shape)


#: cvxopt.cholmod reads one options dictionary for the whole process, and an analysis in a given order changes
#: it for the call: two substructures analysed on two threads would otherwise restore each other's change and
#: leave it set (a later AMD analysis then failed, in 2 of 7 runs of the wide lattice)
_OPTIONS = threading.Lock()


def _symbolic(cholmod: object, spmatrix: object, permutation: np.ndarray | None) -> object:
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
    return analyse(a, groups=groups, with_amd=False).permutation


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
