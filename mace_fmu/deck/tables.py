"""The table builder: bulk cards parsed into the Deck's tables, keyed by ID, with duplicates refused.

Cards that change neither mass nor stiffness are read past and reported; any other card mace-fmu cannot
model is an error, all of them listed at once. GRDSET defaults reach the GRIDs, CELAS1 and PELAS become
CELAS2, SPC becomes SPC1 entries, SPC1 THRU ranges take the grids that exist, and SPCADD/MPCADD sets are
merged.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from mace_fmu.deck.card_tables import CARD_TABLES
from mace_fmu.deck.cards import Celas2, SetUnion, Source
from mace_fmu.deck.fields import Fields, RawCard
from mace_fmu.deck.parsers import PARSERS
from mace_fmu.deck.parsers.constraints import Thru
from mace_fmu.deck.parsers.grids import grdset, grid
from mace_fmu.errors import DeckError

__all__ = ["AERODYNAMIC", "CARD_TABLES", "NON_STRUCTURAL", "bulk_tables"]


#: static loads, whose set a case control's LOAD (or a LOAD card) may select: read past, named in messages
STATIC_LOADS = frozenset({"FORCE", "FORCE1", "FORCE2", "MOMENT", "MOMENT1", "MOMENT2", "PLOAD", "PLOAD1", "PLOAD2",
                          "PLOAD4"})
#: the aeroelastic bulk data of NASTRAN's SOL 144-146 (MSC Nastran Quick Reference Guide, the aeroelastic
#: entries): aerodynamic panels and their properties, splines to the structure, flight conditions, control
#: surfaces, flutter and gust data, monitor points. None changes the structure's mass or stiffness, so every
#: one is read past: the refusal of the cards a reader cannot model says so, and must never list one of them
AERODYNAMIC = frozenset({
    "AECOMP", "AECOMPL", "AECONFIG", "AEDW", "AEFACT", "AEFORCE", "AELINK", "AELIST", "AEPARM", "AEPRESS", "AERO",
    "AEROS", "AESCALE", "AESTAT", "AESURF", "AESURFS", "AESYMXY", "AESYMXZ", "CAERO1", "CAERO2", "CAERO3", "CAERO4",
    "CAERO5", "CSSCHD", "DIVERG", "FLFACT", "FLUTTER", "GUST", "MKAERO1", "MKAERO2", "MONDSP1", "MONPNT1", "MONPNT2",
    "MONPNT3", "PAERO1", "PAERO2", "PAERO3", "PAERO4", "PAERO5", "SPLINE1", "SPLINE2", "SPLINE3", "SPLINE4",
    "SPLINE5", "SPLINE6", "SPLINE7", "SPLINRB", "TRIM", "TRIM2", "UXVEC",
})
#: cards that change neither mass nor stiffness (loads, frequencies, output sets, aerodynamics, ...): read
#: past and reported, never an error; any other card we cannot model is one
NON_STRUCTURAL = STATIC_LOADS | AERODYNAMIC | frozenset({
    "USET", "USET1", "TEMP", "TEMPD", "DAREA", "DLOAD", "RLOAD1", "RLOAD2", "TLOAD1", "TLOAD2", "TABLED1", "TABLED2",
    "TABLED3", "TABLED4", "FREQ", "FREQ1", "FREQ2", "FREQ3", "FREQ4", "FREQ5", "TSTEP", "TSTEPNL", "RANDPS",
    "SET1", "SET2", "SET3", "DESVAR", "DRESP1",
    "DCONSTR", "DVPREL1", "DOPTPRM", "EIGC", "TABDMP1", "PLOTEL", "ECHOOFF", "ECHOON",
    # SUPORT only names the DOFs along which NASTRAN's modal solution computes the rigid-body modes (printed as
    # 0.0 Hz); with a statically determinate set, as NASTRAN requires, the elastic modes are those of the
    # unsupported structure, which is what mace-fmu solves (its rigid-body modes come out near 0 Hz).
    "SUPORT", "SUPORT1",
    # random-response data of the aeroelastic solutions (gust and monitor points: AERODYNAMIC)
    "TABRND1",
    # a material's temperature dependence (MATT1 with its TABLEM1 tables) acts only where the case control
    # selects material temperatures, which the deck's check refuses beside a MATT1; a DTI is a table
    "MATT1", "TABLEM1", "DTI",
})


#: one element ID namespace in NASTRAN. CONM2 has its own: MSC Nastran ran HA144D with CBAR 100 and CONM2 100
#: (its sorted bulk echo is in the .f06 of tests/data/nastran/ha144ds), so a deck may reuse a CBAR's ID on a CONM2
_ELEMENTS = ("CBAR", "CELAS1", "CELAS2", "CBEAM", "CROD", "CONROD", "CMASS1", "CMASS2", "RBAR", "RBE2", "RBE3")


def bulk_tables(raw_cards: list[RawCard], file: str
                ) -> tuple[dict[str, dict[Any, Any]], tuple[tuple[str, int, str], ...]]:
    """Cards keyed by ID (MPC and SPC1 by set ID), with duplicates rejected, and the non-structural cards read past.

    Parameters
    ----------
    raw_cards : list of RawCard
        The bulk cards in deck order, INCLUDEs expanded.
    file : str
        The deck's name, for cards that do not carry their own file.

    Returns
    -------
    tables : dict
        Deck attribute -> its cards by ID (set tables: set ID -> tuple of cards), as keyword arguments of Deck.
    skipped : tuple
        (name, count, first ``file:line``) of each card read past, as ``Deck.skipped``.

    Raises
    ------
    DeckError
        A card mace-fmu cannot model (all of them listed at once), a malformed card, an ID defined twice or
        a set or property that is not defined.
    """
    tables: dict[str, dict[Any, Any]] = {attr: {} for attr in CARD_TABLES.values()}
    sets: dict[str, dict[int, list[Any]]] = {"mpcs": {}, "spc1s": {}}
    elements: dict[int, tuple[str, Any]] = {}
    thru: list[tuple[int, Thru]] = []
    unknown: dict[str, list[RawCard]] = {}
    skipped: dict[str, list[RawCard]] = {}
    for raw in raw_cards:
        if raw.name not in PARSERS:
            (skipped if raw.name in NON_STRUCTURAL else unknown).setdefault(raw.name, []).append(raw)
    if unknown:  # every card we cannot model, once each: card, count, first line
        raise _unknown_cards(unknown, file)
    grdsets = [raw for raw in raw_cards if raw.name == "GRDSET"]
    if len(grdsets) > 1:
        raise DeckError(f"GRDSET defined twice: line {grdsets[0].line} and line {grdsets[1].line} (expected at most "
                        "one)", file=grdsets[1].file or file, line=grdsets[1].line, card="GRDSET")
    defaults = grdset(Fields(grdsets[0], file), Source(grdsets[0].file or file, grdsets[0].line)) if grdsets \
        else (0, 0, "")
    celas1s: list[tuple[Any, Source]] = []
    pelas: dict[int, tuple[float, Source]] = {}
    unions: dict[str, dict[int, SetUnion]] = {"SPCADD": {}, "MPCADD": {}}
    for raw in raw_cards:
        if (raw.name in NON_STRUCTURAL and raw.name not in PARSERS) or raw.name == "GRDSET":
            continue
        parser = PARSERS[raw.name]
        src = Source(raw.file or file, raw.line)
        card: Any = grid(Fields(raw, file), src, defaults) if raw.name == "GRID" else parser(Fields(raw, file), src)
        if raw.name == "PELAS":
            for pid, k, where in card:
                if pid in pelas:
                    raise DeckError(f"PELAS {pid} defined twice: line {pelas[pid][1].line} and line {raw.line}",
                                    file=src.file, line=raw.line, card=f"PELAS {pid}")
                pelas[pid] = (k, where)
            continue
        if raw.name in unions:
            if card.sid in unions[raw.name]:
                raise DeckError(f"{raw.name} {card.sid} defined twice: line {unions[raw.name][card.sid].source.line} "
                                f"and line {raw.line}", file=src.file, line=raw.line, card=f"{raw.name} {card.sid}")
            unions[raw.name][card.sid] = card
            continue
        if raw.name == "CELAS1":
            eid = card[0]
            if eid in elements:
                kind, other = elements[eid]
                raise DeckError(f"element ID {eid} is used twice: {kind} at line {other.source.line} and CELAS1 at "
                                f"line {raw.line} ({', '.join(_ELEMENTS)} share one ID namespace)", file=src.file,
                                line=raw.line, card=f"CELAS1 {eid}")
            celas1s.append((card, src))
            elements[eid] = ("CELAS1", Celas2(id=eid, k=0.0, g1=card[2], c1=card[3], g2=card[4], c2=card[5],
                                             source=src))
            continue
        if raw.name == "SPC":  # one or two fixed DOFs: SPC1 entries of the same set
            for entry in card:
                sets["spc1s"].setdefault(entry.sid, []).append(entry)
            continue
        if raw.name in ("MPC", "SPC1"):
            sid = card.card.sid if isinstance(card, Thru) else card.sid
            group = sets["mpcs" if raw.name == "MPC" else "spc1s"].setdefault(sid, [])
            if isinstance(card, Thru):
                thru.append((len(group), card))
            group.append(card)
            continue
        for one in card if raw.name in ("PMASS", "CORD1R") else (card,):  # several on one card
            _store(raw, one, tables, elements, file)
    _resolve_thru(tables, sets, thru, file)
    for (eid, pid, g1, c1, g2, c2), src in celas1s:  # CELAS1 + PELAS = CELAS2 (QRG)
        if pid not in pelas:
            raise DeckError(f"property {pid} is not defined (expected a PELAS ID)", file=src.file, line=src.line,
                            card=f"CELAS1 {eid}", field="field 3 (PID)")
        if eid in tables["celas2s"]:
            raise DeckError(f"element ID {eid} is used twice: CELAS2 at line {tables['celas2s'][eid].source.line} and "
                            f"CELAS1 at line {src.line}", file=src.file, line=src.line, card=f"CELAS1 {eid}")
        tables["celas2s"][eid] = Celas2(id=eid, k=pelas[pid][0], g1=g1, c1=c1, g2=g2, c2=c2, source=src)
    _union_sets(sets, unions)
    report = tuple((n, len(rs), f"{rs[0].file or file}:{rs[0].line}") for n, rs in sorted(skipped.items()))
    return {**tables, **{name: {sid: tuple(cards) for sid, cards in group.items()} for name, group in sets.items()},
            "static_loads": _static_load_sets(skipped)}, report


#: unknown card names a refusal lists before "and N more" (a deck of foreign elements has dozens)
_LISTED = 6


def _unknown_cards(unknown: dict[str, list[RawCard]], file: str) -> DeckError:
    """One refusal for every card the reader cannot model: each name once, with its count and first line, in a
    few lines; NASTRAN's replication lines ('=', '==', '*...') named as what they are."""
    ordered = sorted(unknown.items(), key=lambda t: (t[1][0].file or file, t[1][0].line))
    name, first = ordered[0][0], ordered[0][1][0]
    replication = [n for n, _ in ordered if n.startswith("=")]
    if replication:
        rs = unknown[replication[0]]
        return DeckError(f"a replication line {replication[0]!r} ({sum(len(unknown[n]) for n in replication)} in all; "
                         "NASTRAN's '=' and '==' shorthand for repeated cards): mace-fmu reads each card written out "
                         "(expected the cards in full, as NASTRAN's bulk-data echo prints them)",
                         file=rs[0].file or file, line=rs[0].line, card=replication[0])
    supported = ", ".join(sorted(PARSERS))
    if len(unknown) == 1 and len(unknown[name]) == 1:
        return DeckError(f"unknown card {name!r} (supported: {supported})", file=first.file or file,
                         line=first.line, card=name)

    def at(raw: RawCard) -> str:  # the deck's own lines by number; an INCLUDE file's by file and line
        return f"line {raw.line}" if (raw.file or file) == file else f"{raw.file}:{raw.line}"

    listed = ", ".join(f"{n} ({len(rs)}x, first at {at(rs[0])})" for n, rs in ordered[:_LISTED])
    more = f" and {len(ordered) - _LISTED} more" if len(ordered) > _LISTED else ""
    every = tuple(f"{n}: {len(rs)} card(s), first at {at(rs[0])}" for n, rs in ordered)
    return DeckError(f"cards this reader cannot model: {listed}{more} (supported: {supported}; cards that change "
                     "neither mass nor stiffness, such as loads and aerodynamic data, are read past)",
                     file=first.file or file, line=first.line, card=name, details=every)


