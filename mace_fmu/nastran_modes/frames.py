"""Grid positions in basic and the axes of each grid's displacement (CD) system, from a results file's
GEOM1 tables or a deck's bulk data (CORD1R/C/S, CORD2R/C/S, any RID chain).

A cylindrical or spherical CD system's axes depend on where the grid is (NASTRAN measures a grid's
components along the local r, theta, z or r, theta, phi directions at the grid): they are evaluated at
each grid's position. Rectangular systems come from mace_fmu.deck.geometry's construction (axes from
points A, B, C).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from mace_fmu.deck.geometry import axes_from_points
from mace_fmu.errors import MaceError
from mace_fmu.nastran_modes.file_modes import CoordCard, FileGeometry


@dataclass(frozen=True)
class System:
    """A coordinate system resolved in basic: origin, rectangular axes (columns) and kind."""

    origin: npt.NDArray[np.float64]  #: (3,) [deck units]
    axes: npt.NDArray[np.float64]  #: (3, 3) unit x, y, z axes of its rectangular frame, as columns in basic
    kind: str  #: "R", "C" or "S"

    def to_basic(self, coordinates: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Basic position of a point given in this system (R: x, y, z; C: r, theta [deg], z; S: r, theta, phi)."""
        return self.origin + self.axes @ _local_cartesian(self.kind, np.asarray(coordinates, dtype=float))

    def axes_at(self, point: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """(3, 3) the system's component directions at the basic ``point``, as columns in basic."""
        if self.kind == "R":
            return self.axes
        x, y, z = self.axes.T @ (np.asarray(point, dtype=float) - self.origin)
        theta = np.arctan2(y, x)  # NASTRAN: theta = 0 on the axis itself
        c, s = np.cos(theta), np.sin(theta)
        if self.kind == "C":
            local = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], dtype=np.float64)
        else:
            polar = np.arctan2(np.hypot(x, y), z)
            cp, sp = np.cos(polar), np.sin(polar)
            local = np.array([[sp * c, cp * c, -s], [sp * s, cp * s, c], [cp, -sp, 0.0]], dtype=np.float64)
        return self.axes @ local


def _local_cartesian(kind: str, q: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    if kind == "R":
        return q
    if kind == "C":
        t = np.radians(q[1])
        return np.array([q[0] * np.cos(t), q[0] * np.sin(t), q[2]])
    t, p = np.radians(q[1]), np.radians(q[2])
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], dtype=np.float64) * float(q[0])


BASIC = System(origin=np.zeros(3), axes=np.eye(3), kind="R")


def resolve_geometry(source: Path, geometry: FileGeometry, *, where: str
                     ) -> tuple[dict[int, npt.NDArray[np.float64]], dict[int, tuple[int, System]]]:
    """(basic position of every grid, grid -> (CD, its system)) from the grids and systems of a results file's
    GEOM1 tables or of a deck (``source`` and ``where``, "table GEOM1" or "bulk data", name them in messages)."""
    systems: dict[int, System] = {0: BASIC}
    positions: dict[int, npt.NDArray[np.float64]] = {}

    def position(gid: int) -> npt.NDArray[np.float64] | None:
        if gid not in positions:
            cp, xyz, _ = geometry.grids[gid]
            if cp not in systems:
                return None
            positions[gid] = systems[cp].to_basic(np.array(xyz))
        return positions[gid]

    pending = sorted(geometry.coords)
    while pending:  # a system needs its RID (CORD2x) or its grids' CP systems (CORD1x): resolve in rounds
        waiting = [cid for cid in pending
                   if not _resolve(source, where, geometry.coords[cid], systems, position, geometry)]
        if len(waiting) == len(pending):
            raise MaceError(f"{source}: {where}: coordinate systems {waiting} cannot be resolved (expected "
                            "RID chains and CORD1 grids that end at the basic system 0)")
        pending = waiting
    for gid, (cp, _, cd) in geometry.grids.items():
        for name, cid in (("CP", cp), ("CD", cd)):
            if cid not in systems and cid >= 0:
                raise MaceError(f"{source}: {where}: GRID {gid}: {name} system {cid} is not defined (expected "
                                "0 or a CORD1x/CORD2x in the file)")
        position(gid)
    cds = {gid: (cd, systems[cd] if cd >= 0 else BASIC) for gid, (_, _, cd) in geometry.grids.items()}
    return positions, cds


def _resolve(source: Path, where: str, card: CoordCard, systems: dict[int, System],
             position: Callable[[int], npt.NDArray[np.float64] | None],
             geometry: FileGeometry) -> bool:
    """Add ``card`` to ``systems`` when what it depends on is known; False while it is not."""
    if card.points is not None:
        if card.rid not in systems:
            return False
        points = [systems[card.rid].to_basic(np.array(p)) for p in card.points]
    else:
        assert card.grids is not None
        points = []
        for gid in card.grids:
            if gid not in geometry.grids:
                raise MaceError(f"{source}: {where}: CORD1{card.kind} {card.id}: grid {gid} is not defined")
            p = position(gid)
            if p is None:
                return False
            points.append(p)
    try:
        axes = axes_from_points(*points)
    except ValueError as exc:
        raise MaceError(f"{source}: {where}: CORD{'2' if card.points else '1'}{card.kind} {card.id}: {exc}") from None
    systems[card.id] = System(origin=points[0], axes=axes, kind=card.kind)
    return True
