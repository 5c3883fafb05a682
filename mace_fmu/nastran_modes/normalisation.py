"""The mass normalisation of NASTRAN's eigenvectors: stated from the generalized masses, checked, and made
phi^T M phi = I when the run asked for another (NORM=MAX or POINT)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mace_fmu.errors import MaceError

#: generalized masses within this of 1 are NASTRAN's NORM=MASS (it prints 7 digits, an OP2 holds 32-bit reals)
MASS_TOLERANCE = 1e-6


def normalise(source: Path, shapes: np.ndarray, generalized_masses: np.ndarray | None) -> tuple[np.ndarray, str]:
    """(mass-normalised shapes, what was found and done) for ``shapes`` (n_dof, n_modes) as the file holds them.

    The generalized mass m_i = phi_i^T M phi_i that NASTRAN printed for each vector; the vector divided by
    sqrt(m_i) has unit generalized mass. Without generalized masses (a punch file, an OP2 without LAMA)
    the vectors are taken as they are, and the returned text says so.
    """
    if generalized_masses is None:
        return shapes, ("not stated: the file has no generalized masses (no LAMA table, or a punch file); the "
                        "vectors are used as NASTRAN wrote them, mass-normalised when the run's EIGRL/EIGR asked "
                        "for NORM=MASS (the default)")
    masses = np.asarray(generalized_masses, dtype=float)
    if np.any(~np.isfinite(masses)) or np.any(masses <= 0.0):
        bad = [i + 1 for i in np.flatnonzero(~(masses > 0.0))]
        raise MaceError(f"{source}: table LAMA: generalized masses of modes (in file order) {bad} are not positive "
                        "(expected phi^T M phi > 0)")
    if np.all(np.abs(masses - 1.0) <= MASS_TOLERANCE):
        return shapes, "MASS"
    return shapes / np.sqrt(masses), (
        f"rescaled to MASS: NASTRAN's generalized masses were {masses.min():.7g} to {masses.max():.7g} (NORM=MAX or "
        "POINT); each vector was divided by the square root of its generalized mass")
