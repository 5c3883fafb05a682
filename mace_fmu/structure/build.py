"""The 1-g (suspended) and 0-g (suspension removed) structures of one deck.

The 1-g structure is the deck as NASTRAN reads it: a gravity preload subcase, then the modes about
the preloaded state. The 0-g structure removes the suspension the structure file names (never a
default borrowed from another deck). Parameter overrides replace card fields with checked values.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from mace_fmu.deck.card_tables import CARD_TABLES, ELEMENT_TABLES
from mace_fmu.deck.cards import Deck, Subcase
from mace_fmu.deck.checks import check_deck
from mace_fmu.errors import DeckError, MaceError
from mace_fmu.structure.file import (Configuration, StructureFile, StructureSpec, _ids_text,
                                     check_instruments_against_deck, check_parameters_against_deck,
                                     check_spec_against_deck, structure_file_for)


@dataclass(frozen=True)
class Structure:
    """One analysable structure: its deck, its preload subcase (1-g only) and its modal subcase."""

    configuration: Configuration  #: "1g" (suspended, preloaded) or "0g" (free)
    deck: Deck  #: the deck of this structure (0-g: without the suspension)
    preload: Subcase | None  #: SPC/MPC/LOAD/NLPARM of the static preload; None for 0-g
    modal: Subcase  #: SPC/MPC of the eigen-solution
    spec: StructureSpec  #: empty when the deck has no structure file
    file: StructureFile | None = None  #: the structure file, None for a deck on its own


#: card -> Deck table of the cards an override may change (a subset of the deck's one card-to-table map)
_OVERRIDE_TABLES = {card: CARD_TABLES[card]
                    for card in ("GRID", "CBAR", "PBAR", "MAT1", "CONM2", "CELAS2", "CORD2R", "GRAV")}


def _checked_value(card: str, cid: int, name: str, old: Any, new: Any) -> Any:
    """``new`` converted to the type of the field it replaces, or a MaceError saying what was expected."""
    def is_number(x: Any) -> bool:
        return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)

    if isinstance(old, tuple):
        if not isinstance(new, (tuple, list)) or len(new) != len(old) or not all(is_number(x) for x in new):
            raise MaceError(f"override of {card} {cid}: field {name!r} takes {len(old)} numbers, got {new!r}")
        return tuple(float(x) if isinstance(o, float) else x for x, o in zip(new, old))
    if isinstance(old, bool) or isinstance(old, str):
        if type(new) is not type(old):
            raise MaceError(f"override of {card} {cid}: field {name!r} takes a {type(old).__name__}, got {new!r}")
        return new
    if isinstance(old, int):
        if not isinstance(new, (int, np.integer)) or isinstance(new, bool):
            raise MaceError(f"override of {card} {cid}: field {name!r} takes an integer ID, got {new!r}")
        return int(new)
    if new is None or is_number(new):  # real fields, possibly blank (None)
        return None if new is None else float(new)
    raise MaceError(f"override of {card} {cid}: field {name!r} takes a real number, got {new!r}")


def apply_overrides(deck: Deck, overrides: Mapping[tuple[str, int], Mapping[str, Any]]) -> Deck:
    """Deck with card fields replaced, e.g. {("MAT1", 2): {"e": 2.4e9}, ("PBAR", 1): {"k1": 0.55}}.

    Values are type-checked against the fields they replace, and the changed deck gets the
    reader's cross-reference and geometry checks; any problem is a MaceError (a ValueError)
    naming the override.

    Parameters
    ----------
    deck : Deck
        The deck.
    overrides : mapping
        (card, ID) -> {field: value}.

    Returns
    -------
    Deck
        A changed copy, cross-referenced and checked as the reader checks a deck.

    Raises
    ------
    MaceError
        A card or field the deck lacks, or a value of the wrong type.
    """
    if not overrides:
        return deck
    tables = {name: dict(getattr(deck, attr)) for name, attr in _OVERRIDE_TABLES.items()}
    for (card, cid), fields in overrides.items():
        if card not in tables:
            raise MaceError(f"override of unknown card type {card!r}; allowed: {sorted(tables)}")
        if cid not in tables[card]:
            raise MaceError(f"override of {card} {cid}: no such card in {deck.path}; {card} IDs there: "
                             f"{_ids_text(list(tables[card]))}")
        old = tables[card][cid]
        allowed = {f.name for f in dataclasses.fields(old)} - {"id", "source"}
        unknown = set(fields) - allowed
        if unknown:
            raise MaceError(f"override of {card} {cid}: unknown field(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
        values = {k: _checked_value(card, cid, k, getattr(old, k), v) for k, v in fields.items()}
        tables[card][cid] = dataclasses.replace(old, **values)
    changed_tables: dict[str, Any] = {attr: tables[name] for name, attr in _OVERRIDE_TABLES.items()}
    changed = dataclasses.replace(deck, **changed_tables)
    try:
        check_deck(changed)
    except DeckError as exc:
        raise MaceError(f"overrides {dict(overrides)} make the deck invalid: {exc}") from None
    return changed


def remove_suspension(deck: Deck, spec: StructureSpec) -> Deck:
    """The deck without the suspension: its grids, elements, MPC equations and SPC entries.

    Parameters
    ----------
    deck : Deck
        The 1-g deck.
    spec : StructureSpec
        The structure file's suspension: grids, elements, MPC and SPC IDs.

    Returns
    -------
    Deck
        A copy without them (the deck itself when the structure file names no suspension).
    """
    gone_g, gone_e = spec.suspension_grids, spec.suspension_elements
    if not gone_g and not gone_e:  # no suspension: the deck as it is (0.04-0.08 s on the 100k-DOF wide lattice)
        return deck
    kept: dict[str, Any] = {}
    for table in ELEMENT_TABLES:
        what, grids_of = _CONNECTIONS[table]
        cards = {i: c for i, c in getattr(deck, table).items() if i not in gone_e}
        for card in cards.values():
            dangling = [g for g in grids_of(card) if g in gone_g]
            if dangling:
                raise DeckError(f"connects suspension grid(s) {dangling} but is not listed as a suspension element in "
                                f"{spec.source} (expected every element on a suspension grid listed there)",
                                file=card.source.file, line=card.source.line, card=f"{what(card)} {card.id}")
        kept[table] = cards
    mpcs = {sid: tuple(e for e in eqs if not any(t.grid in gone_g for t in e.terms)) for sid, eqs in deck.mpcs.items()}
    spc1s = {sid: tuple(dataclasses.replace(c, grids=tuple(g for g in c.grids if g not in gone_g)) for c in cards)
             for sid, cards in deck.spc1s.items()}
    return dataclasses.replace(
        deck, grids={i: g for i, g in deck.grids.items() if i not in gone_g}, mpcs=mpcs,
        spc1s={sid: tuple(c for c in cards if c.grids) for sid, cards in spc1s.items()}, **kept)


#: Deck table -> (card name of an entry, the grids an entry connects): the 0-g structure drops the suspension's
#: elements of every kind, and refuses one left on a removed grid
_CONNECTIONS: dict[str, tuple[Callable[[Any], str], Callable[[Any], tuple[int, ...]]]] = {
    "bars": (lambda c: "CBAR", lambda c: (c.ga, c.gb)),
    "conm2s": (lambda c: "CONM2", lambda c: (c.grid,)),
    "celas2s": (lambda c: "CELAS2", lambda c: (c.g1, c.g2)),
    "beams": (lambda c: "CBEAM", lambda c: (c.ga, c.gb)),
    "rods": (lambda c: c.card, lambda c: (c.ga, c.gb)),
    "scalar_masses": (lambda c: c.card, lambda c: (c.g1, c.g2)),
    "conm1s": (lambda c: "CONM1", lambda c: (c.grid,)),
    "rigids": (lambda c: c.card, lambda c: (c.independent, *(g for g, _ in c.dependent))),
    "interpolations": (lambda c: "RBE3", lambda c: (c.reference, *(g for _, _, grids in c.groups for g in grids))),
}


def _subcases(deck: Deck) -> tuple[Subcase | None, Subcase]:
    """(preload subcase = first with a LOAD, modal subcase = last) from the deck's case control."""
    cases = [deck.subcases[k] for k in sorted(deck.subcases)] or ([deck.global_case] if deck.global_case else [])
    if not cases:
        raise DeckError("no case control: cannot tell which SPC/MPC sets to use (expected CEND, SUBCASEs selecting "
                        "SPC, MPC and LOAD, then BEGIN BULK)", file=deck.path, line=1)
    preload = next((c for c in cases if c.load is not None), None)
    return preload, cases[-1]


