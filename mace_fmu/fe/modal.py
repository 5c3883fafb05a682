"""Eigen-solution of a constrained (K, M) pair: dense for small models, sparse Lanczos for large ones.

NASTRAN's lumped CBAR mass has no rotary inertia and several grids carry no mass at all, so M
is singular. On the dense route those DOFs are removed by static condensation, which is exact
for massless DOFs (their inertia forces are zero, so their motion is the static response to the
others); the remaining M is positive definite, so one dense generalised eigen-solution handles
rigid-body and mechanism modes without a shift: they come out as the cluster of (near) zero
eigenvalues. Large models take the sparse route (shift-invert Lanczos about a small negative
shift), whose cost follows the nonzeros of the factored K - sigma M (DOFs times the band the
structure leaves after reordering) where the dense one grows with the cube of the DOFs.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.linalg as sla
from scipy import sparse

from mace_fmu.errors import MaceError
from mace_fmu.fe.constraints import Constraints
from mace_fmu.fe.dofs import DofMap
from mace_fmu.sparse import factorize, lowest_modes

MASSLESS_RELATIVE_TOLERANCE = 1e-12
#: Largest number of independent DOFs solved densely (every mode at once); above it the sparse route.
#: Measured (benchmarks/RESULTS.md, "FE core at scale"): the MACE deck (474 DOFs, 35 modes) takes the same
#: time either way; a 1,026-DOF tower's 50 modes 0.17 s dense, 0.09 s sparse; 2,976 DOFs 1.87 s / 0.31 s.
DENSE_MAX_DOF = 1000
#: Lanczos stops when each Ritz pair's residual is below this fraction of its Ritz value. The error of a
#: symmetric eigenvalue goes with the square of the residual, a shape's with the residual over the gap to the
#: next eigenvalue. Measured against the same Lanczos run to 1e-10 (benchmarks/RESULTS.md, "Seventh pass"):
#: the 100k-DOF wide lattice's 50 eigenvalues within 2.8e-13 at 1e-6 (4e-15 at 1e-8), its shapes' cosines
#: within 2e-14 of 1 (9e-15), its close pairs (10.0232 and 10.0237 Hz) included; the tower's within 3.6e-14
#: and 1.2e-14, as at 1e-8. NASTRAN prints 7 digits. Each decade of tolerance costs the wide lattice one
#: block of solves: 1e-8 took 18, 1e-6 takes 16.
LANCZOS_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Modes:
    """Natural frequencies [Hz] and mass-normalised shapes over all DOFs in basic coordinates."""

    frequencies_hz: np.ndarray  #: signed: a negative eigenvalue gives a negative frequency
    shapes: np.ndarray  #: (n_dof, n_modes), phi^T M phi = I; translations [m], rotations [rad]
    dofs: DofMap  #: the DOFs (grid, component) of the shapes' rows
    cd_frames: np.ndarray  #: (n_grid, 3, 3) displacement-system axes, for CD components
    labels: tuple[str, ...] = field(default=())  #: one label per mode (empty before labelling)

    def __len__(self) -> int:
        return len(self.frequencies_hz)

    def shape(self, grid: int, component: int, *, system: str = "basic") -> np.ndarray:
        """Component 1-6 of ``grid`` in every mode, in the basic or the grid's CD system."""
        if not 1 <= component <= 6:
            raise MaceError(f"component must be 1-6 (T1 T2 T3 R1 R2 R3), got {component}")
        if system == "basic":
            return self.shapes[self.dofs.index(grid, component)]
        if system != "cd":
            raise MaceError(f"system must be 'basic' or 'cd', got {system!r}")
        idx = self.dofs.indices(grid)
        block = idx[:3] if component <= 3 else idx[3:]
        axes = self.cd_frames[self.dofs.grid_index(grid)]
        return axes[:, (component - 1) % 3] @ self.shapes[block]

    def grid_motion(self, grid: int) -> np.ndarray:
        """(6, n_modes) translations and rotations of ``grid`` in basic."""
        return self.shapes[self.dofs.indices(grid)]


class ModesView:
    """What tables and plots read most, one attribute away (``x.labels``, not ``x.modes.labels``), for a
    structure that holds its :class:`Modes` as ``modes``; shapes stay on :class:`Modes`, which knows their DOFs."""

    modes: Modes

    @property
    def frequencies_hz(self) -> np.ndarray:
        """Natural frequencies [Hz] of the modes (signed: a negative eigenvalue gives a negative one)."""
        return self.modes.frequencies_hz

    @property
    def labels(self) -> tuple[str, ...]:
        """One label per mode: MACE's names ("1st Z bending"), generic ones ("bending Z 1") or NASTRAN's
        mode numbers ("mode 1")."""
        return self.modes.labels

    @property
    def rank_frequencies_hz(self) -> np.ndarray:
        """The frequencies [Hz] per-mode data keyed by rank (a violin family's damping ratios) are ranked by: the
        modes' own, unless they continue other modes (:attr:`mace_fmu.fe.modes.StructureModes.reference_frequencies_hz`)."""
        return self.frequencies_hz


