"""How a Young's modulus or a spring stiffness reaches the modal model, so that it moves every channel as
a full re-solve does.

Three pieces per physical parameter p, all about the configuration the modes are of:

1. the modal stiffness change Phi0^T dK/d(ln p) Phi0 (eq. 4.6-4.9), dK the tangent's total derivative:
   in 1-g with the large-displacement preload, the preload re-solved to first order (a stiffer cable
   takes more of the weight, and the forces and geometry move with it);
2. static-correction vectors W: the residual flexibility's response to the forces the *material*
   part of dK (the preload's forces held) puts on each retained mode. The retained modes cannot
   follow a local change: a gauge or a piezo patch on the changed element reads the rotations of
   massless grids, condensed with the nominal stiffness, and the element's own flexibility lies in
   modes far above the retained band. With W in the Ritz basis (:mod:`mace_fmu.iomodel.reanalysis`)
   the massless DOFs are condensed with the changed stiffness and the truncated modes' static part
   follows. Only the material part enters W's blocks: it is linear in p and positive, so the reduced
   problem stays positive definite for any change; the preload's part, linearised, is not (a cable's
   axial stiffness turned by a first-order rotation);
3. the preload part's first-order change of each retained mode shape, -K^-1 (dK - dK_material) phi_k
   without the retained modes' components, carried as changes of the output rows and modal inputs
   per unit relative change.

Measured on MACE (tests/iomodel/test_parameter_route.py, benchmarks/RESULTS.md): the strain gauge on the
active strut, whose modulus the nominal modes alone moved 31-85 % wrong, follows the re-solve to
better than 0.1 %.

A concentrated mass (CONM2, ``m_<name>``: a scaled body, mass and inertias by one factor) enters the same
way with the roles turned: its mass matrix dM/d(ln m) (exact, the mass is linear in the factor) gives the
modal mass change Phi0^T dM Phi0 and mass-correction vectors, the residual flexibility's response to the
inertia forces dM phi_k the change puts on each retained mode, orthonormalised together with the
stiffness corrections; its material stiffness change is zero. In 1-g the mass changes the weight the
preload carries, d F = dM g (g the GRAV field): the tangent's total derivative with that load change
(:func:`~mace_fmu.fe.preload.tangent_sensitivity`; the linear preload's geometric stiffness is linear in
the load) is its ``total`` stiffness change, carried as the moduli's preload part is.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy import sparse

from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import FEModel, bar_section, conm2_mass
from mace_fmu.fe.beam import natural_stiffness
from mace_fmu.fe.corotational import BarState, material_tangent
from mace_fmu.fe.modal import Modes
from mace_fmu.fe.modes import gravity_field
from mace_fmu.fe.preload import (Preload, geometric_stiffness, linear_preload_solver, linear_tangent_sensitivity,
                                 preload_solver, tangent_sensitivity)
from mace_fmu.iomodel.modal_ss import modal_data
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.parameters.kinds import MASS, MODULUS, SPRING
from mace_fmu.parameters.sets import parameter_names
from mace_fmu.sparse import factorize
from mace_fmu.util.frequency import ZERO_HZ

_RELATIVE_STEP = 1e-3  # the material stiffness is linear in E and k: the difference quotient is exact
#: correction directions (K-orthonormal) kept: eigenvalues of their stiffness Gram matrix above this
#: fraction of the largest; below it they repeat others to round-off
GRAM_TOLERANCE = 1e-10
#: a correction direction whose own frequency lies above this multiple of the highest retained mode
#: acts statically in the retained band: it is condensed as massless (keeping its tiny mass would only
#: bring its round-off into the eigen-solution)
MASSIVE_FACTOR = 10.0
#: the correction solves use K + s M, s this fraction of the lowest flexible omega^2 (rigid bodies and
#: mechanisms make K singular; the loads carry no component along them, so s changes nothing else)
SHIFT_FRACTION = 1e-3
#: a mass parameter whose modal mass change on a zero-frequency mode exceeds this (the modes are mass-normalised:
#: a share of that mode's unit modal mass) is refused (physical_route)
RIGID_SHARE = 1e-6
#: kinds of output rows (ParametricSystem) that the corrections are projected on
ROW_KINDS = ("disp", "rate", "motion", "acc")
#: how a physical parameter acts, for the FMU's parameter description
_TAKES_EFFECT = ("takes effect at initialisation: the structure solved again (mace_fmu.iomodel.resolve), or re-analysed "
                 "on the retained modes and static corrections where the FMU cannot solve it")



@dataclass(frozen=True)
class StiffnessSensitivity:
    """One physical parameter and its stiffness derivatives [N/m, N m/rad per unit ln p] on the basic DOFs."""

    name: str  #: FMU and parameter-set name, e.g. "E_active_strut_center"
    value: float  #: nominal value [Pa, N/m]
    description: str  #: what it is, for the FMU's parameter description
    total: sparse.csr_array  #: dK/d(ln p), the preload re-solved to first order (1-g large preload)
    material: sparse.csr_array  #: the same with the preload's forces held (equal to ``total`` otherwise)
    mass: sparse.csr_array | None = None  #: dM/d(ln p) [kg, kg m, kg m^2] of a mass parameter (None: a stiffness)


def material_sensitivity(fe: FEModel, deck, preload: Preload | None, mid: int, *, solve=None,
                         forces_held: bool = False) -> sparse.csr_array:
    """dK/d(ln E) [N/m, N m/rad] of MAT1 ``mid``: the material stiffness of its bars per unit relative change.

    About the configuration the modes are computed in. 1-g with the large-displacement preload: the
    tangent's total derivative with the preload re-solved to first order
    (:func:`~mace_fmu.fe.preload.tangent_sensitivity`), unless ``forces_held``. Otherwise (the linear
    preload; 0-g; ``forces_held``) the preloaded geometry with the preload's bar forces held, so a change
    of E changes only the material part. Taking the undeformed geometry instead puts spurious strain
    into the near-rigid suspension modes: Z tilt, X twist and 1st Y bending then came out 1.9e-3 to
    2.9e-3 off after E of the Lexan center +5 %, against 7.8e-4 at most this way. The bar stiffness is
    linear in E (and in G, which NASTRAN derives from E when blank), so the difference of the natural
    stiffnesses is exact; only this material's bars are evaluated.
    """
    ids = fe.bars.ids
    mine = np.array([deck.pbars[deck.bars[int(i)].pid].mid == mid for i in ids])
    mat = deck.mat1s[mid]
    plus = dataclasses.replace(mat, e=mat.youngs_modulus * (1 + _RELATIVE_STEP))  # G follows E when blank

    # depends on the section and the length only: once per distinct pair, as the assembly does (a lattice of
    # 100k DOFs has a handful of pairs among its bars, and 8 of a 30k tower's 23 s export went here bar by bar)
    deltas: dict[tuple[int, float], np.ndarray] = {}

    def section_delta(pid: int, length: float) -> np.ndarray:
        if (pid, length) not in deltas:
            sec = bar_section(deck, pid)
            stiffer = dataclasses.replace(sec, e=plus.youngs_modulus, g=plus.shear_modulus)
            deltas[pid, length] = (natural_stiffness(stiffer, length) - natural_stiffness(sec, length)) / _RELATIVE_STEP
        return deltas[pid, length]

    dkn = np.array([section_delta(deck.bars[int(i)].pid, length)
                    for i, length in zip(ids[mine].tolist(), fe.bars.lengths0[mine].tolist())]).reshape(-1, 7, 7)
    if _redistributes(preload) and not forces_held:
        # the gravity load redistributes (suspension cables, springs): the preload re-solved to first order
        return _preload_sensitivity(fe, preload)(fe, preload, bar_mask=mine, dk_natural=dkn, solve=solve)
    bars = dataclasses.replace(fe.bars, ids=ids[mine], node_a=fe.bars.node_a[mine], node_b=fe.bars.node_b[mine],
                               frames0=fe.bars.frames0[mine], lengths0=fe.bars.lengths0[mine], k_natural=dkn)
    if preload is not None:
        state = preload.state
    else:  # 0-g: the undeformed geometry, where the corotational tangent is the linear stiffness
        state = BarState(fe.positions, np.broadcast_to(np.eye(3), (len(fe.positions), 3, 3)))
    # forces held (zero change): only the material part B^T dK_n B of the tangent remains
    return sparse.csr_array(material_tangent(bars, state, fe.dofs.size)[1])


def _redistributes(preload: Preload | None) -> bool:
    """A preload with its constraints: a stiffness change moves the preload itself."""
    return preload is not None and preload.constraints is not None


def _preload_sensitivity(fe: FEModel, preload: Preload):
    """The preload's total derivative of its kind: the large one's (updated geometry) or the linear one's."""
    return tangent_sensitivity if preload.kind == "large" else linear_tangent_sensitivity


