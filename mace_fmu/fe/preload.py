"""Gravity preload of the suspended structure and the tangent stiffness about it.

Two options, as offered by NASTRAN:
- ``"large"`` (SOL 106 with PARAM,LGDISP,1): the load is applied in NLPARM increments with
  Newton iterations on the updated geometry; the tangent of the final state is the Hessian of
  the total potential (material + geometric stiffness at the deformed geometry).
- ``"linear"``: one linear static solution; the geometric stiffness comes from its bar forces,
  evaluated on the undeformed geometry (classic linear prestress).
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np
import scipy.linalg as sla
from scipy import sparse

from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import FEModel
from mace_fmu.fe.constraints import Constraints
from mace_fmu.fe.corotational import (BarState, advanced, bar_dof_indices, deformation_jacobian, internal_force, material_tangent,
                                      rotation_matrix, tangent, tangent_parts)
from mace_fmu.fe.modal import DENSE_MAX_DOF
from mace_fmu.sparse import factorize
from mace_fmu.util.progress import ProgressCallback, Step

PreloadKind = Literal["large", "linear"]
_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Preload:
    """Result of a gravity preload: the deformed state and the stiffness about it."""

    kind: PreloadKind  #: "large" (incremental, updated geometry) or "linear"
    displacements: np.ndarray  #: (n_dof,) translations [m] and rotation vectors [rad], basic
    tangent_stiffness: sparse.csr_array  #: K_T = K_material + K_geometric (+ springs), basic
    bar_forces: np.ndarray  #: (n_bar, 7) natural forces: axial [N], end moments [N m] (local)
    increments: int  #: load increments applied
    iterations: int  #: total Newton iterations
    residual_ratio: float  #: final ``|r| / |F|`` on the independent DOFs
    state: BarState  #: configuration the tangent is about (undeformed for the linear preload)
    constraints: Constraints | None = None  #: the static subcase's constraints (for the preload's sensitivities)
    full_tangents: int = 1  #: tangents with second derivatives built (the costly part; the product's included)


def _solve(k: sparse.sparray, r: np.ndarray, constraints: Constraints) -> np.ndarray:
    """Solve the reduced static system (positive definite about a stable state), or explain: dense
    Cholesky for a small system, sparse LU for a large one."""
    if k.shape[0] > DENSE_MAX_DOF:
        return _factor(k, constraints)(r)
    try:
        return sla.cho_solve(sla.cho_factor(k.toarray()), r)
    except (sla.LinAlgError, np.linalg.LinAlgError):
        raise MaceError(singular_message(k, constraints)) from None


def singular_message(k: sparse.sparray | np.ndarray, constraints: Constraints) -> str:
    """Why the reduced static stiffness ``k`` is singular, naming the grids and components that move freely:
    those without any stiffness on the diagonal (a grid attached to nothing), else, for a system small enough
    to decompose, the DOFs of its null space (a mechanism or a rigid-body motion the SPC and MPC sets leave)."""
    k = sparse.csr_array(k)
    diag = np.abs(k.diagonal())
    free = np.flatnonzero(diag <= 1e-12 * max(float(diag.max(initial=0.0)), 1e-300))
    what = "have no stiffness at all (attached to no element)"
    if not free.size and k.shape[0] <= DENSE_MAX_DOF:
        w, v = np.linalg.eigh(0.5 * (k + k.T).toarray())
        null = v[:, np.abs(w) <= 1e-10 * max(float(np.abs(w).max()), 1e-300)]
        free = np.flatnonzero(np.abs(null).max(axis=1) > 1e-3) if null.size else free
        what = "move without stiffness together (a mechanism or a rigid-body motion)"
    by_grid: dict[int, list[int]] = {}
    for i in free:
        grid, component = constraints.independent[i]
        by_grid.setdefault(grid, []).append(component)
    named = "; ".join(f"grid {g} component(s) {''.join(str(c) for c in sorted(cs))}"
                      for g, cs in list(by_grid.items())[:8]) + ("; ..." if len(by_grid) > 8 else "")
    return ("the preload stiffness is singular: " + (f"{named} {what}; " if by_grid else "")
            + "connect them, constrain them with an SPC (or PARAM,AUTOSPC,YES), or check the static subcase's SPC "
            "and MPC sets")


def _state(model: FEModel, u: np.ndarray) -> BarState:
    """BarState for displacements u (rotation vectors applied to the undeformed triads)."""
    u6 = u.reshape(-1, 6)
    return BarState(positions=model.positions + u6[:, :3], rotations=rotation_matrix(u6[:, 3:]))


def linear_preload(model: FEModel, constraints: Constraints, load: np.ndarray) -> Preload:
    """Linear static solution, then K + K_sigma from its bar forces on the undeformed geometry.

    Parameters
    ----------
    model : FEModel
        The structure.
    constraints : Constraints
        The static subcase's constraints.
    load : numpy.ndarray
        (n_dof,) load [N, N m].

    Returns
    -------
    Preload
        The linear displacements and the prestressed stiffness K + K_sigma.
    """
    t = constraints.transform
    u = t @ _solve(constraints.reduce_sparse(model.stiffness), t.T @ load, constraints)
    n = model.dofs.size
    undeformed = _state(model, np.zeros(n))
    _, b = deformation_jacobian(model.bars, undeformed)
    idx = bar_dof_indices(model.bars)
    d_lin = np.einsum("nki,ni->nk", b, u[idx])
    forces = np.einsum("nij,nj->ni", model.bars.k_natural, d_lin)
    _, k_bars, _ = tangent(model.bars, undeformed, n, natural_forces=forces)
    residual = np.linalg.norm(t.T @ (load - model.stiffness @ u)) / np.linalg.norm(t.T @ load)
    return Preload(kind="linear", displacements=u, tangent_stiffness=sparse.csr_array(k_bars + model.spring_stiffness),
                   bar_forces=forces, increments=1, iterations=1, residual_ratio=float(residual),
                   state=undeformed, constraints=constraints)


def _factor(k: np.ndarray | sparse.sparray, constraints: Constraints) -> Callable[[np.ndarray], np.ndarray]:
    """Sparse LU of the reduced stiffness as a solve function, or a clear error naming a mechanism's DOFs."""
    try:
        return factorize(k)
    except RuntimeError:
        raise MaceError(singular_message(k, constraints)) from None


