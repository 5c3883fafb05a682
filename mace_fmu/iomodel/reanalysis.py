"""Ritz reanalysis on retained modes and static-correction vectors (thesis eq. 4.6-4.9), numpy and scipy only.

The nominal retained modes Phi0 alone cannot follow a stiffness change where the change is local:
a strain gauge or a piezo patch on the changed element reads the rotations of massless grids, whose
motion is the static response to the others, condensed with the nominal stiffness, and the
element's own flexibility lies in modes far above the retained ones. The Ritz basis is therefore
``[Phi0, W]``: W are static-correction vectors, the residual flexibility's response to the forces
each parameter's stiffness change puts on each retained mode (built at export, see
:mod:`mace_fmu.iomodel.stiffness_route`), orthonormal in stiffness, the first ``massive`` of them
orthonormal in mass and the rest massless. In that basis, with p_i the relative change of parameter i,

    K_r = [[Omega0^2 + sum p_i Phi0^T dK_i Phi0,  sum p_i (W^T dK_i Phi0)^T],
           [sum p_i W^T dK_i Phi0,                 W^T K0 W + sum p_i W^T dK_i W]],   M_r = diag(I, I, 0);

the massless part of W is condensed statically (exactly, with the changed stiffness), the rest is an
eigen-solution of the size of the retained modes plus the massive corrections. Each new mode takes the
index of the nominal mode it continues (the one-to-one pairing with the largest total squared overlap,
a MAC in the mass-normalised basis), so per-mode data (damping ratios, labels) follow the physical mode
through a crossing; the other eigenpairs (the corrections' own, far above the retained band) are left
out. Without W (no corrections) this is the reanalysis of eq. 4.6-4.9.

Mass parameters (concentrated masses, :mod:`mace_fmu.iomodel.stiffness_route`) change the mass too:

    M_r = [[I + sum p_i Phi0^T dM_i Phi0,  sum p_i (W^T dM_i Phi0)^T],
           [sum p_i W^T dM_i Phi0,          diag(I, 0) + sum p_i W^T dM_i W]],

condensed with the same static condensation as K_r (the massless corrections' nominal mass stays
neglected, their share of a mass change is kept), and the eigen-problem K_c v = omega^2 M_c v is solved
through the Cholesky factor of M_c, M_c = L L^T: the standard problem L^-1 K_c L^-T y = omega^2 y, v =
L^-T y, mass-normalised in the changed mass. The pairing then scores the overlap M_c v with each
nominal mode.

Shared by the updating engine and copied verbatim into FMUs, which re-analyse their physical
parameters at initialisation.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment


def ritz_reanalysis(omega2_0: np.ndarray, projected_dk: np.ndarray, relative_change: np.ndarray, *,
                    correction_stiffness: np.ndarray | None = None, correction_dk: np.ndarray | None = None,
                    correction_coupling: np.ndarray | None = None, correction_massive: int = 0,
                    projected_dm: np.ndarray | None = None, correction_dm: np.ndarray | None = None,
                    correction_mass_coupling: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(omega^2 [rad^2/s^2], coefficients) after relative stiffness-parameter changes.

    Parameters
    ----------
    omega2_0 : numpy.ndarray
        (n_modes,) nominal eigenvalues [rad^2/s^2] of the retained modes (mass-normalised).
    projected_dk : numpy.ndarray
        (n_parameters, n_modes, n_modes): Phi0^T dK_i Phi0 per unit relative change.
    relative_change : numpy.ndarray
        (n_parameters,) p_i / p_i0 - 1.
    correction_stiffness, correction_dk, correction_coupling : numpy.ndarray, optional
        W^T K0 W (n_w, n_w), W^T dK_i W (n_parameters, n_w, n_w) and W^T dK_i Phi0
        (n_parameters, n_w, n_modes) of the static-correction vectors W; none: the plain reanalysis.
    correction_massive : int
        How many of the vectors (the first ones) carry mass; the rest are massless.
    projected_dm, correction_dm, correction_mass_coupling : numpy.ndarray, optional
        Phi0^T dM_i Phi0 (n_parameters, n_modes, n_modes), W^T dM_i W (n_parameters, n_w, n_w) and
        W^T dM_i Phi0 (n_parameters, n_w, n_modes) [per unit relative change] of the mass parameters (zero for
        a stiffness parameter); none: no parameter changes a mass.

    Returns
    -------
    tuple of numpy.ndarray
        The new eigenvalues (n_modes,) and the coefficients (n_modes + n_w, n_modes): new mode k is
        ``Phi0 @ c[:n_modes, k] + W @ c[n_modes:, k]``.
    """
    rel = np.asarray(relative_change, dtype=float)
    omega2_0 = np.asarray(omega2_0, dtype=float)
    n = len(omega2_0)
    n_w = 0 if correction_stiffness is None else correction_stiffness.shape[0]
    if not np.any(rel != 0.0):
        return omega2_0.copy(), np.eye(n + n_w, n)
    k_r = np.zeros((n + n_w, n + n_w))
    k_r[:n, :n] = np.diag(omega2_0) + np.tensordot(rel, projected_dk, axes=1)
    if n_w:
        coupling = np.tensordot(rel, correction_coupling, axes=1)
        k_r[n:, :n], k_r[:n, n:] = coupling, coupling.T
        k_r[n:, n:] = correction_stiffness + np.tensordot(rel, correction_dk, axes=1)
    k_r = 0.5 * (k_r + k_r.T)
    kept = n + int(correction_massive)  # retained modes and massive corrections; the rest is condensed
    condensation = np.linalg.solve(k_r[kept:, kept:], k_r[kept:, :kept]) if kept < n + n_w else np.zeros((0, kept))
    k_c = k_r[:kept, :kept] - k_r[:kept, kept:] @ condensation
    k_c = 0.5 * (k_c + k_c.T)
    m_c = _condensed_mass(rel, n, n_w, kept, condensation, projected_dm, correction_dm, correction_mass_coupling)
    if m_c is None:
        _, vectors = np.linalg.eigh(k_c)
        overlap = vectors[:n]
    else:
        lower = np.linalg.cholesky(m_c)
        half = np.linalg.solve(lower, np.linalg.solve(lower, k_c).T)  # L^-1 K_c L^-T (K_c symmetric)
        _, y = np.linalg.eigh(0.5 * (half + half.T))
        vectors = np.linalg.solve(lower.T, y)
        overlap = (m_c @ vectors)[:n]
    _, order = linear_sum_assignment(-(overlap ** 2))  # row i: nominal mode i; order[i]: the mode it becomes
    chosen = vectors[:, order]
    # LAPACK's eigenvalues are exact to eps |K_c| absolute, and K_c spans the corrections' stiffness beside
    # the slowest modes'; the Rayleigh quotients of its vectors are exact to eps relative
    w2 = np.einsum("ik,ij,jk->k", chosen, k_c, chosen)
    if m_c is not None:
        w2 = w2 / np.einsum("ik,ij,jk->k", chosen, m_c, chosen)
    return w2, np.vstack([chosen, -condensation @ chosen])


def _condensed_mass(rel: np.ndarray, n: int, n_w: int, kept: int, condensation: np.ndarray,
                    projected_dm: np.ndarray | None, correction_dm: np.ndarray | None,
                    correction_mass_coupling: np.ndarray | None) -> np.ndarray | None:
    """M_c of the module docstring over the kept coordinates, None where no mass changes (M_c = I)."""
    if projected_dm is None or not np.any(np.tensordot(np.abs(rel), np.abs(projected_dm), axes=1)):
        return None
    m_r = np.zeros((n + n_w, n + n_w))
    m_r[:kept, :kept] = np.eye(kept)
    m_r[:n, :n] += np.tensordot(rel, projected_dm, axes=1)
    if n_w and correction_dm is not None:  # without them: the corrections' mass unchanged
        coupling = np.tensordot(rel, correction_mass_coupling, axes=1)
        m_r[n:, :n] += coupling
        m_r[:n, n:] += coupling.T
        m_r[n:, n:] += np.tensordot(rel, correction_dm, axes=1)
    t = np.vstack([np.eye(kept), -condensation])
    m_c = t.T @ (0.5 * (m_r + m_r.T)) @ t
    return 0.5 * (m_c + m_c.T)
