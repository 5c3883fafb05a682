"""Block shift-invert Lanczos against closed forms and a dense eigen-solution of the same matrices.

The references are independent of the method under test: the eigenvalues of a fixed-fixed chain of
equal masses and springs in closed form, the modes of a square membrane lattice (pairs of equal
frequencies) and of a chain with massless DOFs by scipy's dense generalised eigen-solution after
static condensation.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from scipy import sparse

from mace_fmu.fe.modal import LANCZOS_TOLERANCE
from mace_fmu.sparse import lanczos
from mace_fmu.sparse.factor import factorize
from mace_fmu.sparse.lanczos import lowest_modes


def _chain(masses: int, *, k_n_per_m: float = 1.0e4, m_kg: float = 2.0) -> tuple[sparse.csr_array, sparse.csr_array]:
    """K, M of ``masses`` equal masses between equal springs, both ends fixed."""
    main = np.full(masses, 2.0 * k_n_per_m)
    off = np.full(masses - 1, -k_n_per_m)
    k = sparse.csr_array(sparse.diags([off, main, off], [-1, 0, 1]))
    return k, sparse.csr_array(sparse.identity(masses) * m_kg)


def _membrane(side: int) -> tuple[sparse.csr_array, sparse.csr_array]:
    """A square side x side lattice of unit masses on unit springs to its four neighbours, its edge fixed:
    the 5-point Laplacian, whose modes come in pairs of equal eigenvalues (x and y swapped)."""
    one_d = sparse.diags([-np.ones(side - 1), 2.0 * np.ones(side), -np.ones(side - 1)], [-1, 0, 1])
    eye = sparse.identity(side)
    return sparse.csr_array(sparse.kron(one_d, eye) + sparse.kron(eye, one_d)), sparse.csr_array(sparse.identity(side**2))


def _lowest(k: sparse.csr_array, m: sparse.csr_array, count: int, **options: object):
    shift = -1e-3 * float(k.diagonal().max() / m.diagonal().max())
    solve = factorize(k - shift * m, positive_definite=True)
    return lowest_modes(stiffness=k, mass=m, solve=solve, shift=shift, count=count,
                        max_dimension=options.pop("max_dimension", k.shape[0] // 2), **options)


@pytest.mark.parametrize("tolerance", [1e-8, LANCZOS_TOLERANCE])
def test_a_fixed_fixed_chain_matches_its_closed_form(tolerance):
    """2000 masses: omega_j^2 = 4 k / m sin^2(j pi / (2 (N + 1))), the lowest 30 within 1e-11 relative or
    1e-14 of the highest eigenvalue (the rounding of any solver of this matrix, dense ones included);
    every vector M-normalised and, within 1e-10 in the modal assurance criterion, the closed-form shape
    sin(i j pi / (N + 1)). At the default residual tolerance and at the one the modal solution uses."""
    n, k_n_per_m, m_kg = 2000, 1.0e4, 2.0
    k, m = _chain(n, k_n_per_m=k_n_per_m, m_kg=m_kg)
    found = _lowest(k, m, 30, tolerance=tolerance)
    j = np.arange(1, len(found.eigenvalues) + 1)
    exact = 4.0 * k_n_per_m / m_kg * np.sin(j * np.pi / (2 * (n + 1))) ** 2
    assert len(found.eigenvalues) >= 30
    np.testing.assert_allclose(found.eigenvalues, exact, rtol=1e-11, atol=1e-14 * 4.0 * k_n_per_m / m_kg)
    x = found.vectors
    np.testing.assert_allclose(np.einsum("im,im->m", x, m @ x), 1.0, rtol=1e-12)
    shapes = np.sin(np.outer(np.arange(1, n + 1), j) * np.pi / (n + 1))
    mac = (np.einsum("im,im->m", x, shapes) ** 2 / np.einsum("im,im->m", x, x) / np.einsum("im,im->m", shapes, shapes))
    np.testing.assert_allclose(mac[:30], 1.0, atol=1e-10)


def test_pairs_of_equal_frequencies_are_all_found():
    """A 40 x 40 membrane (1600 DOFs): its lowest 40 eigenvalues, among them pairs of equal ones, equal the
    dense solution's within 1e-11 relative: none of a pair is missed (the block holds both)."""
    k, m = _membrane(40)
    found = _lowest(k, m, 40)
    dense = sla.eigh(k.toarray(), m.toarray(), eigvals_only=True)
    assert np.sum(np.isclose(np.diff(dense[:40]), 0.0, atol=1e-9 * dense[40])) >= 10  # the pairs are there
    np.testing.assert_allclose(found.eigenvalues[:40], dense[:40], rtol=1e-11)


