"""The factorisation's ordering is chosen from the matrix: the least fill, whatever the structure's shape.

CHOLMOD's symbolic analysis says how large each candidate's factor would be; the fill each ordering
really gives is counted here independently, from a dense Cholesky factor of the reordered matrix.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse
from support.decks import frame_tower
from threadpoolctl import threadpool_limits

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.fe import modal
from mace_fmu.fe.assembly import assemble
from mace_fmu.fe.constraints import build_constraints
from mace_fmu.fe.modes import compute_modes
from mace_fmu.sparse.factor import factorize
from mace_fmu.sparse.ordering import (
    AMD,
    NESTED_DISSECTION,
    RCM,
    analyse,
    candidate_permutations,
)

pytest.importorskip("cvxopt")
pytest.importorskip("pymetis")


def _lattice(nx: int, ny: int, levels: int) -> tuple[sparse.csr_array, np.ndarray]:
    """K + M of a clamped lattice of nx x ny grids a level (positive definite) and the grid of each row."""
    deck = read_deck_text(frame_tower(nx=nx, ny=ny, levels=levels), name="lattice.bdf")
    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k = constraints.reduce_sparse(model.stiffness)
    m = constraints.reduce_sparse(model.mass)
    return sparse.csr_array(0.5 * (k + k.T) + 0.5 * (m + m.T)), np.array([g for g, _ in constraints.independent])


def _dense_fill(matrix: sparse.csr_array, permutation: np.ndarray) -> int:
    """Nonzeros of the Cholesky factor of the reordered matrix, by numpy's dense Cholesky."""
    with threadpool_limits(1):  # a 2000-row factor: BLAS threads only contend on a loaded machine
        return int(np.count_nonzero(np.linalg.cholesky(matrix[permutation][:, permutation].toarray())))


def test_a_wide_lattice_is_ordered_by_nested_dissection_which_fills_less():
    """10 x 10 grids a level, 3 levels (1800 DOFs): nested dissection's factor has 0.81 of RCM's nonzeros
    (dense count, 183,833 against 227,417), and CHOLMOD's analysis picks it; each candidate's stored factor
    is at least its nonzeros (supernodes are stored as dense blocks)."""
    matrix, grids = _lattice(10, 10, 3)
    analysis = analyse(matrix, groups=grids)
    permutations = candidate_permutations(matrix, groups=grids)
    fill = {name: _dense_fill(matrix, p) for name, p in permutations.items()}
    assert analysis.choice.method == NESTED_DISSECTION
    assert fill[NESTED_DISSECTION] <= 0.85 * fill[RCM]
    assert set(analysis.choice.factor_entries) == {RCM, NESTED_DISSECTION, AMD}
    for name, nonzeros in fill.items():
        assert nonzeros <= analysis.choice.factor_entries[name] <= 2 * nonzeros
    np.testing.assert_array_equal(np.sort(analysis.permutation), np.arange(matrix.shape[0]))
    # each grid's DOFs stay together
    assert np.count_nonzero(np.diff(grids[analysis.permutation])) == len(np.unique(grids)) - 1



def test_an_irregular_graph_takes_cholmods_own_amd_and_is_solved():
    """A random sparse graph (600 rows, 1,500 random links) has no band and no small separators: CHOLMOD's own
    AMD fills least (counted through ctypes beside the other candidates), the analysis carries cvxopt's AMD
    symbolic factor of the same size, and the Cholesky in it solves A x = b."""
    from mace_fmu.sparse.ordering import _entries

    rng = np.random.default_rng(0)
    rows, cols = rng.integers(0, 600, 1500), rng.integers(0, 600, 1500)
    links = sparse.csr_array(sparse.coo_array((np.ones(1500), (rows, cols)), shape=(600, 600)))
    links = links + links.T
    matrix = sparse.csr_array(links + sparse.diags_array(np.asarray(links.sum(axis=1)).ravel() + 1.0))
    analysis = analyse(matrix)
    entries = analysis.choice.factor_entries
    assert analysis.choice.method == AMD and entries[AMD] == min(entries.values())
    assert analysis.permutation is None and _entries(analysis.symbolic, 600) == entries[AMD]
    b = rng.standard_normal(600)
    x = factorize(matrix, positive_definite=True)(b)
    assert np.linalg.norm(matrix @ x - b) <= 1e-10 * np.linalg.norm(b)


def test_the_chosen_orderings_factor_is_the_one_the_analysis_sized(monkeypatch):
    """The symbolic factor a Cholesky is computed in is the one the choice was made with, not a second analysis
    of the same order: a wide lattice (nested dissection), a slender one (RCM) and a thin one (AMD), each factor's
    size the chosen candidate's, and its Cholesky solving A x = b to 1e-10."""
    from mace_fmu.sparse import ordering
    from mace_fmu.sparse.factor import _cholesky
    from mace_fmu.sparse.ordering import _entries

    monkeypatch.setattr(ordering, "symbolic_of_lower", lambda *args: pytest.fail("the order was analysed again"))
    for shape, method in (((10, 10, 3), NESTED_DISSECTION), ((3, 3, 40), RCM), ((2, 2, 40), AMD)):
        matrix, grids = _lattice(*shape)
        ordering._CHOSEN.clear()  # a choice recalled from an earlier test has no factor to give
        analysis = analyse(matrix, groups=grids)
        assert analysis.choice.method == method
        assert _entries(analysis.symbolic, matrix.shape[0]) == analysis.choice.factor_entries[method]
        b = np.random.default_rng(1).standard_normal(matrix.shape[0])
        x = _cholesky(analysis, matrix.shape[0])(b)
        assert np.linalg.norm(matrix @ x - b) <= 1e-10 * np.linalg.norm(b)


