"""NASTRAN bulk-data deck: the card records and the strict reader (imported on first use)."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

_CARDS = ("CBar", "Celas2", "Conm2", "Cord2R", "Deck", "Eigrl", "Grav", "Grid", "Load", "Mat1", "Mpc", "MpcTerm",
          "Nlparm", "Param", "PBar", "Source", "Spc1", "Subcase")
__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    **{name: "cards" for name in _CARDS},
    "DeckError": "mace_fmu.errors",
    "read_deck": "reader",
    "read_deck_text": "reader",
})
