"""RBE3: the reference grid follows the weighted least-squares rigid motion of the independent grids.

Checked against closed forms and an independent computation (mace_fmu/fe/constraints.py,
interpolation_equations):
* a rigid motion of the independent grids (unequal weights, one grid in a rotated CD system, the
  reference off their centroid) comes out at the reference exactly (1e-12);
* a mass on an RBE3 over four springs at the corners of a square: bounce sqrt(4k/m) and the two tilts
  sqrt(4 k a^2 / I), 1e-10;
* the cards it cannot model (rotational independent components, UM) and a set of grids that cannot fix
  the reference's motion are refused with their file and line.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.decks import deck_text, r

from mace_fmu.deck.geometry import coordinate_frames, grid_positions
from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import assemble
from mace_fmu.fe.constraints import build_constraints
from mace_fmu.fe.modes import compute_modes

K, A, M, IXX, IYY = 2.0e4, 0.3, 5.0, 0.4, 0.7  # N/m, m, kg, kg m^2


def _platform(rbe3: str) -> str:
    corners = [(1, A, A), (2, -A, A), (3, -A, -A), (4, A, -A)]
    bulk = [f"GRID,{g},,{r(x)},{r(y)},0.0,,12456" for g, x, y in corners]
    bulk += ["GRID,10,,0.0,0.0,0.0"]
    bulk += [f"CELAS2,{20 + g},{r(K)},{g},3" for g, _, _ in corners]
    bulk += [f"CONM2,30,10,,{r(M)},,,,\n,{r(IXX)},,{r(IYY)},,,{r(1.0)}", rbe3, "EIGRL,1,,,3"]
    return deck_text(bulk, case="METHOD = 1")


def test_a_mass_on_an_rbe3_over_four_springs_bounces_and_tilts_as_the_closed_form(tmp_path):
    path = tmp_path / "platform.bdf"
    path.write_text(_platform("RBE3,40,,10,123456,1.0,123,1,2,\n,3,4"))
    modes = compute_modes(read_deck(path), configuration="0g")
    f = np.sort(modes.frequencies_hz)
    expected = np.sort([math.sqrt(4 * K / M), math.sqrt(4 * K * A**2 / IXX), math.sqrt(4 * K * A**2 / IYY)])
    np.testing.assert_allclose(f[:3], expected / (2 * math.pi), rtol=1e-10)


def test_the_reference_follows_a_rigid_motion_of_the_independent_grids_exactly(tmp_path):
    """Five grids, unequal weights and components, grid 5 in a rotated CD system, the reference away from
    their centroid: translations from u0 + theta0 x (x_i - x_ref) give u0 and theta0 at the reference."""
    bulk = ["CORD2R,7,,0.0,0.0,0.0,0.3,0.4,0.866,\n,1.0,0.2,0.1",
            "GRID,1,,0.0,0.0,0.0", "GRID,2,,1.0,0.1,0.0", "GRID,3,,0.2,1.3,0.1", "GRID,4,,0.9,1.1,0.8",
            "GRID,5,,0.4,0.5,1.2,7", "GRID,9,,0.7,0.2,0.5",
            "RBE3,50,,9,123456,1.0,123,1,2,\n,2.5,12,3,4,0.4,123,5"]
    path = tmp_path / "rbe3.bdf"
    path.write_text(deck_text(bulk))
    deck = read_deck(path)
    model = assemble(deck)
    cons = build_constraints(deck, model.dofs, model.cd_frames, spc_set=None, mpc_set=None)
    assert all(g != 9 for g, _ in cons.independent)
    pos = grid_positions(deck)
    frames = coordinate_frames(deck)
    u0, theta0 = np.array([1e-3, -2e-3, 0.5e-3]), np.array([2e-3, 1e-3, -3e-3])
    values = []
    for grid, component in cons.independent:
        moved = np.concatenate([u0 + np.cross(theta0, pos[grid] - pos[9]), theta0])
        cd = model.cd_frames[model.dofs.grid_index(grid)]
        values.append((np.kron(np.eye(2), cd).T @ moved)[component - 1])
    u = cons.transform @ np.array(values)
    reference = u[model.dofs.indices(9)]
    np.testing.assert_allclose(reference, np.concatenate([u0, theta0]), rtol=0, atol=1e-12)
    assert 7 in frames  # the rotated system was used


@pytest.mark.parametrize(("rbe3", "message"), [
    ("RBE3,40,,10,123456,1.0,123456,1,2,\n,3,4", "C1 = 123456: rotational independent components are not supported"),
    ("RBE3,40,,10,123456,1.0,123,1,2,\n,3,4,UM,1,3", "a UM section"),
    ("RBE3,40,,10,123456,1.0,123,10,1", "grid 10 is REFGRID"),
    ("RBE3,40,,10,123456,1,123,1,2", "WT1"),
])
def test_cards_it_cannot_model_are_refused_with_file_and_line(tmp_path, rbe3, message):
    path = tmp_path / "bad.bdf"
    path.write_text(_platform(rbe3))
    with pytest.raises(MaceError, match=message) as info:
        read_deck(path)
    assert str(info.value).startswith(f"{path}:")


def test_grids_on_one_line_cannot_fix_the_reference_and_are_refused(tmp_path):
    path = tmp_path / "line.bdf"
    path.write_text(_platform("RBE3,40,,10,123456,1.0,123,1,3"))  # two opposite corners: a line
    with pytest.raises(MaceError, match="RBE3 40: its independent grids and components do not fix the reference"):
        compute_modes(read_deck(path), configuration="0g")