def _static_load_sets(skipped: dict[str, list[RawCard]]) -> dict[int, tuple[str, ...]]:
    """Set ID -> names of the static-load cards read past (their SID is field 2), for LOAD selections."""
    out: dict[int, set[str]] = {}
    for name in STATIC_LOADS & set(skipped):
        for raw in skipped[name]:
            sid = raw.fields[0].strip() if raw.fields else ""
            if sid.isdigit():
                out.setdefault(int(sid), set()).add(name)
    return {sid: tuple(sorted(names)) for sid, names in sorted(out.items())}


def _store(raw: RawCard, card: Any, tables: dict[str, dict[Any, Any]], elements: dict[int, tuple[str, Any]],
           file: str) -> None:
    """Put ``card`` in its table, refusing a second card with its key (or its element ID)."""
    key = card.name if raw.name == "PARAM" else card.sid if hasattr(card, "sid") else card.id
    table = tables[CARD_TABLES[raw.name]]
    if key in table:
        # (PBAR and PBARL share one ID table, as do PBEAM and PBEAML, CROD and CONROD, CMASS1 and CMASS2)
        raise DeckError(f"{raw.name} {key} defined twice: line {table[key].source.line} and line {raw.line}",
                        file=raw.file or file, line=raw.line, card=f"{raw.name} {key}")
    if raw.name in _ELEMENTS:
        if key in elements:
            kind, other = elements[key]
            raise DeckError(f"element ID {key} is used twice: {kind} at line {other.source.line} and {raw.name} "
                            f"at line {raw.line} ({', '.join(_ELEMENTS)} share one ID namespace)",
                            file=raw.file or file, line=raw.line, card=f"{raw.name} {key}")
        elements[key] = (raw.name, card)
    table[key] = card


