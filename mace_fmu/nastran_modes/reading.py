"""The front door: NASTRAN's normal modes from an OP2 or a punch file, as the FE core's Modes."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fe.dofs import DofMap
from mace_fmu.fe.modal import Modes
from mace_fmu.nastran_modes.deck_geometry import read_deck_geometry
from mace_fmu.nastran_modes.file_modes import FileModes
from mace_fmu.nastran_modes.frames import resolve_geometry
from mace_fmu.nastran_modes.normalisation import normalise
from mace_fmu.nastran_modes.op2 import read_op2_modes
from mace_fmu.nastran_modes.punch import read_punch_modes


@dataclass(frozen=True)
class NastranModes:
    """NASTRAN's normal modes of one subcase, in basic coordinates and mass-normalised."""

    modes: Modes  #: frequencies [Hz], shapes (n_dof, n_modes) in basic, phi^T M phi = I, DOFs of the grids present
    eigenvalues: np.ndarray  #: [rad^2/s^2] as NASTRAN printed them
    generalized_masses: np.ndarray | None  #: as NASTRAN printed them (before any rescaling); None when not in the file
    normalisation: str  #: "MASS" (generalized masses 1 within 1e-6), or what was found and whether it was rescaled
    grid_positions: dict[int, np.ndarray] | None  #: basic position [deck units] of the grids whose geometry is known
    source: Path  #: the file read
    units: str  #: the units of the shapes and positions
    notes: tuple[str, ...] = ()  #: what was left out or assumed (scalar points, unknown output systems)


def read_nastran_modes(path: str | Path, *, subcase: int | None = None,
                       geometry: str | Path | None = None) -> NastranModes:
    """Read the real eigenvectors and eigenvalues of a NASTRAN SOL 103 run.

    Parameters
    ----------
    path : str or Path
        An OP2 file (32-bit, either byte order: tables OUGV1/BOUGV1, LAMA, GEOM1) or a punch file
        (``.pch``: $EIGENVECTOR blocks); the kind is told from the content.
    subcase : int, optional
        The subcase whose modes are read; needed when the file holds several.
    geometry : str or Path, optional
        The run's deck, read for its GRID, GRDSET, CORD1R/C/S and CORD2R/C/S cards only (with mace_fmu.deck's
        card parsers; other cards, shells and solids included, are passed over): the grids' CD systems and
        positions. Without it an OP2's own GEOM1 tables are used; with neither, every grid's CD system is
        taken as basic (and ``notes`` says so).

    Returns
    -------
    NastranModes
        ``modes.frequencies_hz`` [Hz] = sign(lambda) sqrt(abs(lambda)) / (2 pi); ``modes.shapes`` in basic
        coordinates [deck units per unit modal coordinate], rescaled to unit generalized mass when NASTRAN's
        were not 1; ``modes.cd_frames`` the CD axes of each grid in basic; labels "mode <NASTRAN's number>".
        Scalar and extra points are left out (named in ``notes``).

    Raises
    ------
    MaceError
        One line naming the file, the table (or line) and the record, for a truncated, corrupted or
        unsupported file, or a subcase that is not in it.
    """
    source = Path(path)
    if not source.is_file():
        raise MaceError(f"{source}: no such file (expected an OP2 or a punch file of a SOL 103 run)")
    with source.open("rb") as stream:  # the first word tells the kind; the reader then reads the whole file
        head = stream.read(4)
    is_op2 = head in (b"\x04\x00\x00\x00", b"\x00\x00\x00\x04", b"\x08\x00\x00\x00", b"\x00\x00\x00\x08")
    found = read_op2_modes(source, subcase=subcase) if is_op2 else read_punch_modes(source, subcase=subcase)
    return _to_basic(found, geometry)


def _to_basic(found: FileModes, geometry: str | Path | None) -> NastranModes:
    notes = []
    if found.skipped_points:
        shown = ", ".join(str(p) for p in found.skipped_points[:8]) + (" ..." if len(found.skipped_points) > 8 else "")
        notes.append(f"{len(found.skipped_points)} scalar or extra points left out (IDs {shown})")
    positions = cds = None
    if geometry is not None:
        positions, cds = resolve_geometry(Path(geometry), read_deck_geometry(Path(geometry)), where="bulk data")
    elif found.geometry is not None and found.geometry.grids:
        positions, cds = resolve_geometry(found.source, found.geometry, where="table GEOM1")
    order = np.argsort(found.grid_ids, kind="stable")
    grid_ids = found.grid_ids[order]
    vectors = found.vectors[order]  # (n_grid, 6, n_modes)
    frames = np.repeat(np.eye(3)[None], len(grid_ids), axis=0)
    if cds is None:
        if found.frame == "cd":
            notes.append("the grids' output (CD) systems are not known (no geometry in the file and no geometry= "
                         "deck): every grid's components are taken as basic")
    else:
        missing = [int(g) for g in grid_ids if int(g) not in cds]
        if missing:
            raise MaceError(f"{found.source}: {found.where}: grids {missing[:8]} have eigenvectors but no GRID in the "
                            "geometry (expected the deck of the run that wrote the file)")
        for row, gid in enumerate(grid_ids):
            _, system = cds[int(gid)]
            frames[row] = system.axes_at(positions[int(gid)])
    if found.frame == "cd":
        vectors = np.concatenate([np.einsum("gij,gjm->gim", frames, vectors[:, :3]),
                                  np.einsum("gij,gjm->gim", frames, vectors[:, 3:])], axis=1)
    shapes = vectors.reshape(6 * len(grid_ids), -1)
    shapes, normalisation = normalise(found.source, shapes, found.generalized_masses)
    eigenvalues = np.asarray(found.eigenvalues, dtype=float)
    frequencies = np.sign(eigenvalues) * np.sqrt(np.abs(eigenvalues)) / (2.0 * np.pi)
    modes = Modes(frequencies_hz=frequencies, shapes=shapes, dofs=DofMap(tuple(int(g) for g in grid_ids)),
                  cd_frames=frames, labels=tuple(f"mode {m}" for m in found.mode_numbers))
    return NastranModes(modes=modes, eigenvalues=eigenvalues, generalized_masses=found.generalized_masses,
                        normalisation=normalisation, grid_positions=positions, source=found.source,
                        units="the deck's units", notes=tuple(notes))
