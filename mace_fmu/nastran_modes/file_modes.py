"""What a NASTRAN results file says about normal modes, before coordinate systems and normalisation."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

#: a coordinate system's kind: rectangular, cylindrical or spherical
CoordKind = Literal["R", "C", "S"]
#: the kind of a CORD1x or CORD2x card, by its name's last letter
COORD_KINDS: dict[str, CoordKind] = {"R": "R", "C": "C", "S": "S"}


def xyz(values: tuple[float, ...] | list[float]) -> tuple[float, float, float]:
    """Three coordinates as a triple of floats."""
    x, y, z = values
    return float(x), float(y), float(z)


@dataclass(frozen=True)
class CoordCard:
    """A CORD1R/C/S or CORD2R/C/S as the results file's geometry tables (GEOM1) give it."""

    id: int  #: coordinate system ID
    kind: CoordKind  #: rectangular, cylindrical or spherical
    rid: int | None  #: CORD2x: the system A, B, C are given in; None for a CORD1x
    points: tuple[tuple[float, float, float], ...] | None  #: CORD2x: A, B, C in system ``rid``
    grids: tuple[int, int, int] | None  #: CORD1x: G1 (origin), G2 (on z), G3 (in the x-z plane)


@dataclass(frozen=True)
class FileGeometry:
    """Grids and coordinate systems from a results file (GEOM1 tables of an OP2)."""

    grids: dict[int, tuple[int, tuple[float, float, float], int]]  #: grid ID -> (CP, position in CP, CD)
    coords: dict[int, CoordCard]  #: coordinate system ID -> card


@dataclass(frozen=True)
class FileModes:
    """The eigenvectors of one subcase of a results file, as the file holds them."""

    source: Path  #: the file
    subcase: int  #: the subcase ID
    grid_ids: np.ndarray  #: (n_grid,) grid IDs in the file's order
    vectors: np.ndarray  #: (n_grid, 6, n_modes) T1 T2 T3 R1 R2 R3 of each grid and mode [deck units]
    frame: Literal["cd", "basic"]  #: the systems the components are measured in: each grid's CD, or basic
    mode_numbers: np.ndarray  #: (n_modes,) NASTRAN's mode numbers
    eigenvalues: np.ndarray  #: (n_modes,) [rad^2/s^2]
    generalized_masses: np.ndarray | None  #: (n_modes,) from the eigenvalue table, None when the file has none
    skipped_points: tuple[int, ...]  #: scalar and extra points in the file, left out (one component, no frame)
    geometry: FileGeometry | None  #: the file's own grids and systems, when it has them
    where: str  #: the table or block the eigenvectors came from, for messages
    eigenvalues_from: str = ""  #: the table or block the eigenvalues came from, for messages ("": ``where``)
    #: (NORM, where) the run's eigenvalue request states (EIGR/EIGRL of an OP2's DYNAMICS table): "MASS", "MAX" or
    #: "POINT"; None when the file does not say
    run_normalisation: tuple[str, str] | None = None
    #: NASTRAN's numbers of the vectors that are residual vectors (PARAM,RESVEC: static shapes appended to the
    #: modes and orthogonalised with them), not eigenvectors of the structure
    residual_vectors: tuple[int, ...] = ()
    notes: tuple[str, ...] = ()  #: what the file says that the reader could not settle (kept in the result's notes)
