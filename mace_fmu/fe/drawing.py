"""What a deck's modes offer to draw: each CBAR a tube, each CONM2 a sphere, framed on the test article."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from mace_fmu.structure.drawing import Drawing, DrawnLine, DrawnPoint

if TYPE_CHECKING:
    from mace_fmu.fe.modes import StructureModes

#: Components whose bars are drawn as lines (no bending stiffness worth showing), as fe.labels finds cables.
CABLE_PREFIX = "cable_"
#: Components (name prefixes) of the test article itself: the camera frames them, motion is scaled to them.
ARTICLE_PREFIXES = ("bus", "primary_gimbal", "secondary_gimbal", "reaction_wheels")
#: density [kg/m^3] a concentrated mass is drawn with (steel)
MASS_DENSITY = 7800.0


def tube_outer_radius_m(area_m2: float, inertia_m4: float) -> float:
    """Outer radius of the thin or thick tube with this area and (mean) bending inertia.

    Parameters
    ----------
    area_m2 : float
        Cross-section area [m^2].
    inertia_m4 : float
        Mean bending inertia [m^4].

    Returns
    -------
    float
        The outer radius [m].
    """
    # A = pi (ro^2 - ri^2), I = A (ro^2 + ri^2) / 4  ->  ro^2 = (4 I / A + A / pi) / 2
    return float(np.sqrt(max(4.0 * inertia_m4 / area_m2 + area_m2 / np.pi, 0.0) / 2.0))


def deck_drawing(structure_modes: StructureModes) -> Drawing:
    """The bars and masses of a deck's structure, framed on its test article.

    Parameters
    ----------
    structure_modes : StructureModes
        The modes of the deck's 1-g or 0-g structure.

    Returns
    -------
    Drawing
        Each CBAR a line that bends (a cable's of radius 0), each CONM2 of positive mass a sphere.
    """
    deck = structure_modes.structure.deck
    dofs = structure_modes.model.dofs
    spec = structure_modes.structure.spec
    positions = structure_modes.model.positions
    lines = []
    for bar_id, bar in sorted(deck.bars.items()):
        pbar = deck.pbars[bar.pid]
        component = spec.component_of(bar.ga, bar.gb) or "other"
        radius = 0.0 if component.startswith(CABLE_PREFIX) else tube_outer_radius_m(pbar.area,
                                                                                    0.5 * (pbar.i1 + pbar.i2))
        lines.append(DrawnLine(name=f"bars/{bar_id}", element_id=bar_id, row_a=dofs.grid_index(bar.ga),
                               row_b=dofs.grid_index(bar.gb), radius_m=radius, component=component, bends=True))
    points = []
    for mid, conm in sorted(deck.conm2s.items()):
        if conm.mass <= 0.0:
            continue
        radius = float(np.cbrt(3.0 * conm.mass / (4.0 * np.pi * MASS_DENSITY)))
        points.append(DrawnPoint(name=f"masses/{mid}", row=dofs.grid_index(conm.grid), radius_m=radius,
                                 component=spec.component_of(conm.grid) or "other"))
    box = positions[article_rows(structure_modes)]
    low, high = box.min(axis=0), box.max(axis=0)
    return Drawing(positions_m=positions, grid_ids=dofs.grid_ids, lines=tuple(lines), points=tuple(points),
                   centre_m=0.5 * (low + high), extent_m=high - low, length_m=float((high - low).max()))


def article_rows(structure_modes: StructureModes) -> np.ndarray:
    """Grid rows of the test article: components named ARTICLE_PREFIXES, else every grid but the cables.

    The suspension cables of the 1-g model are 4.7 m long against a 1.7 m article; framing or
    scaling by them would leave the article a speck.

    Parameters
    ----------
    structure_modes : StructureModes
        The modes of the deck's structure.

    Returns
    -------
    numpy.ndarray
        Row indices into the model's grids.
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
