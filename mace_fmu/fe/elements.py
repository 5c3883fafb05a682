"""Stiffness and mass of CBEAM, CROD/CONROD, CONM1 and CMASS1/CMASS2, with NASTRAN's mass conventions.

Each element adds its matrices in basic coordinates to the global K and M that
:func:`mace_fmu.fe.assembly.assemble` builds for CBAR, CONM2 and CELAS2 (it calls
:func:`add_elements`). Units are the deck's (SI for the MACE deck); PARAM,WTMASS is applied by the
caller to the whole mass matrix.

Mass conventions (PARAM,COUPMASS: lumped by default, coupled when > 0; MSC Nastran Quick Reference
Guide, PARAM COUPMASS and the CBEAM/CROD remarks):

* CBEAM lumped: half of (rho A + NSM) L on the three translations of each end, and half of the beam's
  torsional mass moment rho (I1 + I2) L on each end's rotation about the beam axis. NASTRAN includes
  this torsional term in CBEAM's lumped mass (unlike CBAR's): the grid point weight generator of the
  beam_modes run (tests/data/nastran/beam_modes) has Ixx = 3.765757e-3 = the CONM2's 2.59e-3 plus
  rho (I1 + I2) L = 7.4851e-4 * 1.5708 * 1.0 of its one CBEAM, and nothing from its nine CBARs. That
  section is a ROD, whose J equals I1 + I2; MSC's fmondsp run (pyNastran models/aero, BOX beams, not in
  the tests because two of its beams are tapered) tells them apart: with rho J L its torsion modes come
  out 1 % off NASTRAN's, with rho (I1 + I2) L within 0.1 % (the rest being the tapered beams).
* CBEAM coupled (PARAM,COUPMASS > 0): the consistent (Hermitian) bending mass, with the axial and the
  torsional mass lumped as above. The QRG lists CBEAM among the elements COUPMASS applies to without
  saying which terms are coupled; NASTRAN's own run of pyNastran's nlfltr/buckled deck (MSC/NASTRAN
  4/28/98, 71 CBEAMs, tests/data/nastran/nlfltr_buckled) decides it: all 14 elastic modes within 3.4e-7
  this way, against 1.0e-3 with the axial mass consistent, 16 % with the torsional mass consistent and
  42 % without it (tests/fe/test_nastran_decks.py).
* CBAR coupled: the consistent bending mass, the axial mass (rho A + NSM) L / 420 [[175, 35], [35, 175]]
  and no torsional inertia, as COSMIC NASTRAN's BAR element writes it (subroutine BARD, nasa/NASTRAN-95
  mis/bard.f, "CALCULATE THE CONSISTENT/CONVENTIONAL MASS MATRIX"). MSC's pt145 run confirms the missing
  torsional inertia (see :func:`bar_mass`); no published run with results tells the axial terms apart.
  A consistent mass asked for by the caller rather than by the deck is mace-fmu's own: linear axial and
  torsional mass (mace_fmu.fe.beam.local_mass "consistent") for CBAR and CBEAM alike.
* CROD lumped: half the rod's mass on the three translations of each end; coupled: m/6 [[2, 1], [1, 2]]
  on each translation.
* CMASS1/CMASS2: a scalar mass m between DOFs u1 and u2 adds m (u1 - u2)^2 / 2 to the kinetic energy
  (QRG CMASS2: "scalar mass between two degrees-of-freedom"), like a CELAS spring does to the strain
  energy; with G2 blank it is grounded, m u1^2 / 2.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from mace_fmu.deck.cards import CBar, CBeam, Deck
from mace_fmu.deck.geometry import bar_orientations
from mace_fmu.errors import MaceError
from mace_fmu.fe.beam import (BeamSection, MassKind, local_frame, local_frames, local_mass, local_stiffness, to_basic,
                              to_basic_many)
from mace_fmu.fe.dofs import DofMap, scalar_element_entries
from mace_fmu.fe.triplets import MatrixTriplets


def coupled_mass(deck: Deck, mass: MassKind) -> MassKind:
    """The mass formulation NASTRAN would use: coupled ("consistent") when PARAM,COUPMASS > 0, else ``mass``."""
    param = deck.params.get("COUPMASS")
    if param is not None and isinstance(param.values[0], (int, float)) and param.values[0] > 0:
        return "consistent"
    return mass


def bar_mass(sec: BeamSection, length: float, kind: MassKind, deck: Deck) -> np.ndarray:
    """12x12 CBAR mass in element axes [kg, kg m^2].

    NASTRAN's coupled CBAR mass (PARAM,COUPMASS > 0) has no torsional inertia: MSC's pt145 run
    (tests/data/nastran/pt145, COUPMASS 1) gives its torsion modes 236.4137 and 703.4198 Hz only without
    it (with rho (I1 + I2) L / 6 [[2, 1], [1, 2]] on the axis rotation they come out 0.026 % low). So for a
    deck that asks for the coupled mass the torsion term of mace-fmu's consistent matrix is removed, and the
    axial terms are COSMIC NASTRAN's (BARD: (rho A + NSM) L / 420 [[175, 35], [35, 175]], the mean of the
    lumped and the consistent rod); a consistent mass asked for by the caller (``mass="consistent"``) keeps
    mace-fmu's own matrix.
    """
    m = local_mass(sec, length, kind)
    if kind == "consistent" and coupled_mass(deck, "lumped") == "consistent":
        m[np.ix_([3, 9], [3, 9])] = 0.0
        m[np.ix_([0, 6], [0, 6])] = sec.mass_per_length * length / 420.0 * np.array([[175.0, 35.0], [35.0, 175.0]])
    return m


def beam_section(deck: Deck, pid: int) -> BeamSection:
    """BeamSection of PBEAM/PBEAML ``pid`` with its MAT1 (PBEAM's K = 0.0 means rigid in shear)."""
    p = deck.pbeams[pid]
    mat = deck.mat1s[p.mid]
    if p.i12 != 0.0:
        raise MaceError(f"{p.source}: PBEAM {p.id}: I12 = {p.i12:g} is not supported by mace-fmu (expected 0.0: "
                        "principal axes)")
    return BeamSection(area=p.area, i1=p.i1, i2=p.i2, j=p.j, e=mat.youngs_modulus, g=mat.shear_modulus, rho=mat.rho,
                       nsm=p.nsm, k1=p.k1 or None, k2=p.k2 or None)


def beam_mass(sec: BeamSection, length: float, kind: MassKind, deck: Deck) -> np.ndarray:
    """12x12 CBEAM mass in element axes [kg, kg m^2].

    Lumped: CBAR's plus the torsional inertia rho (I1 + I2) L / 2 on each end's axis rotation. Coupled, as a
    deck's PARAM,COUPMASS > 0 asks: the consistent bending mass with that lumped axial and torsional mass
    (NASTRAN's rule; see the module docstring for the run that decides it). A consistent mass asked for by
    the caller keeps mace-fmu's own consistent matrix.
    """
    lumped = local_mass(sec, length, "lumped")
    lumped[3, 3] = lumped[9, 9] = sec.rho * (sec.i1 + sec.i2) * length / 2.0
    if kind == "lumped":
        return lumped
    m = local_mass(sec, length, kind)
    if coupled_mass(deck, "lumped") == "consistent":  # the deck's coupled mass: axial and torsion lumped
        m[np.ix_([0, 3, 6, 9], [0, 3, 6, 9])] = lumped[np.ix_([0, 3, 6, 9], [0, 3, 6, 9])]
    return m


def _rod_matrices(e: float, g: float, area: float, j: float, mass_per_length: float, length: float,
                  kind: MassKind) -> tuple[np.ndarray, np.ndarray]:
    """12x12 stiffness (axial E A / L, torsion G J / L) and mass of a rod in element axes."""
    k = np.zeros((12, 12))
    unit = np.array([[1.0, -1.0], [-1.0, 1.0]])
    k[np.ix_([0, 6], [0, 6])] = e * area / length * unit
    k[np.ix_([3, 9], [3, 9])] = g * j / length * unit
    m = np.zeros((12, 12))
    total = mass_per_length * length
    pair = total / 2.0 * np.eye(2) if kind == "lumped" else total / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    for t in range(3):
        m[np.ix_([t, t + 6], [t, t + 6])] = pair
    return k, m


@dataclass(frozen=True)
class LineElements:
    """CBARs or CBEAMs, all at once: their ends, lengths and element frames, and the distinct (property,
    length) pairs whose element matrices they share (in element axes those depend on the section and the
    length only, and a lattice has a handful of pairs for tens of thousands of elements)."""

    node_a: np.ndarray  #: (n,) row of end A's grid in per-grid arrays
    node_b: np.ndarray  #: (n,) row of end B's grid
    lengths: np.ndarray  #: (n,) [m]
    frames: np.ndarray  #: (n, 3, 3) element axes, rows x, y, z in basic
    distinct: tuple[tuple[int, float], ...]  #: the distinct (property ID, length [m]) pairs
    pair: np.ndarray  #: (n,) each element's index into ``distinct``

    @property
    def count(self) -> int:
        """Number of elements."""
        return len(self.lengths)

    @functools.cached_property  # read for the stiffness and for the mass
    def dof_indices(self) -> np.ndarray:
        """(n, 12) global DOF indices: the six of end A, then the six of end B."""
        six = np.arange(6)
        return np.concatenate([6 * self.node_a[:, None] + six, 6 * self.node_b[:, None] + six], axis=1)

    def to_basic(self, per_pair: Sequence[np.ndarray]) -> np.ndarray:
        """(n, 12, 12) each element's matrix in basic, from one matrix in element axes per distinct pair."""
        return to_basic_many(np.array(per_pair)[self.pair], self.frames)


def line_elements(deck: Deck, cards: Sequence[CBar | CBeam], dofs: DofMap, positions: dict[int, np.ndarray],
                  frames: dict) -> LineElements:
    """The ends, lengths, element frames and distinct (property, length) pairs of ``cards`` (CBAR or CBEAM).

    Parameters
    ----------
    deck : Deck
        The deck the cards belong to (their orientation's coordinate systems).
    cards : sequence of CBar or CBeam
        The elements, in the order wanted.
    dofs : DofMap
        The model's DOFs.
    positions : dict
        Grid ID -> position in basic [m].
    frames : dict
        The deck's coordinate frames.

    Returns
    -------
    LineElements
        The elements' geometry, all at once.
    """
    node_a = dofs.grid_indices([c.ga for c in cards])
    node_b = dofs.grid_indices([c.gb for c in cards])
    # one lookup per grid, not two per element (the wide lattice's 78,304 bars: 0.07 s -> 0.01 s)
    grid_xyz = np.array([positions[g] for g in dofs.grid_ids], dtype=float).reshape(-1, 3)
    axes = grid_xyz[node_b] - grid_xyz[node_a]
    lengths = np.linalg.norm(axes, axis=1)
    element_frames = local_frames(axes, bar_orientations(deck, cards, positions, frames)) if len(cards) \
        else np.zeros((0, 3, 3))
    distinct: dict[tuple[int, float], int] = {}
    pair = np.array([distinct.setdefault((c.pid, length), len(distinct)) for c, length in zip(cards, lengths.tolist())],
                    dtype=np.int64)
    return LineElements(node_a, node_b, lengths, element_frames, tuple(distinct), pair)


def add_elements(deck: Deck, dofs: DofMap, positions: dict[int, np.ndarray], frames: dict, cd_frames: np.ndarray,
                 stiffness: MatrixTriplets, mass: MatrixTriplets, kind: MassKind) -> None:
    """Add the CBEAM, CROD/CONROD, CONM1 and CMASS1/CMASS2 matrices of ``deck`` to ``stiffness`` and ``mass`` in place.

    ``positions``: grid ID -> position in basic [m]; ``frames``: coordinate frames of the deck;
    ``cd_frames``: (n_grid, 3, 3) displacement-system axes; ``kind``: "lumped" or "consistent" mass.
    """
    beams = line_elements(deck, sorted(deck.beams.values(), key=lambda b: b.id), dofs, positions, frames)
    if beams.count:
        pairs = [(beam_section(deck, pid), length) for pid, length in beams.distinct]
        stiffness.add_many(beams.dof_indices, beams.to_basic([local_stiffness(sec, length) for sec, length in pairs]))
        mass.add_many(beams.dof_indices, beams.to_basic([beam_mass(sec, length, kind, deck) for sec, length in pairs]))

    for rod in sorted(deck.rods.values(), key=lambda r: r.id):
        if rod.pid is not None:
            prop = deck.prods[rod.pid]
            mid, area, j, nsm = prop.mid, prop.area, prop.j, prop.nsm
        else:
            assert rod.mid is not None  # a CONROD (deck.checks: a CROD has its PID)
            mid, area, j, nsm = rod.mid, rod.area, rod.j, rod.nsm
        mat = deck.mat1s[mid]
        axis = positions[rod.gb] - positions[rod.ga]
        length = float(np.linalg.norm(axis))
        if length < 1e-9:
            raise MaceError(f"{rod.source}: {rod.card} {rod.id}: zero length (grids {rod.ga} and {rod.gb} coincide)")
        # any vector off the axis: a rod's matrices do not depend on the lateral axes
        trial = np.eye(3)[int(np.argmin(np.abs(axis)))]
        frame = local_frame(axis, trial)
        k, m = _rod_matrices(mat.youngs_modulus, mat.shear_modulus, area, j, mat.rho * area + nsm, length, kind)
        idx = np.concatenate([dofs.indices(rod.ga), dofs.indices(rod.gb)])
        stiffness.add(idx, to_basic(k, frame))
        mass.add(idx, to_basic(m, frame))

    for cm in sorted(deck.conm1s.values(), key=lambda c: c.id):  # CONM1: the 6x6 matrix rotated from CID to basic
        matrix = np.zeros((6, 6))
        matrix[np.tril_indices(6)] = cm.matrix
        matrix = matrix + np.tril(matrix, -1).T
        rot = np.kron(np.eye(2), frames[cm.cid][1])
        idx = dofs.indices(cm.grid)
        mass.add(idx, rot @ matrix @ rot.T)

    for sm in sorted(deck.scalar_masses.values(), key=lambda s: s.id):
        value = sm.mass if sm.mass is not None else deck.pmasses[sm.pid].mass  # type: ignore[index]
        idx, vec = scalar_element_entries(dofs, cd_frames, sm.g1, sm.c1, sm.g2, sm.c2)
        mass.add(idx, value * np.outer(vec, vec))  # repeated DOFs (g1 = g2) add up in the sparse sum