def test_massless_dofs_are_condensed_and_carry_their_static_response():
    """A chain whose every other DOF has no mass: the eigenvalues equal the dense solution of the statically
    condensed problem (1e-11), and each vector's massless DOFs equal -K_oo^-1 K_oa x_a of its massive ones."""
    n = 1201
    k, _ = _chain(n)
    masses = np.where(np.arange(n) % 2 == 0, 3.0, 0.0)
    m = sparse.csr_array(sparse.diags(masses))
    found = _lowest(k, m, 12)
    a, o = np.flatnonzero(masses > 0), np.flatnonzero(masses == 0)
    kd = k.toarray()
    condensed = kd[np.ix_(a, a)] - kd[np.ix_(a, o)] @ np.linalg.solve(kd[np.ix_(o, o)], kd[np.ix_(o, a)])
    dense = sla.eigh(condensed, np.diag(masses[a]), eigvals_only=True)
    np.testing.assert_allclose(found.eigenvalues[:12], dense[:12], rtol=1e-11)
    x = found.vectors[:, :12]
    static = -np.linalg.solve(kd[np.ix_(o, o)], kd[np.ix_(o, a)] @ x[a])
    np.testing.assert_allclose(x[o], static, atol=1e-9 * np.abs(x).max())


def test_a_coupled_mass_on_some_dofs_only():
    """The chain of the test above with a consistent (coupled) mass between each two neighbouring massive DOFs,
    m / 6 [[2, 1], [1, 2]], and none on the others: the eigenvalues equal the dense solution of the statically
    condensed problem (1e-11), the vectors are M-normalised, and their massless DOFs carry the static response
    -K_oo^-1 K_oa x_a of the massive ones."""
    n, mass_kg = 1201, 3.0
    k, _ = _chain(n)
    a, o = np.arange(0, n, 2), np.arange(1, n, 2)
    m = np.zeros((n, n))
    for left, right in zip(a[:-1], a[1:]):
        m[np.ix_([left, right], [left, right])] += mass_kg / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    found = _lowest(k, sparse.csr_array(m), 12)
    kd = k.toarray()
    condensed = kd[np.ix_(a, a)] - kd[np.ix_(a, o)] @ np.linalg.solve(kd[np.ix_(o, o)], kd[np.ix_(o, a)])
    dense = sla.eigh(condensed, m[np.ix_(a, a)], eigvals_only=True)
    np.testing.assert_allclose(found.eigenvalues[:12], dense[:12], rtol=1e-11)
    x = found.vectors[:, :12]
    np.testing.assert_allclose(np.einsum("im,im->m", x, m @ x), 1.0, rtol=1e-12)
    static = -np.linalg.solve(kd[np.ix_(o, o)], kd[np.ix_(o, a)] @ x[a])
    np.testing.assert_allclose(x[o], static, atol=1e-9 * np.abs(x).max())


def test_it_goes_on_until_a_mode_lies_above_the_frequency_asked():
    """Asked for one mode and every mode up to the 25th chain eigenvalue: it returns at least 26, in order,
    the last above it, equal to the dense solution's (1e-11 relative or 1e-14 of the highest eigenvalue)."""
    k, m = _chain(1500)
    dense = sla.eigh(k.toarray(), m.toarray(), eigvals_only=True, subset_by_index=[0, 40])
    found = _lowest(k, m, 1, above=float(dense[24]) * (1 + 1e-9))
    assert len(found.eigenvalues) >= 26 and found.eigenvalues[-1] > dense[24]
    np.testing.assert_allclose(found.eigenvalues, dense[:len(found.eigenvalues)], rtol=1e-11,
                               atol=1e-14 * abs(k).sum(axis=1).max() / m.diagonal().min())  # rounding, as above


def test_a_krylov_space_that_closes_early_is_refilled():
    """Five masses on a chain of 400 DOFs (the rest massless) have five modes: asked for four with a block of
    eight, the space closes after one block; the four equal the dense condensed solution's."""
    n = 400
    k, _ = _chain(n)
    masses = np.zeros(n)
    masses[[40, 120, 200, 280, 360]] = 1.5
    m = sparse.csr_array(sparse.diags(masses))
    found = _lowest(k, m, 4, block_size=8, max_dimension=5)
    a, o = np.flatnonzero(masses), np.flatnonzero(masses == 0)
    kd = k.toarray()
    condensed = kd[np.ix_(a, a)] - kd[np.ix_(a, o)] @ np.linalg.solve(kd[np.ix_(o, o)], kd[np.ix_(o, a)])
    dense = sla.eigh(condensed, np.diag(masses[a]), eigvals_only=True)
    np.testing.assert_allclose(found.eigenvalues[:4], dense[:4], rtol=1e-11)


