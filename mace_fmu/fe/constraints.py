"""MPC and SPC sets eliminated by one transformation: u_basic = T @ u_independent."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from mace_fmu.deck.cards import Deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.dofs import DofMap


@dataclass(frozen=True)
class Constraints:
    """Transformation from the independent DOFs (CD components) to all DOFs in basic."""

    transform: sparse.csr_array  #: T, (n_dof, n_independent); mostly unit columns, so sparse
    independent: tuple[tuple[int, int], ...]  #: (grid, component) of each column of T
    spc_set: int | None
    mpc_set: int | None

    def reduce(self, matrix: np.ndarray | sparse.sparray) -> np.ndarray:
        """T^T A T as a dense array, for a dense or a sparse A."""
        t = self.transform
        if sparse.issparse(matrix):
            return (t.T @ matrix @ t).toarray()
        return (t.T @ (t.T @ matrix).T).T

    def reduce_sparse(self, matrix: np.ndarray | sparse.sparray) -> sparse.csr_array:
        """T^T A T as a sparse (CSR) array, for a dense or a sparse A."""
        t = self.transform
        return sparse.csr_array(t.T @ sparse.csr_array(matrix) @ t)


def cd_rotation(cd_frames: np.ndarray) -> np.ndarray:
    """Block-diagonal Lambda with u_basic = Lambda @ u_cd (translations and rotations per grid)."""
    return sparse.block_diag([blk for r in cd_frames for blk in (r, r)], format="csr")


def build_constraints(deck: Deck, dofs: DofMap, cd_frames: np.ndarray, *, spc_set: int | None,
                      mpc_set: int | None) -> Constraints:
    """Eliminate SPC1 set ``spc_set``, GRID PS fields and MPC set ``mpc_set`` (first term dependent)."""
    n = dofs.size
    fixed = np.zeros(n, dtype=bool)
    for grid in deck.grids.values():
        for c in grid.ps:
            fixed[dofs.index(grid.id, int(c))] = True
    for card in deck.spc1s.get(spc_set, ()) if spc_set is not None else ():
        for g in card.grids:
            for c in card.components:
                fixed[dofs.index(g, int(c))] = True

    equations: dict[int, list[tuple[int, float]]] = {}
    sources = {}
    for mpc in deck.mpcs.get(mpc_set, ()) if mpc_set is not None else ():
        dep = mpc.terms[0]
        d = dofs.index(dep.grid, dep.component)
        if fixed[d]:
            raise MaceError(f"{mpc.source}: MPC {mpc.sid}: dependent DOF {dep.grid}-{dep.component} is also "
                            f"fixed by SPC set {spc_set}; a DOF can be eliminated only once")
        if dep.coefficient == 0.0:
            raise MaceError(f"{mpc.source}: MPC {mpc.sid}: the dependent term of {dep.grid}-{dep.component} "
                            f"has a zero coefficient")
        equations[d] = [(dofs.index(t.grid, t.component), -t.coefficient / dep.coefficient) for t in mpc.terms[1:]]
        sources[d] = mpc.source

    independent = [i for i in range(n) if not fixed[i] and i not in equations]
    column = {i: k for k, i in enumerate(independent)}
    # T in the CD systems, built as triplets: a unit entry per independent DOF, the MPC coefficients
    # of each dependent one (its terms are independent DOFs, so their rows are unit rows)
    rows, cols, values = list(column), list(column.values()), [1.0] * len(column)
    for d, terms in equations.items():
        for i, a in terms:
            if i in equations:
                raise MaceError(f"{sources[d]}: MPC {mpc_set}: DOF {dofs.label(i)} is dependent in another "
                                f"equation and cannot be used as an independent term")
            if i in column:  # a fixed DOF contributes nothing
                rows.append(d), cols.append(column[i]), values.append(a)
    t_cd = sparse.coo_array((values, (rows, cols)), shape=(n, len(independent))).tocsr()  # sums repeated terms
    transform = sparse.csr_array(cd_rotation(cd_frames) @ t_cd)
    return Constraints(transform=transform, independent=tuple(dofs.label(i) for i in independent),
                       spc_set=spc_set, mpc_set=mpc_set)
