"""Element edges read for drawing only: shells, solids and line elements from their cards, errors with their line."""

from __future__ import annotations

import pytest
from support.modes_file import DATA

from mace_fmu.deck.connectivity import read_connectivity
from mace_fmu.errors import DeckError


def test_every_element_card_of_a_mixed_deck_is_read_and_a_grid_keeps_its_systems(tmp_path):
    deck = read_connectivity(DATA / "solid_shell_bar" / "mode_solid_shell_bar.bdf")  # INCLUDEs geom.inc
    assert deck.elements == {"CHEXA": 1, "CPENTA": 2, "CTETRA": 2, "CQUAD4": 4, "CTRIA3": 8, "CBEAM": 1, "CBAR": 1,
                             "CROD": 2}
    (tmp_path / "systems.bdf").write_text("BEGIN BULK\nGRDSET,,5,,,,7\nGRID,1,,1.,2.,3.\nGRID,2,0,4.,5.,6.,0\n"
                                          "CTRIA3,1,1,1,2,2\nENDDATA\n")
    small = read_connectivity(tmp_path / "systems.bdf")
    assert (small.grids[1].cp, small.grids[1].cd, small.grids[1].xyz) == (5, 7, (1.0, 2.0, 3.0))
    assert (small.grids[2].cp, small.grids[2].cd) == (0, 0)
    assert small.edges == ((1, 2),)  # a degenerate triangle: the repeated grid makes no edge


def test_a_bad_element_card_in_the_geometry_deck_names_its_line(tmp_path):
    (tmp_path / "bad.bdf").write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nCQUAD4,7,1,1,2,x,4\nENDDATA\n")
    with pytest.raises(DeckError, match=r"bad.bdf:3: CQUAD4 7: data field 5 is 'x' \(expected a grid ID"):
        read_connectivity(tmp_path / "bad.bdf")