def build_structure(deck: Deck, *, configuration: Configuration, spec: StructureSpec | None = None,
                    overrides: Mapping[tuple[str, int], Mapping[str, Any]] | None = None,
                    structure_file: StructureFile | str | os.PathLike[str] | None = None) -> Structure:
    """The 1-g structure (deck as is, preload subcase + modal subcase) or the 0-g structure.

    Parameters
    ----------
    deck : Deck
        The NASTRAN deck.
    configuration : {"1g", "0g"}
        The suspended, gravity-preloaded structure or the free one.
    spec : StructureSpec, optional
        Replaces the structure file's structure part (e.g. ``StructureSpec.empty()``).
    overrides : mapping, optional
        (card, ID) -> {field: value} changes applied to a copy of the deck (e.g. a modulus).
    structure_file : StructureFile or path, optional
        The structure file; default: the bundled one for the bundled deck, else none: then 0-g is the
        deck's own modal subcase with nothing removed (NASTRAN's SOL 103) and 1-g adds the gravity
        preload of its LOAD subcase.

    Returns
    -------
    Structure
        The deck to analyse, its subcases (preload and modal) and the structure file it came from.

    Raises
    ------
    MaceError
        An unknown configuration, a structure file naming IDs the deck lacks, a 1-g structure without a gravity
        subcase.
    """
    if configuration not in ("1g", "0g"):
        raise MaceError(f"configuration must be '1g' or '0g', got {configuration!r}")
    file = structure_file_for(deck, structure_file)
    if file is not None and file.has("modes"):
        raise MaceError(f"{file.path}: its [modes] table points at NASTRAN's modes, not at the deck {deck.path}: build "
                        "the model from those modes (modal_structure(structure_file); CLI configuration 'modes')")
    spec = spec if spec is not None else (file.spec if file is not None else StructureSpec.empty())
    check_spec_against_deck(spec, deck)
    if file is not None:
        check_parameters_against_deck(file, deck)  # the deck as read: a suspension spring is named for 1-g and 0-g
    deck = apply_overrides(deck, overrides or {})
    preload, modal = _subcases(deck)
    if configuration == "1g":
        if preload is None:
            raise DeckError("the 1-g structure needs a subcase with a LOAD (gravity preload); none of the subcases "
                            "selects one (expected LOAD = set ID in the preload subcase; for the deck's plain modes "
                            "ask for the 0-g structure)", file=deck.path,
                            line=modal.source.line, card=f"SUBCASE {modal.id}" if modal.id else "global case control")
        if file is not None:
            check_instruments_against_deck(file, deck, configuration=configuration)
        return Structure(configuration=configuration, deck=deck, preload=preload, modal=modal, spec=spec, file=file)
    free = remove_suspension(deck, spec)
    if file is not None:
        check_instruments_against_deck(file, free, configuration=configuration)
    return Structure(configuration=configuration, deck=free, preload=None, modal=modal, spec=spec, file=file)