def _preload_solver(fe: FEModel, preload: Preload):
    """One factorisation for all of a preload's sensitivities."""
    return preload_solver(preload) if preload.kind == "large" else linear_preload_solver(fe, preload)


def stiffness_sensitivities(model: VoltsModel, *, only: Sequence[str] | None = None) -> list[StiffnessSensitivity]:
    """The moduli (of the MAT1 cards the bars use), springs and named masses of ``model``'s structure, or those
    named ``only``, with their stiffness (and mass) derivatives."""
    modes = model.structure_modes
    deck, fe, pre = modes.structure.deck, modes.model, modes.preload
    names = parameter_names(deck, modes.structure.file)
    material_name = {mid: name for name, mid in names.materials.items()}
    spring_name = {sid: name for name, sid in names.springs.items()}
    solve = _preload_solver(fe, pre) if _redistributes(pre) else None
    out = []
    for mid in sorted({deck.pbars[b.pid].mid for b in deck.bars.values()}):
        name = MODULUS.named(material_name[mid])
        if only is not None and name not in only:
            continue
        held = material_sensitivity(fe, deck, pre, mid, forces_held=True)
        total = material_sensitivity(fe, deck, pre, mid, solve=solve) if _redistributes(pre) else held
        out.append(StiffnessSensitivity(
            name, deck.mat1s[mid].youngs_modulus, f"Young's modulus of {material_name[mid]} (MAT1 {mid}) [Pa]; "
            f"{_TAKES_EFFECT}", total, held))
    for row, (sid, k) in enumerate(zip(fe.spring_ids, fe.spring_constants)):
        name = SPRING.named(spring_name[sid])
        if only is not None and name not in only:
            continue
        e = sparse.csr_array(fe.spring_vectors[[row]])  # (1, n_dof)
        held = sparse.csr_array(k * (e.T @ e))
        total = sparse.csr_array(_preload_sensitivity(fe, pre)(fe, pre, dk_springs=held, solve=solve)) \
            if _redistributes(pre) else held
        out.append(StiffnessSensitivity(name, float(k), f"stiffness of {spring_name[sid]} (CELAS2 {sid}) [N/m]; "
                                        f"{_TAKES_EFFECT}", total, held))
    for short, eid in names.masses.items():
        name = MASS.named(short)
        if only is not None and name not in only:
            continue
        dm = conm2_mass(deck, fe.dofs, eid)
        out.append(StiffnessSensitivity(name, float(deck.conm2s[eid].mass),
                                        f"mass of {short} (CONM2 {eid}) [kg], its inertias scaled with it; {_TAKES_EFFECT}",
                                        _weight_stiffness(modes, dm, solve), sparse.csr_array(dm.shape), dm))
    return out


