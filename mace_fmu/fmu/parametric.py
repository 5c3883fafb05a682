"""The record between a volts-volts model and the FMU writers: what every FMU of the model carries, built once.

:func:`parametric_model` takes a :class:`~mace_fmu.iomodel.volts.VoltsModel` once: its parametric arrays (the
physical parameters' sensitivities included, the costly part), the frequency bounds declared, the system built at
its nominal parameters (its states), the zero-frequency cluster reduced as the native runtime keeps it, and (on
first use) the Jacobian's pattern. The pythonfmu writer (:mod:`mace_fmu.fmu.export`), the native writer
(:mod:`mace_fmu.fmu.native.export`) and SSP only serialise it: none of them computes a sensitivity or reduces the
cluster again.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType
from typing import Literal, cast

import numpy as np

from mace_fmu.fmu.native.model_description import JacobianPattern
from mace_fmu.fmu.native.resource import Corrections, ZeroCluster, corrections_of, zero_cluster_reduced
from mace_fmu.fmu.variables import model_summary
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.resolve_data import resolve_arrays
from mace_fmu.iomodel.parametric_data import parametric_arrays, with_frequency_bounds
from mace_fmu.iomodel.volts import VoltsModel


@dataclass(frozen=True)
class FmuSignal:
    """An input or output of the model's FMUs."""

    name: str  #: the variable's name (the model's signal name)
    description: str  #: which actuator or sensor, which axis, what a volt means
    unit: str  #: its unit at the model boundary: "V", or a physical one ("N", "m/s^2", "rad", ...)


@dataclass(frozen=True)
class FmuParameter:
    """A tunable parameter of the model's FMUs, with the range every FMU declares."""

    name: str  #: the variable's name (``damping_mode_3``, ``delay_gyro_x``, ``E_steel``, ...)
    nominal: float  #: its start value, the model's own [SI]
    minimum: float  #: declared minimum (-inf: none)
    maximum: float  #: declared maximum (inf: none)
    description: str  #: what it is, with its unit


#: how the FMUs rebuild a block: the modal structure, a constant block, or the parameters' delay, gain or PD
BlockKind = Literal["structure", "const", "delay", "gain", "pd"]


@dataclass(frozen=True)
class FmuBlock:
    """A block of the model's diagram as its FMUs rebuild it for new parameter values."""

    name: str  #: the diagram's block name
    kind: BlockKind  #: how it is rebuilt
    parameters: tuple[str, ...]  #: the parameters it takes (a delay's or a gain's one, a PD's two; none otherwise)
    a: np.ndarray  #: A of the block at the nominal parameters (a constant block's for good)
    b: np.ndarray  #: B
    c: np.ndarray  #: C
    d: np.ndarray  #: D


