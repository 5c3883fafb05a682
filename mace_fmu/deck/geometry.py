"""Coordinate systems, grid positions and bar orientation vectors in NASTRAN's basic system."""

from __future__ import annotations

import numpy as np

from mace_fmu.deck.cards import CBar, Cord2R, Deck
from mace_fmu.errors import DeckError

Frame = tuple[np.ndarray, np.ndarray]  #: (origin (3,), R (3, 3) with the unit axes as columns)

_COLLINEAR_TOL = 1e-12  #: relative size of |AB x AC| below which C counts as lying on the line AB


def axes_from_points(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """CORD2R axes as columns [x y z]: z along A->B, x in the plane of A, B, C; ValueError if degenerate."""
    z = b - a
    ac = c - a
    if np.linalg.norm(z) <= _COLLINEAR_TOL * max(np.linalg.norm(a), np.linalg.norm(b)):
        raise ValueError("points A and B coincide (expected B on the z-axis, away from the origin A)")
    if np.linalg.norm(np.cross(z, ac)) <= _COLLINEAR_TOL * np.linalg.norm(z) * np.linalg.norm(ac):
        raise ValueError("point C lies on the line AB (expected C off the z-axis, in the x-z plane)")
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


def coordinate_frames(deck: Deck) -> dict[int, Frame]:
    """Origin and axes in basic of system 0 and every CORD2R (DeckError for a bad RID chain)."""
    frames: dict[int, Frame] = {0: (np.zeros(3), np.eye(3))}
    for start in deck.coords:
        chain: list[int] = []
        cid = start
        while cid not in frames:
            if cid in chain:
                loop = " -> ".join(str(i) for i in chain[chain.index(cid):] + [cid])
                src = deck.coords[cid].source
                raise DeckError(f"RID chain {loop} is a cycle (expected a chain that ends at the basic system 0)",
                                file=src.file, line=src.line, card=f"CORD2R {cid}", field="field 3 (RID)")
            if cid not in deck.coords:
                src = deck.coords[chain[-1]].source
                raise DeckError(f"coordinate system {cid} is not defined (expected 0 or a CORD2R ID)",
                                file=src.file, line=src.line, card=f"CORD2R {chain[-1]}", field="field 3 (RID)")
            chain.append(cid)
            cid = deck.coords[cid].rid
        # Parents are resolved before children, so each frame needs only its RID's frame.
        for cid in reversed(chain):
            frames[cid] = _frame(deck.coords[cid], frames[deck.coords[cid].rid])
    return frames


def grid_positions(deck: Deck, frames: dict[int, Frame] | None = None) -> dict[int, np.ndarray]:
    """Position in basic of every grid: origin_cp + R_cp @ xyz (CP systems must exist)."""
    frames = coordinate_frames(deck) if frames is None else frames
    return {gid: frames[g.cp][0] + frames[g.cp][1] @ np.asarray(g.xyz, dtype=float)
            for gid, g in deck.grids.items()}


def bar_orientation(deck: Deck, bar: CBar, positions: dict[int, np.ndarray],
                    frames: dict[int, Frame]) -> np.ndarray:
    """Orientation vector of ``bar`` (CBAR or CBEAM) in basic: R_cd(GA) @ v (v itself for OFFT B..), or
    pos[G0] - pos[GA]."""
    if bar.g0 is not None:
        return positions[bar.g0] - positions[bar.ga]
    assert bar.v is not None
    if getattr(bar, "orientation_basic", False):  # OFFT B..
        return np.asarray(bar.v, dtype=float)
    return frames[deck.grids[bar.ga].cd][1] @ np.asarray(bar.v, dtype=float)
