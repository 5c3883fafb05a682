"""Cards no public NASTRAN result checks, against closed forms written here from the cards' textbook meaning.

The decks are those of tests/data/second_solver (also solved by MYSTRAN there, see test_second_solver.py); each
test builds the model's matrices by hand from the card values as the Quick Reference Guide defines them, and
solves K x = w^2 M x with scipy, with no code of mace_fmu:

* CROD: the axial and torsional chains of lumped masses (half the rod's mass on each end's translations, none
  on its rotations; E A / L and G J / L), exact to 1e-10;
* CELAS1/PELAS and CMASS1/PMASS: the spring and mass network (a two-DOF element adds k (u1 - u2)^2 / 2, a
  grounded one k u1^2 / 2, for masses likewise; the two-DOF CMASS1 and the blank G2 on a variant of the deck,
  as MYSTRAN takes neither), exact to 1e-10;
* CONM1: a 6x6 mass on six grounded springs, the matrix given in a rotated CID, exact to 1e-10 (MYSTRAN has no CONM1);
* RBE3 (translational): the reference moves as the weighted least-squares rigid motion of its independent
  grids' translations, exact to 1e-10;
* CORD1R: the same structure built in basic with the system's axes found here from its three grids by
  Gram-Schmidt; frequencies to 1e-10 and mode shapes in the CD system to 1e-8;
* PBARL TUBE and BOX: A and I from the published formulas (Roark's Formulas for Stress and Strain, table
  A.1: hollow circle, hollow rectangle), cantilever frequencies of Euler-Bernoulli: 0.2 % on the first bending
  mode of each plane, 1 % on the second (20 bars of lumped mass, and the section's shear flexibility); the BOX's
  weaker plane holds the orientation vector (DIM2, the height, lies along element y).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla
from support.paths import DATA

from mace_fmu.deck.reader import read_deck, read_deck_text
from mace_fmu.fe.modes import compute_modes

DECKS = DATA / "second_solver"
E, NU, RHO = 7.0e10, 0.33, 2700.0  #: the MAT1 of every deck there [Pa, -, kg/m^3]
G = E / (2.0 * (1.0 + NU))


def ours(name: str, *, max_hz: float | None = None) -> np.ndarray:
    return compute_modes(read_deck(DECKS / f"{name}.bdf"), configuration="0g", max_hz=max_hz).modes.frequencies_hz


def hz(stiffness: np.ndarray, mass: np.ndarray) -> np.ndarray:
    return np.sqrt(sla.eigh(stiffness, mass, eigvals_only=True)) / (2.0 * math.pi)


def chain(n: int, k: float, masses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fixed-free chain of ``n`` equal springs ``k`` with lumped ``masses`` on the free DOFs."""
    stiffness = np.zeros((n, n))
    for e in range(n):  # spring e joins DOF e - 1 (ground for e = 0) and DOF e
        ends = [e - 1, e] if e else [e]
        sign = [1.0, -1.0] if e else [1.0]
        for a, sa in zip(ends, sign):
            for b, sb in zip(ends, sign):
                stiffness[a, b] += k * sa * sb
    return stiffness, np.diag(masses)


def test_crod_axial_and_torsional_chains():
    """crod.bdf: ten 0.3 m CRODs, A 1e-4, J 2e-9, 0.05 kg and I11 1e-5 kg m^2 point masses on grids 2-11."""
    n, length, area, j, point, polar = 10, 0.3, 1.0e-4, 2.0e-9, 0.05, 1.0e-5
    rod = RHO * area * length
    axial_mass = np.full(n, rod + point)
    axial_mass[-1] = rod / 2.0 + point  # the tip has one rod
    axial = hz(*chain(n, E * area / length, axial_mass))
    torsion = hz(*chain(n, G * j / length, np.full(n, polar)))  # a CROD lumps no rotary inertia
    expected = np.sort(np.concatenate([axial, torsion]))[:12]
    np.testing.assert_allclose(ours("crod"), expected, rtol=1e-10)