def _weight_stiffness(modes, dm: sparse.csr_array, solve) -> sparse.csr_array:
    """dK/d(ln m) of a mass parameter with mass matrix ``dm``: the 1-g preload under the weight change dM g (the
    large preload re-solved to first order, the linear one's geometric stiffness linear in the load); zero in
    0-g."""
    pre, struct = modes.preload, modes.structure
    if pre is None or struct.preload is None:
        return sparse.csr_array(dm.shape)
    load = dm @ gravity_field(struct.deck, modes.model, struct.preload.load)
    if pre.constraints is None:
        return sparse.csr_array(dm.shape)
    if pre.kind == "large":
        return sparse.csr_array(tangent_sensitivity(modes.model, pre, load_change=load, solve=solve))
    # the linear preload: the load's change moves the static solution, whose geometric stiffness is linear in it
    return sparse.csr_array(geometric_stiffness(modes.model, pre.constraints, load))


@dataclass(frozen=True)
class PhysicalRoute:
    """The physical parameters of a ParametricSystem and the arrays that carry them (module docstring)."""

    parameters: tuple[tuple[str, float, str], ...]  #: (name, nominal value [SI], description)
    arrays: dict[str, np.ndarray]  #: physical_names, physical_dk, correction_*, *_correction, *_preload, preload_b


