"""The viewer draws a structure known by NASTRAN's modes: its grids and its geometry deck's element edges.

pyNastran's plate_py run (200 CQUAD4 on an 11 x 21 grid of points) and mode_solid_shell_bar (a CHEXA, CPENTA,
CTETRA, shells, a CBAR, a CBEAM and CRODs): the edges counted and named from the cards themselves.
"""

from __future__ import annotations

import numpy as np
from support.modes_file import DATA, RUNS, op2_structure_file

from mace_fmu.deck.connectivity import read_connectivity
from mace_fmu.iomodel.modal_source import modal_structure


def test_the_viewer_draws_the_plates_quads_and_the_solids_corner_edges(tmp_path):
    from mace_fmu.viewer import animate_modes, write_animation_html

    plate = modal_structure(op2_structure_file(tmp_path, "plate_py"))
    animation = animate_modes(plate, ["mode 7", "mode 8"])
    # 10 x 20 CQUAD4 on a 11 x 21 grid of points: 10 x 21 + 11 x 20 edges, no grid left off an edge
    assert len(animation.scene.segments) == 10 * 21 + 11 * 20 and not animation.scene.masses
    assert np.isclose(animation.scene.length_m, 2.0)  # the plate's 1 x 2 extent (its deck's length unit)
    assert write_animation_html(animation, tmp_path / "plate.html", title="plate_py") > 0
    edges = set(read_connectivity(DATA / RUNS["solid_shell_bar"][1]).edges)
    hexa = (2, 3, 4, 1, 8, 5, 6, 7)  # CHEXA 1's corners (geom.inc line 1)
    for a, b in ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)):
        assert (min(hexa[a], hexa[b]), max(hexa[a], hexa[b])) in edges
    assert (2, 4) not in edges  # a face diagonal is no edge
    assert (20, 24) in edges and (18, 22) in edges  # the CROD and the CBEAM as lines
