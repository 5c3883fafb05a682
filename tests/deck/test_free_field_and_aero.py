"""Decks NASTRAN takes: free-field lines longer than one card image, which NASTRAN continues
on implicit continuation images, and the aeroelastic cards, which change neither mass nor stiffness and are read
past, so that a refusal of the cards the reader cannot model never names one of them while saying they are read
past.

The reference for the free-field deck is the same deck in fixed fields, NASTRAN's own layout: a free-field line
is converted to 10-field card images (NASTRAN-95 User's Manual, 2.4.1.2; field 10 of an image is its
continuation field), so the long line must give every field the fixed-field deck gives.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mace_fmu.deck.reader import read_deck_text
from mace_fmu.deck.tables import AERODYNAMIC
from mace_fmu.errors import DeckError
from mace_fmu.fe.modes import compute_modes

CASE = "SOL 103\nCEND\nSPC = 1\nMETHOD = 1\nBEGIN BULK\n"

#: a cantilever of two bars whose PBAR has stress points (first continuation) and shear factors (second), and a
#: CBAR with its continuation written out (zero offsets), in NASTRAN's small fixed fields
FIXED = """GRID    1               0.0     0.0     0.0
GRID    2               0.5     0.0     0.0
GRID    3               1.0     0.0     0.0
MAT1    1       7.0+10          0.33    2700.0
PBAR    1       1       1.0-3   2.0-7   3.0-7   4.0-7   0.5
        0.02    0.02    -0.02   0.02    0.02    -0.02   -0.02   -0.02
        0.85    0.8
CBAR    1       1       1       2       0.0     1.0     0.0
                        0.0     0.0     0.0     0.0     0.0     0.0
CBAR    2       1       2       3       0.0     1.0     0.0
SPC1    1       123456  1
EIGRL   1                       4
"""

#: the same cards, each on one free-field line: 8 data fields, then fields 10 and 1 (continuation markers, blank
#: or '+'), then the next 8
FREE = """GRID,1,,0.0,0.0,0.0
GRID,2,,0.5,0.0,0.0
GRID,3,,1.0,0.0,0.0
MAT1,1,7.0+10,,0.33,2700.0
PBAR,1,1,1.0-3,2.0-7,3.0-7,4.0-7,0.5,,+P1,+P1,0.02,0.02,-0.02,0.02,0.02,-0.02,-0.02,-0.02,,,0.85,0.8
CBAR,1,1,1,2,0.0,1.0,0.0,,,,,,0.0,0.0,0.0,0.0,0.0,0.0
CBAR,2,1,2,3,0.0,1.0,0.0
SPC1,1,123456,1
EIGRL,1,,,4
"""


def _cards(deck, table: str) -> dict:
    """A deck's cards of one table without where they are written (one line in free field, several in fixed)."""
    return {k: dataclasses.replace(card, source=None) for k, card in getattr(deck, table).items()}


def test_a_free_field_line_longer_than_a_card_image_is_read_as_nastran_reads_it():
    """Free-field lines of 19 and 21 items were refused ('expected at most 8 data fields'): NASTRAN takes them."""
    fixed = read_deck_text(CASE + FIXED + "ENDDATA\n", name="fixed.bdf")
    free = read_deck_text(CASE + FREE + "ENDDATA\n", name="free.bdf")
    for name in ("pbars", "bars", "grids", "mat1s"):
        assert _cards(free, name) == _cards(fixed, name), name
    pbar = free.pbars[1]
    assert (pbar.k1, pbar.k2, pbar.nsm, pbar.stress_points[:2]) == (0.85, 0.8, 0.5, (0.02, 0.02))
    np.testing.assert_array_equal(compute_modes(free, configuration="0g").frequencies_hz,
                                  compute_modes(fixed, configuration="0g").frequencies_hz)


def test_a_datum_written_where_a_continuation_marker_belongs_is_refused_not_shifted():
    """'0.02' as the 10th item would be field 10 of the first card image, a continuation field: NASTRAN's reading
    would lose it or shift it into another field, so the line is refused, naming the item and the field."""
    line = "PBAR,1,1,1.0-3,2.0-7,3.0-7,4.0-7,0.5,,0.02,0.02,-0.02,0.02"
    with pytest.raises(DeckError, match=r"^free\.bdf:10: PBAR: free-field line: '0\.02' \(item 10 of the line\) falls "
                                        r"in field 10 of card image 1, a continuation field"):
        read_deck_text(CASE + FREE.replace(FREE.splitlines()[4], line) + "ENDDATA\n", name="free.bdf")


#: aeroelastic cards as a SOL 144-146 deck writes them (their fields are not read: they are read past)
AERO_CARDS = ["AEFACT,97,.3,.7,1.0", "AELIST,1000,1001,THRU,1010", "AELINK,1,ELEV,AILERON,1.0",
              "CAERO3,2000,2001,0,,,,,", "PAERO3,2001,,0", "SPLINE3,3000,2000,1001,,1,3,1.0",
              "MONDSP1,AILDSP,AILERON,CAERO,1,0.0,0.0,0.0", "AESURFS,1,AILERON,,1000,,1001",
              "MONPNT2,ELEM,BAR1,CBAR,FORCE,1", "CSSCHD,10,1,AILERON,,,", "DIVERG,1,3,0.0,0.5",
              "UXVEC,1,,", "TRIM2,1,0.8,", "SPLINE6,4000,2000"]


def test_every_aeroelastic_card_is_read_past_and_named_as_such():
    """The refusal of the cards the reader cannot model said 'aerodynamic data ... are read past' while listing
    AEFACT, AELIST and CAERO3 among them (pyNastran's models/aero/fmondsp.dat: AEFACT, MONDSP1)."""
    deck = read_deck_text(CASE + FIXED + "\n".join(AERO_CARDS) + "\nENDDATA\n", name="aero.bdf")
    skipped = {name for name, _, _ in deck.skipped}
    assert skipped == {card.split(",")[0] for card in AERO_CARDS} and skipped <= AERODYNAMIC
    with pytest.raises(DeckError) as refused:
        read_deck_text(CASE + FIXED + "\n".join(AERO_CARDS) + "\nCQUAD4,7,1,1,2,3,4\nCTRIA3,8,1,1,2,3\nENDDATA\n",
                       name="aero.bdf")
    listed = str(refused.value).split("(supported:")[0]
    assert "cards this reader cannot model: CQUAD4 (1x, first at line " in listed and "CTRIA3 (1x" in listed
    assert not [card for card in AERODYNAMIC if f"{card} (" in listed]
    assert "aerodynamic data, are read past" in str(refused.value)