def physical_route(model: VoltsModel, shapes: np.ndarray, sensitivities: Sequence[StiffnessSensitivity]
                   ) -> PhysicalRoute:
    """The arrays through which ``sensitivities`` act on the retained modes ``shapes`` (n_dof, n_modes) of ``model``.

    Parameters
    ----------
    model : VoltsModel
        The model whose structure, instruments and motion outputs the rows are for.
    shapes : numpy.ndarray
        Its retained mode shapes on the basic DOFs (mass-normalised).
    sensitivities : sequence of StiffnessSensitivity
        The physical parameters, in the order the arrays keep.

    Returns
    -------
    PhysicalRoute
        Parameters and arrays for :func:`mace_fmu.iomodel.parametric_data.with_physical`.
    """
    modes = model.structure_modes
    n = shapes.shape[1]
    frequencies = _frequencies_of(model, n)
    flexible = np.abs(frequencies) >= ZERO_HZ
    dk = np.array([shapes.T @ (s.total @ shapes) for s in sensitivities]).reshape(len(sensitivities), n, n)
    # Rigid-body and mechanism modes carry no strain energy: their computed sensitivities (3e-9
    # of the largest, the round-off of the mechanism shapes) are noise, which the reanalysis
    # would couple into the flexible modes (up to 6e-7 of an output's range for E x 0.5).
    dk[:, ~flexible, :] = 0.0
    dk[:, :, ~flexible] = 0.0
    arrays = {"physical_names": np.array([s.name for s in sensitivities]), "physical_dk": dk}
    if any(s.mass is not None for s in sensitivities):
        dm = np.array([shapes.T @ (s.mass @ shapes) if s.mass is not None else np.zeros((n, n))
                       for s in sensitivities]).reshape(len(sensitivities), n, n)
        # the zero-frequency cluster is reduced once, at export, with its nominal mass: a mass that moves in a
        # rigid-body or mechanism mode would change that cluster's modal inputs, which no FMU recomputes
        moved = [s.name for s, d in zip(sensitivities, dm) if np.max(np.abs(d[~flexible]), initial=0.0) > RIGID_SHARE]
        if moved:
            raise MaceError(f"mass parameter(s) {', '.join(moved)}: the mass moves in a rigid-body or mechanism mode "
                            f"of the {model.structure_modes.structure.configuration} model, whose reduction an FMU "
                            "does not redo; a mass is a parameter of a structure held against rigid motion (name "
                            "none in the structure file's [parameters] masses for this configuration)")
        dm[:, ~flexible, :] = 0.0
        dm[:, :, ~flexible] = 0.0
        arrays["physical_dm"] = dm
    if sensitivities and modes.constraints is not None and np.any(flexible):
        arrays.update(_corrections(model, shapes, frequencies, flexible, sensitivities))
    return PhysicalRoute(tuple((s.name, s.value, s.description) for s in sensitivities), arrays)


