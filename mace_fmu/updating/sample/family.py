"""The two-mass system of thesis Figure 4.3 as a parametrised modal model: force on mass 1, its displacement.

Parameters: ``k_1``, ``k_2`` [N/m] and the modal damping ratios ``damping:mode 1``, ``damping:mode 2``.
The model is the modal state-space of eq. 3.6 (modal damping), as an FE-based model would be; the
"actual" system it is fitted to has physical dampers (:class:`mace_fmu.updating.sample.two_mass.TwoMassSystem`).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from mace_fmu.iomodel.reanalysis import ritz_reanalysis
from mace_fmu.updating.engine.linear_model import LinearModel
from mace_fmu.updating.sample.two_mass import TwoMassSystem

Values = Mapping[str, float]
MODE_LABELS = ("mode 1", "mode 2")
PHYSICAL = ("k_1", "k_2")


def _system(values: Values, masses: TwoMassSystem) -> TwoMassSystem:
    return TwoMassSystem(k1=values["k_1"], k2=values["k_2"], m1=masses.m1, m2=masses.m2)


def modal_model(omega2: np.ndarray, phi: np.ndarray, zeta: np.ndarray) -> LinearModel:
    """eq. 3.6 for force on mass 1 [N] to displacement of mass 1 [m]; ``phi`` mass-normalised (2, n)."""
    n = len(omega2)
    omega = np.sqrt(np.abs(omega2))
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -np.diag(omega2)
    a[n:, n:] = -np.diag(2.0 * zeta * omega)
    b = np.concatenate([np.zeros(n), phi[0]])[:, None]
    c = np.concatenate([phi[0], np.zeros(n)])[None, :]
    states = tuple(f"structure.mode{k + 1}_disp" for k in range(n)) + tuple(f"structure.mode{k + 1}_vel"
                                                                          for k in range(n))
    return LinearModel(a=a, b=b, c=c, d=np.zeros((1, 1)), inputs=("force_1",), outputs=("displacement_1",),
                       state_names=states, mode_labels=MODE_LABELS[:n])


def _zeta(values: Values) -> np.ndarray:
    return np.array([values[f"damping:{label}"] for label in MODE_LABELS])


class TwoMassFamily:
    """The model family of the sample problem (masses known, springs and damping ratios updated)."""

    physical = PHYSICAL

    def __init__(self, masses: TwoMassSystem = TwoMassSystem()):
        self.masses = masses

    def modes(self, values: Values) -> tuple[np.ndarray, np.ndarray]:
        """(omega^2 [rad^2/s^2], mass-normalised shapes) at ``values``."""
        omega, phi = _system(values, self.masses).modes()
        return omega**2, phi

    def full(self, values: Values) -> LinearModel:
        """An eigen-solution at ``values``, then the modal model."""
        omega2, phi = self.modes(values)
        return modal_model(omega2, phi, _zeta(values))

    def basis(self, values: Values) -> TwoMassBasis:
        return TwoMassBasis(self, values)


class TwoMassBasis:
    """Modes of one base point; stiffness sensitivities per unit relative change of k_1 and k_2."""

    physical = PHYSICAL

    def __init__(self, family: TwoMassFamily, values: Values):
        self.family = family
        self.base = {n: values[n] for n in PHYSICAL}
        self.omega2, self.phi0 = family.modes(values)
        k1, k2 = self.base["k_1"], self.base["k_2"]
        dk = [k1 * np.array([[1.0, 0.0], [0.0, 0.0]]), k2 * np.array([[1.0, -1.0], [-1.0, 1.0]])]
        self.projected_dk = np.array([self.phi0.T @ d @ self.phi0 for d in dk])

    def model(self, values: Values, *, frequencies_hz: np.ndarray | None = None,
              phi_r: np.ndarray | None = None) -> LinearModel:
        if frequencies_hz is None:
            rel = np.array([values[n] / self.base[n] - 1.0 for n in PHYSICAL])
            omega2, phi_r = ritz_reanalysis(self.omega2, self.projected_dk, rel)
        else:
            omega2 = np.sign(frequencies_hz) * (2.0 * np.pi * frequencies_hz) ** 2
        return modal_model(omega2, self.phi0 @ phi_r, _zeta(values))

    def modes_of(self, values: Values) -> tuple[np.ndarray, np.ndarray]:
        omega2, phi = self.family.modes(values)
        return np.sqrt(omega2) / (2.0 * np.pi), self.phi0.T @ self.family.masses.mass_matrix @ phi
