"""Which Deck table holds each bulk-data card: the deck package's one card-to-table map.

It imports no other module of mace_fmu, so that the card records, the table builder and the structure stage can all name
tables without importing the parsers (or each other).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

#: card name -> the Deck attribute that holds its records (a PBARL is stored as the PBAR it stands for, a
#: CONROD beside the CRODs, and so on). SPC, SPC1 and MPC go to set tables and CELAS1 becomes a CELAS2 once
#: its PELAS is known, so none of them is here.
CARD_TABLES: Mapping[str, str] = MappingProxyType({
    "GRID": "grids", "CORD2R": "coords", "CBAR": "bars", "PBAR": "pbars", "MAT1": "mat1s", "CONM2": "conm2s",
    "CELAS2": "celas2s", "GRAV": "gravs", "LOAD": "loads", "EIGRL": "eigrls", "NLPARM": "nlparms",
    "PARAM": "params", "PBARL": "pbars", "PBEAML": "pbeams", "PBEAM": "pbeams", "CBEAM": "beams", "CROD": "rods",
    "CONROD": "rods", "PROD": "prods", "CMASS1": "scalar_masses", "CMASS2": "scalar_masses", "PMASS": "pmasses",
    "RBAR": "rigids", "RBE2": "rigids", "EIGR": "eigrs", "CONM1": "conm1s", "CORD1R": "coords",
    "RBE3": "interpolations"})

# The element and mass cards, in the order the structure stage walks their tables (it reports the first
# dangling element it meets, so the order is part of what a user sees).
_ELEMENT_CARDS = ("CBAR", "CONM2", "CELAS2", "CBEAM", "CROD", "CONROD", "CMASS1", "CMASS2", "CONM1", "RBAR", "RBE2",
                  "RBE3")

#: the Deck fields that hold elements and masses (what a structure file's [suspension] elements may name)
ELEMENT_TABLES: tuple[str, ...] = tuple(dict.fromkeys(CARD_TABLES[card] for card in _ELEMENT_CARDS))
