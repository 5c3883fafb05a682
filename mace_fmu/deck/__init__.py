"""NASTRAN bulk-data deck: the card records and the strict reader (imported on first use)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.deck.cards import (CBar, Celas2, Conm2, Cord2R, Deck, Eigrl, Grav, Grid, Load, Mat1, Mpc, MpcTerm,
                                     Nlparm, PBar, Param, Source, Spc1, Subcase)
    from mace_fmu.deck.reader import read_deck, read_deck_text
    from mace_fmu.errors import DeckError

_CARDS = ("CBar", "Celas2", "Conm2", "Cord2R", "Deck", "Eigrl", "Grav", "Grid", "Load", "Mat1", "Mpc", "MpcTerm",
          "Nlparm", "Param", "PBar", "Source", "Spc1", "Subcase")
__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    **{name: "cards" for name in _CARDS},
    "DeckError": "mace_fmu.errors",
    "read_deck": "reader",
    "read_deck_text": "reader",
})
