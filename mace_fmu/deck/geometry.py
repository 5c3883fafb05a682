"""Coordinate systems, grid positions and bar orientation vectors in NASTRAN's basic system."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mace_fmu.deck.cards import CBar, CBeam, Cord1R, Cord2R, Deck
from mace_fmu.errors import DeckError, MaceError

Frame = tuple[np.ndarray, np.ndarray]  #: (origin (3,), R (3, 3) with the unit axes as columns)

_COLLINEAR_TOL = 1e-12  #: relative size of |AB x AC| below which C counts as lying on the line AB


def axes_from_points(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """CORD2R axes as columns [x y z]: z along A->B, x in the plane of A, B, C; MaceError if degenerate."""
    z = b - a
    ac = c - a
    if np.linalg.norm(z) <= _COLLINEAR_TOL * max(np.linalg.norm(a), np.linalg.norm(b)):
        raise MaceError("points A and B coincide (expected B on the z-axis, away from the origin A)")
    if np.linalg.norm(np.cross(z, ac)) <= _COLLINEAR_TOL * np.linalg.norm(z) * np.linalg.norm(ac):
        raise MaceError("point C lies on the line AB (expected C off the z-axis, in the x-z plane)")
    z = z / np.linalg.norm(z)
    x = ac - (ac @ z) * z
    x = x / np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _frame(card: Cord2R, parent: Frame) -> Frame:
    origin, rot = parent
    a, b, c = (origin + rot @ np.asarray(p, dtype=float) for p in (card.a, card.b, card.c))
    try:
        return a, axes_from_points(a, b, c)
    except ValueError as exc:
        raise DeckError(str(exc), file=card.source.file, line=card.source.line, card=f"CORD2R {card.id}",
                        field="field 4 to continuation 1 field 4 (A, B, C)") from None


def _cord1r_frame(card: Cord1R, frames: dict[int, Frame], deck: Deck) -> Frame | None:
    """CORD1R axes from its three grids (origin G1, z towards G2, G3 in the x-z plane), or None while a grid's
    CP system is not known yet."""
    points = []
    for k, (name, gid) in enumerate((("G1", card.g1), ("G2", card.g2), ("G3", card.g3)), start=1):
        grid = deck.grids.get(gid)
        if grid is None:
            raise DeckError(f"grid {gid} is not defined (expected a GRID ID)", file=card.source.file,
                            line=card.source.line, card=f"CORD1R {card.id}",
                            field=f"field {card.field + k} ({name})")
        if grid.cp not in frames:
            if grid.cp not in deck.coords:
                raise DeckError(f"coordinate system {grid.cp} is not defined (expected 0 or a CORD2R or CORD1R ID)",
                                file=grid.source.file, line=grid.source.line, card=f"GRID {grid.id}",
                                field="field 3 (CP)")
            return None
        origin, rot = frames[grid.cp]
        points.append(origin + rot @ np.asarray(grid.xyz, dtype=float))
    try:
        return points[0], axes_from_points(*points)
    except ValueError as exc:
        raise DeckError(str(exc).replace("points A and B", "grids G1 and G2").replace("point C", "grid G3")
                        .replace("line AB", "line G1-G2"), file=card.source.file, line=card.source.line,
                        card=f"CORD1R {card.id}",
                        field=f"fields {card.field + 1}-{card.field + 3} (G1, G2, G3)") from None


def coordinate_frames(deck: Deck) -> dict[int, Frame]:
    """Origin and axes in basic of system 0 and every CORD2R and CORD1R (DeckError for a bad RID chain or
    a CORD1R whose grids are given in a system that depends on it)."""
    frames: dict[int, Frame] = {0: (np.zeros(3), np.eye(3))}
    pending = sorted(deck.coords)
    while pending:  # a CORD1R needs the CP systems of its grids, a CORD2R its RID: resolve in rounds
        waiting = []
        for cid in pending:
            card = deck.coords[cid]
            if isinstance(card, Cord1R):
                frame = _cord1r_frame(card, frames, deck)
                if frame is None:
                    waiting.append(cid)
                else:
                    frames[cid] = frame
            elif card.rid in frames:
                frames[cid] = _frame(card, frames[card.rid])
            else:
                waiting.append(cid)
        if len(waiting) == len(pending):
            _unresolved(deck, waiting)
        pending = waiting
    return frames


def _unresolved(deck: Deck, waiting: list[int]) -> None:
    """The DeckError for systems that can never be resolved: a missing RID, an RID cycle, or a CORD1R cycle."""
    for start in waiting:
        card = deck.coords[start]
        if isinstance(card, Cord1R):
            continue
        chain: list[int] = []
        cid = start
        while cid in deck.coords and not isinstance(deck.coords[cid], Cord1R):
            if cid in chain:
                loop = " -> ".join(str(i) for i in chain[chain.index(cid):] + [cid])
                src = deck.coords[cid].source
                raise DeckError(f"RID chain {loop} is a cycle (expected a chain that ends at the basic system 0)",
                                file=src.file, line=src.line, card=f"CORD2R {cid}", field="field 3 (RID)")
            chain.append(cid)
            cid = deck.coords[cid].rid  # type: ignore[union-attr]
        if cid not in deck.coords and cid != 0:
            src = deck.coords[chain[-1]].source
            raise DeckError(f"coordinate system {cid} is not defined (expected 0 or a CORD2R or CORD1R ID)",
                            file=src.file, line=src.line, card=f"CORD2R {chain[-1]}", field="field 3 (RID)")
    card = next(c for c in (deck.coords[i] for i in waiting) if isinstance(c, Cord1R))
    raise DeckError("the grids G1, G2, G3 are given in coordinate systems that depend on this one (expected grids "
                    "whose CP systems do not need it)", file=card.source.file, line=card.source.line,
                    card=f"CORD1R {card.id}", field=f"fields {card.field + 1}-{card.field + 3} (G1, G2, G3)")


def grid_positions(deck: Deck, frames: dict[int, Frame] | None = None) -> dict[int, np.ndarray]:
    """Position in basic of every grid: origin_cp + R_cp @ xyz (CP systems must exist)."""
    frames = coordinate_frames(deck) if frames is None else frames
    return {gid: frames[g.cp][0] + frames[g.cp][1] @ np.asarray(g.xyz, dtype=float)
            for gid, g in deck.grids.items()}


def bar_orientation(deck: Deck, bar: CBar | CBeam, positions: dict[int, np.ndarray],
                    frames: dict[int, Frame]) -> np.ndarray:
    """Orientation vector of ``bar`` (CBAR or CBEAM) in basic: R_cd(GA) @ v (v itself for OFFT B..), or
    pos[G0] - pos[GA] (:func:`bar_orientations` of the one bar)."""
    vector: np.ndarray = bar_orientations(deck, [bar], positions, frames)[0]
    return vector


def bar_orientations(deck: Deck, bars: Sequence[CBar | CBeam], positions: dict[int, np.ndarray],
                     frames: dict[int, Frame]) -> np.ndarray:
    """Orientation vector in basic of every bar of ``bars`` (CBAR or CBEAM), all at once (a 100k-DOF lattice has
    78k): R_cd(GA) @ v, v itself for OFFT B.., or pos[G0] - pos[GA]; (n, 3)."""
    out = np.zeros((len(bars), 3))
    if not bars:
        return out
    by_grid = np.array([b.g0 is not None for b in bars])
    if by_grid.any():
        chosen = [(b.g0, b.ga) for b, g in zip(bars, by_grid) if g and b.g0 is not None]
        out[by_grid] = (np.array([positions[g0] for g0, _ in chosen]) - np.array([positions[ga] for _, ga in chosen]))
    rest = np.flatnonzero(~by_grid)
    if rest.size:
        vectors = np.array([bars[i].v for i in rest.tolist()], dtype=float)
        # OFFT B..: the vector is in basic; otherwise in GA's displacement system, one rotation per system
        system = np.array([-1 if getattr(bars[i], "orientation_basic", False) else deck.grids[bars[i].ga].cd
                           for i in rest.tolist()])
        for cd in np.unique(system):
            mine = system == cd
            out[rest[mine]] = vectors[mine] if cd == -1 else vectors[mine] @ frames[int(cd)][1].T
    return out
