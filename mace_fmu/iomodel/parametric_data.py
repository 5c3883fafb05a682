"""The arrays of a :class:`~mace_fmu.iomodel.parametric.ParametricSystem` made from a volts-volts model.

Blocks and wiring of the diagram, the retained modes projected on the instruments, the tunable
parameters (modal damping ratios, modal frequency scales, delays, servo gains, physical
parameters) with their nominal values, declared ranges and descriptions, and the physical
parameters' projected stiffness sensitivities. FMUs
carry these arrays as ``resources/model.npz``; the updating engine re-analyses with them.
"""

from __future__ import annotations

import dataclasses
from typing import Mapping, Sequence

import numpy as np
from scipy import sparse

from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import FEModel, bar_section
from mace_fmu.fe.beam import natural_stiffness
from mace_fmu.fe.corotational import BarState, material_tangent
from mace_fmu.fe.preload import Preload, preload_solver, tangent_sensitivity
from mace_fmu.iomodel.instruments import Servos
from mace_fmu.iomodel.modal_ss import modal_data
from mace_fmu.iomodel.motion import motion_unit, parse_motion_output
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.parameters.kinds import (DAMPING, DELAY, FREQUENCY_SCALE, declared_range, kind_of_fmu_name, mode_number,
                                       split_loop_name)
from mace_fmu.parameters.sets import parameter_names
from mace_fmu.util.frequency import ZERO_HZ
from modelica_like import PD, Gain, PadeDelay

_RELATIVE_STEP = 1e-3  # the material stiffness is linear in E and k: the difference quotient is exact


def signal_descriptions(model: VoltsModel) -> tuple[list[str], list[str]]:
    """Input and output descriptions that say which actuator or sensor, which axis and what a volt means."""
    inst = model.instruments
    gimbals = set(inst.servos.gimbals) if model.electronics.servos else set()
    wheels = set(inst.servos.wheels) if model.electronics.servos else set()
    ins = []
    for name in model.system.input_labels:
        a = inst.actuator(name)
        if name in gimbals:
            ins.append(f"{a.description}: commanded relative angle through the gimbal servo, 1 V = 1 deg")
        elif name in wheels:
            ins.append(f"{a.description}: speed-loop command [V]")
        else:
            ins.append(f"{a.description} [V], {a.gain} N m/V")
    outs = []
    for name in model.system.output_labels:
        motion = parse_motion_output(name)
        if motion is None:
            sensor = inst.sensor(name)
            outs.append(f"{sensor.description} [V], {sensor.gain} V per {sensor.unit}")
        else:
            grid, comp = motion
            what = "translation along" if comp.startswith("t") else "rotation about"
            outs.append(f"grid {grid}: {what} basic {comp[1].upper()} [{motion_unit(comp)}], from the equilibrium "
                        "(animation output)")
    return ins, outs


def _blocks(model: VoltsModel) -> tuple[dict, list[tuple[str, float, str]]]:
    """Block arrays and the non-physical block parameters (name, value, description)."""
    ic = model.diagram.connection_matrices()
    kinds, params, arrays, parameters = [], [], {}, []
    sv = model.instruments.servos
    for i, block in enumerate(ic.blocks):
        name = block.name
        # block kinds by class; which servo gain a Gain block carries, by the name volts.py gives it
        if name == "structure":
            kinds.append("structure"), params.append("")
        elif isinstance(block, PadeDelay):
            kinds.append("delay"), params.append(name)
            what = name.removeprefix(DELAY.fmu_prefix)
            parameters.append((name, float(block.delay),
                               f"time delay of {what} [s] (Pade order {model.electronics.pade_order})"))
        elif isinstance(block, Gain) and name.startswith(("kf_", "kb_")):
            wheel = name[len("kf_"):]
            kinds.append("gain"), params.append(sv.parameter_name(wheel, "K_f" if name.startswith("kf_") else "K_b"))
        elif isinstance(block, PD):
            gimbal = name.removeprefix("servo_")
            kinds.append("pd"), params.append(f"{sv.parameter_name(gimbal, 'K_a')},{sv.parameter_name(gimbal, 'K_r')}")
        else:
            kinds.append("const"), params.append("")
        for m in "ABCD":
            arrays[f"block{i}_{m}"] = np.asarray(getattr(block, m), dtype=float)
    parameters += _loop_gain_parameters(sv, [p for field in params for p in field.split(",")])
    ins = [list(ic.inputs).index(n) for n in model.system.input_labels]
    outs = [list(ic.outputs).index(n) for n in model.system.output_labels]
    arrays.update(block_kinds=np.array(kinds), block_params=np.array(params),
                  block_names=np.array([b.name for b in ic.blocks]), wiring=ic.wiring, entry=ic.entry[:, ins],
                  exit=ic.exit[outs], pade_order=np.array(model.electronics.pade_order))
    return arrays, parameters


