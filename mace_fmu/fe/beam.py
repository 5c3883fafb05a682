"""CBAR as a 3-D two-node beam: local frame, stiffness and mass matrices (SI units).

Local DOF order per node: u, v, w (translations along element x, y, z) then rx, ry, rz.
Plane 1 is the element x-y plane (bending stiffness E*I1, shear factor K1), plane 2 the x-z
plane (E*I2, K2), as in NASTRAN's CBAR. A blank shear factor means no shear flexibility
(Euler-Bernoulli), which is also NASTRAN's rule.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

MassKind = Literal["lumped", "consistent"]


@dataclass(frozen=True)
class BeamSection:
    """Section and material of one bar, all SI."""

    area: float  #: A [m^2]
    i1: float  #: plane-1 bending inertia (about element z) [m^4]
    i2: float  #: plane-2 bending inertia (about element y) [m^4]
    j: float  #: torsion constant [m^4]
    e: float  #: Young's modulus [Pa]
    g: float  #: shear modulus [Pa]
    rho: float  #: density [kg/m^3]
    nsm: float = 0.0  #: non-structural mass [kg/m]
    k1: float | None = None  #: shear area factor, plane 1 (None: rigid in shear)
    k2: float | None = None  #: shear area factor, plane 2

    @property
    def mass_per_length(self) -> float:
        """rho*A + nsm [kg/m]."""
        return self.rho * self.area + self.nsm


def local_frame(axis: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    """Rows are the element x, y, z unit vectors in basic; y lies in the plane of x and v."""
    x = axis / np.linalg.norm(axis)
    y = orientation - orientation.dot(x) * x
    y = y / np.linalg.norm(y)
    return np.array([x, y, np.cross(x, y)])


def local_frames(axes: np.ndarray, orientations: np.ndarray) -> np.ndarray:
    """(n, 3, 3) frames of :func:`local_frame` for n bars at once (axes and orientation vectors (n, 3))."""
    x = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    y = orientations - np.einsum("ni,ni->n", orientations, x)[:, None] * x
    y = y / np.linalg.norm(y, axis=1, keepdims=True)
    return np.stack([x, y, np.cross(x, y)], axis=1)


def _shear_parameter(e_i: float, g: float, k: float | None, area: float, length: float) -> float:
    """Phi = 12 E I / (k G A L^2); zero when the section is rigid in shear."""
    if k is None or k == 0.0 or g == 0.0 or area == 0.0:
        return 0.0
    return 12.0 * e_i / (k * g * area * length**2)


def local_stiffness(sec: BeamSection, length: float) -> np.ndarray:
    """12x12 stiffness in element axes [N/m, N, N m/rad], Timoshenko when K1/K2 are given."""
    L = length
    k = np.zeros((12, 12))
    ea, gj = sec.e * sec.area / L, sec.g * sec.j / L
    k[np.ix_([0, 6], [0, 6])] = ea * np.array([[1, -1], [-1, 1]])
    k[np.ix_([3, 9], [3, 9])] = gj * np.array([[1, -1], [-1, 1]])
    # Plane 1 (v, rz) and plane 2 (w, ry): the sign of the coupling term flips with the
    # right-hand rule (+rz turns x towards +y, +ry turns x towards -z).
    for (t, r, sign), e_i, kk in (((1, 5, 1.0), sec.e * sec.i1, sec.k1), ((2, 4, -1.0), sec.e * sec.i2, sec.k2)):
        phi = _shear_parameter(e_i, sec.g, kk, sec.area, L)
        c = e_i / ((1.0 + phi) * L**3)
        s = sign * 6.0 * L
        block = c * np.array([
            [12.0, s, -12.0, s],
            [s, (4.0 + phi) * L**2, -s, (2.0 - phi) * L**2],
            [-12.0, -s, 12.0, -s],
            [s, (2.0 - phi) * L**2, -s, (4.0 + phi) * L**2],
        ])
        idx = [t, r, t + 6, r + 6]
        k[np.ix_(idx, idx)] = block
    return k


# Natural deformations of a corotational beam: axial stretch of node B, then the three local
# rotations of node A and of node B (node A at the origin, node B on the chord).
NATURAL_DOFS = (6, 3, 4, 5, 9, 10, 11)


def natural_stiffness(sec: BeamSection, length: float) -> np.ndarray:
    """7x7 stiffness on (stretch, rotations A, rotations B); positive definite, no rigid modes."""
    return local_stiffness(sec, length)[np.ix_(NATURAL_DOFS, NATURAL_DOFS)]


def local_mass(sec: BeamSection, length: float, kind: MassKind = "lumped") -> np.ndarray:
    """12x12 mass in element axes [kg, kg m^2]; NASTRAN's default CBAR mass is lumped."""
    m = sec.mass_per_length * length
    if kind == "lumped":
        # Half the bar mass at each end, translations only (NASTRAN COUPMASS default).
        return np.diag(np.tile([m / 2] * 3 + [0.0] * 3, 2))
    L = length
    mm = np.zeros((12, 12))
    mm[np.ix_([0, 6], [0, 6])] = m / 6.0 * np.array([[2, 1], [1, 2]])
    polar = sec.rho * (sec.i1 + sec.i2) * L
    mm[np.ix_([3, 9], [3, 9])] = polar / 6.0 * np.array([[2, 1], [1, 2]])
    for t, r, sign in ((1, 5, 1.0), (2, 4, -1.0)):
        s = sign * L
        block = m / 420.0 * np.array([
            [156.0, 22 * s, 54.0, -13 * s],
            [22 * s, 4 * L * L, 13 * s, -3 * L * L],
            [54.0, 13 * s, 156.0, -22 * s],
            [-13 * s, -3 * L * L, -22 * s, 4 * L * L],
        ])
        idx = [t, r, t + 6, r + 6]
        mm[np.ix_(idx, idx)] = block
    return mm


def to_basic(matrix_local: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Rotate a 12x12 element matrix from element axes (rows of ``frame``) to basic axes."""
    t = np.kron(np.eye(4), frame)
    return t.T @ matrix_local @ t


def to_basic_many(matrices_local: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """:func:`to_basic` for n element matrices (n, 12, 12) with their frames (n, 3, 3) at once."""
    n = len(matrices_local)
    # T = blockdiag(frame x 4): (T^T K T)[a i, b j] = frame[p, i] K[a p, b q] frame[q, j], as two batched
    # 3x3 products (frame^T on each 3-row block, then frame on each 3-column block); numpy's einsum
    # of the same took nine times as long for 70k bars
    rows = np.matmul(frames.transpose(0, 2, 1)[:, None], matrices_local.reshape(n, 4, 3, 12))
    return np.matmul(rows.reshape(n, 12, 4, 3), frames[:, None]).reshape(n, 12, 12)
