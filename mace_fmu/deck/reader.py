"""Strict reader for the subset of NASTRAN bulk data that mace-fmu understands: its two entry points.

Every problem is a DeckError pointing at ``file:line``, the card and the field; nothing is guessed.
Field positions follow fields.py: data field 1 is field 2 of a card's first line. The reader puts
together files.py (deck files, INCLUDEs), parsers/ (one module per card family), tables.py (cards into
the Deck's tables) and checks.py (cross references).
"""

from __future__ import annotations

import os

from mace_fmu.deck.cards import Deck
from mace_fmu.deck.checks import check_deck, check_selections
from mace_fmu.deck.fields import case_control, check_text, split_sections
from mace_fmu.deck.files import cards_with_includes, deck_file_text, without_begin_bulk
from mace_fmu.deck.tables import bulk_tables
from mace_fmu.errors import DeckError
from mace_fmu.util.collector import collector_paused


def read_deck(path: str | os.PathLike[str]) -> Deck:
    """Read and validate the NASTRAN bulk-data deck in file ``path`` (INCLUDE files relative to it).

    Parameters
    ----------
    path : str or path-like
        The deck (``.bdf``, ``.dat``, ``.nas``): free, small or large field.

    Returns
    -------
    Deck
        Every card we model as a frozen record, with the file and line it came from; cards that do not
        change mass or stiffness are read past and listed in ``Deck.skipped``.

    Raises
    ------
    DeckError
        With the file, line, card and field, and what was expected; every card we cannot model is
        listed at once.
    """
    return read_deck_text(deck_file_text(path), name=os.fspath(path))


def read_deck_text(text: str, *, name: str = "<string>") -> Deck:
    """Read and validate a deck given as text; ``name`` stands for the file in error messages.

    Parameters
    ----------
    text : str
        The bulk data (and case control) as a NASTRAN deck file would hold it.
    name : str
        What error messages call the text.

    Returns
    -------
    Deck
        The validated cards.

    Raises
    ------
    DeckError
        A malformed or inconsistent card: the message names ``name``, the line, the card and the field.
    """
    with collector_paused():  # hundreds of thousands of objects, none in a cycle (mace_fmu.util.collector)
        return _read(text, name)


def _read(text: str, name: str) -> Deck:
    # Split on newlines only, so that line numbers match what an editor shows.
    physical = text.removeprefix("\ufeff").split("\n")  # a byte-order mark, which some editors write
    if physical and physical[-1] == "":
        physical.pop()
    lines = [(number, line.rstrip("\r")) for number, line in enumerate(physical, start=1)]
    check_text(lines, name)
    case, bulk = split_sections(lines, name)
    global_case, subcases, selections = case_control(case, name) if case is not None else (None, {}, {})
    bulk = without_begin_bulk(bulk)
    raw_cards = cards_with_includes(bulk, name, stack=(os.path.abspath(name),))
    if not raw_cards:
        raise DeckError("no bulk data cards (expected GRID, CBAR and the other cards before ENDDATA)", file=name,
                        line=min(bulk[-1][0] + 1, lines[-1][0]) if bulk else lines[-1][0])
    tables, skipped = bulk_tables(raw_cards, name)
    deck = Deck(path=name, subcases=subcases, global_case=global_case, skipped=skipped, **tables)
    check_deck(deck)  # split from the selections check: decks changed in code (structure.build) go through it too
    check_selections(deck, selections)
    return deck