#: what each servo gain is, for the FMU's parameter descriptions
_GAIN_DESCRIPTIONS = {"K_f": "reaction wheel speed loop forward gain (eq. 3.18)",
                      "K_b": "reaction wheel speed loop backward (tachometer) gain",
                      "K_a": "gimbal servo angle gain [V/deg] (eq. 3.20)",
                      "K_r": "gimbal servo rate gain [V/(deg/s)] (eq. 3.20)"}


def _loop_gain_parameters(servos: Servos, names: list[str]) -> list[tuple[str, float, str]]:
    """(name, value, description) of every servo gain the blocks name, once each: the shared ones first
    (K_f, K_b, K_a, K_r, the order MACE's FMUs have always had), then each loop's own in block order."""
    shared = [n for n in _GAIN_DESCRIPTIONS if n in names]
    own = [n for n in dict.fromkeys(names) if n not in _GAIN_DESCRIPTIONS]
    out = []
    for name in shared + own:
        symbol, actuator = split_loop_name(name)
        if not symbol:
            continue
        if actuator:
            what = f"{_GAIN_DESCRIPTIONS[symbol]} of {actuator}'s loop alone"
            out.append((name, servos.gain(actuator, symbol), what))
        else:
            out.append((name, servos.shared_gain(symbol), _GAIN_DESCRIPTIONS[symbol]))
    return out


def material_sensitivity(fe: FEModel, deck, preload: Preload | None, mid: int, *,
                         solve=None) -> sparse.csr_array:
    """dK/d(ln E) [N/m, N m/rad] of MAT1 ``mid``: the material stiffness of its bars per unit relative change.

    About the configuration the modes are computed in. 1-g with the large-displacement preload: the
    tangent's total derivative with the preload re-solved to first order
    (:func:`~mace_fmu.fe.preload.tangent_sensitivity`: a stiffer cable takes more of the weight, and the
    forces and geometry move with it). Otherwise (the linear preload; 0-g) the preloaded geometry with
    the preload's bar forces held, so a change of E changes only the material part. Taking the
    undeformed geometry instead puts
    spurious strain into the near-rigid suspension modes: Z tilt, X twist and 1st Y bending then
    came out 1.9e-3 to 2.9e-3 off after E of the Lexan center +5 %, against 7.8e-4 at most this
    way. The bar stiffness is linear in E (and in G, which NASTRAN derives from E when blank), so
    the difference of the natural stiffnesses is exact; only this material's bars are evaluated.
    """
    ids = fe.bars.ids
    mine = np.array([deck.pbars[deck.bars[int(i)].pid].mid == mid for i in ids])
    mat = deck.mat1s[mid]
    plus = dataclasses.replace(mat, e=mat.youngs_modulus * (1 + _RELATIVE_STEP))  # G follows E when blank

    def section_delta(pid: int, length: float) -> np.ndarray:
        sec = bar_section(deck, pid)
        stiffer = dataclasses.replace(sec, e=plus.youngs_modulus, g=plus.shear_modulus)
        return (natural_stiffness(stiffer, length) - natural_stiffness(sec, length)) / _RELATIVE_STEP

    dkn = np.array([section_delta(deck.bars[int(i)].pid, length)
                    for i, length in zip(ids[mine], fe.bars.lengths0[mine])]).reshape(-1, 7, 7)
    if preload is not None and preload.kind == "large" and preload.constraints is not None:
        # the gravity load redistributes (suspension cables, springs): the preload re-solved to first order
        return tangent_sensitivity(fe, preload, bar_mask=mine, dk_natural=dkn, solve=solve)
    bars = dataclasses.replace(fe.bars, ids=ids[mine], node_a=fe.bars.node_a[mine], node_b=fe.bars.node_b[mine],
                               frames0=fe.bars.frames0[mine], lengths0=fe.bars.lengths0[mine], k_natural=dkn)
    if preload is not None:
        state = preload.state
    else:  # 0-g: the undeformed geometry, where the corotational tangent is the linear stiffness
        state = BarState(fe.positions, np.broadcast_to(np.eye(3), (len(fe.positions), 3, 3)))
    # forces held (zero change): only the material part B^T dK_n B of the tangent remains
    return material_tangent(bars, state, fe.dofs.size)[1]