@dataclass(frozen=True)
class ParametricModel:
    """A volts-volts model as its FMUs carry it (module docstring): built by :func:`parametric_model`."""

    summary: str  #: one-line description for the FMUs' model descriptions
    inputs: tuple[FmuSignal, ...]  #: the FMUs' inputs, in the model's order
    outputs: tuple[FmuSignal, ...]  #: the FMUs' outputs, in the model's order
    parameters: tuple[FmuParameter, ...]  #: the tunable parameters, in the parameter vector's order
    physical_names: tuple[str, ...]  #: the physical parameters (moduli, springs, masses) among them
    #: (n_physical, n_modes, n_modes) each physical parameter's stiffness change per relative change (p / p0 - 1),
    #: projected on the retained modes
    stiffness_sensitivities: np.ndarray
    #: (n_physical, n_modes, n_modes) each mass parameter's projected mass change (zeros for the others; None
    #: without mass parameters)
    mass_sensitivities: np.ndarray | None
    mode_labels: tuple[str, ...]  #: one label per retained mode (the calculated frequencies' descriptions)
    frequencies_hz: np.ndarray  #: the retained modes' nominal frequencies [Hz], before reanalysis and scales
    state_names: tuple[str, ...]  #: "block.state" of the system built at the nominal parameters
    #: the ParametricSystem's arrays (blocks, wiring, modal rows, the physical parameters' sensitivities), as a
    #: pythonfmu FMU stores them (``resources/model.npz``) and the native runtime's data is made from
    arrays: Mapping[str, np.ndarray]
    cluster: ZeroCluster  #: the zero-frequency cluster reduced at the nominal parameters (the native runtime's)
    corrections: Corrections  #: the reanalysis's static corrections and the preload's shape changes
    blocks: tuple[FmuBlock, ...]  #: the diagram's blocks, in the wiring's order
    wiring: np.ndarray  #: (block inputs, block outputs) 0/1: which block output feeds which block input
    entry: np.ndarray  #: (block inputs, model inputs) 0/1: which model input feeds which block input
    exit: np.ndarray  #: (model outputs, block outputs) 0/1: which block output is which model output
    pade_order: int  #: order of every delay's Pade approximation
    structure_outputs: tuple[str, ...]  #: the modal structure block's outputs, in its order

    @property
    def signal_units(self) -> dict[str, str]:
        """Input and output name -> unit at the model boundary."""
        return {s.name: s.unit for s in (*self.inputs, *self.outputs)}

    @property
    def ranges(self) -> dict[str, tuple[float, float]]:
        """Parameter name -> (declared minimum, declared maximum), infinite where none is declared."""
        return {p.name: (p.minimum, p.maximum) for p in self.parameters}

    @cached_property
    def jacobian(self) -> JacobianPattern:
        """Where (A, B, C, D) can be nonzero for any parameter values (:func:`jacobian_pattern`), found once."""
        return jacobian_pattern(ParametricSystem(self.arrays))


def parametric_model(model: VoltsModel, *, arrays: Mapping[str, np.ndarray] | None = None,
                     frequency_bounds: Mapping[int, float] | None = None) -> ParametricModel:
    """What every FMU of ``model`` carries, computed once (module docstring).

    Parameters
    ----------
    model : VoltsModel
        The volts-volts model (:func:`~mace_fmu.iomodel.volts.volts_model`).
    arrays : mapping, optional
        Its parametric arrays (:func:`~mace_fmu.iomodel.parametric_data.parametric_arrays`) if already computed
        (default: computed here, every physical parameter's sensitivities included).
    frequency_bounds : mapping of int to float, optional
        1-based mode -> relative bound: the declared min/max of that mode's ``frequency_scale_mode_<k>``,
        1 -+ bound (:func:`~mace_fmu.iomodel.parametric_data.with_frequency_bounds`).

    Returns
    -------
    ParametricModel
        The record the FMU writers serialise.

    Raises
    ------
    MaceError
        A frequency bound for a mode the model lacks or out of [0, 1); a parameter outside its range.
    """
    arrays = parametric_arrays(model, resolve=True) if arrays is None else dict(arrays)
    if len(arrays["physical_names"]) and "resolve_kind" not in arrays:  # the FMU solves its structure again
        arrays.update(resolve_arrays(model, [str(n) for n in arrays["physical_names"]]))
    if frequency_bounds:
        arrays = with_frequency_bounds(arrays, frequency_bounds)
    system = ParametricSystem(arrays)
    system.build(system.nominal)

    def signals(names: np.ndarray, descriptions: np.ndarray, units: np.ndarray) -> tuple[FmuSignal, ...]:
        return tuple(FmuSignal(name=str(n), description=str(d), unit=str(u))
                     for n, d, u in zip(names, descriptions, units))

    parameters = tuple(FmuParameter(name=name, nominal=float(value), minimum=float(low), maximum=float(high),
                                    description=str(description))
                       for name, value, low, high, description in zip(
                           system.parameter_names, system.nominal, system.minimum, system.maximum,
                           arrays["param_descriptions"]))
    return ParametricModel(summary=model_summary(model),
                           inputs=signals(arrays["inputs"], arrays["input_descriptions"], arrays["input_units"]),
                           outputs=signals(arrays["outputs"], arrays["output_descriptions"], arrays["output_units"]),
                           parameters=parameters, physical_names=tuple(str(x) for x in arrays["physical_names"]),
                           stiffness_sensitivities=np.asarray(arrays["physical_dk"], dtype=float),
                           mass_sensitivities=np.asarray(arrays["physical_dm"], dtype=float)
                           if "physical_dm" in arrays else None,
                           mode_labels=system.mode_labels, frequencies_hz=np.asarray(arrays["frequencies_hz"],
                                                                                     dtype=float),
                           state_names=tuple(system.state_names),
                           arrays=MappingProxyType(arrays), cluster=zero_cluster_reduced(arrays),
                           corrections=corrections_of(arrays),
                           blocks=_blocks(arrays), wiring=np.asarray(arrays["wiring"], dtype=float),
                           entry=np.asarray(arrays["entry"], dtype=float), exit=np.asarray(arrays["exit"], dtype=float),
                           pade_order=int(arrays["pade_order"]),
                           structure_outputs=tuple(str(x) for x in arrays["structure_outputs"]))