def _frequencies_of(model: VoltsModel, n: int) -> np.ndarray:
    """Frequencies [Hz] of the first ``n`` modes of the model's structure (the retained ones)."""
    return np.asarray(model.structure_modes.frequencies_hz[:n], dtype=float)


class _Independent:
    """The constrained problem the modes solve, on the independent DOFs: K + s M factored once."""

    def __init__(self, model: VoltsModel, shapes: np.ndarray, frequencies: np.ndarray, flexible: np.ndarray):
        modes = model.structure_modes
        t = modes.constraints.transform
        self.t = t
        self.k = sparse.csr_array(t.T @ modes.stiffness @ t)
        self.m = sparse.csr_array(t.T @ modes.model.mass @ t)
        # the grid of each independent DOF: the ordering then works on the graph of grids, as the modes' did
        groups = np.array([grid for grid, _ in modes.constraints.independent])
        # T phi_i = shapes
        self.phi = factorize(sparse.csr_array(t.T @ t), positive_definite=True, groups=groups)(t.T @ shapes)
        shift = SHIFT_FRACTION * float(np.min((2.0 * np.pi * frequencies[flexible]) ** 2))
        try:
            self.solve = factorize(self.k + shift * self.m, positive_definite=True, groups=groups)
        except RuntimeError:
            raise MaceError("static corrections: K + s M is singular (a DOF with neither stiffness nor mass)") from None

    def reduce(self, matrix: sparse.sparray) -> sparse.csr_array:
        return sparse.csr_array(self.t.T @ matrix @ self.t)

    def residual(self, forces: np.ndarray) -> np.ndarray:
        """K^-1 of ``forces`` without their components along the retained modes: the part the truncated
        modes and the massless DOFs take; the result carries no retained mode either."""
        forces = forces - self.m @ (self.phi @ (self.phi.T @ forces))  # no work on any retained mode
        response = self.solve(forces) if forces.shape[1] else forces
        return response - self.phi @ (self.phi.T @ (self.m @ response))


def _corrections(model: VoltsModel, shapes: np.ndarray, frequencies: np.ndarray, flexible: np.ndarray,
                 sensitivities: Sequence[StiffnessSensitivity]) -> dict[str, np.ndarray]:
    """The static-correction vectors' blocks and rows, and the preload's shape changes (module docstring)."""
    ind = _Independent(model, shapes, frequencies, flexible)
    material = [ind.reduce(s.material) for s in sensitivities]
    masses = [ind.reduce(s.mass) if s.mass is not None else None for s in sensitivities]
    flex = ind.phi[:, flexible]
    # the residual flexibility's response to each parameter's forces on each retained mode: a stiffness's
    # dK phi_k, a mass's inertia forces dM phi_k (omega_k^2 scales a column, which the orthonormalisation undoes)
    w = np.hstack([ind.residual((dk if dm is None else dm) @ flex) for dk, dm in zip(material, masses)]) \
        if material else np.zeros((ind.phi.shape[0], 0))
    w, massive = _orthonormal(ind, w, max_hz=float(np.max(np.abs(frequencies))))
    n, n_w = shapes.shape[1], w.shape[1]

    def blocks(changes: list) -> tuple[np.ndarray, np.ndarray]:
        """W^T dX_i W and W^T dX_i Phi0 of each parameter's stiffness or mass change dX_i."""
        square = np.array([_symmetric(w.T @ (d @ w)) for d in changes]).reshape(len(changes), n_w, n_w)
        coupling = np.zeros((len(changes), n_w, n))
        coupling[:, :, flexible] = np.array([w.T @ (d @ flex) for d in changes]).reshape(
            len(changes), n_w, int(flexible.sum()))
        return square, coupling

    out: dict[str, np.ndarray] = {"correction_massive": np.array(massive, dtype=np.int64),
                                  "correction_stiffness": _symmetric(w.T @ (ind.k @ w))}
    out["correction_dk"], out["correction_coupling"] = blocks(material)
    if any(dm is not None for dm in masses):
        zero = sparse.csr_array(ind.m.shape)
        out["correction_dm"], out["correction_mass_coupling"] = blocks([zero if dm is None else dm for dm in masses])
    projected = _project(model, ind.t @ w)
    out["correction_b"] = projected.pop("b")
    out.update({f"{kind}_correction": rows for kind, rows in projected.items()})
    # the preload's part of each parameter: first-order shape changes of the flexible modes
    preload = {f"{kind}_preload": [] for kind in ROW_KINDS} | {"preload_b": []}
    for s in sensitivities:
        change = np.zeros((ind.phi.shape[0], n))
        part = ind.reduce(s.total - s.material)
        if part.nnz:
            change[:, flexible] = -ind.residual(part @ flex)
        rows = _project(model, ind.t @ change)
        preload["preload_b"].append(rows.pop("b"))
        for kind, value in rows.items():
            preload[f"{kind}_preload"].append(value)
    out.update({key: np.array(value).reshape(len(sensitivities), *_shape_of(value, n)) for key, value in
                preload.items()})
    return out


