"""Parsers of the constraint cards: MPC equations, SPC and SPC1 fixed DOFs, and SPCADD/MPCADD set unions.

Field layouts and defaults are those of the cards' entries in the MSC Nastran Quick Reference Guide (QRG).
"""

from __future__ import annotations

from dataclasses import dataclass

from mace_fmu.deck.cards import Mpc, MpcTerm, SetUnion, Source, Spc1
from mace_fmu.deck.fields import Fields


def mpc(f: Fields, src: Source) -> Mpc:
    """MPC (QRG): SID G1 C1 A1 G2 C2 A2, then two G C A terms per continuation; the first is the dependent DOF."""
    sid = f.ident(1, "SID")
    terms: list[MpcTerm] = []
    for base in range(0, max(len(f), 8), 8):
        if base:
            f.blank(base + 1, "unused")
        for d in (base + 2, base + 5):
            texts = (f.text(d), f.text(d + 1), f.text(d + 2))
            if not any(texts):
                continue
            k = len(terms) + 1
            for offset, what in enumerate(("grid", "component", "coefficient")):
                if not texts[offset]:
                    raise f.error(f"MPC term {k} is incomplete: {what} blank (expected G, C and A)", d + offset,
                                  f"{'GCA'[offset]}{k}")
            terms.append(MpcTerm(grid=f.integer(d, f"G{k}", minimum=1), component=f.component(d + 1, f"C{k}"),
                                 coefficient=f.real(d + 2, f"A{k}")))
        f.blank(base + 8, "unused")
    if not terms:
        raise f.error("MPC has no terms (expected G1 C1 A1 ...)", 2, "G1")
    if terms[0].coefficient == 0.0:
        raise f.error("the dependent term has coefficient 0.0 (expected a non-zero A1)", 4, "A1")
    return Mpc(sid=sid, terms=tuple(terms), source=src)


@dataclass(frozen=True)
class Thru:
    """SPC1 in the G1 THRU G2 form; grids are filled in once all GRIDs are known."""

    card: Spc1
    first: int
    last: int


def spc1(f: Fields, src: Source) -> Spc1 | Thru:
    """SPC1 (QRG): SID C G1 G2 ..., or SID C G1 THRU G2 (a Thru, filled in once all grids are known)."""
    sid = f.ident(1, "SID")
    comps = f.components(2, "C")
    if f.text(4).upper() == "THRU":
        first, last = f.integer(3, "G1", minimum=1), f.integer(5, "G2", minimum=1)
        f.end(5)
        if last < first:
            raise f.error(f"G2 = {last} is below G1 = {first} (expected G1 THRU G2 with G1 <= G2)", 5, "G2")
        return Thru(Spc1(sid=sid, components=comps, grids=(), source=src), first, last)
    grids = tuple(f.integer(d, f"G{d - 2}", minimum=1) for d in range(3, len(f) + 1) if f.text(d))
    if not grids:
        raise f.error("no grids listed (expected G1 ...)", 3, "G1")
    return Spc1(sid=sid, components=comps, grids=grids, source=src)


def spc(f: Fields, src: Source) -> tuple[Spc1, ...]:
    """SPC: up to two (grid, components, enforced value) triples; a fixed DOF only (the value must be 0),
    stored as SPC1 entries of the same set."""
    sid = f.ident(1, "SID")
    out = []
    for k, d in enumerate((2, 5), start=1):
        if not f.text(d):
            if k == 1:
                raise f.error("no grid (expected G1 C1 D1)", 2, "G1")
            continue
        grid = f.integer(d, f"G{k}", minimum=1)
        comps = f.components(d + 1, f"C{k}")
        if f.real(d + 2, f"D{k}", 0.0) != 0.0:
            raise f.error("an enforced displacement is not supported (expected D blank or 0.0: a fixed DOF)",
                          d + 2, f"D{k}")
        out.append(Spc1(sid=sid, components=comps, grids=(grid,), source=src))
    f.end(7)
    return tuple(out)


def spcadd(f: Fields, src: Source) -> SetUnion:
    """SPCADD / MPCADD (QRG): SID S1 S2 ...: the union of the listed sets."""
    sid = f.ident(1, "SID")
    sets = tuple(f.integer(d, f"S{d - 1}", minimum=1) for d in range(2, len(f) + 1) if f.text(d))
    if not sets:
        raise f.error("no sets listed (expected S1 ...)", 2, "S1")
    if sid in sets:
        k = sets.index(sid)
        raise f.error(f"set {sid} lists itself (expected other set IDs)", 2 + k, f"S{k + 1}")
    return SetUnion(sid=sid, card=f.raw.name, sets=sets, source=src)
