"""Two substructures factored on two cores and joined at their interface (mace_fmu.sparse.substructures): the
cut is a true separation, and the solutions, the factor's pieces and the modes equal a second solver's
(SciPy's SuperLU, LAPACK's dense Cholesky, ARPACK on SuperLU)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import linalg as sla
from scipy import sparse
from scipy.sparse.linalg import eigsh, splu
from support.decks import frame_tower

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.fe.assembly import assemble
from mace_fmu.fe.constraints import build_constraints
from mace_fmu.sparse import cholmod as cholmod_module
from mace_fmu.sparse import factor, substructures
from mace_fmu.sparse.cholmod import CholeskySolve, SymbolicFactor, numeric, symbolic_factor
from mace_fmu.sparse.ordering import NESTED_DISSECTION, RCM, _lower_spmatrix, _symbolic, analyse, symbolic_of_lower

pytest.importorskip("cvxopt")


def _lattice(nx: int, ny: int, levels: int) -> tuple[sparse.csr_array, sparse.csr_array, np.ndarray]:
    """K and M of a clamped lattice of nx x ny grids a level, and the grid of each row."""
    deck = read_deck_text(frame_tower(nx=nx, ny=ny, levels=levels), name="lattice.bdf")
    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k = constraints.reduce_sparse(model.stiffness)
    m = constraints.reduce_sparse(model.mass)
    return (sparse.csr_array(0.5 * (k + k.T)), sparse.csr_array(0.5 * (m + m.T)),
            np.array([g for g, _ in constraints.independent]))


@pytest.fixture(scope="module")
def wide() -> tuple[sparse.csr_array, sparse.csr_array, np.ndarray]:
    """A 10 x 10-grid lattice, 8 levels (4,800 DOFs): nested dissection is its ordering."""
    return _lattice(10, 10, 8)


@pytest.fixture(scope="module")
def slender() -> tuple[sparse.csr_array, sparse.csr_array, np.ndarray]:
    """A 3 x 3-grid tower, 40 levels (2,160 DOFs): reverse Cuthill-McKee is its ordering."""
    return _lattice(3, 3, 40)


def _solve(matrix: sparse.csr_array, grids: np.ndarray) -> substructures.SubstructuredSolve:
    solve = substructures.substructured_cholesky(matrix, analyse(matrix, groups=grids), min_factor_entries=0)
    assert isinstance(solve, substructures.SubstructuredSolve)
    return solve


@pytest.mark.parametrize("shape, ordering", [("wide", NESTED_DISSECTION), ("slender", RCM)])
def test_the_cut_separates_the_matrix(shape, ordering, request):
    """No entry joins the two substructures; with the interface they hold every row once; the interface is
    one level of the lattice or less (6 DOFs per grid), and each side holds at least a third of the rows."""
    k, m, grids = request.getfixturevalue(shape)
    matrix = sparse.csr_array(k + m)
    analysis = analyse(matrix, groups=grids)
    assert analysis.choice.method == ordering
    cut = substructures.bisect(matrix, analysis.permutation)
    first, second = cut.substructures
    assert abs(matrix[first][:, second]).sum() == 0
    every = np.concatenate([first, second, cut.interface])
    assert np.array_equal(np.sort(every), np.arange(matrix.shape[0]))
    per_level = 6 * len(np.unique(grids)) // (8 if shape == "wide" else 40)
    assert 0 < len(cut.interface) <= per_level
    assert min(len(first), len(second)) >= matrix.shape[0] // 3


@pytest.mark.parametrize("shape", ["wide", "slender"])
@pytest.mark.parametrize("width", [1, 16, 33])
def test_solutions_equal_scipys_lu(shape, width, request):
    """K - sigma M below the first eigenvalue (the modal solution's), 1, 16 and 33 right-hand sides: the
    substructured solution equals SuperLU's of the whole matrix within 1e-11 of its largest entry."""
    k, m, grids = request.getfixturevalue(shape)
    matrix = sparse.csr_array(k + 1e-3 * m)
    b = np.random.default_rng(width).standard_normal((matrix.shape[0], width))
    expected = splu(sparse.csc_array(matrix)).solve(b)
    x = _solve(matrix, grids)(b)
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-11 * np.abs(expected).max())
    np.testing.assert_allclose(_solve(matrix, grids)(b[:, 0]), expected[:, 0], rtol=0,
                               atol=1e-11 * np.abs(expected).max())