def solve_modes(stiffness: np.ndarray | sparse.sparray, mass: np.ndarray | sparse.sparray, constraints: Constraints,
                dofs: DofMap, cd_frames: np.ndarray, *, max_hz: float | None = None,
                wanted_hz: float | None = None, wanted_count: int | None = None) -> Modes:
    """Modes of the constrained system, those with frequency <= ``max_hz`` [Hz] when given.

    Up to :data:`DENSE_MAX_DOF` independent DOFs: one dense eigen-solution gives every mode (the
    massless DOFs condensed out). Above it, sparse block shift-invert Lanczos finds the lowest
    modes only: at least those up to ``wanted_hz`` [Hz] (or ``max_hz``) and at least the lowest
    ``wanted_count``; the caller picks among them (an EIGRL's V1, V2, ND).

    Parameters
    ----------
    stiffness, mass : numpy.ndarray or scipy.sparse array
        K [N/m, N m/rad] and M [kg, kg m^2] on the basic DOFs.
    constraints : Constraints
        The modal subcase's constraints.
    dofs : DofMap
        The model's DOFs.
    cd_frames : numpy.ndarray
        Displacement frames of the grids.
    max_hz : float, optional
        Keep the modes up to this frequency [Hz].
    wanted_hz : float, optional
        The sparse route finds at least the modes up to this [Hz].
    wanted_count : int, optional
        The sparse route finds at least this many modes.

    Returns
    -------
    Modes
        Frequencies [Hz] and mass-normalised shapes on the basic DOFs.
    """
    k = constraints.reduce_sparse(stiffness)
    m = constraints.reduce_sparse(mass)
    k = sparse.csr_array(0.5 * (k + k.T))
    m = sparse.csr_array(0.5 * (m + m.T))
    massive = int(np.count_nonzero(~_massless(m.diagonal())))
    # Lanczos pays off for a few of many modes; asked for a good part of them, the dense route is faster
    found = None
    if k.shape[0] > DENSE_MAX_DOF and (wanted_count or 0) < massive // 4:
        found = _sparse_modes(k, m, constraints, massive=massive,
                              up_to_hz=wanted_hz if wanted_hz is not None else max_hz, count=wanted_count)
    freq, phi = found if found is not None else _dense_modes(k.toarray(), m.toarray(), constraints)
    keep = np.ones_like(freq, dtype=bool) if max_hz is None else freq <= max_hz
    return Modes(frequencies_hz=freq[keep], shapes=constraints.transform @ phi[:, keep], dofs=dofs,
                 cd_frames=cd_frames)


def _massless(m_diag: np.ndarray) -> np.ndarray:
    return m_diag <= MASSLESS_RELATIVE_TOLERANCE * max(float(m_diag.max()), 1e-300)


def _dense_modes(k: np.ndarray, m: np.ndarray, constraints: Constraints) -> tuple[np.ndarray, np.ndarray]:
    """Every mode (signed frequencies [Hz], shapes over the independent DOFs) by static condensation of
    the massless DOFs and one dense generalised eigen-solution."""
    eigval, phi = _condensed_eigh(k, m, lambda k_oo, o: _unrestrained_message(k_oo, o, constraints))
    return np.sign(eigval) * np.sqrt(np.abs(eigval)) / (2.0 * np.pi), phi


