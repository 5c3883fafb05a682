"""Degrees of freedom named by (grid, component): the only way code addresses a DOF."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mace_fmu.errors import MaceError

COMPONENT_NAMES = ("T1", "T2", "T3", "R1", "R2", "R3")


@dataclass(frozen=True)
class DofMap:
    """Six DOFs per grid, grids in ascending ID order; components 1-6 as in NASTRAN."""

    grid_ids: tuple[int, ...]  #: grid IDs in DOF order, six DOFs each

    def __post_init__(self) -> None:
        object.__setattr__(self, "_row", {g: i for i, g in enumerate(self.grid_ids)})

    @property
    def size(self) -> int:
        """Number of DOFs (6 per grid)."""
        return 6 * len(self.grid_ids)

    def grid_index(self, grid: int) -> int:
        """Row of ``grid`` in per-grid arrays; KeyError names the grid when it is not in the model."""
        try:
            return self._row[grid]  # type: ignore[attr-defined]
        except KeyError:
            raise KeyError(f"grid {grid} is not in this model") from None

    def grid_indices(self, grids: list[int]) -> np.ndarray:
        """Row of each of ``grids`` in per-grid arrays, all at once (a 100k-DOF lattice's bars name 150,000);
        an unknown grid gets :meth:`grid_index`'s KeyError."""
        known = np.asarray(self.grid_ids, dtype=np.int64)
        wanted = np.asarray(grids, dtype=np.int64)
        found = np.minimum(np.searchsorted(known, wanted), max(len(known) - 1, 0))  # grid_ids ascend
        if len(wanted) and (not len(known) or np.any(known[found] != wanted)):
            return np.array([self.grid_index(g) for g in grids], dtype=np.int64)
        return found.astype(np.int64)

    def index(self, grid: int, component: int) -> int:
        """Global index of component 1-6 of ``grid``."""
        if not 1 <= component <= 6:
            raise MaceError(f"component must be 1-6, got {component}")
        return 6 * self.grid_index(grid) + component - 1

    def indices(self, grid: int) -> np.ndarray:
        """The six global indices of ``grid``."""
        start = 6 * self.grid_index(grid)
        return np.arange(start, start + 6)

    def label(self, index: int) -> tuple[int, int]:
        """(grid, component) of a global index."""
        return self.grid_ids[index // 6], index % 6 + 1


def cd_component_entries(dofs: DofMap, cd_frames: np.ndarray, grid: int, component: int
                         ) -> tuple[np.ndarray, np.ndarray]:
    """(DOF indices, coefficients) of the row vector that picks component 1-6 of ``grid``, measured in
    its CD system (``cd_frames``: (n_grid, 3, 3), columns = axes in basic), from basic DOFs."""
    row = dofs.grid_index(grid)
    block = 6 * row + (0 if component <= 3 else 3)
    return np.arange(block, block + 3), cd_frames[row][:, (component - 1) % 3]


def cd_component_vector(dofs: DofMap, cd_frames: np.ndarray, grid: int, component: int) -> np.ndarray:
    """Dense row vector that picks component 1-6 of ``grid``, measured in its CD system, from basic DOFs."""
    vec = np.zeros(dofs.size)
    idx, coefficients = cd_component_entries(dofs, cd_frames, grid, component)
    vec[idx] = coefficients
    return vec


def scalar_element_entries(dofs: DofMap, cd_frames: np.ndarray, g1: int, c1: int, g2: int | None, c2: int | None
                           ) -> tuple[np.ndarray, np.ndarray]:
    """(DOF indices, coefficients) of u1 - u2 for a scalar element (CELAS, CMASS) between component ``c1``
    of ``g1`` and ``c2`` of ``g2`` (each in its grid's CD system); ``g2`` None: grounded, u1 alone."""
    idx, coefficients = cd_component_entries(dofs, cd_frames, g1, c1)
    if g2 is None:
        return idx, coefficients
    assert c2 is not None  # a second grid comes with its component
    idx2, coefficients2 = cd_component_entries(dofs, cd_frames, g2, c2)
    return np.concatenate([idx, idx2]), np.concatenate([coefficients, -coefficients2])
