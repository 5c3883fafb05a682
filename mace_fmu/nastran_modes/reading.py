"""The front door: NASTRAN's normal modes from an OP2 or a punch file, as the FE core's Modes."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from mace_fmu.errors import MaceError
from mace_fmu.fe.dofs import DofMap
from mace_fmu.fe.modal import Modes
from mace_fmu.nastran_modes.deck_geometry import read_deck_geometry
from mace_fmu.nastran_modes.file_modes import FileModes
from mace_fmu.nastran_modes.frames import System, resolve_geometry
from mace_fmu.nastran_modes.normalisation import normalise
from mace_fmu.nastran_modes.op2 import read_op2_modes
from mace_fmu.nastran_modes.punch import read_punch_modes
from mace_fmu.util.frequency import ZERO_HZ


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


#: how a formatted (ASCII) OUTPUT2 file opens: NASTRAN's character set, the key to the encoding of what follows
FORMATTED_OUTPUT2 = b"X 0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ"
#: the first bytes read to tell a binary OP2, a formatted one, a punch file and anything else apart
HEAD_BYTES = 4096


def read_nastran_modes(path: str | Path, *, subcase: int | None = None, geometry: str | Path | None = None,
                       normalisation: str | None = None) -> NastranModes:
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
    normalisation : {"mass"}, optional
        The user's statement that the vectors are mass-normalised, for a file without generalized masses whose
        vectors look normalised otherwise (the largest component of each is 1); without it such a file is
        refused (:mod:`mace_fmu.nastran_modes.normalisation`).

    Returns
    -------
    NastranModes
        ``modes.frequencies_hz`` [Hz] = sign(lambda) sqrt(abs(lambda)) / (2 pi); ``modes.shapes`` in basic
        coordinates [deck units per unit modal coordinate], rescaled to unit generalized mass when NASTRAN's
        were not 1; ``modes.cd_frames`` the CD axes of each grid in basic; labels "mode <NASTRAN's number>",
        "residual vector <k>" for the vectors beyond the run's ND or V2 (PARAM,RESVEC). Scalar and extra points
        are left out (named in ``notes``).

    Raises
    ------
    MaceError
        One line naming the file, the table (or line) and the record, for a truncated, corrupted or
        unsupported file (a formatted OUTPUT2; a buckling, complex eigenvalue or static run's results, said to be
        what they are), a subcase that is not in it, a negative eigenvalue (an unstable mode), or vectors that
        the file shows are not mass-normalised and cannot be (no generalized masses).
    """
    source = Path(path)
    if not source.is_file():
        raise MaceError(f"{source}: no such file (expected an OP2 or a punch file of a SOL 103 run)")
    with source.open("rb") as stream:  # the first bytes tell the kind; the reader then reads the whole file
        head = stream.read(HEAD_BYTES)
    kind = _kind_of(head)
    if kind == "formatted":
        raise MaceError(f"{source}: a formatted (ASCII) OUTPUT2 file: it opens with NASTRAN's character-set line "
                        "(expected a binary OP2, OUTPUT2's default unformatted form, e.g. PARAM,POST,-1; or a punch "
                        "file)")
    found = read_punch_modes(source, subcase=subcase) if kind == "text" else read_op2_modes(source, subcase=subcase)
    return _to_basic(found, geometry, normalisation=normalisation)


def _kind_of(head: bytes) -> str:
    """"op2" (binary: Fortran records, or anything else that is not text, which the OP2 reader names), "formatted"
    (a formatted OUTPUT2), or "text" (a punch file, or text the punch reader names): told from the content, not
    from the file's suffix."""
    if head[:4] in (b"\x04\x00\x00\x00", b"\x00\x00\x00\x04", b"\x08\x00\x00\x00", b"\x00\x00\x00\x08"):
        return "op2"
    if b"\x00" in head:
        return "op2"  # binary, not an OP2's first record: the OP2 reader says what it found
    if head.lstrip().upper().startswith(FORMATTED_OUTPUT2):
        return "formatted"
    return "text"