def _condensed_eigh(k: np.ndarray, m: np.ndarray, unrestrained: Callable[[np.ndarray, np.ndarray], str]
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues [rad^2/s^2] and M-normalised vectors of K phi = w^2 M phi, the massless DOFs condensed.

    Massless DOFs (a zero on M's diagonal) are condensed statically. A massless combination of massive
    DOFs (M singular without a zero on its diagonal, e.g. grids whose only mass is an RBE3's or an MPC's
    reference point) is found in M's eigenbasis and condensed there, since the generalised solver needs a
    positive definite M.
    """
    diag = np.diag(m)
    massless = _massless(diag)
    a, o = np.flatnonzero(~massless), np.flatnonzero(massless)
    k_oo = k[np.ix_(o, o)]
    if len(o) == 0:
        k_oo = np.eye(0)
    try:
        with warnings.catch_warnings():  # a singular K_oo is reported below, naming its DOFs
            warnings.simplefilter("ignore", sla.LinAlgWarning)
            lu = sla.lu_factor(k_oo, check_finite=True)
        if len(o) and np.min(np.abs(np.diag(lu[0]))) <= 1e-12 * np.max(np.abs(np.diag(k_oo))):
            raise np.linalg.LinAlgError
    except (np.linalg.LinAlgError, ValueError):
        raise MaceError(unrestrained(k_oo, o)) from None
    coupling = sla.lu_solve(lu, k[np.ix_(o, a)])  # K_oo^-1 K_oa
    k_cond = k[np.ix_(a, a)] - k[np.ix_(a, o)] @ coupling
    k_cond = 0.5 * (k_cond + k_cond.T)
    m_aa = m[np.ix_(a, a)]
    if _positive_definite(m_aa):
        eigval, vec = sla.eigh(k_cond, m_aa)
    else:
        lam, basis = sla.eigh(m_aa)
        lam = np.where(_massless(lam), 0.0, lam)
        eigval, vec = _condensed_eigh(basis.T @ k_cond @ basis, np.diag(lam), lambda *_: (
            "the stiffness of a massless combination of DOFs is singular (it moves without mass or restraint: "
            "check the MPC, RBE2 and RBE3 cards that carry the mass, or constrain it with an SPC)"))
        vec = basis @ vec
    phi = np.zeros((len(diag), vec.shape[1]))
    phi[a] = vec
    phi[o] = -coupling @ vec
    return eigval, phi


def _positive_definite(m: np.ndarray) -> bool:
    """True when M has no massless combination of its DOFs (its Cholesky pivots stay above the tolerance)."""
    if not m.size:
        return True
    try:
        factor = sla.cholesky(m, lower=True)
    except (np.linalg.LinAlgError, sla.LinAlgError):
        return False
    return bool(np.min(np.diag(factor)) ** 2 > MASSLESS_RELATIVE_TOLERANCE * np.max(np.diag(m)))


def _sparse_modes(k: sparse.csr_array, m: sparse.csr_array, constraints: Constraints, *, massive: int,
                  up_to_hz: float | None, count: int | None) -> tuple[np.ndarray, np.ndarray] | None:
    """The lowest modes by block shift-invert Lanczos (mace_fmu.sparse.lanczos) about a small negative shift:
    (K - sigma M)^-1 M maps every eigenvalue above the shift, rigid-body modes included, to a large one
    in order, and the massless DOFs' infinite eigenvalues to zero, so they need no condensation. With
    ``count`` that many are found at least; the Krylov space grows until one lies above ``up_to_hz`` too.
    None when that would take more than half the modes there are (the dense route is then the faster);
    ``massive``: the number of DOFs with mass, which bounds the modes there are."""
    n = k.shape[0]
    if count is None and up_to_hz is None:
        raise MaceError(f"a model of {n} independent DOFs is solved for its lowest modes only: give a frequency "
                        "range (max_hz, --max-hz, or the deck's EIGRL V2) or a number of modes (EIGRL ND)")
    if massive < 4:
        return None
    # the shift: a millionth of a typical K_ii / M_ii [(rad/s)^2] below zero, under every eigenvalue of a
    # stable structure (its rigid-body zeros included) and well clear of the first flexible one
    scale = float(np.median(k.diagonal()[k.diagonal() > 0]) / np.median(m.diagonal()[m.diagonal() > 0]))
    sigma = -1e-6 * scale
    try:
        solve = factorize(k - sigma * m, positive_definite=True,
                          groups=np.array([grid for grid, _ in constraints.independent]))
    except RuntimeError:
        raise MaceError(_unrestrained_message_sparse(k, m, constraints)) from None
    found = lowest_modes(stiffness=k, mass=m, solve=solve, shift=sigma, count=max(count or 0, 1),
                         above=None if up_to_hz is None else (2.0 * np.pi * up_to_hz) ** 2,
                         tolerance=LANCZOS_TOLERANCE, max_dimension=massive // 2)
    if found is None:  # more than half the modes there are: the dense route is the faster
        return None
    eigval = found.eigenvalues
    freq = np.sign(eigval) * np.sqrt(np.abs(eigval)) / (2.0 * np.pi)
    vec = found.vectors  # mass-normalised, as the dense route
    return freq, vec


def _unrestrained_message_sparse(k: sparse.csr_array, m: sparse.csr_array, constraints: Constraints) -> str:
    """Name the DOFs that have neither mass nor stiffness on the diagonal (the sparse route's singular case)."""
    kd, md = k.diagonal(), m.diagonal()
    free = np.flatnonzero((np.abs(kd) <= 1e-12 * np.abs(kd).max()) & _massless(md))
    names = ", ".join(f"{g}-{c}" for g, c in (constraints.independent[i] for i in free[:12]))
    return ("K - sigma M is singular: some DOFs have neither mass nor stiffness"
            + (f" ({names})" if names else "") + "; connect them, give them mass, or constrain them with an SPC")


def _unrestrained_message(k_oo: np.ndarray, o: np.ndarray, constraints: Constraints) -> str:
    """Name the massless DOFs whose stiffness is singular (neither mass nor restraint)."""
    w, v = np.linalg.eigh(0.5 * (k_oo + k_oo.T))
    scale = max(np.abs(w).max(), 1.0)
    null = v[:, np.abs(w) <= 1e-10 * scale]
    involved = np.flatnonzero(np.abs(null).max(axis=1) > 1e-3) if null.size else np.arange(0)
    names = ", ".join(f"{g}-{c}" for g, c in (constraints.independent[o[i]] for i in involved[:12]))
    return ("the stiffness of the massless DOFs is singular: these DOFs have neither mass nor "
            f"stiffness ({names}); connect them, give them mass, or constrain them with an SPC")