@pytest.mark.parametrize("analysed_by", ["cvxopt", "ctypes"])
def test_the_factors_pieces_equal_lapacks_dense_cholesky(slender, analysed_by):
    """The triangular solves and the trailing block read from CHOLMOD's supernodal factor, against LAPACK's
    dense Cholesky of the same matrix in the factor's own order: for the symbolic factor cvxopt makes and for
    the one made through ctypes (the substructures' route), whose trailing block is read from its last
    supernodes only (40 rows) and from all of them (the whole factor)."""
    k, m, _ = slender
    matrix = sparse.csr_array(k + m)
    n = matrix.shape[0]
    order = np.random.default_rng(1).permutation(n)  # any ordering: the factor's own is read back
    lower = sparse.csc_array(sparse.tril(matrix))
    lower.sort_indices()
    symbolic = (_symbolic(cholmod_module.load(), _lower_spmatrix(lower), order) if analysed_by == "cvxopt"
                else symbolic_factor(lower, order))
    assert isinstance(symbolic, SymbolicFactor) == (analysed_by == "ctypes")
    assert numeric(symbolic, lower) is True
    solve = CholeskySolve(symbolic, n)
    p = solve.permutation()
    dense = sla.cholesky(matrix.toarray()[np.ix_(p, p)], lower=True)
    for size in (40, n):
        np.testing.assert_allclose(solve.trailing_block(size), dense[-size:, -size:], rtol=0,
                                   atol=1e-12 * np.abs(dense).max())
    b = np.random.default_rng(2).standard_normal((n, 3))
    for transpose in (False, True):
        expected = sla.solve_triangular(dense, b, lower=True, trans=1 if transpose else 0)
        np.testing.assert_allclose(solve.triangular(b, transpose=transpose), expected, rtol=0,
                                   atol=1e-10 * np.abs(expected).max())
    expected = sla.cho_solve((dense, True), b[p])
    np.testing.assert_allclose(solve(b)[p], expected, rtol=0, atol=1e-10 * np.abs(expected).max())
    with pytest.raises(ValueError, match="column-major"):  # the in-place sweep reads its array as CHOLMOD does
        solve.sweep(np.ones((n, 3)), transpose=False, workspace=solve.sweep_workspace(3))
    with pytest.raises(ValueError, match="workspace"):
        solve.sweep(np.ones((n, 3), order="F"), transpose=False, workspace=solve.sweep_workspace(1)[:0])


def test_a_matrix_that_is_not_positive_definite_goes_to_the_lu_at_once(wide, monkeypatch):
    """K - sigma M with sigma above the first eigenvalue: the ctypes factorisation says False, the substructures
    say the matrix is not positive definite, and factorize goes to its LU without factoring the whole matrix
    again (substructures forced on this 4,800-DOF lattice); the LU's solution equals SuperLU's."""
    k, m, grids = wide
    first = eigsh(k, M=m, k=1, sigma=0.0, return_eigenvectors=False)[0]
    matrix = sparse.csr_array(k - 2.0 * first * m)
    with pytest.raises(substructures.NotPositiveDefinite):
        substructures.substructured_cholesky(matrix, analyse(matrix, groups=grids), min_factor_entries=0)
    lower = sparse.csc_array(sparse.tril(matrix))
    lower.sort_indices()
    symbolic = symbolic_of_lower(lower, np.arange(matrix.shape[0]))
    assert numeric(symbolic, lower) is False
    monkeypatch.setattr(substructures, "MIN_FACTOR_ENTRIES", 0)
    monkeypatch.setattr(factor, "_cholesky", lambda *args: pytest.fail("the whole matrix was factored again"))
    b = np.random.default_rng(3).standard_normal(matrix.shape[0])
    expected = splu(sparse.csc_array(matrix)).solve(b)
    np.testing.assert_allclose(factor.factorize(matrix, positive_definite=True, groups=grids)(b), expected, rtol=0,
                               atol=1e-9 * np.abs(expected).max())


def test_small_factors_stay_whole(wide):
    """Below MIN_FACTOR_ENTRIES (the default) the whole matrix is factored: a 4,800-DOF lattice's factor is far
    smaller."""
    k, m, grids = wide
    matrix = sparse.csr_array(k + m)
    analysis = analyse(matrix, groups=grids)
    assert analysis.choice.factor_entries[analysis.choice.method] < substructures.MIN_FACTOR_ENTRIES
    assert substructures.substructured_cholesky(matrix, analysis) is None
    assert isinstance(factor.factorize(matrix, positive_definite=True, groups=grids), CholeskySolve)


