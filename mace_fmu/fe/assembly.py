"""Global linear stiffness, mass and gravity load of a deck, in basic coordinates (SI)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from mace_fmu.deck.cards import Deck
from mace_fmu.deck.geometry import coordinate_frames, grid_positions
from mace_fmu.errors import MaceError
from mace_fmu.fe.corotational import Bars
from mace_fmu.fe.beam import BeamSection, MassKind, local_stiffness, natural_stiffness
from mace_fmu.fe.dofs import DofMap, scalar_element_entries
from mace_fmu.fe.elements import add_elements, bar_mass, coupled_mass, line_elements
from mace_fmu.fe.triplets import MatrixTriplets


@dataclass(frozen=True)
class FEModel:
    """Linear FE matrices of one structure in basic coordinates; DOFs named by DofMap."""

    dofs: DofMap  #: the DOFs (grid, component) of the matrices
    positions: np.ndarray  #: (n_grid, 3) undeformed grid positions [m]
    cd_frames: np.ndarray  #: (n_grid, 3, 3) columns = displacement-system axes in basic
    stiffness: sparse.csr_array  #: linear K [N/m, N, N m/rad], sparse: memory grows with DOFs, not DOFs^2
    mass: sparse.csr_array  #: M [kg, kg m, kg m^2]
    bars: Bars  #: every CBAR as arrays, for the corotational preload
    spring_stiffness: sparse.csr_array  #: the CELAS2 part of ``stiffness``
    spring_ids: tuple[int, ...]  #: CELAS2 IDs
    spring_vectors: sparse.csr_array  #: (n_spring, n_dof) spring elongation per unit DOF
    spring_constants: np.ndarray  #: (n_spring,) [N/m or N m/rad]


def bar_section(deck: Deck, pid: int) -> BeamSection:
    """BeamSection of PBAR ``pid`` with its MAT1 (G from E and NU when blank)."""
    p = deck.pbars[pid]
    mat = deck.mat1s[p.mid]
    return BeamSection(area=p.area, i1=p.i1, i2=p.i2, j=p.j, e=mat.youngs_modulus, g=mat.shear_modulus,
                       rho=mat.rho, nsm=p.nsm, k1=p.k1, k2=p.k2)


def _conm2_matrix(mass: float, offset: np.ndarray, inertia_cg: np.ndarray) -> np.ndarray:
    """6x6 grid mass of a point mass at ``offset`` from the grid with inertia about its c.g."""
    s = np.array([[0.0, -offset[2], offset[1]], [offset[2], 0.0, -offset[0]], [-offset[1], offset[0], 0.0]])
    m = np.zeros((6, 6))
    m[:3, :3] = mass * np.eye(3)
    m[:3, 3:] = -mass * s
    m[3:, :3] = mass * s
    m[3:, 3:] = inertia_cg + mass * s.T @ s
    return m


def _conm2_basic(cm, frames) -> np.ndarray:
    """6x6 mass [kg, kg m, kg m^2] of CONM2 ``cm`` at its grid, in basic axes (before PARAM,WTMASS)."""
    if cm.cid == -1:
        raise MaceError(f"{cm.source}: CONM2 {cm.id}: CID = -1 (absolute c.g.) is not supported")
    rot = frames[cm.cid][1]
    i11, i21, i22, i31, i32, i33 = cm.inertia
    inertia = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
    return _conm2_matrix(cm.mass, rot @ np.array(cm.offset), rot @ inertia @ rot.T)


def conm2_mass(deck: Deck, dofs: DofMap, element: int) -> sparse.csr_array:
    """The mass matrix [kg, kg m, kg m^2] one CONM2 adds to a model's (basic DOFs ``dofs``, PARAM,WTMASS applied).

    Linear in the card's mass when its inertias scale with it (a scaled body): it is then the derivative of
    the model's mass matrix with respect to the relative change of that mass.

    Parameters
    ----------
    deck : Deck
        The deck the model was assembled from.
    dofs : DofMap
        The model's DOFs (:attr:`FEModel.dofs`).
    element : int
        The CONM2 element ID.

    Returns
    -------
    scipy.sparse.csr_array
        (n_dof, n_dof), nonzero on the CONM2's grid only.
    """
    block = _conm2_basic(deck.conm2s[element], coordinate_frames(deck)) * mass_factor(deck)
    idx = dofs.indices(deck.conm2s[element].grid)
    rows, cols = np.meshgrid(idx, idx, indexing="ij")
    return sparse.csr_array((block.ravel(), (rows.ravel(), cols.ravel())), shape=(dofs.size, dofs.size))


def mass_factor(deck: Deck) -> float:
    """PARAM,WTMASS: NASTRAN multiplies every mass term by it (element and CONM2 masses alike), e.g. 1/386.1
    for a deck in weight units (lbf, in); 1 without the parameter."""
    param = deck.params.get("WTMASS")
    return 1.0 if param is None else float(param.values[0])  # the reader checked it is a positive number


def _rotation_invariant(matrix: np.ndarray) -> bool:
    """Whether an element matrix (12 x 12) is diagonal with each 3 x 3 block a multiple of the identity:
    then T^T M T = M for every element frame T."""
    diagonal = np.diag(matrix)
    return (np.count_nonzero(matrix - np.diag(diagonal)) == 0
            and bool(np.all(diagonal.reshape(4, 3) == diagonal.reshape(4, 3)[:, :1])))


def assemble(deck: Deck, *, mass: MassKind = "lumped") -> FEModel:
    """Assemble K and M of every element of ``deck`` (no constraints applied), as sparse matrices.

    ``mass``: "lumped" (NASTRAN's default) or "consistent"; a deck's PARAM,COUPMASS > 0 asks for the coupled
    (consistent) mass, as in NASTRAN.

    Parameters
    ----------
    deck : Deck
        The deck (structure already chosen: :func:`~mace_fmu.structure.build.build_structure`).
    mass : {"lumped", "consistent"}
        The mass formulation.

    Returns
    -------
    FEModel
        Sparse stiffness [N/m, N m/rad] and mass [kg, kg m^2] on the basic DOFs, the DOF map, the bars and
        the springs.
    """
    mass = coupled_mass(deck, mass)
    frames = coordinate_frames(deck)
    pos = grid_positions(deck)
    dofs = DofMap(tuple(sorted(deck.grids)))
    n = dofs.size
    positions = np.array([pos[g] for g in dofs.grid_ids])
    cd_frames = np.array([frames[deck.grids[g].cd][1] for g in dofs.grid_ids])
    k_glob, m_glob = MatrixTriplets(n), MatrixTriplets(n)

    bar_cards = sorted(deck.bars.values(), key=lambda b: b.id)
    lines = line_elements(deck, bar_cards, dofs, pos, frames)
    pairs = [(bar_section(deck, pid), length) for pid, length in lines.distinct]
    k_one = [local_stiffness(sec, length) for sec, length in pairs]
    m_one = [bar_mass(sec, length, mass, deck) for sec, length in pairs]
    kn_one = [natural_stiffness(sec, length) for sec, length in pairs]
    if lines.count:
        k_glob.add_many(lines.dof_indices, lines.to_basic(k_one))
        if all(_rotation_invariant(m_e) for m_e in m_one):
            # NASTRAN's lumped bar mass: m I on each end's translations, the same in every frame, so
            # only its diagonal is added (a 100k-DOF tower's mass blocks would be 80 MB of zeros)
            m_glob.add_diagonal(lines.dof_indices, np.array([np.diag(m_e) for m_e in m_one])[lines.pair])
        else:
            m_glob.add_many(lines.dof_indices, lines.to_basic(m_one))
    kn = np.array(kn_one)[lines.pair] if lines.count else np.zeros((0, 7, 7))

    for cm in deck.conm2s.values():
        m_glob.add(dofs.indices(cm.grid), _conm2_basic(cm, frames))

    springs = sorted(deck.celas2s.values(), key=lambda sp: sp.id)
    rows, cols, values = [np.zeros(0, int)], [np.zeros(0, int)], [np.zeros(0)]
    for row, sp in enumerate(springs):
        idx, coefficients = scalar_element_entries(dofs, cd_frames, sp.g1, sp.c1, sp.g2, sp.c2)
        rows.append(np.full(len(idx), row))
        cols.append(idx)
        values.append(coefficients)
    vectors = sparse.coo_array((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
                               shape=(len(springs), n)).tocsr()
    constants = np.array([sp.k for sp in springs], dtype=float)
    k_spring = sparse.csr_array(vectors.T @ sparse.diags_array(constants) @ vectors) if springs else \
        sparse.csr_array((n, n))
    add_elements(deck, dofs, pos, frames, cd_frames, k_glob, m_glob, mass)  # CBEAM, CROD, CMASS (fe/elements.py)
    stiffness = sparse.csr_array(k_glob.matrix() + k_spring)
    mass_matrix = sparse.csr_array(m_glob.matrix() * mass_factor(deck))

    bars = Bars(ids=np.array([b.id for b in bar_cards], dtype=np.int64), node_a=lines.node_a, node_b=lines.node_b,
                frames0=lines.frames.reshape(-1, 3, 3), lengths0=lines.lengths,
                k_natural=np.array(kn).reshape(-1, 7, 7))
    return FEModel(dofs=dofs, positions=positions, cd_frames=cd_frames, stiffness=stiffness, mass=mass_matrix,
                   bars=bars, spring_stiffness=k_spring, spring_ids=tuple(sp.id for sp in springs),
                   spring_vectors=vectors, spring_constants=constants)
