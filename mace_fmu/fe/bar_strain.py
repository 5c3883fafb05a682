"""Strain at a point of a CBAR, as a weighted sum of its grids' DOFs (a strain gauge's reading).

The bar's end forces are recovered from its element stiffness, f = K_e u_e in element axes, the
way NASTRAN recovers CBAR forces and stresses: axial force N = f(u_B), end moments M(0) = -f(theta_A),
M(L) = f(theta_B) in each bending plane, the moment linear in between (no load along the element).
The strain at position x and fibre (y, z) of the section, in element axes, is then

    eps = N / (E A) - y M_z(x) / (E I1) + z M_y(x) / (E I2),

exact for Euler-Bernoulli and Timoshenko (K1/K2) sections alike, since it reads the element's own
statics. Torsion (shear strain) and the PBAR stress points are not modelled.
"""

from __future__ import annotations

import numpy as np

from mace_fmu.deck.cards import Deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import FEModel, bar_section
from mace_fmu.fe.beam import local_stiffness

#: element-axes DOF of each end force in a 12-vector (u, v, w, rx, ry, rz at A, then at B)
_AXIAL_B, _RY_A, _RZ_A, _RY_B, _RZ_B = 6, 4, 5, 10, 11


def bar_strain_weights(model: FEModel, deck: Deck, *, bar_id: int, position: float, fiber_y_m: float,
                       fiber_z_m: float) -> tuple[tuple[int, int, float], ...]:
    """(grid, component 1-6 in the grid's CD system, weight) whose weighted sum is the strain [1] of
    CBAR ``bar_id`` at ``position`` (0: end A, 1: end B, a fraction of its length) and fibre
    (``fiber_y_m``, ``fiber_z_m``) [m] from the section's centroid in element axes.
    """
    rows = np.flatnonzero(model.bars.ids == bar_id)
    if len(rows) == 0:
        raise MaceError(f"bar {bar_id} is not a CBAR of {deck.path} (strain gauges read CBAR elements)")
    if not 0.0 <= position <= 1.0:
        raise MaceError(f"bar {bar_id}: position {position} is not a fraction of the bar's length in [0, 1]")
    row = int(rows[0])
    card = deck.bars[bar_id]
    section = bar_section(deck, card.pid)
    if section.area <= 0.0 or (fiber_y_m != 0.0 and section.i1 <= 0.0) or (fiber_z_m != 0.0 and section.i2 <= 0.0):
        raise MaceError(f"bar {bar_id}: PBAR {card.pid} has no area or bending inertia for a fibre at "
                        f"y = {fiber_y_m} m, z = {fiber_z_m} m")
    k = local_stiffness(section, float(model.bars.lengths0[row]))
    moment_z = (1.0 - position) * -k[_RZ_A] + position * k[_RZ_B]
    moment_y = (1.0 - position) * -k[_RY_A] + position * k[_RY_B]
    local = k[_AXIAL_B] / (section.e * section.area)
    if fiber_y_m != 0.0:
        local = local - fiber_y_m * moment_z / (section.e * section.i1)
    if fiber_z_m != 0.0:
        local = local + fiber_z_m * moment_y / (section.e * section.i2)
    frame = model.bars.frames0[row]  # rows: element axes in basic
    out = []
    for end, node in enumerate((model.bars.node_a[row], model.bars.node_b[row])):
        grid, cd = model.dofs.grid_ids[node], model.cd_frames[node]  # cd columns: CD axes in basic
        for block in range(2):  # translations, rotations
            weights = local[6 * end + 3 * block: 6 * end + 3 * block + 3] @ frame @ cd
            out += [(int(grid), 3 * block + c + 1, float(w)) for c, w in enumerate(weights)]
    scale = max(abs(w) for *_, w in out)
    return tuple(d for d in out if abs(d[2]) > 1e-14 * scale)
