"""Parsers of the cards that place grids: GRID, its GRDSET defaults, and the CORD2R and CORD1R systems."""

from __future__ import annotations

import numpy as np

from mace_fmu.deck.cards import Cord1R, Cord2R, Grid, Source
from mace_fmu.deck.fields import Fields
from mace_fmu.deck.geometry import axes_from_points
from mace_fmu.deck.parsers.layouts import two_groups, vec


def grid(f: Fields, src: Source, defaults: tuple[int, int, str] = (0, 0, "")) -> Grid:
    """GRID; blank CP, CD and PS take the GRDSET values ``defaults`` (QRG GRDSET), else 0, 0 and none."""
    gid = f.ident(1, "ID")
    cp = f.integer(2, "CP", defaults[0], minimum=0)
    xyz = vec(f, 3, ("X1", "X2", "X3"))
    cd = f.integer(6, "CD", defaults[1], minimum=0)
    ps = f.components(7, "PS", defaults[2])
    f.blank(8, "SEID")
    f.end(8)
    return Grid(id=gid, cp=cp, xyz=xyz, cd=cd, ps=ps, source=src)


def grdset(f: Fields, src: Source) -> tuple[int, int, str]:
    """GRDSET (QRG): defaults of GRID's CP (field 3), CD (field 7) and PS (field 8)."""
    f.blank(1, "unused")
    cp = f.integer(2, "CP", 0, minimum=0)
    for d in (3, 4, 5):
        f.blank(d, "unused")
    cd = f.integer(6, "CD", 0, minimum=0)
    ps = f.components(7, "PS", "")
    f.blank(8, "SEID")
    f.end(8)
    return cp, cd, ps


def cord2r(f: Fields, src: Source) -> Cord2R:
    """CORD2R (QRG): CID RID A1 A2 A3 B1 B2 B3; C1 C2 C3, three points that must span a plane."""
    cid = f.ident(1, "CID")
    rid = f.integer(2, "RID", 0, minimum=0)
    a, b, c = vec(f, 3, ("A1", "A2", "A3")), vec(f, 6, ("B1", "B2", "B3")), vec(f, 9, ("C1", "C2", "C3"))
    f.end(11)
    try:
        axes_from_points(np.array(a), np.array(b), np.array(c))
    except ValueError as exc:
        raise f.error(str(exc), 3, "A, B, C", 11) from None
    return Cord2R(id=cid, rid=rid, a=a, b=b, c=c, source=src)


def cord1r(f: Fields, src: Source) -> tuple[Cord1R, ...]:
    """CORD1R (QRG): up to two CIDi G1i G2i G3i groups."""
    out = []
    for k, d in two_groups(f, "CID1 G1A G2A G3A", "CIDA"):
        cid = f.integer(d, f"CID{'AB'[k - 1]}", minimum=1)
        f.label = f"CORD1R {cid}"
        grids = tuple(f.integer(d + i, f"G{i}{'AB'[k - 1]}", minimum=1) for i in (1, 2, 3))
        if len(set(grids)) < 3:
            raise f.error(f"grids {grids} are not three different grids", d + 1, "G1-G3", d + 3)
        out.append(Cord1R(id=cid, g1=grids[0], g2=grids[1], g3=grids[2], source=src, field=d + 1))
    f.end(8)
    return tuple(out)