def _shape_of(value: list[np.ndarray], n: int) -> tuple[int, ...]:
    return value[0].shape if value else (0, n)


def _symmetric(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + a.T)


def _orthonormal(ind: _Independent, w: np.ndarray, *, max_hz: float) -> tuple[np.ndarray, int]:
    """The span of ``w`` as stiffness-orthonormal vectors without their repeats, ordered massive first
    (mass-orthonormal: the directions whose own frequency lies within MASSIVE_FACTOR x ``max_hz``), then the
    massless ones; and how many are massive."""
    if not w.shape[1]:
        return w, 0
    gram = _symmetric(w.T @ (ind.k @ w) + 0.0)
    lam, u = np.linalg.eigh(gram)
    keep = lam > GRAM_TOLERANCE * max(float(lam.max()), 1e-300)
    w = w @ (u[:, keep] / np.sqrt(lam[keep]))
    w = w - ind.phi @ (ind.phi.T @ (ind.m @ w))
    lam, u = np.linalg.eigh(_symmetric(w.T @ (ind.m @ w)))
    # w is K-normalised: lam = 1 / omega^2 of each direction
    massive = lam > 1.0 / (2.0 * np.pi * MASSIVE_FACTOR * max(max_hz, ZERO_HZ)) ** 2
    return np.hstack([w @ (u[:, massive] / np.sqrt(lam[massive])), w @ u[:, ~massive]]), int(massive.sum())


def _project(model: VoltsModel, vectors: np.ndarray) -> dict[str, np.ndarray]:
    """Output rows of each kind (n_rows, n_vectors) and the modal inputs ``b`` (n_vectors, n_actuators) of
    basic-DOF ``vectors``, as :func:`~mace_fmu.iomodel.modal_ss.modal_data` reads modes."""
    modes = model.structure_modes.modes
    count = vectors.shape[1]
    as_modes = Modes(frequencies_hz=np.zeros(count), shapes=vectors, dofs=modes.dofs, cd_frames=modes.cd_frames,
                     labels=("",) * count)
    data = modal_data(as_modes, model.instruments, max_hz=np.inf, motion_grids=list(model.plant.motion_grids))

    def table(rows: dict[str, np.ndarray]) -> np.ndarray:
        return np.array(list(rows.values())).reshape(len(rows), count)

    return {"disp": table(data.disp_out), "rate": table(data.rate_out), "motion": table(data.motion_out),
            "acc": table(data.acc_out), "b": data.modal_b}