def _union_sets(sets: dict[str, dict[int, list[Any]]], unions: dict[str, dict[int, SetUnion]]) -> None:
    """SPCADD / MPCADD: the set is the union of the listed SPC1/SPC (MPC) sets, which must exist and may not
    themselves be SPCADD (MPCADD) sets (QRG)."""
    for name, table, what in (("SPCADD", "spc1s", "an SPC or SPC1 set ID"), ("MPCADD", "mpcs", "an MPC set ID")):
        for sid, card in unions[name].items():
            if sid in sets[table]:
                raise DeckError(f"set {sid} is both an {name} and a set of {'SPC/SPC1' if name == 'SPCADD' else 'MPC'} "
                                f"cards (expected a new set ID; first such card at line "
                                f"{sets[table][sid][0].source.line})", file=card.source.file, line=card.source.line,
                                card=f"{name} {sid}", field="field 2 (SID)")
        for sid, card in unions[name].items():
            merged: list[Any] = []
            for k, s in enumerate(card.sets, start=1):
                if s not in sets[table] or s in unions[name]:
                    raise DeckError(f"set {s} is not defined (expected {what})", file=card.source.file,
                                    line=card.source.line, card=f"{name} {sid}", field=f"S{k}")
                merged += sets[table][s]
            sets[table][sid] = merged


def _resolve_thru(tables: dict[str, dict[Any, Any]], sets: dict[str, dict[int, list[Any]]],
                  thru: list[tuple[int, Thru]], file: str) -> None:
    """MSC rule: grids of a THRU range that do not exist are skipped."""
    for index, item in thru:
        group = sets["spc1s"][item.card.sid]
        grids = tuple(g for g in sorted(tables["grids"]) if item.first <= g <= item.last)
        if not grids:
            raise DeckError(f"no GRID exists in {item.first} THRU {item.last} (expected at least one)", file=file,
                            line=item.card.source.line, card=f"SPC1 {item.card.sid}", field="fields 4-6 (G1 THRU G2)")
        group[index] = replace(item.card, grids=grids)