def _blocks(arrays: Mapping[str, np.ndarray]) -> tuple[FmuBlock, ...]:
    """The blocks of a ParametricSystem's ``arrays`` (``block_kinds``, ``block_params``, ``block<i>_A`` ...)."""
    def matrix(i: int, m: str) -> np.ndarray:
        return np.asarray(arrays[f"block{i}_{m}"], dtype=float)

    return tuple(FmuBlock(name=str(name), kind=cast(BlockKind, str(kind)),
                          parameters=tuple(str(param).split(",")) if str(param) else (),
                          a=matrix(i, "A"), b=matrix(i, "B"), c=matrix(i, "C"), d=matrix(i, "D"))
                 for i, (name, kind, param) in enumerate(zip(arrays["block_names"], arrays["block_kinds"],
                                                             arrays["block_params"])))


def jacobian_pattern(system: ParametricSystem, *, samples: int = 2, seed: int = 0) -> JacobianPattern:
    """Where (A, B, C, D) of ``system`` can be nonzero for any parameter values.

    The union of the nonzero entries at the nominal parameters and at ``samples`` random sets (each parameter
    within 10 % of its nominal value, or 1 % of its range from a zero nominal, inside its declared range).
    Entries that no parameter reaches (the block structure's zeros) stay zero in every build; the random sets
    reach those a parameter at its nominal value happens to zero (a damping or gain of 0), and the physical
    parameters' reanalysis mixes the flexible modes as any change of them does.

    Parameters
    ----------
    system : ParametricSystem
        The model's parametric system.
    samples : int
        How many random parameter sets besides the nominal one.
    seed : int
        Seed of the random sets.

    Returns
    -------
    JacobianPattern
        Boolean arrays of the shapes of A, B, C and D; the system is left built at its nominal parameters.
    """
    rng = np.random.default_rng(seed)
    nominal, low, high = system.nominal, system.minimum, system.maximum
    span = np.where(np.isfinite(high - low), high - low, 1.0)
    sets = [nominal]
    for _ in range(samples):
        step = np.where(nominal != 0.0, 0.1 * nominal, 0.01 * span) * rng.uniform(0.5, 1.0, len(nominal))
        sets.append(np.clip(nominal + step * rng.choice([-1.0, 1.0], len(nominal)), low, high))
    patterns = [np.asarray(m) != 0.0 for m in system.build(sets[0])]
    for params in sets[1:]:
        patterns = [p | (np.asarray(m) != 0.0) for p, m in zip(patterns, system.build(params))]
    system.build(nominal)  # leave the system as built at its nominal parameters
    return JacobianPattern(a=patterns[0], b=patterns[1], c=patterns[2], d=patterns[3])
