"""The arrays with which :class:`~mace_fmu.iomodel.resolve.ExactModes` solves a structure again.

The FE data the re-solve needs (bars, springs, masses, gravity, constraints, the nominal equilibrium and modes)
and the instruments' influence rows on every DOF, so that new mode shapes project on the outputs and inputs as
the export projects the nominal ones (:func:`mace_fmu.iomodel.modal_ss.modal_data`).
"""

from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import reverse_cuthill_mckee

from mace_fmu.fe.assembly import conm2_mass
from mace_fmu.fe.corotational import BarState, material_tangent
from mace_fmu.fe.modal import DENSE_MAX_DOF
from mace_fmu.fe.modes import gravity_field
from mace_fmu.iomodel.modal_ss import modal_data
from mace_fmu.iomodel.stiffness_route import ROW_KINDS
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.parameters.kinds import MASS, MODULUS, SPRING
from mace_fmu.parameters.sets import parameter_names
from mace_fmu.util.frequency import ZERO_HZ


def _coo(key: str, matrix: sparse.sparray) -> dict[str, np.ndarray]:
    m = sparse.coo_array(matrix)
    return {f"{key}_data": m.data.astype(np.float64), f"{key}_rows": m.row.astype(np.int64),
            f"{key}_cols": m.col.astype(np.int64)}


def _profile_ordered(transform: sparse.sparray, matrix: sparse.sparray) -> sparse.csr_array:
    """``transform``'s columns in reverse Cuthill-McKee order of T^T A T: the reduced matrices become bands, whose
    Cholesky factors the runtime computes within their envelope (570 static DOFs of MACE: 76,000 multiply-adds
    instead of 31 million)."""
    if transform.shape[1] == 0:
        return sparse.csr_array(transform)
    reduced = sparse.csr_array(transform.T @ matrix @ transform)
    order = reverse_cuthill_mckee(reduced, symmetric_mode=True)
    return sparse.csr_array(sparse.csc_array(transform)[:, order])


def resolve_supported(model: VoltsModel) -> bool:
    """Whether ``model``'s structure can be solved again at initialisation: an FE model (not NASTRAN's modes)
    in 0-g or with the large-displacement 1-g preload, small enough for a dense eigen-solution."""
    modes = model.structure_modes.solved_structure
    if modes is None:  # NASTRAN's modes: no FE to solve
        return False
    pre = modes.preload
    return (bool(modes.physical_kinds) and modes.constraints is not None and (pre is None or pre.kind == "large")
            and modes.model.dofs.size <= DENSE_MAX_DOF)


