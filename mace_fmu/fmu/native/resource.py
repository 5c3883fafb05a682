"""The data a native FMU's C runtime reads (``resources/mace_model.bin``), made from a model's record.

The record (:class:`~mace_fmu.fmu.parametric.ParametricModel`) carries the array set of
:func:`mace_fmu.iomodel.parametric_data.parametric_arrays`, which
:class:`~mace_fmu.iomodel.parametric.ParametricSystem` turns into (A, B, C, D). The runtime
repeats that rebuild in C with one step done once, when the record is built: the zero-frequency cluster (rigid
bodies, mechanisms) is rotated and reduced by the rules of :mod:`mace_fmu.iomodel.modal_core`.
A stiffness change cannot move those modes (their sensitivities are zero in the arrays), so the
reduction the reference recomputes at every build is the same each time.

File layout (little-endian, see mace_data.c): ``MACEFMU1``, u32 format version, u32 entry count, then per entry
u32 name length, name, u32 type (1 float64, 2 int64, 3 NUL-separated UTF-8 strings), u32 ndim,
u64 dims, zero padding to 8 bytes, the data, zero padding to 8 bytes.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np
from scipy import sparse

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.modal_core import reduce_zero_cluster
from mace_fmu.iomodel.model_options import MAX_PADE_ORDER as MAX_ORDER
from mace_fmu.parameters.kinds import kind_of_fmu_name, mode_number
from mace_fmu.util.frequency import ZERO_HZ

if TYPE_CHECKING:  # the record holds this module's ZeroCluster
    from mace_fmu.fmu.parametric import ParametricModel

MAGIC = b"MACEFMU1"
FORMAT_VERSION = 1  #: the file layout (shared with the controller FMU's data)
#: the plant's arrays (``format_version``): 2 added the static corrections of the reanalysis, 3 the mass
#: parameters' mass changes (``physical_dm``, ``correction_dm``, ``correction_mass_coupling``; zeros without masses)
MODEL_FORMAT = 3
MAX_PADE_ORDER = MAX_ORDER  #: the runtime's Pade coefficients are exact integer ratios up to this order
# The codes below are the runtime's enums in mace_model.c, in their order (tests/fmu/test_native_layers.py holds
# them to the C source): BLOCK_*, PARAM_*, COUNT_* and ROW_*.
BLOCK_KINDS = {"structure": 0, "const": 1, "delay": 2, "gain": 3, "pd": 4}
PARAMETER_KINDS = {"damping": 0, "delay": 1, "gain": 2, "physical": 3, "frequency_scale": 4}
#: the entries of the ``counts`` array, in order (mace_model.c COUNT_IN, COUNT_OUT, ...)
COUNTS = ("in", "out", "par", "modes", "flex", "blocks", "pade", "states", "so", "ms", "phys", "ub", "yb", "corr",
          "massive")
_FLOAT, _INT, _TEXT = 1, 2, 3
ROW_DISPLACEMENT, ROW_RATE, ROW_ACCELERATION = 0, 1, 2  #: struct_row_kind: what a structure output reads


@dataclass(frozen=True)
class ZeroCluster:
    """The modal inputs, structure output rows and kept states after the nominal zero-cluster reduction (the
    runtime's entries of these names, in this order)."""

    modal_b: np.ndarray  #: (n_modes, n_modal_inputs) modal input rows, the cluster rotated
    struct_rows: np.ndarray  #: (n_structure_outputs, n_modes) what each structure output reads of the modes
    struct_row_kind: np.ndarray  #: per structure output: ROW_DISPLACEMENT, ROW_RATE or ROW_ACCELERATION
    keep_disp: np.ndarray  #: per mode: 1 where its displacement is a state
    keep_rate: np.ndarray  #: per mode: 1 where its rate is a state
    flexible: np.ndarray  #: the flexible modes' indices


def zero_cluster_reduced(arrays: Mapping[str, np.ndarray]) -> ZeroCluster:
    """The zero-frequency cluster of a ParametricSystem's ``arrays`` reduced at the nominal parameters.

    Parameters
    ----------
    arrays : mapping
        A ParametricSystem's arrays (:func:`~mace_fmu.iomodel.parametric_data.parametric_arrays`).

    Returns
    -------
    ZeroCluster
        Modal input rows, structure output rows and kept states after the reduction.
    """
    freq = np.asarray(arrays["frequencies_hz"], dtype=float)
    n = len(freq)
    zero = np.flatnonzero(np.abs(freq) < ZERO_HZ)
    disp = {str(k): np.asarray(v, dtype=float) for k, v in zip(arrays["disp_names"], arrays["disp_rows"])}
    rate = {str(k): np.asarray(v, dtype=float) for k, v in zip(arrays["rate_names"], arrays["rate_rows"])}
    motion = {str(k): np.asarray(v, dtype=float) for k, v in zip(arrays["motion_names"], arrays["motion_rows"])}
    acc = ({str(k): np.asarray(v, dtype=float) for k, v in zip(arrays["acc_names"], arrays["acc_rows"])}
           if "acc_names" in arrays else {})
    labels = tuple(str(x) for x in arrays["mode_labels"])
    _, _, modal_b, n_ctrl, n_kept, _ = reduce_zero_cluster(zero, np.zeros((0, n)), labels,
                                                           np.asarray(arrays["modal_b"], dtype=float),
                                                           disp, rate, motion, acc)
    keep_disp, keep_rate = np.ones(n, dtype=np.int64), np.ones(n, dtype=np.int64)
    keep_rate[zero[n_ctrl:]] = 0
    keep_disp[zero[n_kept:]] = 0
    rows, row_kind = [], []  # what each structure output reads: 0 displacement, 1 rate, 2 acceleration
    for name in (str(x) for x in arrays["structure_outputs"]):
        if name in acc:
            rows.append(acc[name])
            row_kind.append(ROW_ACCELERATION)
        elif name in disp or name in motion:
            rows.append(disp[name] if name in disp else motion[name])
            row_kind.append(ROW_DISPLACEMENT)
        else:
            rows.append(rate[name])
            row_kind.append(ROW_RATE)
    return ZeroCluster(modal_b=modal_b, struct_rows=np.array(rows).reshape(len(rows), n),
                       struct_row_kind=np.array(row_kind, dtype=np.int64), keep_disp=keep_disp, keep_rate=keep_rate,
                       flexible=np.flatnonzero(np.abs(freq) >= ZERO_HZ).astype(np.int64))


def _kind_of_rows(arrays: Mapping[str, np.ndarray]) -> list[tuple[str, int]]:
    """For each structure output: which row kind holds it (``acc``, ``disp``, ``motion``, ``rate``) and where."""
    where = {}
    for kind in ("rate", "motion", "disp", "acc"):  # later kinds win, as in zero_cluster_reduced
        for k, name in enumerate(arrays.get(f"{kind}_names", [])):
            where[str(name)] = (kind, k)
    return [where[str(name)] for name in arrays["structure_outputs"]]


@dataclass(frozen=True)
class Corrections:
    """The reanalysis's static-correction vectors and the 1-g preload's first-order shape changes, over every retained
    mode, rows in structure-output order (zeros of the right sizes for a model without them)."""

    stiffness: np.ndarray  #: (n_w, n_w) the correction vectors' projected stiffness
    dk: np.ndarray  #: (n_physical, n_w, n_w) each physical parameter's change of it
    coupling: np.ndarray  #: (n_physical, n_w, n_modes) each physical parameter's coupling of them to the modes
    b: np.ndarray  #: (n_w, n_modal_inputs) their modal inputs
    rows: np.ndarray  #: (n_structure_outputs, n_w) what each structure output reads of them
    preload_rows: np.ndarray  #: (n_physical, n_structure_outputs, n_modes) the preload's change of the output rows
    preload_b: np.ndarray  #: (n_physical, n_modes, n_modal_inputs) its change of the modal inputs
    dm: np.ndarray  #: (n_physical, n_w, n_w) each mass parameter's change of their mass
    mass_coupling: np.ndarray  #: (n_physical, n_w, n_modes) each mass parameter's coupling of them to the modes
    massive: int  #: how many of the correction vectors carry mass


def corrections_of(arrays: Mapping[str, np.ndarray]) -> Corrections:
    """The static corrections and preload shape changes that ``arrays`` hold, read once for the record.

    Parameters
    ----------
    arrays : mapping
        The model's parametric arrays, :func:`~mace_fmu.iomodel.parametric_data.parametric_arrays` (the keys
        ``correction_*``, ``<kind>_correction``, ``<kind>_preload``, ``preload_b``).

    Returns
    -------
    Corrections
        Over every retained mode, rows in structure-output order; zeros of the right sizes where the arrays have none.
    """
    n_phys, n_in = len(arrays["physical_names"]), np.shape(arrays["modal_b"])[1]
    n_modes, outputs = len(arrays["frequencies_hz"]), _kind_of_rows(arrays)
    n_w = np.shape(arrays["correction_stiffness"])[0] if "correction_stiffness" in arrays else 0

    def table(suffix: str, width: int) -> np.ndarray:
        if f"disp_{suffix}" not in arrays or width == 0:  # (-1, 0) is no shape numpy can infer
            return np.zeros((len(outputs), width))
        return np.array([np.asarray(arrays[f"{kind}_{suffix}"], dtype=float).reshape(-1, width)[k]
                         for kind, k in outputs]).reshape(len(outputs), width)

    def preload(kind_k: tuple[str, int]) -> np.ndarray:
        kind, k = kind_k
        return np.asarray(arrays[f"{kind}_preload"], dtype=float)[:, k]

    return Corrections(
        stiffness=np.asarray(arrays.get("correction_stiffness", np.zeros((0, 0))), dtype=float),
        dk=np.asarray(arrays.get("correction_dk", np.zeros((n_phys, 0, 0))), dtype=float),
        coupling=np.asarray(arrays.get("correction_coupling", np.zeros((n_phys, 0, n_modes))), dtype=float),
        b=np.asarray(arrays.get("correction_b", np.zeros((0, n_in))), dtype=float).reshape(n_w, n_in),
        rows=table("correction", n_w),
        preload_rows=(np.stack([preload(o) for o in outputs], axis=1) if "disp_preload" in arrays and outputs
                      else np.zeros((n_phys, len(outputs), n_modes))).reshape(n_phys, len(outputs), n_modes),
        preload_b=(np.asarray(arrays["preload_b"], dtype=float) if "preload_b" in arrays
                   else np.zeros((n_phys, n_modes, n_in))),
        # the mass parameters' (zeros for a stiffness parameter, and without mass parameters)
        dm=np.asarray(arrays.get("correction_dm", np.zeros((n_phys, n_w, n_w))), dtype=float).reshape(n_phys, n_w, n_w),
        mass_coupling=np.asarray(arrays.get("correction_mass_coupling", np.zeros((n_phys, n_w, n_modes))), dtype=float),
        massive=int(arrays["correction_massive"]) if "correction_massive" in arrays else 0)


def _corrections(corrections: Corrections, flexible: np.ndarray) -> dict[str, np.ndarray]:
    """The runtime's correction entries: ``corrections`` over the flexible modes."""
    c = corrections
    n_phys, n_outputs = len(c.dk), len(c.rows)
    n_w, n_in, n_flex = len(c.stiffness), c.b.shape[1], len(flexible)
    return {
        "correction_stiffness": c.stiffness,
        "correction_dk": c.dk,
        "correction_coupling": c.coupling[:, :, flexible].reshape(n_phys, n_w, n_flex),
        "correction_b": c.b,
        "correction_rows": c.rows,
        "preload_rows": c.preload_rows[:, :, flexible].reshape(n_phys, n_outputs, n_flex),
        "preload_b": c.preload_b[:, flexible].reshape(n_phys, n_flex, n_in),
        "correction_dm": c.dm,
        "correction_mass_coupling": c.mass_coupling[:, :, flexible].reshape(n_phys, n_w, n_flex),
    }


def _blocks(model: ParametricModel, *, index: Mapping[str, int]) -> tuple[np.ndarray, dict[str, np.ndarray], set[str]]:
    """Each block's row of ``block_info`` (kind code, states, inputs, outputs, its parameters' indices), the
    constant blocks' matrices, and the names of the parameters that are delays."""
    cluster = model.cluster
    n_states_structure = int(cluster.keep_disp.sum() + cluster.keep_rate.sum())
    rows: list[list[int]] = []
    blocks: dict[str, np.ndarray] = {}
    delay_params: set[str] = set()
    for i, block in enumerate(model.blocks):
        p0 = p1 = -1
        if block.kind == "structure":
            n_x, n_u, n_y = n_states_structure, cluster.modal_b.shape[1], len(model.structure_outputs)
        elif block.kind == "delay":
            n_x, n_u, n_y, p0 = model.pade_order, 1, 1, index[block.parameters[0]]
            delay_params.add(block.parameters[0])
        elif block.kind == "gain":
            n_x, n_u, n_y, p0 = 0, 1, 1, index[block.parameters[0]]
        elif block.kind == "pd":
            n_x, n_u, n_y = 0, 2, 1
            p0, p1 = (index[p] for p in block.parameters)
        elif block.kind == "const":
            n_y, n_u = block.d.shape
            n_x = int(block.a.shape[0])
            for m, matrix, shape in zip("ABCD", (block.a, block.b, block.c, block.d),
                                        ((n_x, n_x), (n_x, n_u), (n_y, n_x), (n_y, n_u))):
                blocks[f"block{i}_{m}"] = matrix.reshape(shape)
        else:
            raise MaceError(f"native FMU: block {i} has the unknown kind {block.kind!r}")
        rows.append([BLOCK_KINDS[block.kind], n_x, n_u, n_y, p0, p1])
    info = np.array(rows, dtype=np.int64).reshape(-1, 6)
    if info[:, 2].sum() != model.wiring.shape[0] or info[:, 3].sum() != model.wiring.shape[1]:
        raise MaceError("native FMU: block inputs/outputs do not match the wiring matrix")
    return info, blocks, delay_params


def _parameter_codes(names: list[str], *, physical: list[str], delays: set[str]) -> tuple[np.ndarray, np.ndarray]:
    """Each parameter's runtime kind code (:data:`PARAMETER_KINDS`) and index (its mode, its physical parameter,
    or -1)."""
    codes = []
    for name in names:
        kind = kind_of_fmu_name(name)
        if kind is not None and kind.per_mode:
            codes.append((PARAMETER_KINDS[kind.name], mode_number(name) - 1))
        elif name in physical:
            codes.append((PARAMETER_KINDS["physical"], physical.index(name)))
        else:
            codes.append((PARAMETER_KINDS["delay" if name in delays else "gain"], -1))
    table = np.array(codes, dtype=np.int64).reshape(-1, 2)
    return table[:, 0].copy(), table[:, 1].copy()


def runtime_arrays(model: ParametricModel) -> dict[str, np.ndarray | list[str]]:
    """The C runtime's arrays (see the module docstring) of what a model's FMUs carry.

    Parameters
    ----------
    model : ParametricModel
        The record (:func:`~mace_fmu.fmu.parametric.parametric_model`): its parameters, signals, sensitivities
        and reduced zero-frequency cluster, and the ParametricSystem's arrays of its blocks and corrections.

    Returns
    -------
    dict
        Name -> float64 or int64 array, or list of strings, in the order :func:`resource_bytes` writes them.

    Raises
    ------
    MaceError
        A Pade order the runtime does not take, a block of unknown kind, blocks that do not match the wiring.
    """
    cluster = model.cluster
    names = [p.name for p in model.parameters]
    physical = list(model.physical_names)
    pade_order = model.pade_order
    if not 1 <= pade_order <= MAX_PADE_ORDER:
        raise MaceError(f"native FMU: Pade order must be 1..{MAX_PADE_ORDER}, got {pade_order}")
    flexible = cluster.flexible
    info, blocks, delays = _blocks(model, index={name: k for k, name in enumerate(names)})
    par_kind, par_index = _parameter_codes(names, physical=physical, delays=delays)
    corrections = _corrections(model.corrections, flexible)
    counts = {"in": len(model.inputs), "out": len(model.outputs), "par": len(names),
              "modes": len(model.frequencies_hz), "flex": len(flexible), "blocks": len(info), "pade": pade_order,
              "states": int(info[:, 1].sum()), "so": len(model.structure_outputs),
              "ms": cluster.modal_b.shape[1], "phys": len(physical), "ub": model.wiring.shape[0],
              "yb": model.wiring.shape[1], "corr": corrections["correction_stiffness"].shape[0],
              "massive": model.corrections.massive}
    dk = model.stiffness_sensitivities[:, flexible][:, :, flexible]
    dm = (model.mass_sensitivities if model.mass_sensitivities is not None
          else np.zeros_like(model.stiffness_sensitivities))[:, flexible][:, :, flexible]
    out: dict[str, np.ndarray | list[str]] = {
        "format_version": np.array([MODEL_FORMAT], dtype=np.int64),
        "counts": np.array([counts[name] for name in COUNTS], dtype=np.int64),
        "param_nominal": np.array([p.nominal for p in model.parameters], dtype=float),
        "param_min": np.array([p.minimum for p in model.parameters], dtype=float),
        "param_max": np.array([p.maximum for p in model.parameters], dtype=float),
        "param_kind": par_kind, "param_index": par_index,
        "frequencies_hz": model.frequencies_hz,
        "physical_dk": dk.reshape(len(physical), len(flexible), len(flexible)),
        "physical_dm": dm.reshape(len(physical), len(flexible), len(flexible)),
        "block_info": info, "wiring": model.wiring, "entry": model.entry, "exit": model.exit,
        "input_names": [s.name for s in model.inputs], "output_names": [s.name for s in model.outputs],
        "param_names": names,
    }
    out["me_order"] = model_exchange_order(info)
    out.update((f.name, getattr(cluster, f.name)) for f in fields(cluster))
    out.update(corrections)
    out.update(blocks)
    out.update(_resolve(model.arrays, flexible))
    return out


#: the entries of the ``resolve_counts`` array, in order (mace_model.c RS_LARGE, RS_DOF, ...)
RESOLVE_COUNTS = ("large", "dof", "grid", "bar", "spring", "static", "modal", "zero", "count", "mass_nnz", "dm_nnz",
                  "other_nnz", "static_t_nnz", "modal_t_nnz")


def _resolve(arrays: Mapping[str, np.ndarray], flexible: np.ndarray) -> dict[str, np.ndarray]:
    """The runtime's re-solve entries (mace_resolve.h) from the ``resolve_*`` arrays
    (:func:`~mace_fmu.iomodel.resolve_data.resolve_arrays`); none without them (the runtime then re-analyses)."""
    if "resolve_kind" not in arrays:
        return {}
    a = {k: np.asarray(v) for k, v in arrays.items() if k.startswith("resolve_")}
    n = int(a["resolve_n_dof"])
    n_static, n_modal = (int(x) for x in a["resolve_independent"])
    zero = a["resolve_reference_zero"].astype(bool)
    reference_shapes = a["resolve_reference_shapes"][:, flexible]
    mass = sparse.coo_array((a["resolve_mass_data"], (a["resolve_mass_rows"], a["resolve_mass_cols"])), shape=(n, n))
    weighted = mass.tocsr() @ reference_shapes
    # each structure output's influence row, by the rules of zero_cluster_reduced
    rows = [a[f"resolve_{kind}_rows"][k] for kind, k in _kind_of_rows(arrays)]
    counts = {"large": int(str(a["resolve_kind"]) == "large"), "dof": n, "grid": n // 6,
              "bar": len(a["resolve_bar_lengths0"]), "spring": len(a["resolve_spring_constants"]),
              "static": n_static, "modal": n_modal, "zero": int(zero.sum()),
              "count": int(np.ceil(1.5 * len(zero))), "mass_nnz": len(a["resolve_mass_data"]),
              "dm_nnz": len(a["resolve_dm_data"]), "other_nnz": len(a["resolve_other_data"]),
              "static_t_nnz": len(a["resolve_static_t_data"]), "modal_t_nnz": len(a["resolve_modal_t_data"])}
    out: dict[str, np.ndarray] = {
        "resolve_counts": np.array([counts[k] for k in RESOLVE_COUNTS], dtype=np.int64),
        "resolve_bar_nodes": a["resolve_bar_nodes"].astype(np.int64),
        "resolve_frames0": a["resolve_bar_frames0"].reshape(-1, 9).astype(float),
        "resolve_lengths0": a["resolve_bar_lengths0"].astype(float),
        "resolve_k_natural": a["resolve_bar_k_natural"].reshape(-1, 49).astype(float),
        "resolve_bar_param": a["resolve_bar_parameter"].astype(np.int64),
        "resolve_spring_vectors": a["resolve_spring_vectors"].reshape(-1, n).astype(float),
        "resolve_spring_k": a["resolve_spring_constants"].astype(float),
        "resolve_spring_param": a["resolve_spring_parameter"].astype(np.int64),
        "resolve_dm_part": a["resolve_dm_part"].astype(np.int64),
        "resolve_gravity": a["resolve_gravity"].astype(float), "resolve_load": a["resolve_load"].astype(float),
        "resolve_displacements": a["resolve_displacements"].astype(float),
        "resolve_positions": a["resolve_state_positions"].astype(float),
        "resolve_rotations": a["resolve_state_rotations"].reshape(-1, 9).astype(float),
        "resolve_reference": np.ascontiguousarray(weighted),
        "resolve_reference_norm": np.einsum("im,im->m", reference_shapes, weighted),
        "resolve_struct_rows": np.array(rows, dtype=float).reshape(len(rows), n),
        "resolve_inputs": a["resolve_inputs"].astype(float),
    }
    for key in ("mass", "dm", "other", "static_t", "modal_t"):
        out.update({f"resolve_{key}_rows": a[f"resolve_{key}_rows"].astype(np.int64),
                    f"resolve_{key}_cols": a[f"resolve_{key}_cols"].astype(np.int64),
                    f"resolve_{key}_vals": a[f"resolve_{key}_data"].astype(float)})
    return out


def count_of(data: Mapping[str, np.ndarray | list[str]], name: str) -> int:
    """One entry of a runtime data file's ``counts`` by its name (:data:`COUNTS`), e.g. ``count_of(data, "states")``."""
    return int(np.asarray(data["counts"])[COUNTS.index(name)])


def model_exchange_order(info: np.ndarray) -> np.ndarray:
    """The order of a native FMU's continuous states in model exchange: position i holds model state
    ``order[i]`` (the model's own order is block by block, the structure first).

    The delays' states come first, then the other dynamic blocks' (the Bessel filters), then the
    structure's displacements and last its rates. SUNDIALS' dense LU, which fmpy's CVode
    factorises I - gamma J with, skips the updates of a zero in the pivot row but not the rows
    below: the rows of the structure's rates, dense through the servo loops, cost least at the
    end. On the 1-g model this halves the LU (3.7 to 1.7 million multiply-adds, 2.4 to 1.2 ms).
    """
    offsets = np.concatenate([[0], np.cumsum(info[:, 1])])
    rank = {BLOCK_KINDS["delay"]: 0, BLOCK_KINDS["const"]: 1, BLOCK_KINDS["structure"]: 2}
    blocks = sorted((k for k in range(len(info)) if info[k, 1] > 0), key=lambda k: (rank.get(int(info[k, 0]), 1), k))
    return np.concatenate([np.arange(offsets[k], offsets[k + 1]) for k in blocks] or [np.zeros(0)]).astype(np.int64)


def resource_bytes(arrays: Mapping[str, np.ndarray | list[str]]) -> bytes:
    """``arrays`` (float64, int64 or lists of strings) in the runtime's file layout."""
    chunks = [MAGIC, struct.pack("<II", FORMAT_VERSION, len(arrays))]
    size = len(MAGIC) + 8

    def add(data: bytes) -> None:
        nonlocal size
        chunks.append(data)
        size += len(data)

    def pad() -> None:
        add(b"\0" * (-size % 8))

    for name, value in arrays.items():
        key = name.encode()
        if isinstance(value, list):
            kind, data, dims = _TEXT, b"".join(s.encode() + b"\0" for s in value), (len(value),)
        else:
            value = np.asarray(value)
            kind = _FLOAT if value.dtype.kind == "f" else _INT
            data = np.ascontiguousarray(value, dtype="<f8" if kind == _FLOAT else "<i8").tobytes()
            dims = value.shape
        add(struct.pack("<I", len(key)) + key + struct.pack("<II", kind, len(dims)))
        add(struct.pack(f"<{len(dims)}Q", *dims))
        if kind == _TEXT:
            add(struct.pack("<Q", len(data)))  # byte length of the strings
        pad()
        add(data)
        pad()
    return b"".join(chunks)
