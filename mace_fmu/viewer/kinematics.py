"""Deformed positions along bars from nodal translations and rotations (cubic Hermite), in metres."""

from __future__ import annotations

import numpy as np

from mace_fmu.viewer.scene import Scene


def points_along_bars(scene: Scene, displacements: np.ndarray, s: np.ndarray, row_a: np.ndarray,
                      row_b: np.ndarray) -> np.ndarray:
    """Deformed positions [m] at fractions ``s`` of bars ``row_a``-``row_b``, for each frame.

    ``displacements`` is (n_frames, n_grid, 6): translations [m] and small rotations [rad] in basic
    axes. Each displacement component is the cubic Hermite curve through the two nodes whose
    end slopes are rotation x chord, so a bent bar is drawn bent and a rigid motion stays exact.
    """
    xa, xb = scene.positions_m[row_a], scene.positions_m[row_b]
    chord = xb - xa  # (n, 3), length L along the bar
    ua, ub = displacements[:, row_a, :3], displacements[:, row_b, :3]
    # slope d(u)/ds at the ends: rotation x chord (what a rigid rotation does to the bar axis)
    ta = np.cross(displacements[:, row_a, 3:], chord)
    tb = np.cross(displacements[:, row_b, 3:], chord)
    h1 = 1 - 3 * s**2 + 2 * s**3
    h2 = s - 2 * s**2 + s**3
    h3 = 3 * s**2 - 2 * s**3
    h4 = -s**2 + s**3
    u = h1[:, None] * ua + h2[:, None] * ta + h3[:, None] * ub + h4[:, None] * tb
    points: np.ndarray = xa + s[:, None] * chord + u
    return points