def test_the_lus_ordering_reuses_the_choice_a_cholesky_analysis_made(monkeypatch):
    """A matrix expected positive definite that is not goes from CHOLMOD to the LU: the LU's permutation is the
    one the Cholesky's analysis of the same pattern chose (nested dissection here, the least fill with AMD
    analysed too, so also without it), not a second round of orderings and analyses."""
    from mace_fmu.sparse import ordering

    matrix, grids = _lattice(10, 10, 3)
    chosen = analyse(matrix, groups=grids)
    assert chosen.choice.method == NESTED_DISSECTION
    monkeypatch.setattr(ordering, "candidate_permutations", lambda *args, **kwargs: pytest.fail("ordered again"))
    np.testing.assert_array_equal(ordering.least_fill_permutation(matrix, groups=grids), chosen.permutation)


def test_a_slender_tower_keeps_reverse_cuthill_mckee():
    """3 x 3 grids a level, 20 levels: the band is one level wide, RCM fills least (dense count) and is chosen."""
    matrix, grids = _lattice(3, 3, 20)
    analysis = analyse(matrix, groups=grids)
    permutations = candidate_permutations(matrix, groups=grids)
    assert analysis.choice.method == RCM
    assert _dense_fill(matrix, permutations[RCM]) < _dense_fill(matrix, permutations[NESTED_DISSECTION])
    assert min(analysis.choice.factor_entries.values()) == analysis.choice.factor_entries[RCM]


def test_a_pattern_stored_on_one_side_only_is_ordered_and_solved():
    """T^T K T products leave an entry on one side of the diagonal only where its mirror cancelled: METIS
    needs a symmetric graph (it crashed on the 100k tower's static corrections before the graph was
    symmetrised). The LU of such a matrix solves it exactly."""
    matrix, _ = _lattice(4, 4, 3)
    lower_only = matrix.tolil()
    i, j = 5, int(matrix[[5]].indices[-1])  # an off-diagonal entry of row 5, above the diagonal
    assert j > i
    lower_only[j, i] = 0.0  # its mirror removed from the pattern
    lower_only = sparse.csr_array(lower_only)
    lower_only.eliminate_zeros()
    assert lower_only[[j]].indices.tolist().count(i) == 0
    permutations = candidate_permutations(lower_only)  # no groups: METIS on the DOFs' graph
    np.testing.assert_array_equal(np.sort(permutations[NESTED_DISSECTION]), np.arange(matrix.shape[0]))
    b = np.arange(matrix.shape[0], dtype=float)
    x = factorize(lower_only)(b)
    assert np.linalg.norm(lower_only @ x - b) <= 1e-10 * np.linalg.norm(b)


def test_many_right_hand_sides_are_solved_at_once_as_one_by_one():
    """A block of columns through one pass of the Cholesky factor: each column as its own solve, and A X = B."""
    matrix, grids = _lattice(10, 10, 3)
    solve = factorize(matrix, positive_definite=True, groups=grids)
    b = np.random.default_rng(35).standard_normal((matrix.shape[0], 7))
    x = solve(b)
    one_by_one = np.column_stack([solve(b[:, j]) for j in range(b.shape[1])])
    np.testing.assert_allclose(x, one_by_one, rtol=0, atol=1e-12 * np.abs(one_by_one).max())
    assert np.linalg.norm(matrix @ x - b) <= 1e-10 * np.linalg.norm(b)
    # the LU (no Cholesky asked for) takes the same ordering and gives the same x
    np.testing.assert_allclose(factorize(matrix, groups=grids)(b), x, rtol=0, atol=1e-9 * np.abs(x).max())


def test_modes_of_a_wide_lattice_by_nested_dissection_equal_the_dense_routes(tmp_path, monkeypatch):
    """The 1800-DOF wide lattice (its factor ordered by nested dissection) through shift-invert Lanczos: the
    deck's 50 modes agree with the dense eigen-solution's to 1e-9."""
    deck_path = tmp_path / "wide.bdf"
    deck_path.write_text(frame_tower(nx=10, ny=10, levels=3))
    monkeypatch.setattr(modal, "DENSE_MAX_DOF", 10**9)
    dense = compute_modes(deck_path, configuration="0g")
    monkeypatch.setattr(modal, "DENSE_MAX_DOF", 0)
    lanczos = compute_modes(deck_path, configuration="0g")
    assert len(dense.modes) == len(lanczos.modes) == 50
    np.testing.assert_allclose(lanczos.frequencies_hz, dense.frequencies_hz, rtol=1e-9)


@pytest.mark.slow
def test_at_100k_dofs_the_wide_lattice_takes_nested_dissection_and_the_tower_rcm():
    """The benchmark's two 100k-DOF shapes (benchmarks/RESULTS.md, docs/guide/own_structure.md): 16 x 16 grids
    a level, nested dissection's factor 0.71 of RCM's (1079 against 1510 entries per DOF); the 6 x 6-grid
    tower keeps RCM, whose factor is 0.76 of nested dissection's (263 against 346). Symbolic analyses
    only: these are counts, the same on any machine and under any load."""
    wide, wide_grids = _lattice(16, 16, 64)
    chosen = analyse(wide, groups=wide_grids).choice
    per_dof = chosen.entries_per_row(wide.shape[0])
    assert chosen.method == NESTED_DISSECTION
    assert per_dof[NESTED_DISSECTION] <= 0.72 * per_dof[RCM]
    assert per_dof[NESTED_DISSECTION] <= 1100
    tower, tower_grids = _lattice(6, 6, 462)
    chosen = analyse(tower, groups=tower_grids).choice
    per_dof = chosen.entries_per_row(tower.shape[0])
    assert chosen.method == RCM
    assert per_dof[RCM] <= 0.77 * per_dof[NESTED_DISSECTION]
    assert per_dof[RCM] <= 270
