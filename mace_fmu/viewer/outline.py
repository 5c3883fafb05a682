"""The scene of a structure known by NASTRAN's modes: its grids and its elements' edges (from the geometry deck).

Shells are drawn as the edges of their faces, solids as the edges of their corners, bars and rods as
lines (:mod:`mace_fmu.deck.connectivity`); a grid on no edge is drawn as a small sphere. Only grids
whose eigenvectors are in the modes file can move, so an edge to any other grid is left out.
"""

from __future__ import annotations

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.modal_source import ModalStructure
from mace_fmu.viewer.scene import BarSegment, MassBody, Scene

#: edge radius and grid-sphere radius as fractions of the structure's largest extent
EDGE_RADIUS_FRACTION = 0.002
GRID_RADIUS_FRACTION = 0.006


def outline_scene(structure: ModalStructure) -> Scene:
    """The grids and edges of ``structure`` as a Scene; a MaceError when nothing can be drawn, naming what to add."""
    grids = structure.modes.dofs.grid_ids
    positions = structure.positions or {}
    known = [g for g in grids if g in positions]
    if not known:
        raise MaceError(f"{structure.file.path}: nothing to draw: {structure.source.name} gives no grid positions "
                        "and [modes] names no geometry deck (add geometry = \"<the run's deck>\")")
    row = {g: k for k, g in enumerate(grids)}
    xyz = np.array([positions[g] if g in positions else np.full(3, np.nan) for g in grids], dtype=float)
    low, high = np.nanmin(xyz, axis=0), np.nanmax(xyz, axis=0)
    xyz[np.isnan(xyz[:, 0])] = 0.5 * (low + high)  # never drawn: no edge or sphere reaches a grid without position
    length = float((high - low).max()) or 1.0
    spec = structure.file.spec
    edges = structure.connectivity.edges if structure.connectivity is not None else ()
    drawn = [(a, b) for a, b in edges if a in row and b in row and a in positions and b in positions]
    segments = tuple(BarSegment(name=f"edges/{a}_{b}/0", bar_id=0, row_a=row[a], row_b=row[b], s0=0.0, s1=1.0,
                                  radius_m=EDGE_RADIUS_FRACTION * length,
                                  component=spec.component_of(a, b) or "other") for a, b in drawn)
    on_edge = {g for pair in drawn for g in pair}
    spheres = tuple(MassBody(name=f"grids/{g}", row=row[g], radius_m=GRID_RADIUS_FRACTION * length,
                              component=spec.component_of(g) or "other") for g in known if g not in on_edge)
    return Scene(positions_m=xyz, grid_ids=tuple(grids), segments=segments, masses=spheres,
                      centre_m=0.5 * (low + high), extent_m=high - low, length_m=length)