def _check_eigenvalues(found: FileModes) -> None:
    """A negative eigenvalue is an unstable mode (a pole at +sqrt(-lambda) 1/s), not a vibration: refused, one line
    naming the mode and its value. Rigid-body modes' round-off (|f| below ZERO_HZ, either sign) is no such mode."""
    eigenvalues = np.asarray(found.eigenvalues, dtype=float)
    hz = np.sqrt(np.abs(eigenvalues)) / (2.0 * np.pi)
    bad = np.flatnonzero((eigenvalues < 0) & (hz >= ZERO_HZ))
    if bad.size:
        k = int(bad[0])
        more = f" ({bad.size - 1} more negative)" if bad.size > 1 else ""
        raise MaceError(f"{found.source}: {found.eigenvalues_from or found.where}: mode {int(found.mode_numbers[k])} "
                        f"has the eigenvalue {eigenvalues[k]:.7g} rad^2/s^2 (-{hz[k]:.4g} Hz){more}: an unstable "
                        f"mode, a pole at +{np.sqrt(-eigenvalues[k]):.4g} 1/s, which no model of vibrations holds "
                        "(expected eigenvalues >= 0: a structure under a compressive preload beyond buckling, or a "
                        "modelling error; rigid-body round-off below 0.01 Hz is taken as 0)")


def _to_basic(found: FileModes, geometry: str | Path | None, *, normalisation: str | None = None) -> NastranModes:
    _check_eigenvalues(found)
    notes = list(found.notes)
    if found.skipped_points:
        shown = ", ".join(str(p) for p in found.skipped_points[:8]) + (" ..." if len(found.skipped_points) > 8 else "")
        notes.append(f"{len(found.skipped_points)} scalar or extra points left out (IDs {shown})")
    positions: dict[int, npt.NDArray[np.float64]] | None = None
    cds: dict[int, tuple[int, System]] | None = None
    if geometry is not None:
        positions, cds = resolve_geometry(Path(geometry), read_deck_geometry(Path(geometry)), where="bulk data")
    elif found.geometry is not None and found.geometry.grids:
        positions, cds = resolve_geometry(found.source, found.geometry, where="table GEOM1")
    order = np.argsort(found.grid_ids, kind="stable")
    grid_ids = found.grid_ids[order]
    vectors = found.vectors[order]  # (n_grid, 6, n_modes)
    frames = np.repeat(np.eye(3)[None], len(grid_ids), axis=0)
    if cds is None or positions is None:
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
    shapes, normalised = normalise(found.source, shapes, found.generalized_masses,
                                   run_normalisation=found.run_normalisation,
                                   file_vectors=found.vectors.reshape(-1, found.vectors.shape[2]), stated=normalisation,
                                   where=found.where)
    eigenvalues = np.asarray(found.eigenvalues, dtype=float)
    frequencies = np.sign(eigenvalues) * np.sqrt(np.abs(eigenvalues)) / (2.0 * np.pi)
    residual = {m: k for k, m in enumerate(found.residual_vectors, start=1)}
    labels = tuple(f"residual vector {residual[int(m)]}" if int(m) in residual else f"mode {m}"
                   for m in found.mode_numbers)
    if residual:
        notes.append(f"{len(residual)} residual vector(s) (NASTRAN's vectors {', '.join(map(str, residual))}, beyond "
                     "what the run's eigenvalue request asked for: PARAM,RESVEC) kept as pseudo-modes, labelled "
                     "'residual vector <k>'")
    modes = Modes(frequencies_hz=frequencies, shapes=shapes, dofs=DofMap(tuple(int(g) for g in grid_ids)),
                  cd_frames=frames, labels=labels)
    return NastranModes(modes=modes, eigenvalues=eigenvalues, generalized_masses=found.generalized_masses,
                        normalisation=normalised, grid_positions=positions, source=found.source,
                        units="the deck's units", notes=tuple(notes))
