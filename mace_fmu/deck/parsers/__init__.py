"""Parsers of the bulk-data cards mace-fmu models, one module per card family, and the table of them.

A parser takes a card's typed fields and where the card starts, ``(Fields, Source)``, and returns its
record (a tuple of records for a card that carries several, such as PMASS or CORD1R); any problem is a
DeckError naming the card and the field. The table builder (tables.py) looks each card up in ``PARSERS``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

from mace_fmu.deck.cards import Source
from mace_fmu.deck.fields import Fields
from mace_fmu.deck.parsers import bars, constraints, grids, rigid, solution, springs_masses

__all__ = ["PARSERS"]

#: card name -> its parser (every card name here is one mace-fmu models)
PARSERS: Mapping[str, Callable[[Fields, Source], Any]] = MappingProxyType({
    "GRID": grids.grid, "CORD2R": grids.cord2r, "CBAR": bars.cbar, "PBAR": bars.pbar, "MAT1": bars.mat1,
    "CONM2": springs_masses.conm2, "CELAS2": springs_masses.celas2, "MPC": constraints.mpc,
    "SPC1": constraints.spc1, "SPC": constraints.spc, "GRAV": solution.grav, "LOAD": solution.load,
    "EIGRL": solution.eigrl, "NLPARM": solution.nlparm, "PARAM": solution.param, "PBARL": bars.pbarl,
    "PBEAML": bars.pbeaml, "PBEAM": bars.pbeam, "CBEAM": bars.cbeam, "CROD": bars.crod, "CONROD": bars.conrod,
    "PROD": bars.prod, "CMASS1": springs_masses.cmass1, "CMASS2": springs_masses.cmass2,
    "PMASS": springs_masses.pmass, "RBAR": rigid.rbar, "RBE2": rigid.rbe2, "EIGR": solution.eigr,
    "GRDSET": grids.grdset, "CELAS1": springs_masses.celas1, "PELAS": springs_masses.pelas,
    "CONM1": springs_masses.conm1, "SPCADD": constraints.spcadd, "MPCADD": constraints.spcadd,
    "CORD1R": grids.cord1r, "RBE3": rigid.rbe3})
