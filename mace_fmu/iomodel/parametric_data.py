"""The arrays of a :class:`~mace_fmu.iomodel.parametric.ParametricSystem` made from a volts-volts model.

Blocks and wiring of the diagram, the retained modes projected on the instruments, the tunable
parameters (modal damping ratios, modal frequency scales, delays, servo gains, physical
parameters) with their nominal values, declared ranges and descriptions, and the physical
parameters' projected stiffness sensitivities. FMUs
carry these arrays as ``resources/model.npz``; the updating engine re-analyses with them.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.instruments import Servos, force_unit
from mace_fmu.iomodel.modal_ss import modal_data
from mace_fmu.iomodel.motion import motion_unit, parse_motion_output
from mace_fmu.iomodel.resolve_data import resolve_arrays
from mace_fmu.iomodel.stiffness_route import PhysicalRoute, physical_route, stiffness_sensitivities
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.parameters.frequency_bounds import relative_bound, scale_range
from mace_fmu.parameters.kinds import (DAMPING, DELAY, FREQUENCY_SCALE, declared_range, kind_of_fmu_name, mode_number,
                                       split_loop_name)
from mace_fmu.util.frequency import ZERO_HZ
from modelica_like import PD, Gain, PadeDelay


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
        elif a.input_unit != "V":
            ins.append(f"{a.description} [{a.input_unit}]")
        else:
            force = force_unit(a.dofs)
            ins.append(f"{a.description} [V], {a.gain} {'N or N m' if force == 'physical unit' else force}/V")
    outs = []
    for name in model.system.output_labels:
        motion = parse_motion_output(name)
        if motion is None:
            sensor = inst.sensor(name)
            outs.append(f"{sensor.description} [{sensor.unit}]" if sensor.output_unit != "V" else
                        f"{sensor.description} [V], {sensor.gain} V per {sensor.unit}")
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


def parametric_arrays(model: VoltsModel, *, physical: bool | Sequence[str] = True,
                      frequency_bounds: Mapping[int, float] | None = None, resolve: bool = False
                      ) -> dict[str, np.ndarray]:
    """Everything a ParametricSystem (and an FMU) needs to rebuild ``model`` for new parameter values.

    ``physical=False`` leaves out the moduli and springs and their stiffness sensitivities (the
    costly part): the system then rebuilds for new damping ratios, frequency scales, delays and
    gains only; a list of names keeps just those (see also :func:`with_physical`).
    ``frequency_bounds`` (1-based mode number -> relative bound, 0.011 for +-1.1 %) declares the
    range [1 - b, 1 + b] of those modes' ``frequency_scale_mode_<k>`` (:func:`with_frequency_bounds`).
    ``resolve``: the physical parameters take effect by a full re-solve of the structure
    (:mod:`mace_fmu.iomodel.resolve`, exact) where :func:`~mace_fmu.iomodel.resolve_data.resolve_supported`
    allows, else by reanalysis.
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
        output_descriptions=np.array(outs), input_units=np.array([model.signal_units[n] for n in sys_.input_labels]),
        output_units=np.array([model.signal_units[n] for n in sys_.output_labels]), physical_names=np.array([], dtype=str), physical_dk=np.zeros((0, n, n)),
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
    if physical is not True:
        model.structure_modes.check_physical(physical)
    if not model.structure_modes.physical_kinds:  # NASTRAN's modes: no FE, no moduli or springs
        return arrays
    sensitivities = stiffness_sensitivities(model, only=None if physical is True else physical)
    arrays = with_physical(arrays, physical_route(model, data.shapes, sensitivities))
    if resolve:
        arrays.update(resolve_arrays(model, [str(n) for n in arrays["physical_names"]]))
    return arrays


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
        lowest, highest = scale_range(relative_bound(bound, what=f"frequency bounds: mode {mode}"))
        k = names.index(name)
        # never below the scale's own minimum (a mode pushed into the zero-frequency cluster)
        low[k], high[k] = max(lowest, low[k]), highest
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
    for (name, value, description), (low, high) in zip(parameters, ranges):
        # FMI: min <= start <= max, which every host checks; such an FMU would be refused wherever it is run
        if not low <= value <= high:
            raise MaceError(f"parameter {name} = {value!r} ({description}) lies outside the range its FMU declares, "
                            f"[{low:g}, {high:g}]: every host would refuse the FMU")
    out.update(
        param_names=np.array(old + new), param_values=np.concatenate([out.get("param_values", []),
                                                                       [p[1] for p in parameters]]).astype(float),
        param_descriptions=np.array(list(out.get("param_descriptions", [])) + [p[2] for p in parameters]),
        param_min=np.concatenate([out.get("param_min", []), [r[0] for r in ranges]]).astype(float),
        param_max=np.concatenate([out.get("param_max", []), [r[1] for r in ranges]]).astype(float))
    return out


def with_physical(arrays: dict[str, np.ndarray], route: PhysicalRoute) -> dict[str, np.ndarray]:
    """``arrays`` (written without physical parameters) with ``route``'s parameters and arrays added."""
    if len(arrays["physical_names"]):
        raise MaceError("with_physical: the arrays already have physical parameters")
    out = _with_parameters(arrays, route.parameters)
    out.update(route.arrays)
    return out