def large_displacement_preload(model: FEModel, constraints: Constraints, load: np.ndarray, *, increments: int = 10,
                               max_iterations: int = 25, path_tolerance: float = 1e-3,
                               final_tolerance: float = 1e-14, progress: ProgressCallback | None = None) -> Preload:
    """Incremental Newton solution on the updated geometry (dead load), tangent of the final state.

    Each increment starts from a secant predictor and iterates with modified Newton: full
    tangents (second derivatives) in the first increment, where the unstressed cables have no
    lateral stiffness, and whenever an iteration stops contracting; otherwise the material
    stiffness of the current state plus the last full tangent's geometric stiffness scaled with
    the load. Intermediate increments only have to stay on the load path, to NLPARM's work
    tolerance ``path_tolerance`` (EPSW); the last one converges to ``final_tolerance``, and the
    tangent of its end state is the product. The same equilibrium and tangent as plain Newton
    (``tests/fe/test_preload_iterations.py``) with a fifth of the full tangents. The work criterion
    is NASTRAN's (CONV=W): the force residual itself stalls at round-off because the short
    aluminium links are ~1e10 N/m stiff.

    Parameters
    ----------
    model : FEModel
        The structure.
    constraints : Constraints
        The static subcase's constraints.
    load : numpy.ndarray
        (n_dof,) dead load [N, N m] (gravity).
    increments : int
        Load increments (NLPARM NINC).
    max_iterations : int
        Newton iterations per increment (NLPARM MAXITER).
    path_tolerance : float
        Work tolerance of the intermediate increments (NLPARM EPSW).
    final_tolerance : float
        Work tolerance of the last increment.
    progress : callable, optional
        Called with a :class:`~mace_fmu.util.progress.Step` per increment.

    Returns
    -------
    Preload
        The deformed state, the tangent stiffness about it, the bar forces and the convergence record.

    Raises
    ------
    MaceError
        A singular stiffness (a mechanism) or an increment that does not converge.
    """
    t = constraints.transform
    n = model.dofs.size
    u = np.zeros(n)  # translations and accumulated spins, for the springs and the report
    k_springs = model.spring_stiffness
    state = BarState(model.positions.copy(), np.broadcast_to(np.eye(3), (len(model.positions), 3, 3)).copy())
    total_iterations = 0
    last_increment = np.zeros(n)

    advance = advanced
    geometric, reference_step, tangents = None, 0, 0
    for step in range(1, increments + 1):
        final = step == increments
        target = load * step / increments
        state = advance(state, last_increment)  # secant predictor
        u_start = u.copy()
        u = u + last_increment
        previous, refresh = np.inf, geometric is None
        for it in range(1, max_iterations + 1):  # noqa: B007  (read after the loop: the count it took)
            # Full Newton from the unstressed state (the cables have no lateral stiffness yet) and when
            # an iteration stops contracting. Elsewhere the iteration matrix is the material stiffness
            # at the current state (first derivatives: cheap) plus the last full tangent's geometric
            # stiffness scaled with the load, which gravity's stress stiffness (cables, pendulum
            # stages) is proportional to; second derivatives cost 11x. (Keeping one factorisation per
            # increment instead diverged on a 100k-DOF tower and saved nothing measurable at 10k.)
            if step == 1 or refresh:
                parts = tangent_parts(model.bars, state, n)
                f_int, k_bars = parts.internal_force, parts.material + parts.geometric
                geometric, reference_step, tangents = parts.geometric, step, tangents + 1
            else:
                assert geometric is not None  # the first step's, or the one given
                f_int, k_material = material_tangent(model.bars, state, n)
                k_bars = k_material + (step / reference_step) * geometric
            solve = _factor(t.T @ (k_bars + k_springs) @ t, constraints)
            residual = t.T @ (target - f_int - model.spring_stiffness @ u)
            delta = t @ solve(residual)
            total_iterations += 1
            state = advance(state, delta)
            u = u + delta
            work_ratio = abs(delta @ (t @ residual)) / max(abs(u @ target), 1e-300)
            if work_ratio <= (final_tolerance if final else path_tolerance):
                break
            refresh, previous = work_ratio > 0.25 * previous, work_ratio
        else:
            raise MaceError(f"gravity preload did not converge: increment {step}/{increments}, work ratio "
                            f"{work_ratio:.2e} after {max_iterations} iterations")
        last_increment = u - u_start
        detail = f"{it} iterations, work ratio {work_ratio:.1e}, {tangents} tangents so far"
        _log.debug("gravity preload increment %d/%d: %s", step, increments, detail)
        if progress is not None:
            progress(Step(task="gravity preload", done=step, total=increments, detail=detail))
    f_int, k_bars, forces = tangent(model.bars, state, n)
    ratio = np.linalg.norm(t.T @ (load - f_int - model.spring_stiffness @ u)) / np.linalg.norm(t.T @ load)
    return Preload(kind="large", displacements=u, tangent_stiffness=sparse.csr_array(k_bars + model.spring_stiffness),
                   bar_forces=forces, increments=increments, iterations=total_iterations, residual_ratio=float(ratio),
                   state=state, constraints=constraints, full_tangents=tangents + 1)


