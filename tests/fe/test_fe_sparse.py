"""The sparse route of the FE core (large models): the same modes as the dense route and as theory.

Above DENSE_MAX_DOF independent DOFs the lowest modes come from shift-invert Lanczos on sparse
matrices (mace_fmu.fe.modal); these tests force that route on small decks, where the dense route
and closed-form solutions give the answer to compare with.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import sparse
from support.decks import deck_text, frame_tower, line_of_bars

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.errors import MaceError
from mace_fmu.fe import modal
from mace_fmu.fe.assembly import assemble
from mace_fmu.fe.constraints import build_constraints
from mace_fmu.fe.modal import solve_modes
from mace_fmu.fe.modes import compute_modes

E, NU, RHO, L = 2.0e11, 0.3, 7800.0, 1.0
D = 0.02
AREA, INERTIA = math.pi * D**2 / 4, math.pi * D**4 / 64


@pytest.fixture()
def sparse_route(monkeypatch):
    monkeypatch.setattr(modal, "DENSE_MAX_DOF", 0)


def test_lattice_tower_modes_equal_the_dense_routes(tmp_path, monkeypatch):
    """A 1,134-DOF lattice tower (lumped bar mass: every rotation massless): the 50 modes the deck's EIGRL
    asks for, by both routes, agree to 1e-9 in frequency and are the same shapes (MAC > 1 - 1e-9)."""
    deck_path = tmp_path / "tower.bdf"
    deck_path.write_text(frame_tower(nx=3, ny=3, levels=20))
    monkeypatch.setattr(modal, "DENSE_MAX_DOF", 10**9)
    dense = compute_modes(deck_path, configuration="0g")
    monkeypatch.setattr(modal, "DENSE_MAX_DOF", 0)
    lanczos = compute_modes(deck_path, configuration="0g")
    assert isinstance(lanczos.model.stiffness, sparse.sparray) and lanczos.model.dofs.size == 1134
    assert len(dense.modes) == len(lanczos.modes) == 50
    np.testing.assert_allclose(lanczos.frequencies_hz, dense.frequencies_hz, rtol=1e-9)
    m = dense.model.mass
    a, b = dense.modes.shapes, lanczos.modes.shapes
    np.testing.assert_allclose(b.T @ (m @ b), np.eye(50), atol=1e-9)  # mass-normalised
    # modes of equal frequency (the tower's square section) may mix: compare the subspaces
    cross = a.T @ (m @ b)
    assert np.all(np.abs(np.linalg.svd(cross, compute_uv=False) - 1.0) < 1e-9)


def test_cantilever_by_lanczos_matches_euler_bernoulli(sparse_route):
    """beta_n L = 1.875104, 4.694091, 7.854757 with 20 consistent-mass bars, through the sparse route."""
    bulk = line_of_bars(n=20, length=L, e=E, nu=NU, rho=RHO, area=AREA, i=INERTIA, ps="345")
    bulk.append("SPC1,1,123456,1")
    deck = read_deck_text(deck_text(bulk))
    model = assemble(deck, mass="consistent")
    cons = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    modes = solve_modes(model.stiffness, model.mass, cons, model.dofs, model.cd_frames, wanted_count=3)
    exact = np.array([1.875104, 4.694091, 7.854757]) ** 2 * math.sqrt(E * INERTIA / (RHO * AREA * L**4)) / (2 * math.pi)
    np.testing.assert_allclose(modes.frequencies_hz[:3], exact, rtol=5e-3)


def test_a_free_structure_gives_its_rigid_body_modes(sparse_route):
    """Free-free: the shift below zero finds the six rigid-body modes (0 Hz) before the first bending mode."""
    bulk = line_of_bars(n=20, length=L, e=E, nu=NU, rho=RHO, area=AREA, i=INERTIA)
    deck = read_deck_text(deck_text(bulk))
    model = assemble(deck, mass="consistent")
    cons = build_constraints(deck, model.dofs, model.cd_frames, spc_set=None, mpc_set=None)
    modes = solve_modes(model.stiffness, model.mass, cons, model.dofs, model.cd_frames, wanted_count=8)
    f = modes.frequencies_hz
    free_free = 4.730041**2 * math.sqrt(E * INERTIA / (RHO * AREA * L**4)) / (2 * math.pi)
    assert np.all(np.abs(f[:6]) < 1e-3) and f[6] == pytest.approx(free_free, rel=5e-3)


def test_the_sparse_route_needs_to_know_where_to_stop(sparse_route):
    bulk = line_of_bars(n=4, length=L, e=E, nu=NU, rho=RHO, area=AREA, i=INERTIA) + ["SPC1,1,123456,1"]
    deck = read_deck_text(deck_text(bulk))
    model = assemble(deck, mass="consistent")
    cons = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    with pytest.raises(MaceError, match="solved for its lowest modes only: give a frequency range"):
        solve_modes(model.stiffness, model.mass, cons, model.dofs, model.cd_frames)


def test_mace_0g_by_lanczos_equals_the_dense_route(monkeypatch):
    """The bundled deck (mechanisms, MPCs, massless DOFs, a free-free 0-g structure) through the sparse
    route: every flexible mode below 250 Hz within 1e-7 of the dense route's (measured 7e-9)."""
    dense = compute_modes(configuration="0g", max_hz=250.0)
    monkeypatch.setattr(modal, "DENSE_MAX_DOF", 0)
    lanczos = compute_modes(configuration="0g", max_hz=250.0)
    a, b = dense.frequencies_hz, lanczos.frequencies_hz
    assert len(a) == len(b) == 35
    flexible = np.abs(a) > 0.01
    np.testing.assert_allclose(b[flexible], a[flexible], rtol=1e-7)
    assert np.all(np.abs(b[~flexible]) < 0.01)