#: scalar_springs_masses.bdf, as its cards say: DOFs x1..x6 of grids 1-6 and y6 of grid 6; grid 7 is clamped
SCALAR_DOFS = ["x1", "x2", "x3", "x4", "x5", "x6", "y6"]
SPRINGS = [(1.0e4, "x1", None), (2.0e4, "x1", "x2"), (1.5e4, "x2", "x3"), (2.0e4, "x3", "x4"),
           (3.0e4, "x4", "x5"), (1.0e4, "x5", "y6"), (1.5e4, "y6", None), (3.0e4, "x6", "x4")]
#: CMASS1s, and the 0.5 kg CONM2 on grid 6 (its x and y; z is fixed)
MASSES = [(1.0, "x1", None), (2.0, "x2", None), (1.0, "x3", None), (0.5, "x4", None), (2.0, "x5", None),
          (0.5, "x6", None), (0.5, "x6", None), (0.5, "y6", None)]


def _scalar_matrix(elements) -> np.ndarray:
    out = np.zeros((7, 7))
    for value, a, b in elements:
        v = np.zeros(7)
        v[SCALAR_DOFS.index(a)] = 1.0
        if b is not None:
            v[SCALAR_DOFS.index(b)] = -1.0
        out += value * np.outer(v, v)
    return out


def test_celas1_cmass1_network():
    expected = hz(_scalar_matrix(SPRINGS), _scalar_matrix(MASSES))
    np.testing.assert_allclose(ours("scalar_springs_masses"), expected, rtol=1e-10)


def test_celas1_grounded_by_a_blank_g2_and_cmass1_between_two_dofs():
    """What MYSTRAN does not take, on the same network: the springs to the clamped grid 7 grounded by a blank G2,
    two properties on one PELAS card, and a 0.3 kg CMASS1 between x3 and x4, m (u3 - u4)^2 / 2."""
    text = (DECKS / "scalar_springs_masses.bdf").read_text()
    for old, new in (("CELAS1  11      1       1       1       7       1", "CELAS1,11,5,1,1"),
                     ("CELAS1  17      3       6       2       7       2", "CELAS1,17,6,6,2"),
                     ("ENDDATA", "PELAS,5,1.0E4,,,6,1.5E4\nCMASS1,28,14,3,1,4,1\nPMASS,14,0.3\nENDDATA")):
        assert old in text
        text = text.replace(old, new)
    modes = compute_modes(read_deck_text(text), configuration="0g").modes.frequencies_hz
    expected = hz(_scalar_matrix(SPRINGS), _scalar_matrix(MASSES + [(0.3, "x3", "x4")]))
    np.testing.assert_allclose(modes, expected, rtol=1e-10)
    assert not np.allclose(modes, ours("scalar_springs_masses"), rtol=1e-3)  # the two-DOF mass matters


def _rotation(origin, z_point, xz_point) -> np.ndarray:
    """Columns = the x, y, z axes of a rectangular system from three points (CORD2R / CORD1R rule)."""
    z = np.asarray(z_point, float) - origin
    z /= np.linalg.norm(z)
    x = np.asarray(xz_point, float) - origin
    x -= (x @ z) * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def test_conm1_in_a_rotated_system_on_six_springs():
    """A rigid body's 6x6 mass (2 kg, its centre of gravity off the grid, full inertia) given in a rotated CID,
    on grounded springs along the six basic components: w^2 = eig(K, R M R^T)."""
    m, offset = 2.0, np.array([0.1, -0.05, 0.2])
    inertia = np.array([[0.04, 0.002, -0.003], [0.002, 0.05, 0.001], [-0.003, 0.001, 0.03]])
    skew = np.array([[0, -offset[2], offset[1]], [offset[2], 0, -offset[0]], [-offset[1], offset[0], 0]])
    # kinetic energy m |u + theta x r|^2 / 2 + theta^T J theta / 2, u + theta x r = u - [r]x theta
    mass = np.block([[m * np.eye(3), -m * skew], [m * skew, inertia + m * skew.T @ skew]])
    lower = [mass[i, j] for i in range(6) for j in range(i + 1)]  # M11 M21 M22 M31 ... M66
    fields = [f"{v:.12e}" for v in lower]
    conm1 = "CONM1,5,1,2," + ",".join(fields[:5]) + "\n," + ",".join(fields[5:13]) + "\n," + ",".join(fields[13:])
    springs = [4.0e4, 6.0e4, 5.0e4, 3.0e3, 2.0e3, 4.0e3]
    cards = ["CORD2R,2,,0.,0.,0.,0.3,0.4,0.866\n,1.,0.2,0.1", "GRID,1,,0.5,0.2,-0.1", conm1, "EIGRL,1,,,6"]
    cards += [f"CELAS2,{10 + c},{k:.6e},1,{c}" for c, k in enumerate(springs, start=1)]
    deck = read_deck_text("SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\n" + "\n".join(cards) + "\nENDDATA\n")
    rot = np.kron(np.eye(2), _rotation(np.zeros(3), [0.3, 0.4, 0.866], [1.0, 0.2, 0.1]))
    expected = hz(np.diag(springs), rot @ mass @ rot.T)
    np.testing.assert_allclose(compute_modes(deck, configuration="0g").modes.frequencies_hz, expected, rtol=1e-10)
    # the rotation matters: the same matrix read in basic gives other frequencies
    assert not np.allclose(hz(np.diag(springs), mass), expected, rtol=1e-3)