def physical_sensitivities(model: VoltsModel, shapes: np.ndarray, *, only: Sequence[str] | None = None
                           ) -> tuple[list[tuple[str, float, str]], np.ndarray]:
    """Physical parameters (name, value, description) and Phi0^T dK/d(ln p) Phi0 for each (or for ``only``)."""
    deck, fe = model.structure_modes.structure.deck, model.structure_modes.model
    names = parameter_names(deck, model.structure_modes.structure.file)
    material_name = {mid: name for name, mid in names.materials.items()}
    spring_name = {sid: name for name, sid in names.springs.items()}
    used = sorted({deck.pbars[b.pid].mid for b in deck.bars.values()})
    pre = model.structure_modes.preload
    solve = preload_solver(pre) if pre is not None and pre.kind == "large" and pre.constraints is not None else None
    parameters, sensitivities = [], []
    for mid in used:
        e = deck.mat1s[mid].youngs_modulus
        label = material_name[mid]
        if only is not None and f"E_{label}" not in only:
            continue
        dk = material_sensitivity(fe, deck, pre, mid, solve=solve)
        parameters.append((f"E_{label}", e, f"Young's modulus of {label} (MAT1 {mid}) [Pa]; takes effect by "
                                            "reanalysis on the retained modes"))
        sensitivities.append(shapes.T @ (dk @ shapes))
    for row, (sid, k) in enumerate(zip(fe.spring_ids, fe.spring_constants)):
        label = spring_name[sid]
        if only is not None and f"k_{label}" not in only:
            continue
        parameters.append((f"k_{label}", float(k), f"stiffness of {label} (CELAS2 {sid}) [N/m]; reanalysis"))
        if pre is not None and pre.kind == "large" and pre.constraints is not None:
            e = sparse.csr_array(fe.spring_vectors[[row]])  # (1, n_dof)
            dk = tangent_sensitivity(fe, pre, dk_springs=k * (e.T @ e), solve=solve)
            sensitivities.append(shapes.T @ (dk @ shapes))
            continue
        v = (fe.spring_vectors[[row]] @ shapes)[0]
        sensitivities.append(k * np.outer(v, v))
    n = shapes.shape[1]
    dk = np.array(sensitivities).reshape(len(parameters), n, n)
    # Rigid-body and mechanism modes carry no strain energy: their computed sensitivities (3e-9
    # of the largest, the round-off of the mechanism shapes) are noise, which the reanalysis
    # would couple into the flexible modes (up to 6e-7 of an output's range for E x 0.5).
    zero = np.abs(model.structure_modes.frequencies_hz[:n]) < ZERO_HZ
    dk[:, zero, :] = 0.0
    dk[:, :, zero] = 0.0
    return parameters, dk


def parametric_arrays(model: VoltsModel, *, physical: bool | Sequence[str] = True,
                      frequency_bounds: Mapping[int, float] | None = None) -> dict[str, np.ndarray]:
    """Everything a ParametricSystem (and an FMU) needs to rebuild ``model`` for new parameter values.

    ``physical=False`` leaves out the moduli and springs and their stiffness sensitivities (the
    costly part): the system then rebuilds for new damping ratios, frequency scales, delays and
    gains only; a list of names keeps just those (see also :func:`with_physical`).
    ``frequency_bounds`` (1-based mode number -> relative bound, 0.011 for +-1.1 %) declares the
    range [1 - b, 1 + b] of those modes' ``frequency_scale_mode_<k>`` (:func:`with_frequency_bounds`).
    """
    sys_ = model.system
    ins, outs = signal_descriptions(model)
    max_hz = float(np.max(model.plant.frequencies_hz))
    data = modal_data(model.structure_modes.modes, model.instruments, max_hz=max_hz,
                      motion_grids=list(model.plant.motion_grids))
    arrays, parameters = _blocks(model)
    damping = [(DAMPING.fmu_name(k + 1), float(z), f"open-loop damping ratio of mode {k + 1}: {label}")
               for k, (z, label) in enumerate(zip(model.plant.damping, data.labels))]
    scales = [(FREQUENCY_SCALE.fmu_name(k + 1), 1.0, f"open-loop natural frequency of mode {k + 1} ({label}) "
               "relative to the model's, after reanalysis [-]; min/max: the mode's frequency bounds when declared")
              for k, label in enumerate(data.labels)
              if abs(data.frequencies_hz[k]) >= ZERO_HZ]  # rigid bodies and mechanisms have no frequency to scale
    n = len(data.labels)
    arrays.update(
        inputs=np.array(sys_.input_labels), outputs=np.array(sys_.output_labels), input_descriptions=np.array(ins),
        output_descriptions=np.array(outs), physical_names=np.array([], dtype=str), physical_dk=np.zeros((0, n, n)),
        frequencies_hz=data.frequencies_hz, mode_labels=np.array(data.labels), modal_b=data.modal_b,
        disp_names=np.array(list(data.disp_out)), disp_rows=np.array(list(data.disp_out.values())),
        rate_names=np.array(list(data.rate_out)), rate_rows=np.array(list(data.rate_out.values())),
        motion_names=np.array(list(data.motion_out), dtype=str),
        motion_rows=np.array(list(data.motion_out.values())).reshape(len(data.motion_out), len(data.labels)),
        acc_names=np.array(list(data.acc_out), dtype=str),
        acc_rows=np.array(list(data.acc_out.values())).reshape(len(data.acc_out), len(data.labels)),
        structure_outputs=np.array(data.output_order))
    frequencies = {FREQUENCY_SCALE.fmu_name(k + 1): float(f) for k, f in enumerate(data.frequencies_hz)}
    arrays = _with_parameters(arrays, damping + scales + parameters, frequencies_hz=frequencies)
    if frequency_bounds:
        arrays = with_frequency_bounds(arrays, frequency_bounds)
    if physical is False:
        return arrays
    entries, dk = physical_sensitivities(model, data.shapes, only=None if physical is True else physical)
    return with_physical(arrays, entries, dk)


