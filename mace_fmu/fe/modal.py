"""Eigen-solution of a constrained (K, M) pair with massless DOFs condensed out exactly.

NASTRAN's lumped CBAR mass has no rotary inertia and several grids carry no mass at all, so M
is singular. Those DOFs are removed by static condensation, which is exact for massless DOFs
(their inertia forces are zero, so their motion is the static response to the others). The
remaining M is positive definite, so one dense generalised eigen-solution handles rigid-body and
mechanism modes without a shift: they come out as the cluster of (near) zero eigenvalues.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from mace_fmu.errors import MaceError
from mace_fmu.fe.constraints import Constraints
from mace_fmu.fe.dofs import DofMap

MASSLESS_RELATIVE_TOLERANCE = 1e-12


@dataclass(frozen=True)
class Modes:
    """Natural frequencies [Hz] and mass-normalised shapes over all DOFs in basic coordinates."""

    frequencies_hz: np.ndarray  #: signed: a negative eigenvalue gives a negative frequency
    shapes: np.ndarray  #: (n_dof, n_modes), phi^T M phi = I; translations [m], rotations [rad]
    dofs: DofMap
    cd_frames: np.ndarray  #: (n_grid, 3, 3) displacement-system axes, for CD components
    labels: tuple[str, ...] = field(default=())

    def __len__(self) -> int:
        return len(self.frequencies_hz)

    def shape(self, grid: int, component: int, *, system: str = "basic") -> np.ndarray:
        """Component 1-6 of ``grid`` in every mode, in the basic or the grid's CD system."""
        if not 1 <= component <= 6:
            raise ValueError(f"component must be 1-6 (T1 T2 T3 R1 R2 R3), got {component}")
        if system == "basic":
            return self.shapes[self.dofs.index(grid, component)]
        if system != "cd":
            raise ValueError(f"system must be 'basic' or 'cd', got {system!r}")
        idx = self.dofs.indices(grid)
        block = idx[:3] if component <= 3 else idx[3:]
        axes = self.cd_frames[self.dofs.grid_index(grid)]
        return axes[:, (component - 1) % 3] @ self.shapes[block]

    def grid_motion(self, grid: int) -> np.ndarray:
        """(6, n_modes) translations and rotations of ``grid`` in basic."""
        return self.shapes[self.dofs.indices(grid)]


def solve_modes(stiffness: np.ndarray, mass: np.ndarray, constraints: Constraints, dofs: DofMap,
                cd_frames: np.ndarray, *, max_hz: float | None = None) -> Modes:
    """All modes with frequency <= ``max_hz`` (all when None) of the constrained system."""
    t = constraints.transform
    k = constraints.reduce(stiffness)
    m = constraints.reduce(mass)
    k = 0.5 * (k + k.T)
    m = 0.5 * (m + m.T)
    diag = np.diag(m)
    massless = diag <= MASSLESS_RELATIVE_TOLERANCE * diag.max()
    a, o = np.flatnonzero(~massless), np.flatnonzero(massless)
    k_oo = k[np.ix_(o, o)]
    if len(o) == 0:
        k_oo = np.eye(0)
    try:
        lu = sla.lu_factor(k_oo, check_finite=True)
        if len(o) and np.min(np.abs(np.diag(lu[0]))) <= 1e-12 * np.max(np.abs(np.diag(k_oo))):
            raise np.linalg.LinAlgError
    except (np.linalg.LinAlgError, ValueError):
        raise MaceError(_unrestrained_message(k_oo, o, constraints)) from None
    coupling = sla.lu_solve(lu, k[np.ix_(o, a)])  # K_oo^-1 K_oa
    k_cond = k[np.ix_(a, a)] - k[np.ix_(a, o)] @ coupling
    k_cond = 0.5 * (k_cond + k_cond.T)
    eigval, vec = sla.eigh(k_cond, m[np.ix_(a, a)])
    freq = np.sign(eigval) * np.sqrt(np.abs(eigval)) / (2.0 * np.pi)
    keep = np.ones_like(freq, dtype=bool) if max_hz is None else freq <= max_hz
    vec = vec[:, keep]
    phi = np.zeros((len(diag), vec.shape[1]))
    phi[a] = vec
    phi[o] = -coupling @ vec
    return Modes(frequencies_hz=freq[keep], shapes=t @ phi, dofs=dofs, cd_frames=cd_frames)


def _unrestrained_message(k_oo: np.ndarray, o: np.ndarray, constraints: Constraints) -> str:
    """Name the massless DOFs whose stiffness is singular (neither mass nor restraint)."""
    w, v = np.linalg.eigh(0.5 * (k_oo + k_oo.T))
    scale = max(np.abs(w).max(), 1.0)
    null = v[:, np.abs(w) <= 1e-10 * scale]
    involved = np.flatnonzero(np.abs(null).max(axis=1) > 1e-3) if null.size else np.arange(0)
    names = ", ".join(f"{g}-{c}" for g, c in (constraints.independent[o[i]] for i in involved[:12]))
    return ("the stiffness of the massless DOFs is singular: these DOFs have neither mass nor "
            f"stiffness ({names}); connect them, give them mass, or constrain them with an SPC")