def _conm2(m: float, i11, i21, i22, i31, i32, i33) -> np.ndarray:
    """CONM2's 6x6 at its grid (no offset): NASTRAN's inertia matrix has -I21, -I31, -I32 off the diagonal."""
    inertia = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
    return sla.block_diag(m * np.eye(3), inertia)


def test_rbe3_reference_is_the_weighted_least_squares_rigid_motion():
    """rbe3.bdf: the reference grid 10 carries a 5 kg CONM2; its motion q = (u0, theta0) minimises
    sum_i w_i |u_i - (u0 + theta0 x (x_i - x_ref))|^2 over the corners' translations u_i, so
    q = (sum w_i X_i^T X_i)^-1 sum w_i X_i^T u_i with X_i = [I, -[x_i - x_ref]x]."""
    corners = {1: (0.4, 0.25, 0.0), 2: (-0.4, 0.25, 0.05), 3: (-0.4, -0.25, 0.0), 4: (0.4, -0.25, -0.1)}
    weights = {1: 1.0, 2: 2.5, 3: 1.0, 4: 2.5}
    springs = {1: (1.0e4, 2.0e4, 3.0e4), 2: (1.5e4, 1.0e4, 2.5e4), 3: (2.0e4, 1.5e4, 2.0e4), 4: (1.0e4, 3.0e4, 3.5e4)}
    reference = np.array([0.1, -0.05, 0.2])
    blocks = []
    for x in corners.values():
        r = np.asarray(x) - reference
        skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        blocks.append(np.hstack([np.eye(3), -skew]))
    normal = sum(weights[g] * b.T @ b for g, b in zip(corners, blocks))
    interpolation = np.linalg.solve(normal, np.hstack([weights[g] * b.T for g, b in zip(corners, blocks)]))
    stiffness = np.diag(np.concatenate([springs[g] for g in corners]))
    mass = 0.2 * np.eye(12) + interpolation.T @ _conm2(5.0, 0.4, 0.02, 0.7, -0.03, 0.01, 0.9) @ interpolation
    np.testing.assert_allclose(ours("rbe3"), hz(stiffness, mass), rtol=1e-10)


