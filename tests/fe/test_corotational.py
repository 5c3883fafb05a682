"""The corotational beam (fe.corotational) against independent computations.

* its material tangent at the undeformed state against the classic T^T K_local T assembly;
* its first derivatives against a closed-form small-displacement kinematics and against plain
  central differences at a deformed, stressed state;
* exact invariance of the natural deformations under a finite rigid motion;
* its geometric stiffness under an axial force against the consistent beam-column matrix;
* its rotation helpers against scipy's Rotation.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.decks import deck_text, r

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import Bars, assemble, bar_section
from mace_fmu.fe.beam import local_stiffness, to_basic
from mace_fmu.fe.corotational import (BarState, bar_dof_indices, deformation_derivatives, deformation_jacobian,
                                      material_tangent, natural_deformations, rotation_matrix, rotation_vector_small,
                                      tangent, tangent_parts, undeformed_jacobian)

E, NU, RHO = 2.0e11, 0.3, 7800.0
SKEW = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
P2 = np.array([1.2, 0.0, 0.0]) + 0.8 * SKEW  # end of the skew bar


def _bulk() -> list[str]:
    """Four bars in different orientations, sections and orientation conventions."""
    return [
        f"MAT1,1,{r(E)},,{r(NU)},{r(RHO)}",
        # I1 != I2 so that swapping the two bending planes would show
        f"PBAR,1,1,{r(1.0e-4)},{r(1.0e-8)},{r(3.0e-8)},{r(2.0e-8)}",
        # Timoshenko: K1/K2 on the second continuation; a short thick bar so that shear matters
        f"PBAR,2,1,{r(2.0e-3)},{r(2.0e-6)},{r(1.2e-6)},{r(2.5e-6)}\n,,,,,,,,\n,{r(0.85)},{r(0.75)}",
        f"PBAR,3,1,{r(5.0e-5)},{r(4.0e-9)},{r(7.0e-9)},{r(1.0e-9)}",
        # skew displacement system (the MACE wheel axis system)
        "CORD2R,1,0,0.0,0.0,0.0,0.0,0.57729,0.81654\n,1.0,0.0,0.0",
        "GRID,1,,0.0,0.0,0.0,1",
        "GRID,2,,1.2,0.0,0.0",
        f"GRID,3,,{r(P2[0])},{r(P2[1])},{r(P2[2])}",
        "GRID,4,,0.3,-0.4,0.9",
        "CBAR,11,1,1,2,0.0,0.0,1.0",  # along X, orientation along Z
        "CBAR,12,2,2,3,0.3,-1.0,2.0",  # skew axis, orientation not along Z, Timoshenko
        "CBAR,13,3,3,4,1",  # orientation by grid G0 = 1
        "CBAR,14,1,1,4,1.0,0.0,0.0",  # orientation vector in GA's CD system (CORD2R 1)
    ]


@pytest.fixture(scope="module")
def model():
    return assemble(read_deck_text(deck_text(_bulk())))


def _undeformed(model) -> BarState:
    return BarState(positions=model.positions, rotations=np.broadcast_to(np.eye(3), (len(model.positions), 3, 3)).copy())


def _one_bar(bars: Bars, k: int) -> Bars:
    """The same Bars restricted to bar ``k`` (node indices kept global)."""
    sl = slice(k, k + 1)
    return dataclasses.replace(bars, ids=bars.ids[sl], node_a=bars.node_a[sl], node_b=bars.node_b[sl],
                               frames0=bars.frames0[sl], lengths0=bars.lengths0[sl], k_natural=bars.k_natural[sl])


def _deformed_state(model, seed: int = 1) -> BarState:
    rng = np.random.default_rng(seed)
    n = len(model.positions)
    return BarState(positions=model.positions + 0.02 * rng.standard_normal((n, 3)),
                    rotations=rotation_matrix(0.08 * rng.standard_normal((n, 3))))


# ---------------------------------------------------------------------------------------------
# Linear stiffness: corotational Hessian at the undeformed state == T^T K_local T


def test_deck_covers_the_intended_cases(model):
    """Guard against a test deck that silently tests less than it claims."""
    frames = model.bars.frames0
    np.testing.assert_allclose(frames[1][0], SKEW, atol=1e-12)
    assert abs(frames[2][1] @ np.array([0.0, 0.0, 1.0])) < 0.99  # G0 orientation, not Z
    # bar 14: v = x axis of CORD2R 1 = basic X, so its y axis is in the plane of the chord and X
    chord = model.positions[3] - model.positions[0]
    assert abs(np.cross(chord, [1.0, 0.0, 0.0]) @ frames[3][1]) < 1e-12
    sec = bar_section(read_deck_text(deck_text(_bulk())), 2)
    assert sec.k1 == 0.85 and sec.k2 == 0.75
    euler = dataclasses.replace(sec, k1=None, k2=None)
    # shear flexibility lowers the transverse stiffness of the short bar by several per cent
    assert local_stiffness(sec, 0.8)[1, 1] < 0.95 * local_stiffness(euler, 0.8)[1, 1]


def test_material_tangent_equals_linear_stiffness(model):
    n = model.dofs.size
    _, k, g = tangent(model.bars, _undeformed(model), n, natural_forces=np.zeros((len(model.bars.ids), 7)))
    assert np.all(g == 0.0)
    k, stiffness = k.toarray(), model.stiffness.toarray()
    scale = np.abs(stiffness).max()
    np.testing.assert_allclose(k, stiffness, rtol=0, atol=1e-8 * scale)
    # Stiff axial terms must not hide errors in the soft torsion/bending terms: compare with
    # symmetric diagonal scaling too (every entry relative to its own row and column).
    dsq = np.sqrt(np.diag(stiffness))
    np.testing.assert_allclose(k / np.outer(dsq, dsq), stiffness / np.outer(dsq, dsq), rtol=0, atol=1e-9)


@pytest.mark.parametrize("k", range(4))
def test_material_tangent_per_bar_equals_element_matrix(model, k):
    """Each bar alone: the 12x12 tangent equals to_basic(local_stiffness) of that bar."""
    deck = read_deck_text(deck_text(_bulk()))
    bars = _one_bar(model.bars, k)
    pid = deck.bars[int(bars.ids[0])].pid
    expected = to_basic(local_stiffness(bar_section(deck, pid), float(bars.lengths0[0])), bars.frames0[0])
    _, kt, _ = tangent(bars, _undeformed(model), model.dofs.size, natural_forces=np.zeros((1, 7)))
    idx = bar_dof_indices(bars)[0]
    np.testing.assert_allclose(kt.toarray()[np.ix_(idx, idx)], expected, rtol=0, atol=1e-8 * np.abs(expected).max())


# ---------------------------------------------------------------------------------------------
# First derivatives: closed-form small-displacement kinematics


def _analytic_natural(frame: np.ndarray, length: float, q: np.ndarray) -> np.ndarray:
    """Linearised (stretch, local rotations A, local rotations B) of nodal motion q (12,) in basic.

    Element axes are the rows of ``frame``. The chord rotates by (., -(wB - wA)/L, (vB - vA)/L).
    About the bar axis the corotated frame follows the MEAN twist of the two ends (its y axis is
    the average of the rotated y axes), so its rotation about x is (rxA + rxB)/2 and the local
    twists are +-(rxA - rxB)/2; the torsional energy GJ/(2L) (rxA - rxB)^2 is the same as with a
    frame that does not twist.
    """
    ua, ra, ub, rb = (frame @ q[i:i + 3] for i in (0, 3, 6, 9))
    psi = np.array([0.5 * (ra[0] + rb[0]), -(ub[2] - ua[2]) / length, (ub[1] - ua[1]) / length])
    return np.concatenate([[ub[0] - ua[0]], ra - psi, rb - psi])


def test_first_derivatives_at_undeformed_state_match_linear_kinematics(model):
    d, b, d2 = deformation_derivatives(model.bars, _undeformed(model))
    assert d.shape == (4, 7) and b.shape == (4, 7, 12) and d2.shape == (4, 7, 12, 12)
    np.testing.assert_allclose(d, 0.0, atol=1e-14)
    rng = np.random.default_rng(7)
    for k in range(4):
        frame, length = model.bars.frames0[k], model.bars.lengths0[k]
        for _ in range(5):
            q = rng.standard_normal(12)
            expected = _analytic_natural(frame, length, q)
            np.testing.assert_allclose(b[k] @ q, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_closed_form_undeformed_jacobian_equals_the_complex_step_one(model):
    """The labels of an unloaded structure take B in closed form: the same matrix, for bars along skew
    axes, with a G0 and a CORD2R orientation."""
    closed = undeformed_jacobian(model.bars)
    _, stepped = deformation_jacobian(model.bars, _undeformed(model))
    np.testing.assert_allclose(closed, stepped, rtol=0, atol=1e-12 * np.abs(stepped).max())
    for k in range(len(model.bars.ids)):  # and the linear kinematics of the test above
        q = np.random.default_rng(k).standard_normal(12)
        expected = _analytic_natural(model.bars.frames0[k], model.bars.lengths0[k], q)
        np.testing.assert_allclose(closed[k] @ q, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_twist_follows_mean_end_rotation(model):
    """The one place where a naive 'frame does not twist' kinematics differs: rows 1 and 4 of B."""
    _, b, _ = deformation_derivatives(model.bars, _undeformed(model))
    frame = model.bars.frames0[0]  # the X bar
    q = np.zeros(12)
    q[3:6] = 0.01 * frame[0]  # twist node A about the bar axis by 0.01 rad
    np.testing.assert_allclose(b[0] @ q, [0, 0.005, 0, 0, -0.005, 0, 0], atol=1e-15)


# ---------------------------------------------------------------------------------------------
# Finite rigid motion


def _bar_ends(model, k, state: BarState):
    a, bnode = model.bars.node_a[k], model.bars.node_b[k]
    return state.positions[a], state.positions[bnode], state.rotations[a], state.rotations[bnode]


@pytest.mark.parametrize("k", range(4))
def test_natural_deformations_vanish_after_finite_rigid_motion(model, k):
    axis = np.array([0.4, -1.0, 0.7]) / np.linalg.norm([0.4, -1.0, 0.7])
    q = rotation_matrix(math.radians(40.0) * axis)
    shift = np.array([0.3, -2.0, 1.1])
    xa, xb, ra, rb = _bar_ends(model, k, _undeformed(model))
    frames0, lengths0 = model.bars.frames0[k], model.bars.lengths0[k]
    d = natural_deformations(q @ xa + shift, q @ xb + shift, q @ ra, q @ rb, frames0, lengths0)
    np.testing.assert_allclose(d, 0.0, atol=1e-12)
    # and a deformed bar keeps exactly its natural deformations under the same rigid motion
    xa, xb, ra, rb = _bar_ends(model, k, _deformed_state(model))
    before = natural_deformations(xa, xb, ra, rb, frames0, lengths0)
    after = natural_deformations(q @ xa + shift, q @ xb + shift, q @ ra, q @ rb, frames0, lengths0)
    assert np.abs(before).max() > 1e-3  # really deformed
    np.testing.assert_allclose(after, before, rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------------------------
# Complex-step derivatives vs plain central differences at a deformed, stressed state


def _perturbed_d(model, k, state: BarState, dq: np.ndarray) -> np.ndarray:
    """natural_deformations after nodal translations and spins dq (12,) of bar k (real arithmetic)."""
    xa, xb, ra, rb = _bar_ends(model, k, state)
    return natural_deformations(xa + dq[0:3], xb + dq[6:9], rotation_matrix(dq[3:6]) @ ra,
                                rotation_matrix(dq[9:12]) @ rb, model.bars.frames0[k], model.bars.lengths0[k])


def test_first_derivatives_match_central_differences_at_deformed_state(model):
    state = _deformed_state(model)
    d, b, _ = deformation_derivatives(model.bars, state)
    assert np.abs(d).max() > 1e-3  # a stressed state, not the trivial one
    h = 1e-6
    for k in range(4):
        fd = np.empty((7, 12))
        for i in range(12):
            e = np.zeros(12)
            e[i] = h
            fd[:, i] = (_perturbed_d(model, k, state, e) - _perturbed_d(model, k, state, -e)) / (2 * h)
        np.testing.assert_allclose(d[k], _perturbed_d(model, k, state, np.zeros(12)), rtol=0, atol=1e-15)
        np.testing.assert_allclose(b[k], fd, rtol=0, atol=1e-6 * np.abs(b[k]).max())


def test_second_derivatives_match_central_differences_at_deformed_state(model):
    """D2 against second differences of natural_deformations (combined spin vectors, as in D2)."""
    state = _deformed_state(model, seed=3)
    _, _, d2 = deformation_derivatives(model.bars, state)
    h = 1e-4
    k = 1  # the skew Timoshenko bar
    f = lambda dq: _perturbed_d(model, k, state, dq)  # noqa: E731
    fd = np.empty((7, 12, 12))
    eye = np.eye(12) * h
    for i in range(12):
        for j in range(12):
            fd[:, i, j] = (f(eye[i] + eye[j]) - f(eye[i] - eye[j]) - f(-eye[i] + eye[j]) + f(-eye[i] - eye[j])) / (4 * h * h)
    np.testing.assert_allclose(d2[k], fd, rtol=0, atol=1e-5 * np.abs(d2[k]).max())


def test_tangent_parts_are_the_material_and_the_force_weighted_second_derivatives(model):
    """At a stressed state: material = sum_e B^T K_n B and geometric = sum_e sum_k g_k D2_k, each from the
    per-bar derivatives assembled here (1e-12); their sum is ``tangent``; ``material_tangent`` (first
    derivatives only, the preload's cheap iterations) gives the same material part and force."""
    state = _deformed_state(model, seed=5)
    n = model.dofs.size
    d, b, d2 = deformation_derivatives(model.bars, state)
    g = np.einsum("nij,nj->ni", model.bars.k_natural, d)
    material, geometric, force = np.zeros((n, n)), np.zeros((n, n)), np.zeros(n)
    for idx, b_e, d2_e, g_e, kn in zip(bar_dof_indices(model.bars), b, d2, g, model.bars.k_natural):
        material[np.ix_(idx, idx)] += b_e.T @ kn @ b_e
        k_g = np.einsum("k,kij->ij", g_e, d2_e)
        geometric[np.ix_(idx, idx)] += 0.5 * (k_g + k_g.T)
        force[idx] += b_e.T @ g_e
    parts = tangent_parts(model.bars, state, n)
    scale = np.abs(material).max()
    np.testing.assert_allclose(parts.material.toarray(), material, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(parts.geometric.toarray(), geometric, rtol=0, atol=1e-12 * scale)
    assert np.abs(geometric).max() > 1e-6 * scale  # stressed: the geometric part is not empty
    f_total, k_total, _ = tangent(model.bars, state, n)
    np.testing.assert_allclose(k_total.toarray(), material + geometric, rtol=0, atol=1e-12 * scale)
    f_cheap, k_cheap = material_tangent(model.bars, state, n)
    np.testing.assert_allclose(k_cheap.toarray(), material, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(f_cheap, force, rtol=0, atol=1e-12 * np.abs(force).max())
    np.testing.assert_allclose(f_total, force, rtol=0, atol=1e-12 * np.abs(force).max())


# ---------------------------------------------------------------------------------------------
# Geometric stiffness of an axially loaded bar


def _beam_column(p: float, length: float, sign: float) -> np.ndarray:
    """Consistent geometric stiffness on (t1, r1, t2, r2); sign -1 for the x-z plane (w, ry)."""
    s = sign * 3 * length
    return p / (30 * length) * np.array([[36, s, -36, s], [s, 4 * length**2, -s, -length**2],
                                         [-36, -s, 36, -s], [s, -length**2, -s, 4 * length**2]])


@pytest.mark.parametrize("k", [0, 1])
@pytest.mark.parametrize("p", [1500.0, -800.0])
def test_geometric_stiffness_is_consistent_beam_column_matrix(model, k, p):
    bars = _one_bar(model.bars, k)
    state, n = _undeformed(model), model.dofs.size
    forces = np.zeros((1, 7))
    forces[0, 0] = p
    _, k_total, _ = tangent(bars, state, n, natural_forces=forces)
    _, k_material, _ = tangent(bars, state, n, natural_forces=np.zeros((1, 7)))
    idx = bar_dof_indices(bars)[0]
    k_geo = (k_total - k_material).toarray()[np.ix_(idx, idx)]
    t = np.kron(np.eye(4), bars.frames0[0])
    k_loc = t @ k_geo @ t.T  # element axes
    length = float(bars.lengths0[0])
    for dofs, sign in (([1, 5, 7, 11], 1.0), ([2, 4, 8, 10], -1.0)):
        expected = _beam_column(p, length, sign)
        np.testing.assert_allclose(k_loc[np.ix_(dofs, dofs)], expected, rtol=0, atol=1e-6 * np.abs(expected).max())
    # no coupling between the two bending planes, and the string term alone would be P/L
    assert np.abs(k_loc[np.ix_([1, 5, 7, 11], [2, 4, 8, 10])]).max() < 1e-6 * abs(p) / length
    assert k_loc[1, 1] == pytest.approx(1.2 * p / length, rel=1e-6)


# ---------------------------------------------------------------------------------------------
# Rotation helpers


@pytest.mark.parametrize("theta", [
    [1e-9, -2e-9, 3e-9], [0.0, 0.0, 0.0], [4e-4, 1e-4, -3e-4], [1e-3, 0.0, 0.0], [0.3, -0.2, 0.1],
    [2.0, 0.0, 0.0], [-1.0, 1.2, 1.0], [0.0, 2.9, -1.1],
])
def test_rotation_matrix_matches_scipy(theta):
    theta = np.array(theta)
    np.testing.assert_allclose(rotation_matrix(theta), Rotation.from_rotvec(theta).as_matrix(), rtol=0, atol=2e-15)


def test_rotation_matrix_is_vectorised():
    thetas = np.random.default_rng(0).standard_normal((5, 2, 3))
    expected = Rotation.from_rotvec(thetas.reshape(-1, 3)).as_matrix().reshape(5, 2, 3, 3)
    np.testing.assert_allclose(rotation_matrix(thetas), expected, rtol=0, atol=2e-15)


@pytest.mark.parametrize(("angle", "tol"), [(1e-9, 1e-15), (0.01, 1e-15), (0.1, 1e-13), (0.2, 1e-10),
                                            (0.3, 1e-8), (0.39, 1e-6)])
def test_rotation_vector_small_inverts_rotation_matrix(angle, tol):
    """The inverse is a truncated asin series: exact near the identity, ~2e-7 relative at 0.4 rad."""
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    theta = angle * axis
    np.testing.assert_allclose(rotation_vector_small(rotation_matrix(theta)), theta, rtol=0, atol=tol * angle)


def test_rotation_vector_small_rejects_large_rotation():
    with pytest.raises(MaceError, match="exceeds 0.5 rad"):
        rotation_vector_small(rotation_matrix(np.array([0.0, 0.9, 0.0])))
    with pytest.raises(MaceError):
        rotation_vector_small(rotation_matrix(np.array([[0.0, 0.0, 0.1], [0.6, 0.3, 0.0]])))  # any of a stack


@pytest.mark.parametrize("angle", [3.0, math.pi])
def test_rotation_vector_small_rejects_rotation_near_pi(angle):
    with pytest.raises(MaceError):
        rotation_vector_small(rotation_matrix(np.array([0.0, 0.0, angle])))


def test_large_models_are_differentiated_in_chunks_of_bars_with_the_same_result(model, monkeypatch):
    """Bars are batched in chunks (bounded memory on 100k-DOF decks): chunks of 3 of the 4 bars give
    the unchunked force and tangent bit for bit."""
    import mace_fmu.fe.corotational as corotational

    state = _deformed_state(model, seed=7)
    n = model.dofs.size
    whole = tangent_parts(model.bars, state, n)
    monkeypatch.setattr(corotational, "_CHUNK_BARS", 3)
    chunked = tangent_parts(model.bars, state, n)
    assert len(model.bars.ids) == 4
    np.testing.assert_array_equal(chunked.internal_force, whole.internal_force)
    np.testing.assert_array_equal(chunked.material.toarray(), whole.material.toarray())
    np.testing.assert_array_equal(chunked.geometric.toarray(), whole.geometric.toarray())
