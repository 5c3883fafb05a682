"""The structure as drawable bodies: bar segments, lumped masses, springs (SI units, basic axes)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fe.drawing import tube_outer_radius_m  # noqa: F401 (the viewer's name for it, as before)
from mace_fmu.iomodel.source import ModalSource

#: RGB colours by component name prefix (``mace_em.toml`` [components]); anything else is "other".
COMPONENT_COLOURS: dict[str, int] = {
    "bus": 0x4A7FC1, "primary_gimbal": 0xE08A2E, "secondary_gimbal": 0xD1495B, "reaction_wheels": 0x3FA34D,
    "suspension": 0x888888, "cable": 0x555555, "other": 0x9E9E9E,
}


def component_colour(component: str) -> int:
    """RGB colour of a component: the entry whose name is the longest prefix of it."""
    matches = [name for name in COMPONENT_COLOURS if component.startswith(name)]
    return COMPONENT_COLOURS[max(matches, key=len)] if matches else COMPONENT_COLOURS["other"]


@dataclass(frozen=True)
class BarSegment:
    """One straight piece of a bar, ``s0``..``s1`` along it (0 = GA, 1 = GB)."""

    name: str  #: scene path, "bars/<cbar id>/<k>"
    bar_id: int
    row_a: int  #: grid row of GA in the DofMap
    row_b: int
    s0: float
    s1: float
    radius_m: float  #: outer radius of the section; 0 for a cable (drawn as a line)
    component: str


@dataclass(frozen=True)
class MassBody:
    """A CONM2 drawn as a sphere at its grid, radius from its mass (steel density)."""

    name: str  #: "masses/<conm2 id>"
    row: int
    radius_m: float
    component: str


@dataclass(frozen=True)
class Scene:
    """Everything the viewer draws, with undeformed grid positions [m] (deck basic axes, Y up)."""

    positions_m: np.ndarray  #: (n_grid, 3)
    grid_ids: tuple[int, ...]  #: the grid of each row of ``positions_m``
    segments: tuple[BarSegment, ...]  #: the bars, in pieces
    masses: tuple[MassBody, ...]  #: the lumped masses
    centre_m: np.ndarray  #: (3,) centre of the test article's bounding box (bus, gimbals, wheels)
    extent_m: np.ndarray  #: (3,) size of that box along X, Y, Z
    length_m: float  #: largest extent of the test article, for scaling deflections


def build_scene(structure_modes: ModalSource, *, segments_per_bar: int = 4) -> Scene:
    """Bodies of a computed structure, as its modal source draws it (:meth:`ModalSource.drawing`): a deck's CBARs
    in ``segments_per_bar`` pieces and CONM2s as spheres; NASTRAN's modes' element edges and lone grids.

    Parameters
    ----------
    structure_modes : ModalSource
        Computed modes of a deck, or NASTRAN's modes with their geometry deck.
    segments_per_bar : int
        Pieces each bar is drawn in (1 or more; an element edge is drawn in one).

    Returns
    -------
    Scene
        The drawable bodies and the undeformed grid positions.
    """
    if segments_per_bar < 1:
        raise MaceError(f"segments_per_bar must be >= 1, got {segments_per_bar}")
    drawing = structure_modes.drawing()
    segments = []
    for line in drawing.lines:
        pieces = segments_per_bar if line.bends else 1
        edges = np.linspace(0.0, 1.0, pieces + 1)
        segments += [BarSegment(name=f"{line.name}/{k}", bar_id=line.element_id, row_a=line.row_a, row_b=line.row_b,
                                s0=float(edges[k]), s1=float(edges[k + 1]), radius_m=line.radius_m,
                                component=line.component) for k in range(pieces)]
    masses = tuple(MassBody(name=p.name, row=p.row, radius_m=p.radius_m, component=p.component)
                   for p in drawing.points)
    return Scene(positions_m=drawing.positions_m, grid_ids=tuple(drawing.grid_ids), segments=tuple(segments),
                 masses=masses, centre_m=drawing.centre_m, extent_m=drawing.extent_m, length_m=drawing.length_m)