def test_cord1r_structure_is_the_same_structure_built_in_basic():
    """cord1r.bdf, rebuilt here with the beam along basic z from the origin: system 9's axes R come from grids
    91, 92 (given in CORD2R 5, itself from its three points) and 93; the CONROD's far end is R^T (x95 - x91).
    Same frequencies (1e-10) and the same tip motion in the CD system (1e-8), up to each mode's sign."""
    r5 = _rotation(np.zeros(3), [0.3, 0.4, 0.866], [1.0, 0.2, 0.1])
    a, c = np.array([1.0, 2.0, 3.0]), np.array([2.0, 2.5, 3.5])
    b = r5 @ np.array([0.2, -0.4, 1.1])
    r9 = _rotation(a, b, c)
    far = r9.T @ (np.array([1.4, 0.04, 2.0]) - a)
    cards = ["EIGRL,1,,,8", "MAT1,1,7.0E10,,.33,2700.", "PBAR,1,1,7.0E-4,4.0E-8,9.0E-8,1.0E-8", "SPC1,1,123456,1",
             f"GRID,95,,{far[0]:.15e},{far[1]:.15e},{far[2]:.15e},,123456", "CELAS2,50,1.0E3,9,1",
             "CELAS2,51,4.0E3,9,2", "CONM2,60,9,,.5", "CONROD,70,9,95,1,1.0E-7"]
    cards += [f"GRID,{k + 1},,0.,0.,{0.25 * k:.2f}" for k in range(9)]
    cards += [f"CBAR,{k + 1},1,{k + 1},{k + 2},1.,0.,0." for k in range(8)]
    basic = compute_modes(read_deck_text("SOL 103\nCEND\nSPC = 1\nMETHOD = 1\nBEGIN BULK\n" + "\n".join(cards)
                                         + "\nENDDATA\n"), configuration="0g").modes
    cord1r = compute_modes(read_deck(DECKS / "cord1r.bdf"), configuration="0g").modes
    np.testing.assert_allclose(cord1r.frequencies_hz, basic.frequencies_hz, rtol=1e-10)
    for component in (1, 2, 3):
        np.testing.assert_allclose(np.abs(cord1r.shape(9, component, system="cd")),
                                   np.abs(basic.shape(9, component)), rtol=0, atol=1e-8)
    # the tip's motion in basic is R times its motion in system 9
    tip_basic = np.array([cord1r.shape(9, c) for c in (1, 2, 3)])
    tip_cd = np.array([cord1r.shape(9, c, system="cd") for c in (1, 2, 3)])
    np.testing.assert_allclose(tip_basic, r9 @ tip_cd, rtol=0, atol=1e-10)


BETA_L = np.array([1.875104069, 4.694091133])  #: cantilever roots of cos(bL) cosh(bL) = -1


@pytest.mark.parametrize(("name", "area", "i_plane1", "i_plane2"), [
    # hollow circle, outer and inner radius 0.03, 0.025: A = pi (R^2 - r^2), I = pi (R^4 - r^4) / 4
    ("pbarl_tube", math.pi * (0.03**2 - 0.025**2), math.pi * (0.03**4 - 0.025**4) / 4,
     math.pi * (0.03**4 - 0.025**4) / 4),
    # hollow rectangle, width 0.06 (along element z), height 0.03 (along y), walls 0.003 (flanges), 0.002 (webs):
    # A = b h - b_i h_i, I1 (bending in plane 1, about z) = (b h^3 - b_i h_i^3) / 12, I2 = (h b^3 - h_i b_i^3) / 12
    ("pbarl_box", 0.06 * 0.03 - 0.056 * 0.024, (0.06 * 0.03**3 - 0.056 * 0.024**3) / 12,
     (0.03 * 0.06**3 - 0.024 * 0.056**3) / 12),
])
def test_pbarl_cantilever_bends_as_euler_bernoulli_with_the_published_section(name, area, i_plane1, i_plane2):
    """4 m cantilevers of 20 CBARs: the first two bending modes of each plane against
    f = (beta L)^2 / (2 pi L^2) sqrt(E I / (rho A)). NASTRAN's lumped bar mass converges from below as (n / N)^2:
    20 bars put the first mode 0.14 % and the second 0.6 % low; the shear flexibility NASTRAN gives the section
    (K1, K2) lowers them by up to 0.03 % and 0.2 % more. Hence 0.2 % and 1 %, both below Euler-Bernoulli."""
    length = 4.0
    exact = np.sort(np.concatenate([BETA_L**2 / (2 * math.pi * length**2) * math.sqrt(E * i / (RHO * area))
                                    for i in (i_plane1, i_plane2)]))
    modes = compute_modes(read_deck(DECKS / f"{name}.bdf"), configuration="0g").modes
    f = modes.frequencies_hz[:4]
    np.testing.assert_allclose(f[:2], exact[:2], rtol=2e-3)
    np.testing.assert_allclose(f[2:], exact[2:], rtol=1e-2)
    assert np.all(f < exact)
    if name == "pbarl_box":
        # plane 1 (I1, the smaller: DIM2 is the height along element y) holds the orientation vector (0, .6, .8):
        # the first mode's tip moves along it
        tip = np.array([modes.shape(21, c)[0] for c in (1, 2, 3)])
        np.testing.assert_allclose(np.abs(tip) / np.linalg.norm(tip), [0.0, 0.6, 0.8], atol=1e-9)