def test_a_space_larger_than_allowed_gives_none():
    """The dense route takes over (modal._sparse_modes) when the space would exceed ``max_dimension``."""
    k, m = _chain(600)
    assert _lowest(k, m, 40, max_dimension=32) is None


@pytest.mark.parametrize("seed", [1, 2])
def test_the_result_does_not_depend_on_the_start_block(seed):
    """Other random start blocks: the same 20 membrane eigenvalues within 1e-12 relative."""
    k, m = _membrane(30)
    reference = _lowest(k, m, 20).eigenvalues[:20]
    np.testing.assert_allclose(_lowest(k, m, 20, seed=seed).eigenvalues[:20], reference, rtol=1e-12)


@pytest.mark.parametrize("tolerance, shared", [(1e-8, False), (LANCZOS_TOLERANCE, False), (LANCZOS_TOLERANCE, True)])
def test_a_lattice_s_modes_equal_arpacks_on_the_same_factor(tolerance, shared, monkeypatch):
    """A second solver on the same matrices: a clamped 4 x 4-grid lattice tower of 30 levels (2,880 DOFs, no
    rotary mass: half the DOFs massless), its 30 lowest eigenvalues by ARPACK's single-vector shift-invert
    Lanczos (scipy's eigsh) and by the block Lanczos agree within 1e-11 relative, the shapes within 1e-8 in
    the modal assurance criterion: at the default residual tolerance and at the modal solution's, and with
    the Gram-Schmidt's products shared out between threads (``shared``: from the first vector on, where a
    large model's take the threads from 4M basis entries)."""
    if shared:
        monkeypatch.setattr(lanczos, "SHARED_GRAM_SCHMIDT_ENTRIES", 0)
        monkeypatch.setattr(lanczos, "usable_cores", lambda: 3)  # three shares of the rows, whatever the machine
    from scipy.sparse.linalg import LinearOperator, eigsh
    from support.decks import frame_tower

    from mace_fmu.deck.reader import read_deck_text
    from mace_fmu.fe.assembly import assemble
    from mace_fmu.fe.constraints import build_constraints

    deck = read_deck_text(frame_tower(nx=4, ny=4, levels=30), name="lattice.bdf")
    model = assemble(deck)
    constraints = build_constraints(deck, model.dofs, model.cd_frames, spc_set=1, mpc_set=None)
    k = sparse.csr_array(constraints.reduce_sparse(model.stiffness))
    m = sparse.csr_array(constraints.reduce_sparse(model.mass))
    k, m = sparse.csr_array(0.5 * (k + k.T)), sparse.csr_array(0.5 * (m + m.T))
    shift = -1e-6 * float(np.median(k.diagonal()) / np.median(m.diagonal()[m.diagonal() > 0]))
    solve = factorize(k - shift * m, positive_definite=True)
    found = lowest_modes(stiffness=k, mass=m, solve=solve, shift=shift, count=30, max_dimension=k.shape[0] // 4,
                         tolerance=tolerance)
    op = LinearOperator(k.shape, matvec=lambda x: solve(np.asarray(x, dtype=float).ravel()), dtype=float)
    values, vectors = eigsh(k, k=30, M=m, sigma=shift, which="LM", OPinv=op, tol=1e-12, ncv=80)
    order = np.argsort(values)
    values, vectors = values[order], vectors[:, order]
    np.testing.assert_allclose(found.eigenvalues[:30], values, rtol=1e-11)
    x = found.vectors[:, :30]
    mac = np.einsum("im,im->m", x, m @ vectors) ** 2 / (np.einsum("im,im->m", x, m @ x)
                                                         * np.einsum("im,im->m", vectors, m @ vectors))
    distinct = np.r_[True, np.diff(values) > 1e-6 * values[1:]] & np.r_[np.diff(values) > 1e-6 * values[:-1], True]
    np.testing.assert_allclose(mac[distinct], 1.0, atol=1e-8)  # a repeated pair's vectors are any basis of it