def tangent_sensitivity(model: FEModel, preload: Preload, *, bar_mask: np.ndarray | None = None,
                        dk_natural: np.ndarray | None = None, dk_springs: sparse.sparray | None = None,
                        load_change: np.ndarray | None = None, relative_step: float = 1e-2, solve: Callable[[np.ndarray], np.ndarray] | None = None
                        ) -> sparse.csr_array:
    """d K_T / d(ln p) about a large-displacement preload, the preload re-solved to first order (sparse, basic).

    A stiffness parameter p enters the bars ``bar_mask`` through d K_n / d(ln p) = ``dk_natural``
    (n_masked, 7, 7) and/or the springs through ``dk_springs`` (n_dof x n_dof). Changing it puts the
    deformed structure out of balance by d f = (d K_n d, d K_s u) at the same deformation; the
    equilibrium moves by d u = -K_T^-1 d f (dead load), and with it the bar forces and the geometry the
    geometric stiffness depends on. Returned: [K_T(S + h du, p (1 + h)) - K_T(S - h du, p (1 - h))] / 2h,
    the tangent's total derivative (material part, new forces, new geometry). Holding the preload's
    forces instead (the material part alone) missed 22-92 % of the 1-g responses' derivatives with
    respect to the suspension cables' moduli, which redistribute the gravity load among the cables.
    ``load_change`` (n_dof,) [N, N m per unit ln p] is the dead load's own change, a mass parameter's weight
    (d M times the gravity field, :func:`mace_fmu.fe.modes.gravity_field`): the equilibrium then moves by
    K_T^-1 (d F - d f).
    ``solve`` (:func:`preload_solver`) reuses one factorisation of the reduced tangent for many parameters.
    """
    if preload.kind != "large" or preload.constraints is None:
        raise MaceError("tangent_sensitivity: needs a large-displacement preload with its constraints")
    n = model.dofs.size
    bars = model.bars
    df = np.zeros(n)
    if dk_natural is not None:
        mask = np.asarray(bar_mask, dtype=bool)
        changed = dataclasses.replace(bars, ids=bars.ids[mask], node_a=bars.node_a[mask], node_b=bars.node_b[mask],
                                      frames0=bars.frames0[mask], lengths0=bars.lengths0[mask], k_natural=dk_natural)
        df += internal_force(changed, preload.state, n)
    if dk_springs is not None:
        df += dk_springs @ preload.displacements
    if load_change is not None:
        df -= load_change
    t = preload.constraints.transform
    du = -(t @ (solve or preload_solver(preload))(t.T @ df))
    out = []
    for sign in (1.0, -1.0):
        h = sign * relative_step
        k_nat = bars.k_natural
        if dk_natural is not None:
            k_nat = k_nat.copy()
            k_nat[np.asarray(bar_mask, dtype=bool)] += h * dk_natural
        _, k_bars, _ = tangent(dataclasses.replace(bars, k_natural=k_nat), advanced(preload.state, h * du), n)
        out.append(sparse.csr_array(k_bars))
    dk = (out[0] - out[1]) / (2.0 * relative_step)
    return dk if dk_springs is None else sparse.csr_array(dk + sparse.csr_array(dk_springs))


