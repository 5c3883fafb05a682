"""Element edges of a deck, read for drawing only: which grids each element's outline joins.

The deck reader builds FE for the cards it knows and refuses the others; a model whose modes
NASTRAN computed (shells, solids) is drawn from its connectivity alone. This scanner reads the
same text layer (sections, INCLUDEs, small/large/free fields, continuations) and takes from each
element card its grid IDs, nothing else: shells (CQUAD4, CTRIA3 and their higher-order and
R-variants, CSHEAR) as the edges of their corner grids, solids (CHEXA, CPENTA, CTETRA) as the
edges of their corner grids, line elements (CBAR, CBEAM, CROD, CONROD, CTUBE, CBUSH) and RBE2 legs
as lines. Mid-side grids of higher-order elements are not drawn (edges are straight between
corners). GRID cards give each grid's position and its CP and CD system IDs (GRDSET's defaults
applied); the positions are in basic where CP is 0, and coordinate systems are not resolved here.
Every other card is read past.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from mace_fmu.deck.cards import Source
from mace_fmu.deck.fields import Fields, RawCard, check_text, parse_int, split_sections
from mace_fmu.deck.files import cards_with_includes, deck_file_text, without_begin_bulk
from mace_fmu.deck.parsers.grids import grdset, grid
from mace_fmu.errors import DeckError

#: corner-to-corner edges of each element's outline, as 0-based positions in its corner grid list
_QUAD = ((0, 1), (1, 2), (2, 3), (3, 0))
_TRIA = ((0, 1), (1, 2), (2, 0))
_HEXA = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7))
_PENTA = ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5))
_TETRA = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
_LINE = ((0, 1),)

#: card -> (data field of its first grid, number of corner grids, edges between corners); data fields
#: numbered from 1 as NASTRAN does (EID is data field 1)
ELEMENT_OUTLINES: dict[str, tuple[int, int, tuple[tuple[int, int], ...]]] = {
    "CQUAD4": (3, 4, _QUAD), "CQUAD8": (3, 4, _QUAD), "CQUADR": (3, 4, _QUAD), "CSHEAR": (3, 4, _QUAD),
    "CQUAD": (3, 4, _QUAD),
    "CTRIA3": (3, 3, _TRIA), "CTRIA6": (3, 3, _TRIA), "CTRIAR": (3, 3, _TRIA),
    "CHEXA": (3, 8, _HEXA), "CPENTA": (3, 6, _PENTA), "CTETRA": (3, 4, _TETRA),
    "CBAR": (3, 2, _LINE), "CBEAM": (3, 2, _LINE), "CROD": (3, 2, _LINE), "CTUBE": (3, 2, _LINE),
    "CBUSH": (3, 2, _LINE), "CONROD": (2, 2, _LINE),
}


@dataclass(frozen=True)
class GridPoint:
    """A GRID card as drawing needs it."""

    xyz: tuple[float, float, float]  #: X1-X3 in the CP system [deck length unit]
    cp: int  #: the system X1-X3 are in (0: basic)
    cd: int  #: the displacement (output) system (0: basic)


@dataclass(frozen=True)
class Connectivity:
    """The outline of a deck's elements: grid pairs to draw as lines, and its grids."""

    edges: tuple[tuple[int, int], ...]  #: (grid, grid), each pair once, smaller ID first
    elements: dict[str, int]  #: card name -> how many of them were read
    path: str  #: the deck
    grids: dict[int, GridPoint] = field(default_factory=dict)  #: GRID ID -> position and systems


def _grid(card: RawCard, d: int, file: str) -> int:
    text = card.fields[d - 1] if d <= len(card.fields) else ""
    value = parse_int(text)
    if value is None or value <= 0:
        line = card.lines[d - 1] if d <= len(card.lines) else card.line
        raise DeckError(f"data field {d} is {text!r} (expected a grid ID, a positive integer)", file=card.file or file,
                        line=line, card=f"{card.name} {card.fields[0] if card.fields else ''}".strip())
    return value


def _rbe2_legs(card: RawCard, file: str) -> list[tuple[int, int]]:
    """RBE2: EID, GN, CM, GM1, GM2, ... (ALPHA, a real, may end the list): lines from GN to each GM."""
    independent = _grid(card, 2, file)
    legs = []
    for text in card.fields[3:]:
        if not text:
            continue
        value = parse_int(text)
        if value is None:  # THRU is not drawn expanded; ALPHA (a real) ends the list
            if text.upper() == "THRU":
                raise DeckError("RBE2 with THRU is not read for drawing (list the dependent grids)", file=card.file
                                or file, line=card.line, card=f"RBE2 {card.fields[0]}")
            break
        legs.append((independent, value))
    return legs


def bulk_cards(path: str | os.PathLike[str]) -> list[RawCard]:
    """The bulk data cards of the deck ``path`` (case control skipped), its INCLUDEs expanded; DeckError
    (file, line) for a file that cannot be read or a malformed card."""
    file = os.fspath(path)
    text = deck_file_text(file).removeprefix("\ufeff")
    numbered = [(k, line.rstrip("\r")) for k, line in enumerate(text.split("\n"), start=1)]
    check_text(numbered, file)
    _, bulk = split_sections(numbered, file)
    return cards_with_includes(without_begin_bulk(bulk), file, stack=(os.path.abspath(file),))


def read_connectivity(path: str | os.PathLike[str]) -> Connectivity:
    """The edges of every element of the deck ``path`` whose outline is drawn (module docstring).

    Parameters
    ----------
    path : str or path-like
        A NASTRAN deck (case control optional), with its INCLUDEs.

    Returns
    -------
    Connectivity
        Edges as grid pairs, the count of each element card read, and the grids (position, CP, CD).

    Raises
    ------
    DeckError
        A file that cannot be read, or an element card whose grid field is not a grid ID (file, line and card).
    """
    file = os.fspath(path)
    cards = bulk_cards(file)
    edges: set[tuple[int, int]] = set()
    counts: dict[str, int] = {}
    settings = next((c for c in cards if c.name == "GRDSET"), None)
    defaults = grdset(Fields(settings, file), Source(settings.file or file, settings.line)) \
        if settings is not None else (0, 0, "")
    grids: dict[int, GridPoint] = {}
    for card in cards:
        if card.name == "GRID":
            point = grid(Fields(card, file), Source(card.file or file, card.line), defaults)
            grids[point.id] = GridPoint(xyz=point.xyz, cp=point.cp, cd=point.cd)
            continue
        if card.name == "RBE2":
            pairs = _rbe2_legs(card, file)
        elif card.name in ELEMENT_OUTLINES:
            first, corners, outline = ELEMENT_OUTLINES[card.name]
            corner = [_grid(card, first + k, file) for k in range(corners)]
            # a degenerate element (a CHEXA as a wedge, a CQUAD4 as a triangle) repeats a grid: no edge there
            pairs = [(corner[a], corner[b]) for a, b in outline if corner[a] != corner[b]]
        else:
            continue
        counts[card.name] = counts.get(card.name, 0) + 1
        edges.update((min(a, b), max(a, b)) for a, b in pairs)
    return Connectivity(edges=tuple(sorted(edges)), elements=counts, path=str(Path(file)), grids=grids)
