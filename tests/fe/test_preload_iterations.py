"""The 1-g preload's cheap intermediate iterations end at the equilibrium full Newton finds.

Intermediate load increments iterate on the material stiffness of the current state plus the last
full tangent's geometric stiffness scaled with the load (fe/preload.py); the answer must not depend
on it: the same deformed state and tangent as plain Newton with a full tangent every iteration.
"""

from __future__ import annotations

import numpy as np

from mace_fmu.fe.modes import compute_modes, gravity_load
from mace_fmu.fe.preload import large_displacement_preload


def test_mace_preload_ends_where_full_newton_ends_with_a_fifth_of_the_tangents():
    modes = compute_modes(configuration="1g")
    pre = modes.preload
    assert pre.increments == 20  # NLPARM NINC of the bundled deck
    assert pre.full_tangents <= 5, pre.full_tangents  # one a Newton iteration would be 27 (2026-11-24)
    load = gravity_load(modes.structure.deck, modes.model, modes.structure.preload.load)
    # one increment: every iteration is a full Newton step from the unstressed state
    newton = large_displacement_preload(modes.model, pre.constraints, load, increments=1, max_iterations=50)
    assert newton.full_tangents == newton.iterations + 1
    # the force residual stalls at round-off of the ~1e10 N/m aluminium links, alike in both
    assert pre.residual_ratio < 1e-6 and newton.residual_ratio < 1e-6
    sag = np.abs(newton.state.positions - modes.model.positions).max()
    assert sag > 1e-3  # metres: a real preload
    np.testing.assert_allclose(pre.state.positions, newton.state.positions, rtol=0, atol=1e-8 * sag)
    np.testing.assert_allclose(pre.state.rotations, newton.state.rotations, rtol=0, atol=1e-9)
    k_ref = newton.tangent_stiffness.toarray()
    assert np.abs(pre.tangent_stiffness.toarray() - k_ref).max() <= 1e-9 * np.abs(k_ref).max()
    np.testing.assert_allclose(pre.bar_forces, newton.bar_forces, rtol=0, atol=1e-7 * np.abs(newton.bar_forces).max())
