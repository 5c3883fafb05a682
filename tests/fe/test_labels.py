"""The labels' strain energies per family of natural DOFs against a second computation."""

from __future__ import annotations

import numpy as np

from mace_fmu.fe.labels import _CHUNK, _FAMILIES, _family_energies


def test_family_energies_in_shared_chunks_equal_one_product_over_every_bar():
    """12,000 random bars of which 9,500 are chosen (three chunks, shared among threads), 6 modes: each family's
    energy 1/2 d_f^T k_ff d_f equals one einsum over every chosen bar at once, d = B phi (1e-12 relative)."""
    rng = np.random.default_rng(3)
    bars, dofs, modes = 12_000, 600, 6
    jacobian = rng.standard_normal((bars, 7, 12))
    k_natural = rng.standard_normal((bars, 7, 7))
    k_natural = k_natural @ k_natural.transpose(0, 2, 1)  # symmetric, as a stiffness
    dof_index = rng.integers(0, dofs, size=(bars, 12))
    shapes = rng.standard_normal((dofs, modes))
    chosen = np.sort(rng.choice(bars, size=9_500, replace=False))
    assert len(chosen) > 2 * _CHUNK

    found = _family_energies(jacobian, k_natural, dof_index, shapes, chosen)

    d = np.einsum("bij,bjm->bim", jacobian[chosen], shapes[dof_index[chosen]])
    for f, family in enumerate(_FAMILIES):
        at = np.array(family)
        k_ff = k_natural[chosen][:, at][:, :, at]
        expected = 0.5 * np.einsum("bim,bij,bjm->bm", d[:, at], k_ff, d[:, at])
        np.testing.assert_allclose(found[f], expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
