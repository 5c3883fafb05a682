"""Element matrices gathered as (row, column, value) triplets into one sparse global matrix.

Assembly adds thousands of small dense blocks; collecting them as triplets and letting scipy sum
the duplicates once costs memory and time in proportion to the number of element entries, where
adding into a dense n x n matrix costs n^2 memory before the first element.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse


class MatrixTriplets:
    """A global matrix under assembly: ``add`` blocks, then ``matrix`` sums them into CSR."""

    def __init__(self, size: int) -> None:
        self.size = size  #: number of rows and columns (DOFs)
        # int32 indices where they fit, as scipy would pick for the matrix: half the memory traffic
        self._index = np.int32 if size < 2**31 - 1 else np.int64
        self._rows: list[np.ndarray] = []
        self._cols: list[np.ndarray] = []
        self._values: list[np.ndarray] = []

    def add(self, idx: np.ndarray, block: np.ndarray) -> None:
        """Add the square ``block`` at the DOFs ``idx`` (rows and columns alike)."""
        idx = np.asarray(idx, dtype=self._index)
        self._rows.append(np.repeat(idx, len(idx)))
        self._cols.append(np.tile(idx, len(idx)))
        self._values.append(np.asarray(block, dtype=float).ravel())

    def add_many(self, idx: np.ndarray, blocks: np.ndarray) -> None:
        """Add blocks (n, k, k) at DOFs idx (n, k): one call for a batch of like elements."""
        idx = np.asarray(idx, dtype=self._index)
        k = idx.shape[1]
        self._rows.append(np.repeat(idx, k, axis=1).ravel())
        self._cols.append(np.tile(idx, (1, k)).ravel())
        self._values.append(np.asarray(blocks, dtype=float).ravel())

    def add_diagonal(self, idx: np.ndarray, diagonals: np.ndarray) -> None:
        """Add diagonal blocks, given by their diagonals (n, k), at DOFs idx (n, k)."""
        idx = np.asarray(idx, dtype=self._index).ravel()
        self._rows.append(idx)
        self._cols.append(idx)
        self._values.append(np.asarray(diagonals, dtype=float).ravel())

    def matrix(self) -> sparse.csr_array:
        """The sum of every block added, as CSR."""
        if not self._values:
            return sparse.csr_array((self.size, self.size))
        values = _joined(self._values)
        # exact zeros (a lumped mass block's off-diagonal, an axis-aligned bar's uncoupled terms) are
        # dropped before the sort that sums duplicates: most of a lumped mass matrix's entries
        kept = values != 0.0
        rows, cols = _joined(self._rows)[kept], _joined(self._cols)[kept]
        return sparse.coo_array((values[kept], (rows, cols)), shape=(self.size, self.size)).tocsr()


def _joined(parts: list[np.ndarray]) -> np.ndarray:
    """The batches as one array. One batch (the usual: all of a model's bars in one add_many) is taken as it is,
    not copied: on a virtual machine a process's first touch of memory costs about 1 ms a megabyte, and the wide
    100k-DOF lattice's 11 million stiffness triplets are 180 MB."""
    return parts[0] if len(parts) == 1 else np.concatenate(parts)
