"""The mass normalisation of NASTRAN's eigenvectors: stated from the generalized masses, checked, and made
phi^T M phi = I when the run asked for another (NORM=MAX or POINT).

Without generalized masses (an OP2 without its LAMA table, a punch file) the vectors cannot be rescaled: they
are taken as mass-normalised, NASTRAN's default, only when nothing says otherwise. The run's eigenvalue request
(EIGR/EIGRL NORM in an OP2's DYNAMICS table) or the vectors themselves (the largest component of every vector
exactly 1: NORM=MAX; one component 1 in every vector: NORM=POINT) may say otherwise: then every modal gain would
be off by an unknown factor, and the vectors are refused unless the user states that they are mass-normalised
(``normalisation="mass"``, the structure file's ``[modes] normalisation = "mass"``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mace_fmu.errors import MaceError

#: generalized masses within this of 1 are NASTRAN's NORM=MASS (it prints 7 digits, an OP2 holds 32-bit reals)
MASS_TOLERANCE = 1e-6
#: a component within this of 1 is NASTRAN's 1.0 of NORM=MAX or POINT (a 32-bit real, or 7 printed digits)
UNIT_TOLERANCE = 1e-6
#: what a user may state of the vectors' normalisation
STATED = ("mass",)


def shape_normalisation(vectors: np.ndarray) -> str | None:
    """"MAX" when the largest component of every vector is 1, "POINT" when one component is 1 in every vector (of
    two or more), None when the vectors show neither (``vectors``: (n_dof, n_modes) as the file holds them)."""
    flat = np.abs(np.asarray(vectors, dtype=float).reshape(-1, np.shape(vectors)[-1]))
    if flat.size == 0:
        return None
    if np.all(np.abs(flat.max(axis=0) - 1.0) <= UNIT_TOLERANCE):
        return "MAX"
    if flat.shape[1] > 1 and np.any(np.all(np.abs(flat - 1.0) <= UNIT_TOLERANCE, axis=1)):
        return "POINT"
    return None


def normalise(source: Path, shapes: np.ndarray, generalized_masses: np.ndarray | None, *,
              run_normalisation: tuple[str, str] | None = None, file_vectors: np.ndarray | None = None,
              stated: str | None = None, where: str = "") -> tuple[np.ndarray, str]:
    """(mass-normalised shapes, what was found and done) for ``shapes`` (n_dof, n_modes) as the file holds them.

    Parameters
    ----------
    source : Path
        The file, for messages.
    shapes : numpy.ndarray
        (n_dof, n_modes) the vectors [deck units per unit modal coordinate], in basic.
    generalized_masses : numpy.ndarray or None
        m_i = phi_i^T M phi_i as NASTRAN printed them (LAMA); None when the file has none.
    run_normalisation : (str, str), optional
        (NORM, where) of the run's eigenvalue request, when the file states it.
    file_vectors : numpy.ndarray, optional
        The vectors as the file holds them (in the grids' own systems), whose components tell NORM=MAX or POINT.
    stated : {"mass"}, optional
        The user's statement that the vectors are mass-normalised, for a file that cannot show it.
    where : str
        The table or block the vectors came from, for messages.

    Returns
    -------
    (numpy.ndarray, str)
        The shapes with unit generalized masses, and what was found ("MASS", or what and how it was rescaled).

    Raises
    ------
    MaceError
        Generalized masses that are not positive; vectors without generalized masses that the file shows are not
        mass-normalised (unless ``stated``), one line saying what the file holds and what to add.
    """
    if stated is not None and stated not in STATED:
        raise MaceError(f"{source}: normalisation {stated!r}: expected {' or '.join(map(repr, STATED))} (the "
                        "statement that the file's vectors are mass-normalised)")
    if generalized_masses is not None:
        masses = np.asarray(generalized_masses, dtype=float)
        if np.any(~np.isfinite(masses)) or np.any(masses <= 0.0):
            bad = [i + 1 for i in np.flatnonzero(~(masses > 0.0))]
            raise MaceError(f"{source}: table LAMA: generalized masses of modes (in file order) {bad} are not "
                            "positive (expected phi^T M phi > 0)")
        if np.all(np.abs(masses - 1.0) <= MASS_TOLERANCE):
            return shapes, "MASS"
        return shapes / np.sqrt(masses), (
            f"rescaled to MASS: NASTRAN's generalized masses were {masses.min():.7g} to {masses.max():.7g} (NORM=MAX "
            "or POINT); each vector was divided by the square root of its generalized mass")
    at = f"{source}: {where}: " if where else f"{source}: "
    if run_normalisation is not None and run_normalisation[0] != "MASS":
        norm, request = run_normalisation
        raise MaceError(f"{at}the eigenvectors are normalised to NORM={norm} ({request}) and the file holds no "
                        "generalized masses (no LAMA table) to make them mass-normalised: every modal gain would be "
                        "off by an unknown factor (expected the LAMA table in the OP2, PARAM,POST,-1, or a run with "
                        "NORM=MASS, the default)")
    shown = shape_normalisation(file_vectors if file_vectors is not None else shapes)
    if stated == "mass":
        return shapes, ("MASS, as stated (normalisation = \"mass\"): the file has no generalized masses to check it"
                        + (f", and its vectors look like NORM={shown}" if shown else ""))
    if shown is not None:
        how = ("the largest component of every vector is 1" if shown == "MAX"
               else "one component is 1 in every vector")
        raise MaceError(f"{at}the eigenvectors look normalised to NORM={shown} ({how}) and the file holds no "
                        "generalized masses (no LAMA table) to make them mass-normalised: every modal gain would be "
                        "off by an unknown factor (expected the OP2 with its LAMA table, PARAM,POST,-1; or, if they "
                        "are mass-normalised after all, say so: [modes] normalisation = \"mass\", "
                        "read_nastran_modes(normalisation=\"mass\"))")
    if run_normalisation is not None:
        return shapes, (f"MASS, as the run asked ({run_normalisation[1]}: NORM=MASS); the file has no generalized "
                        "masses to check it")
    return shapes, ("not stated: the file has no generalized masses (no LAMA table, or a punch file); the "
                    "vectors are used as NASTRAN wrote them, mass-normalised when the run's EIGRL/EIGR asked "
                    "for NORM=MASS (the default)")