def with_frequency_bounds(arrays: Mapping[str, np.ndarray], bounds: Mapping[int, float]) -> dict[str, np.ndarray]:
    """``arrays`` with ``frequency_scale_mode_<k>`` declared in [1 - b, 1 + b] for each 1-based mode k -> bound b.

    A MaceError for a mode the arrays lack or a bound that is not a number in [0, 1)."""
    out = dict(arrays)
    names = [str(n) for n in out["param_names"]]
    low, high = np.array(out["param_min"], dtype=float), np.array(out["param_max"], dtype=float)
    for mode, bound in bounds.items():
        name = FREQUENCY_SCALE.fmu_name(mode) if isinstance(mode, int) else str(mode)
        if name not in names:
            scaled = [mode_number(n) for n in names if kind_of_fmu_name(n) is FREQUENCY_SCALE]
            raise MaceError(f"frequency bounds: the model has no frequency scale for mode {mode!r} (modes "
                            f"{min(scaled)}..{max(scaled)}; rigid-body and mechanism modes have none)")
        if isinstance(bound, bool) or not isinstance(bound, (int, float, np.floating)) or not 0.0 <= bound < 1.0:
            raise MaceError(f"frequency bounds: mode {mode}: {bound!r} is not a relative bound in [0, 1) "
                            "(0.011 for +-1.1 %)")
        k = names.index(name)
        # never below the scale's own minimum (a mode pushed into the zero-frequency cluster)
        low[k], high[k] = max(1.0 - float(bound), low[k]), 1.0 + float(bound)
    out.update(param_min=low, param_max=high)
    return out


def _with_parameters(arrays: dict[str, np.ndarray], parameters: Sequence[tuple[str, float, str]], *,
                     frequencies_hz: Mapping[str, float] | None = None) -> dict:
    """``arrays`` with (name, value, description) parameters appended, and the range each declares
    (:func:`mace_fmu.parameters.kinds.declared_range`; ``frequencies_hz`` gives a frequency scale's mode
    frequency [Hz])."""
    out = dict(arrays)
    old = list(out.get("param_names", []))
    new = [p[0] for p in parameters]
    ranges = [declared_range(name, value, frequency_hz=(frequencies_hz or {}).get(name)) for name, value, _ in parameters]
    out.update(
        param_names=np.array(old + new), param_values=np.concatenate([out.get("param_values", []),
                                                                       [p[1] for p in parameters]]).astype(float),
        param_descriptions=np.array(list(out.get("param_descriptions", [])) + [p[2] for p in parameters]),
        param_min=np.concatenate([out.get("param_min", []), [r[0] for r in ranges]]).astype(float),
        param_max=np.concatenate([out.get("param_max", []), [r[1] for r in ranges]]).astype(float))
    return out


def with_physical(arrays: dict[str, np.ndarray], parameters: Sequence[tuple[str, float, str]],
                  projected_dk: np.ndarray) -> dict[str, np.ndarray]:
    """``arrays`` with physical parameters (name, value, description) and their Phi0^T dK Phi0 added."""
    out = _with_parameters(arrays, parameters)
    out["physical_names"] = np.array(list(arrays["physical_names"]) + [p[0] for p in parameters])
    out["physical_dk"] = np.concatenate([arrays["physical_dk"], np.asarray(projected_dk).reshape(
        len(parameters), *arrays["physical_dk"].shape[1:])])
    return out
