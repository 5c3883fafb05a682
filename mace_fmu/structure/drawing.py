"""What a modal source offers to draw: lines and points on its grids, and the box the camera frames.

Each modal source says what it looks like (:meth:`mace_fmu.iomodel.source.ModalSource.drawing`): a deck's
modes draw its bars as tubes and its concentrated masses as spheres (:func:`mace_fmu.fe.drawing.deck_drawing`),
NASTRAN's modes their geometry deck's element edges and their lone grids
(:func:`mace_fmu.iomodel.modal_source.outline_drawing`). The viewer turns a drawing into its scene without
asking which source it came from.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class DrawnLine:
    """A straight body between two grids: a bar (drawn in pieces, to bend with the modes) or an element edge."""

    name: str  #: scene path prefix, "bars/<cbar id>" or "edges/<grid a>_<grid b>"
    element_id: int  #: the bar's ID (0 for an element edge)
    row_a: int  #: grid row of its first end in the source's grid order
    row_b: int  #: grid row of its second end
    radius_m: float  #: outer radius drawn; 0 for a cable (drawn as a line)
    component: str  #: the structure file's component it belongs to ("other" when none)
    bends: bool  #: drawn in several pieces (a bar) rather than one (an element edge)


@dataclass(frozen=True)
class DrawnPoint:
    """A sphere on one grid: a concentrated mass, or a grid on no line."""

    name: str  #: scene path, "masses/<conm2 id>" or "grids/<grid>"
    row: int  #: grid row in the source's grid order
    radius_m: float  #: sphere radius
    component: str  #: the structure file's component it belongs to ("other" when none)


@dataclass(frozen=True)
class Drawing:
    """Everything a modal source offers to draw, in its grids' order (SI units, basic axes)."""

    positions_m: np.ndarray  #: (n_grid, 3) undeformed grid positions [m]
    grid_ids: tuple[int, ...]  #: the grids, in the order of the rows
    lines: tuple[DrawnLine, ...]  #: bars or element edges
    points: tuple[DrawnPoint, ...]  #: concentrated masses or lone grids
    centre_m: np.ndarray  #: (3,) centre of the box the camera frames
    extent_m: np.ndarray  #: (3,) size of that box along X, Y, Z
    length_m: float  #: its largest extent, for scaling deflections
