"""NASTRAN bulk-data deck: the card records and the strict reader."""

from mace_fmu.deck.cards import (CBar, Celas2, Conm2, Cord2R, Deck, Eigrl, Grav, Grid, Load, Mat1, Mpc, MpcTerm,
                                 Nlparm, Param, PBar, Source, Spc1, Subcase)
from mace_fmu.deck.reader import read_deck, read_deck_text
from mace_fmu.errors import DeckError

__all__ = ["CBar", "Celas2", "Conm2", "Cord2R", "Deck", "DeckError", "Eigrl", "Grav", "Grid", "Load", "Mat1", "Mpc",
           "MpcTerm", "Nlparm", "Param", "PBar", "Source", "Spc1", "Subcase", "read_deck", "read_deck_text"]
