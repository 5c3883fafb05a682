"""The two-mass spring-damper system of thesis Figures 4.3 and A.1: wall -k1,c1- m1 -k2,c2- m2.

Section 4.3 (model updating sample problem) drives mass 1 with a force and measures mass 1
(collocated: Table 4.2's zero is sqrt(k2/m2)); Appendix A.1 (LQG sensitivity) measures mass 2.
SI units throughout: kg, N/m, N s/m, rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import control as ct
import numpy as np
import scipy.linalg as sla

Mass = Literal[1, 2]


@dataclass(frozen=True)
class TwoMassSystem:
    """Physical parameters; defaults are the thesis's 'actual' system (k1 = 0.75, k2 = 1.20)."""

    k1: float = 0.75  #: wall to mass 1 [N/m]
    k2: float = 1.20  #: mass 1 to mass 2 [N/m]
    m1: float = 1.0  #: [kg]
    m2: float = 1.0  #: [kg]
    c1: float = 0.01  #: wall to mass 1 [N s/m]
    c2: float = 0.01  #: mass 1 to mass 2 [N s/m]

    @property
    def mass_matrix(self) -> np.ndarray:
        """M [kg]."""
        return np.diag([self.m1, self.m2])

    @property
    def stiffness_matrix(self) -> np.ndarray:
        """K [N/m]."""
        return np.array([[self.k1 + self.k2, -self.k2], [-self.k2, self.k2]])

    @property
    def damping_matrix(self) -> np.ndarray:
        """C [N s/m] of the physical dampers (not proportional to K when k1 != k2)."""
        return np.array([[self.c1 + self.c2, -self.c2], [-self.c2, self.c2]])

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Undamped natural frequencies [rad/s] and mass-normalised mode shapes (columns)."""
        w2, phi = sla.eigh(self.stiffness_matrix, self.mass_matrix)
        phi = phi * np.sign(phi[0])  # mass 1 moves positively in every mode
        return np.sqrt(w2), phi

    def state_space(self, *, force_on: Mass = 1, measured: Mass = 1) -> ct.StateSpace:
        """x = [q1, q2, q1', q2']; input force [N] on ``force_on``, output displacement [m] of ``measured``."""
        m_inv = np.linalg.inv(self.mass_matrix)
        a = np.block([[np.zeros((2, 2)), np.eye(2)], [-m_inv @ self.stiffness_matrix, -m_inv @ self.damping_matrix]])
        b = np.zeros((4, 1))
        b[1 + force_on, 0] = 1.0 / (self.m1, self.m2)[force_on - 1]
        c = np.zeros((1, 4))
        c[0, measured - 1] = 1.0
        return ct.ss(a, b, c, np.zeros((1, 1)), inputs=[f"force_{force_on}"], outputs=[f"displacement_{measured}"],
                     states=["q1", "q2", "q1_dot", "q2_dot"], name="two_mass")
