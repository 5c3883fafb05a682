"""Ritz reanalysis on retained modes (thesis eq. 4.6-4.9), numpy and scipy only.

K_r = Omega0^2 + sum_i dp_i Phi0^T dK_i Phi0 with dp_i the relative change of parameter i and
dK_i its stiffness sensitivity per unit relative change; the eigen-solution of the reduced
problem gives the new omega^2 and Phi_R, and Phi = Phi0 Phi_R. Mass-normalised nominal modes make
the reduced mass matrix the identity (the parameters here are stiffnesses only).

Shared by the updating engine and copied verbatim into FMUs, which re-analyse their physical
parameters at initialisation.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment


def ritz_reanalysis(omega2_0: np.ndarray, projected_dk: np.ndarray,
                    relative_change: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(omega^2 [rad^2/s^2], Phi_R) after relative stiffness-parameter changes.

    ``projected_dk`` is (n_parameters, n_modes, n_modes): Phi0^T dK_i Phi0 per unit relative
    change. Each new mode takes the index of the nominal mode it continues (the one-to-one
    pairing with the largest total squared overlap, a MAC in the mass-normalised basis), so
    per-mode data (damping ratios, labels) follow the physical mode through a crossing.
    """
    rel = np.asarray(relative_change, dtype=float)
    n = len(omega2_0)
    if not np.any(rel != 0.0):
        return np.asarray(omega2_0, dtype=float).copy(), np.eye(n)
    k_r = np.diag(omega2_0) + np.tensordot(rel, projected_dk, axes=1)
    w2, phi_r = np.linalg.eigh(0.5 * (k_r + k_r.T))
    _, order = linear_sum_assignment(-(phi_r**2))
    return w2[order], phi_r[:, order]
