"""MPC and SPC sets eliminated by one transformation: u_basic = T @ u_independent."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from mace_fmu.deck.cards import Deck
from mace_fmu.deck.geometry import grid_positions
from mace_fmu.errors import MaceError
from mace_fmu.fe.dofs import DofMap


@dataclass(frozen=True)
class Constraints:
    """Transformation from the independent DOFs (CD components) to all DOFs in basic."""

    transform: sparse.csr_array  #: T, (n_dof, n_independent); mostly unit columns, so sparse
    independent: tuple[tuple[int, int], ...]  #: (grid, component) of each column of T
    spc_set: int | None  #: the SPC set applied (None: none)
    mpc_set: int | None  #: the MPC set applied (None: none)

    def reduce(self, matrix: np.ndarray | sparse.sparray) -> np.ndarray:
        """T^T A T as a dense array, for a dense or a sparse A."""
        return self.reduce_sparse(matrix).toarray()

    def reduce_sparse(self, matrix: np.ndarray | sparse.sparray) -> sparse.csr_array:
        """T^T A T as a sparse (CSR) array, for a dense or a sparse A."""
        t = self.transform
        return sparse.csr_array(t.T @ sparse.csr_array(matrix) @ t)


def cd_rotation(cd_frames: np.ndarray) -> sparse.csr_array:
    """Block-diagonal Lambda with u_basic = Lambda @ u_cd (translations and rotations per grid)."""
    blocks = np.repeat(np.asarray(cd_frames, dtype=float), 2, axis=0)  # each grid's frame for u, then theta
    count = len(blocks)
    # one 3 x 3 block per row of blocks: BSR holds exactly that (a list of 200,000 blocks to block_diag took 0.3 s)
    rotation = sparse.bsr_array((blocks, np.arange(count), np.arange(count + 1)), shape=(3 * count, 3 * count)).tocsr()
    rotation.eliminate_zeros()  # a basic frame's zeros would widen every product's pattern
    return rotation


def _rigid_transfer(offset_m: np.ndarray) -> np.ndarray:
    """G (6 x 6): the motion (u, theta) [m, rad] of a point ``offset_m`` [m] away that moves rigidly with
    a point whose motion is (u0, theta0): u = u0 + theta0 x offset = u0 - skew(offset) theta0, theta = theta0."""
    x, y, z = offset_m
    g = np.eye(6)
    g[:3, 3:] = -np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return g


def _check_free(d: int, what: str, fixed: np.ndarray, equations: dict, sources: dict, labels: dict) -> None:
    """A rigid or interpolation element may make DOF ``d`` dependent only if nothing eliminated it before."""
    if fixed[d]:
        raise MaceError(f"{what} is also fixed by an SPC or a GRID PS field; a DOF can be eliminated only once")
    if d in equations:
        raise MaceError(f"{what} is already dependent in {labels[d]} ({sources[d]}); a DOF can be dependent only once")


def rigid_equations(deck: Deck, dofs: DofMap, cd_frames: np.ndarray, fixed: np.ndarray,
                    equations: dict[int, list[tuple[int, float]]], sources: dict, labels: dict) -> None:
    """Add the equations of every RBAR and RBE2 (always in force, like NASTRAN's rigid elements) to
    ``equations`` (dependent index -> [(index, coefficient)], CD components).

    A dependent grid moves rigidly with the independent grid: in basic, u_d = u_i + theta_i x (x_d - x_i) and
    theta_d = theta_i; each dependent CD component is that row of Lambda_d^T G Lambda_i.
    """
    if not deck.rigids:
        return
    pos = grid_positions(deck)
    for r in sorted(deck.rigids.values(), key=lambda e: e.id):
        i_row = dofs.grid_index(r.independent)
        lam_i = np.kron(np.eye(2), cd_frames[i_row])
        i_idx = dofs.indices(r.independent)
        for grid, comps in r.dependent:
            d_row = dofs.grid_index(grid)
            coupling = np.kron(np.eye(2), cd_frames[d_row]).T @ _rigid_transfer(pos[grid] - pos[r.independent]) @ lam_i
            for c in comps:
                d = dofs.index(grid, int(c))
                label = f"{r.card} {r.id}"
                _check_free(d, f"{r.source}: {label}: dependent DOF {grid}-{c}", fixed, equations, sources, labels)
                row = coupling[int(c) - 1]
                equations[d] = [(int(i_idx[k]), float(row[k])) for k in range(6) if abs(row[k]) > 1e-15]
                sources[d], labels[d] = r.source, label


def interpolation_equations(deck: Deck, dofs: DofMap, cd_frames: np.ndarray, fixed: np.ndarray,
                            equations: dict[int, list[tuple[int, float]]], sources: dict, labels: dict) -> None:
    """Add the equations of every RBE3 to ``equations`` (dependent index -> [(index, coefficient)], CD components).

    The reference grid moves with the rigid motion q = (u, theta) [m, rad] about it that best fits, in the
    weighted least-squares sense, the listed translations of the independent grids (the QRG's RBE3: "the
    motion at a reference grid point is the least square weighted average of the motions at the other grid
    points"). Independent grid i at r_i from the reference, rigidly moved, translates by u + theta x r_i
    = [I, -skew(r_i)] q; each listed CD component c is the row of Lambda_i^T [I, -skew(r_i)] it reads, with
    the group's weight w. q = (H^T W H)^-1 H^T W o over the observations o; the reference's REFC components
    are those rows of Lambda_ref^T q. A set of grids that cannot fix all six motions (fewer than three
    points, or all on one line) is refused, as the fit has no unique answer.
    """
    if not deck.interpolations:
        return
    pos = grid_positions(deck)
    for e in sorted(deck.interpolations.values(), key=lambda x: x.id):
        label = f"RBE3 {e.id}"
        rows, weights, columns = [], [], []
        for weight, comps, grids in e.groups:
            for grid in grids:
                reads = cd_frames[dofs.grid_index(grid)].T @ _rigid_transfer(pos[grid] - pos[e.reference])[:3]
                for c in comps:
                    rows.append(reads[int(c) - 1])
                    weights.append(weight)
                    columns.append(dofs.index(grid, int(c)))
        h, w = np.array(rows), np.array(weights)
        normal = h.T @ (w[:, None] * h)
        if np.linalg.cond(normal) > 1e12:
            raise MaceError(f"{e.source}: {label}: its independent grids and components do not fix the reference "
                            f"grid {e.reference}'s six rigid motions (expected at least three grids not on one "
                            "line, with enough translations listed)")
        fit = np.linalg.solve(normal, h.T * w)  # (6, n_observations): q from the observations
        coupling = np.kron(np.eye(2), cd_frames[dofs.grid_index(e.reference)]).T @ fit
        for c in e.reference_components:
            d = dofs.index(e.reference, int(c))
            _check_free(d, f"{e.source}: {label}: dependent DOF {e.reference}-{c}", fixed, equations, sources, labels)
            terms: dict[int, float] = {}
            for column, value in zip(columns, coupling[int(c) - 1]):
                terms[column] = terms.get(column, 0.0) + float(value)
            equations[d] = [(i, v) for i, v in terms.items() if abs(v) > 1e-15]
            sources[d], labels[d] = e.source, label


def build_constraints(deck: Deck, dofs: DofMap, cd_frames: np.ndarray, *, spc_set: int | None,
                      mpc_set: int | None) -> Constraints:
    """Eliminate SPC1 set ``spc_set``, GRID PS fields, MPC set ``mpc_set`` (first term dependent) and the
    dependent DOFs of every RBAR, RBE2 and RBE3.

    Parameters
    ----------
    deck : Deck
        The deck whose SPC1, GRID PS, MPC, RBAR, RBE2 and RBE3 cards apply.
    dofs : DofMap
        The model's DOFs (grid, component).
    cd_frames : numpy.ndarray
        (n_grids, 3, 3) displacement frames of the grids.
    spc_set, mpc_set : int or None
        The case control's SPC and MPC sets (None: none).

    Returns
    -------
    Constraints
        The transformation T from the independent DOFs to all DOFs.
    """
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
    labels = {d: f"MPC {mpc_set}" for d in equations}
    rigid_equations(deck, dofs, cd_frames, fixed, equations, sources, labels)
    interpolation_equations(deck, dofs, cd_frames, fixed, equations, sources, labels)

    independent = [i for i in range(n) if not fixed[i] and i not in equations]
    column = {i: k for k, i in enumerate(independent)}
    # T in the CD systems as sparse rows {column: coefficient}: a unit row per independent DOF, none for a
    # fixed one, and for a dependent one the sum of its terms' rows. A term may itself be dependent (RBAR
    # chains, RBE2 on an RBAR's grid): substitute it, as NASTRAN solves its m-set equations together; a
    # cycle has no solution.
    rows: dict[int, dict[int, float]] = {i: {k: 1.0} for i, k in column.items()}

    def row(i: int) -> dict[int, float]:
        return rows.get(i, {})

    def resolve(d: int, path: tuple[int, ...]) -> None:
        if d in rows:
            return
        if d in path:
            loop = " -> ".join(f"{labels[x]} ({sources[x]})" for x in path[path.index(d):])
            raise MaceError(f"{sources[d]}: {labels[d]}: dependent DOF {dofs.label(d)} depends on itself through "
                            f"{loop}")
        out: dict[int, float] = {}
        for i, a in equations[d]:
            if i in equations:
                resolve(i, path + (d,))
            for k, v in row(i).items():
                out[k] = out.get(k, 0.0) + a * v
        rows[d] = out

    for d in equations:
        resolve(d, ())
    r_idx = [i for i, entries in rows.items() for _ in entries]
    c_idx = [k for entries in rows.values() for k in entries]
    values = [v for entries in rows.values() for v in entries.values()]
    t_cd = sparse.coo_array((values, (r_idx, c_idx)), shape=(n, len(independent))).tocsr()
    transform = sparse.csr_array(cd_rotation(cd_frames) @ t_cd)
    return Constraints(transform=transform, independent=tuple(dofs.label(i) for i in independent),
                       spc_set=spc_set, mpc_set=mpc_set)