def resolve_arrays(model: VoltsModel, physical_names: Sequence[str]) -> dict[str, np.ndarray]:
    """The ``resolve_*`` arrays of ``model`` for the physical parameters ``physical_names`` (their order in the
    parameter vector's physical part); empty when :func:`resolve_supported` says no."""
    modes = model.structure_modes.solved_structure
    if not resolve_supported(model) or modes is None:
        return {}
    fe, pre, deck = modes.model, modes.preload, modes.structure.deck
    assert modes.constraints is not None  # resolve_supported
    n = fe.dofs.size
    names = parameter_names(deck, modes.structure.file)
    index = {name: k for k, name in enumerate(physical_names)}
    material_of = {mid: MODULUS.named(short) for short, mid in names.materials.items()}
    spring_of = {sid: SPRING.named(short) for short, sid in names.springs.items()}
    bar_parameter = np.array([index.get(material_of.get(deck.pbars[deck.bars[int(i)].pid].mid, ""), -1)
                              for i in fe.bars.ids], dtype=np.int64)
    spring_parameter = np.array([index.get(spring_of.get(int(sid), ""), -1) for sid in fe.spring_ids], dtype=np.int64)
    dm_parts = [(index[MASS.named(short)], sparse.coo_array(conm2_mass(deck, fe.dofs, eid)))
                for short, eid in names.masses.items() if MASS.named(short) in index]
    undeformed = BarState(fe.positions, np.broadcast_to(np.eye(3), (len(fe.positions), 3, 3)))
    if pre is None:
        state, displacements = undeformed, np.zeros(n)
        gravity, static_t = np.zeros(n), sparse.csr_array((n, 0))
        # every element no parameter scales (the bars' and springs' parts are rebuilt from their data)
        other = sparse.csr_array(fe.stiffness - material_tangent(fe.bars, undeformed, n)[1] - fe.spring_stiffness)
        other.data[np.abs(other.data) <= 1e-12 * np.max(np.abs(fe.stiffness.data))] = 0.0
        other.eliminate_zeros()
    else:
        struct = modes.structure
        assert struct.preload is not None and struct.preload.load is not None and pre.constraints is not None
        state, displacements = pre.state, pre.displacements
        gravity = gravity_field(deck, fe, struct.preload.load)
        static_t, other = pre.constraints.transform, sparse.csr_array((n, n))
    stiffness = fe.stiffness if pre is None else pre.tangent_stiffness
    static_t = _profile_ordered(static_t, stiffness)
    modal_t = _profile_ordered(modes.constraints.transform, abs(stiffness) + abs(fe.mass))
    identity = dataclasses.replace(modes.modes, frequencies_hz=np.zeros(n), shapes=np.eye(n), labels=("",) * n)
    influence = modal_data(identity, model.instruments, max_hz=np.inf, motion_grids=list(model.plant.motion_grids))
    rows = {"disp": influence.disp_out, "rate": influence.rate_out, "motion": influence.motion_out,
            "acc": influence.acc_out}
    out: dict[str, np.ndarray] = {
        "resolve_kind": np.array("none" if pre is None else "large"), "resolve_n_dof": np.array(n),
        "resolve_bar_nodes": np.column_stack([fe.bars.node_a, fe.bars.node_b]).astype(np.int64),
        "resolve_bar_frames0": fe.bars.frames0, "resolve_bar_lengths0": fe.bars.lengths0,
        "resolve_bar_k_natural": fe.bars.k_natural, "resolve_bar_parameter": bar_parameter,
        "resolve_spring_vectors": sparse.csr_array(fe.spring_vectors).toarray().reshape(-1, n),
        "resolve_spring_constants": np.asarray(fe.spring_constants, dtype=np.float64),
        "resolve_spring_parameter": spring_parameter,
        "resolve_dm_part": np.concatenate([np.full(dm.nnz, p) for p, dm in dm_parts] or [np.zeros(0)]).astype(np.int64),
        "resolve_gravity": gravity, "resolve_load": fe.mass @ gravity,
        "resolve_independent": np.array([static_t.shape[1], modal_t.shape[1]]),
        "resolve_state_positions": state.positions, "resolve_state_rotations": np.array(state.rotations),
        "resolve_displacements": displacements,
        "resolve_reference_shapes": modes.modes.shapes,
        "resolve_reference_zero": np.abs(modes.modes.frequencies_hz) < ZERO_HZ,
        "resolve_zero_hz": np.array(ZERO_HZ),
        "resolve_inputs": influence.modal_b,
        **_coo("resolve_mass", fe.mass), **_coo("resolve_other", other),
        **_coo("resolve_static_t", static_t), **_coo("resolve_modal_t", modal_t),
    }
    dm_all = sparse.coo_array((n, n)) if not dm_parts else sparse.coo_array(
        (np.concatenate([dm.data for _, dm in dm_parts]),
         (np.concatenate([dm.row for _, dm in dm_parts]), np.concatenate([dm.col for _, dm in dm_parts]))),
        shape=(n, n))
    out.update({"resolve_dm_data": dm_all.data.astype(np.float64), "resolve_dm_rows": dm_all.row.astype(np.int64),
                "resolve_dm_cols": dm_all.col.astype(np.int64)})
    for kind in ROW_KINDS:
        out[f"resolve_{kind}_rows"] = np.array(list(rows[kind].values()), dtype=np.float64).reshape(len(rows[kind]), n)
    return out
