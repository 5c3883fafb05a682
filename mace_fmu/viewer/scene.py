"""The structure as drawable bodies: bar segments, lumped masses, springs (SI units, basic axes)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import StructureModes
from mace_fmu.iomodel.modal_source import ModalStructure

#: RGB colours by component name prefix (``mace_em.toml`` [components]); anything else is "other".
COMPONENT_COLOURS: dict[str, int] = {
    "bus": 0x4A7FC1, "primary_gimbal": 0xE08A2E, "secondary_gimbal": 0xD1495B, "reaction_wheels": 0x3FA34D,
    "suspension": 0x888888, "cable": 0x555555, "other": 0x9E9E9E,
}
#: Components whose bars are drawn as lines (no bending stiffness worth showing), as fe.labels finds cables.
CABLE_PREFIX = "cable_"
#: Components (name prefixes) of the test article itself: the camera frames them, motion is scaled to them.
ARTICLE_PREFIXES = ("bus", "primary_gimbal", "secondary_gimbal", "reaction_wheels")


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


def tube_outer_radius_m(area_m2: float, inertia_m4: float) -> float:
    """Outer radius of the thin or thick tube with this area and (mean) bending inertia."""
    # A = pi (ro^2 - ri^2), I = A (ro^2 + ri^2) / 4  ->  ro^2 = (4 I / A + A / pi) / 2
    return float(np.sqrt(max(4.0 * inertia_m4 / area_m2 + area_m2 / np.pi, 0.0) / 2.0))


def build_scene(structure_modes: StructureModes | ModalStructure, *, segments_per_bar: int = 4) -> Scene:
    """Bodies of a computed structure: each CBAR in ``segments_per_bar`` pieces, each CONM2 a sphere; for
    NASTRAN's modes (a ModalStructure) the grids and the geometry deck's element edges (mace_fmu.viewer.outline).

    Parameters
    ----------
    structure_modes : StructureModes or ModalStructure
        Computed modes of a deck, or NASTRAN's modes with their geometry deck.
    segments_per_bar : int
        Pieces each bar is drawn in (1 or more).

    Returns
    -------
    Scene
        The drawable bodies and the undeformed grid positions.
    """
    if segments_per_bar < 1:
        raise MaceError(f"segments_per_bar must be >= 1, got {segments_per_bar}")
    if isinstance(structure_modes, ModalStructure):
        from mace_fmu.viewer.outline import outline_scene

        return outline_scene(structure_modes)
    deck = structure_modes.structure.deck
    dofs = structure_modes.model.dofs
    spec = structure_modes.structure.spec
    positions = structure_modes.model.positions
    segments = []
    for bar_id, bar in sorted(deck.bars.items()):
        pbar = deck.pbars[bar.pid]
        component = spec.component_of(bar.ga, bar.gb) or "other"
        cable = component.startswith(CABLE_PREFIX)
        radius = 0.0 if cable else tube_outer_radius_m(pbar.area, 0.5 * (pbar.i1 + pbar.i2))
        edges = np.linspace(0.0, 1.0, segments_per_bar + 1)
        for k in range(segments_per_bar):
            segments.append(BarSegment(name=f"bars/{bar_id}/{k}", bar_id=bar_id, row_a=dofs.grid_index(bar.ga),
                                       row_b=dofs.grid_index(bar.gb), s0=float(edges[k]), s1=float(edges[k + 1]),
                                       radius_m=radius, component=component))
    masses = []
    for mid, conm in sorted(deck.conm2s.items()):
        if conm.mass <= 0.0:
            continue
        radius = float(np.cbrt(3.0 * conm.mass / (4.0 * np.pi * 7800.0)))
        masses.append(MassBody(name=f"masses/{mid}", row=dofs.grid_index(conm.grid), radius_m=radius,
                               component=spec.component_of(conm.grid) or "other"))
    box = positions[article_rows(structure_modes)]
    low, high = box.min(axis=0), box.max(axis=0)
    return Scene(positions_m=positions, grid_ids=dofs.grid_ids, segments=tuple(segments), masses=tuple(masses),
                 centre_m=0.5 * (low + high), extent_m=high - low, length_m=float((high - low).max()))


def article_rows(structure_modes: StructureModes) -> np.ndarray:
    """Grid rows of the test article: components named ARTICLE_PREFIXES, else every grid but the cables.

    The suspension cables of the 1-g model are 4.7 m long against a 1.7 m article; framing or
    scaling by them would leave the article a speck.
    """
    spec = structure_modes.structure.spec
    ids = structure_modes.model.dofs.grid_ids

    def rows(keep: Callable[[str], bool]) -> np.ndarray:
        grids = frozenset().union(*(g for name, g in spec.components.items() if keep(name)))
        return np.flatnonzero([g in grids for g in ids])

    article = rows(lambda name: name.startswith(ARTICLE_PREFIXES))
    if article.size:
        return article
    cables = rows(lambda name: name.startswith(CABLE_PREFIX))
    return np.setdiff1d(np.arange(len(ids)), cables) if cables.size < len(ids) else np.arange(len(ids))