def _tower_matrix(shift: float) -> sparse.csr_array:
    """K - shift M of a small clamped tower (positive definite for a negative shift)."""
    deck = read_deck_text(frame_tower(nx=2, ny=2, levels=6, with_gravity=False), name="tower.bdf")
    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k = constraints.reduce_sparse(model.stiffness)
    m = constraints.reduce_sparse(model.mass)
    return sparse.csr_array(0.5 * (k + k.T) - shift * 0.5 * (m + m.T))


def test_the_cholesky_and_the_lu_solve_alike_and_an_indefinite_matrix_falls_back_to_the_lu():
    """CHOLMOD's L L^T (in the ordering chosen by fill) and SuperLU's LU give the same x to rounding; a matrix that is
    not positive definite is refused by the Cholesky and solved by the LU all the same."""
    pytest.importorskip("cvxopt")
    from mace_fmu.sparse.factor import _cholesky, factorize
    from mace_fmu.sparse.ordering import analyse

    definite = _tower_matrix(-1.0)
    b = np.random.default_rng(3).standard_normal(definite.shape[0])
    by_cholesky, by_lu = factorize(definite, positive_definite=True)(b), factorize(definite)(b)
    scale = np.linalg.norm(by_lu)
    assert np.linalg.norm(by_cholesky - by_lu) <= 1e-9 * scale
    assert np.linalg.norm(definite @ by_cholesky - b) <= 1e-9 * np.linalg.norm(b)
    # shifted past the lowest eigenvalues: indefinite, yet regular
    indefinite = _tower_matrix(4 * math.pi**2 * 40.0**2)
    assert _cholesky(analyse(indefinite), indefinite.shape[0]) is None
    x = factorize(indefinite, positive_definite=True)(b)
    assert np.linalg.norm(indefinite @ x - b) <= 1e-8 * np.linalg.norm(b)


def test_the_cd_rotation_is_the_block_diagonal_of_each_grids_frame_twice():
    """The CD rotation built as one block array equals scipy's block_diag of each grid's frame (translations,
    then rotations), on random frames and on basic ones (whose zeros it does not store)."""
    from scipy.spatial.transform import Rotation

    from mace_fmu.fe.constraints import cd_rotation

    frames = np.concatenate([Rotation.random(40, random_state=3).as_matrix(), np.broadcast_to(np.eye(3), (5, 3, 3))])
    expected = sparse.block_diag([block for frame in frames for block in (frame, frame)], format="csr")
    built = cd_rotation(frames)
    assert abs(built - expected).max() == 0.0
    assert built.nnz == 80 * 9 + 10 * 3  # a basic frame stores its three ones only
