"""The geometry of the run's deck, read for the output systems only: GRID, GRDSET, CORD1R/C/S, CORD2R/C/S.

A deck of shells or solids has cards the FE core cannot model (mace_fmu.deck.read_deck refuses them), but
its grids and coordinate systems are all that turning NASTRAN's eigenvectors into basic needs. They are
read with mace_fmu.deck's own text layer (INCLUDE, free/small/large fields, GRDSET defaults) and card
parsers (a CORD2C or CORD2S has a CORD2R's fields, a CORD1C or CORD1S a CORD1R's); every other card is
passed over.
"""

from __future__ import annotations

import os
from pathlib import Path

from mace_fmu.deck.cards import Source
from mace_fmu.deck.connectivity import bulk_cards
from mace_fmu.deck.fields import Fields
from mace_fmu.deck.parsers.grids import cord1r, cord2r, grdset, grid
from mace_fmu.errors import DeckError
from mace_fmu.nastran_modes.file_modes import COORD_KINDS, CoordCard, FileGeometry, xyz


def read_deck_geometry(path: Path) -> FileGeometry:
    """GRIDs and coordinate systems of the deck at ``path``; DeckError (file, line, card, field) for a bad one."""
    name = os.fspath(path)
    raw_cards = bulk_cards(name)
    defaults = (0, 0, "")
    for raw in raw_cards:
        if raw.name == "GRDSET":
            defaults = grdset(Fields(raw, name), Source(raw.file or name, raw.line))
    grids: dict[int, tuple[int, tuple[float, float, float], int]] = {}
    coords: dict[int, CoordCard] = {}
    for raw in raw_cards:
        src = Source(raw.file or name, raw.line)
        if raw.name == "GRID":
            card = grid(Fields(raw, name), src, defaults)
            if card.id in grids:
                raise DeckError(f"GRID {card.id} is defined twice (expected one GRID per ID)", file=src.file,
                                line=src.line, card=f"GRID {card.id}")
            grids[card.id] = (card.cp, xyz(card.xyz), card.cd)
        elif raw.name in ("CORD2R", "CORD2C", "CORD2S"):
            c2 = cord2r(Fields(raw, name), src)
            coords[c2.id] = CoordCard(id=c2.id, kind=COORD_KINDS[raw.name[-1]], rid=c2.rid,
                                      points=(xyz(c2.a), xyz(c2.b), xyz(c2.c)), grids=None)
        elif raw.name in ("CORD1R", "CORD1C", "CORD1S"):
            for c1 in cord1r(Fields(raw, name), src):
                coords[c1.id] = CoordCard(id=c1.id, kind=COORD_KINDS[raw.name[-1]], rid=None, points=None,
                                          grids=(c1.g1, c1.g2, c1.g3))
    if not grids:
        raise DeckError("no GRID cards (expected the deck of the run that wrote the modes)", file=name, line=0)
    return FileGeometry(grids=grids, coords=coords)