def linear_tangent_sensitivity(model: FEModel, preload: Preload, *, bar_mask: np.ndarray | None = None,
                               dk_natural: np.ndarray | None = None, dk_springs: sparse.sparray | None = None,
                               load_change: np.ndarray | None = None,
                               solve: Callable[[np.ndarray], np.ndarray] | None = None) -> sparse.csr_array:
    """d K_T / d(ln p) about a linear preload, its static solution re-solved (sparse, basic).

    The linear preload's tangent is K + K_sigma(N), N = K_n B u the bar forces of the linear solution u = K^-1 F
    on the undeformed geometry (:func:`linear_preload`). A stiffness change d K (bars ``bar_mask`` by
    ``dk_natural``, springs by ``dk_springs``; a mass's weight ``load_change``) moves the solution by
    d u = K^-1 (d F - d K u), and the forces by d N = d K_n B u + K_n B d u, which K_sigma is linear in: the
    derivative is exact (d K + K_sigma(d N)). Holding the forces instead (the material part alone) left the
    1-g FMU with a linear preload 0.22 % off the re-solve at +-5 % of every modulus at once. ``solve``
    (:func:`linear_preload_solver`) reuses one factorisation of the reduced K for many parameters.
    """
    if preload.kind != "linear" or preload.constraints is None:
        raise MaceError("linear_tangent_sensitivity: needs a linear preload with its constraints")
    n = model.dofs.size
    bars = model.bars
    _, b = deformation_jacobian(bars, preload.state)
    idx = bar_dof_indices(bars)
    u = preload.displacements
    deformation = np.einsum("nki,ni->nk", b, u[idx])
    dk = sparse.csr_array((n, n))
    dn_own = np.zeros_like(preload.bar_forces)
    df = np.zeros(n)
    if dk_natural is not None:
        mask = np.asarray(bar_mask, dtype=bool)
        dn_own[mask] = np.einsum("nij,nj->ni", dk_natural, deformation[mask])
        f_e = np.einsum("nki,nk->ni", b[mask], dn_own[mask])
        df += np.bincount(idx[mask].ravel(), weights=f_e.ravel(), minlength=n)
        dk_bars = np.zeros_like(bars.k_natural)
        dk_bars[mask] = dk_natural
        dk = dk + material_tangent(dataclasses.replace(bars, k_natural=dk_bars), preload.state, n)[1]
    if dk_springs is not None:
        df += dk_springs @ u
        dk = dk + sparse.csr_array(dk_springs)
    if load_change is not None:
        df -= load_change
    t = preload.constraints.transform
    du = -(t @ (solve or linear_preload_solver(model, preload))(t.T @ df))
    dn = dn_own + np.einsum("nij,nj->ni", bars.k_natural, np.einsum("nki,ni->nk", b, du[idx]))
    geometric = tangent_parts(bars, preload.state, n, natural_forces=dn).geometric
    return sparse.csr_array(dk + geometric)


def linear_preload_solver(model: FEModel, preload: Preload) -> Callable[[np.ndarray], np.ndarray]:
    """Solve with the linear preload's reduced stiffness T^T K T (factored once): its static solution's matrix."""
    constraints = _constraints(preload)
    t = constraints.transform
    return _factor(t.T @ model.stiffness @ t, constraints)


def preload_solver(preload: Preload) -> Callable[[np.ndarray], np.ndarray]:
    """Solve with the preload's reduced tangent T^T K_T T (factored once): for :func:`tangent_sensitivity`."""
    constraints = _constraints(preload)
    t = constraints.transform
    return _factor(t.T @ preload.tangent_stiffness @ t, constraints)


def _constraints(preload: Preload) -> Constraints:
    """The static subcase's constraints a preload was solved with (every preload this module makes has them)."""
    if preload.constraints is None:
        raise MaceError("the preload carries no constraints: solve it with linear_preload or "
                        "large_displacement_preload")
    return preload.constraints


def geometric_stiffness(model: FEModel, constraints: Constraints, load: np.ndarray) -> sparse.csr_array:
    """K_sigma of the linear static solution under ``load`` (undeformed geometry), basic DOFs.

    Buckling load factors lambda solve (K + lambda K_sigma) phi = 0.
    """
    return linear_preload(model, constraints, load).tangent_stiffness - model.stiffness