def test_one_core_factors_the_whole(wide, monkeypatch):
    """On one core the two halves would run one after the other: the whole matrix is factored instead."""
    k, m, grids = wide
    matrix = sparse.csr_array(k + m)
    analysis = analyse(matrix, groups=grids)
    assert isinstance(substructures.substructured_cholesky(matrix, analysis, min_factor_entries=0),
                      substructures.SubstructuredSolve)
    monkeypatch.setattr(substructures, "usable_cores", lambda: 1)
    assert substructures.substructured_cholesky(matrix, analysis, min_factor_entries=0) is None


@pytest.mark.parametrize("shared_gram_schmidt", [False, True], ids=["one-blas-thread", "blas-on-every-core"])
def test_the_lowest_modes_through_substructures_equal_arpacks(wide, monkeypatch, shared_gram_schmidt):
    """The modal solution's shift-invert Lanczos on substructures (forced on the 4,800-DOF lattice), with its
    Gram-Schmidt on one BLAS thread or (forced, as from 32 MB of basis) on every core: its 12 lowest
    eigenvalues equal ARPACK's (scipy's eigsh, shift-invert on SuperLU) within 1e-10."""
    from mace_fmu.sparse import lanczos
    from mace_fmu.sparse.lanczos import lowest_modes

    k, m, grids = wide
    monkeypatch.setattr(substructures, "MIN_FACTOR_ENTRIES", 0)
    if shared_gram_schmidt:
        monkeypatch.setattr(lanczos, "SHARED_GRAM_SCHMIDT_ENTRIES", 0)
        monkeypatch.setattr(lanczos, "usable_cores", lambda: 2)
    sigma = -1e-3
    solve = factor.factorize(sparse.csr_array(k - sigma * m), positive_definite=True, groups=grids)
    assert isinstance(solve, substructures.SubstructuredSolve)
    found = lowest_modes(stiffness=k, mass=m, solve=solve, shift=sigma, count=12, above=None, tolerance=1e-8,
                         max_dimension=k.shape[0] // 2)
    expected = np.sort(eigsh(k, M=m, k=12, sigma=sigma, return_eigenvectors=False))
    np.testing.assert_allclose(found.eigenvalues[:12], expected, rtol=1e-10)


def test_a_simplicial_factor_is_recognised_and_not_read_as_supernodes(slender):
    """CHOLMOD's simplicial L D L^T (asked for through cvxopt's options) has no supernodes to read and a unit
    triangle: the ctypes factorisation refuses it (None: cvxopt's route) and CholeskySolve does not offer its
    triangle, so the substructures are never built on one."""
    import cvxopt.cholmod

    k, m, _ = slender
    matrix = sparse.csr_array(k + m)
    saved = dict(cvxopt.cholmod.options)
    cvxopt.cholmod.options["supernodal"] = 0
    try:  # cvxopt's own analysis (the ctypes one is always supernodal)
        symbolic = _symbolic(cvxopt.cholmod, _lower_spmatrix(matrix), np.arange(matrix.shape[0]))
    finally:
        cvxopt.cholmod.options.clear()
        cvxopt.cholmod.options.update(saved)
    lower = sparse.csc_array(sparse.tril(matrix))
    lower.sort_indices()
    assert numeric(symbolic, lower) is None
    assert CholeskySolve(symbolic, matrix.shape[0]).supernodal_ll is False


def test_analyses_on_two_threads_leave_cholmods_options_as_they_were(wide):
    """Two substructures are analysed on two threads, and cvxopt.cholmod keeps one options dictionary that an
    analysis in a given order changes for the call: 400 analyses from two threads, switching threads as often
    as Python can, leave the dictionary as it was, and CHOLMOD's own AMD analysis works after them (without
    the lock, a thread restored the other's change and left it set: 2 of 7 runs of the wide lattice failed)."""
    import sys
    import threading

    from mace_fmu.sparse.cholmod import load
    from mace_fmu.sparse.ordering import _lower_spmatrix, _symbolic

    cholmod = load()
    k, m, _ = wide
    lower = _lower_spmatrix(sparse.csr_array(k + m))
    permutation = np.arange(k.shape[0])
    before = dict(cholmod.options)
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        threads = [threading.Thread(target=lambda: [_symbolic(cholmod, lower, permutation) for _ in range(200)])
                   for _ in range(2)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
    finally:
        sys.setswitchinterval(interval)
    assert dict(cholmod.options) == before
    assert _symbolic(cholmod, lower, None) is not None
