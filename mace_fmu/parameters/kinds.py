"""One record per kind of model parameter: its names, its SI unit and the range every FMU declares.

A modal parameter has two spellings: by its mode's label (``damping:1st Z bending``), so that a set
fits any model that has such a mode, and by the mode's 1-based number in the model's retained-mode
order (``damping_mode_14``), because an FMU's variables are fixed. A
:class:`~mace_fmu.parameters.sets.ParameterSet` takes both (the engine and the 0-g prediction write
labels, an FMU update writes the FMU's numbers); where a set meets a model the names are resolved
to its modes once (:mod:`mace_fmu.parameters.per_mode`). Physical parameters, delays and gains are
spelled the same in both. This module is the only place that decodes a name: every other module
asks it.

The range is what both FMU kinds declare as ``min``/``max`` and refuse outside, so that a host
that honours the model description never meets a refusal (:func:`declared_range`). Ranges are
physical limits plus the reach of the models behind them:

- Young's moduli and spring stiffnesses: [0.7, 1.5] x nominal, the range over which the FMUs'
  parameter route (reanalysis with static corrections, mace_fmu.iomodel.stiffness_route) was
  validated against full re-solves: every output of both MACE models within 0.4 % of its range at
  either end, one parameter at a time (tests/iomodel/test_parameter_route.py). Beyond it the 1-g preload's
  first-order redistribution limits it (the Lexan center's modulus at 0.5 x: 1.8 %); zero, which would
  remove an element, is far outside. A full re-solve (``mace-fmu export --parameters``) takes any
  positive value.
- concentrated masses (CONM2, ``m_<name>``): [0.7, 1.5] x nominal, validated the same way on the three-storey
  frame's floors (examples/three_storey_frame; tests/iomodel/test_mass_route.py): the reanalysis with the
  mass change and mass-correction vectors, and the 1-g preload's weight re-solved to first order.
- delays: [0, 1] s (a millisecond-sampled loop with a second of delay is meaningless).
- damping ratios: [0, 1]; 1 is a critically damped mode, still a linear system.
- frequency scales: [0.1, 10], or the bounds given at export (Table 5.3's for the 0-g model).
  The lower end is raised for a mode below 0.1 Hz so that no scale moves a flexible mode into the
  zero-frequency cluster, which a native FMU reduces once at export.
- servo gains: +-1000 x |nominal| (+-1000 for a nominal 0): a gain may make a loop unstable (a run
  of it then ends with an overflow the FMU reports, as a real loop would saturate), but a thousand
  times the design gain is no loop anyone builds, and 1e308 overflowed the system's matrices before
  the first step (model exchange returned NaN derivatives).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal

from mace_fmu.errors import MaceError
from mace_fmu.util.frequency import ZERO_HZ  # the zero-frequency cluster's edge [Hz]

KindName = Literal["modulus", "spring", "mass", "delay", "gain", "damping", "frequency_scale"]


@dataclass(frozen=True)
class ParameterKind:
    """How one kind of parameter is named, in which unit, and over which range it is valid.

    ``minimum`` and ``maximum`` are absolute, or factors on the nominal value where
    ``relative_to_nominal`` is set.
    """

    name: KindName  #: the kind, e.g. "modulus"
    set_prefix: str  #: prefix of the name in a ParameterSet ("" for the gains, named in full)
    fmu_prefix: str  #: prefix of the name in an FMU
    unit: str  #: SI unit ("1" for dimensionless)
    minimum: float  #: lowest valid value (relative to nominal when relative_to_nominal)
    maximum: float  #: highest valid value (relative to nominal when relative_to_nominal)
    relative_to_nominal: bool = False  #: the range is a multiple of the nominal value
    per_mode: bool = False  #: named by mode label in a set and by 1-based mode number in an FMU
    exact_names: Mapping[str, str] = field(default_factory=dict)  #: name -> unit, for kinds without a prefix
    description: str = ""  #: what a parameter of this kind is, with its unit
    #: an exact name may also carry an actuator, ``K_a_<actuator>``: the gain of that actuator's loop alone
    per_actuator: bool = False

    def range_for(self, nominal: float) -> tuple[float, float]:
        """[min, max] of a parameter of this kind with nominal value ``nominal`` (SI).

        Parameters
        ----------
        nominal : float
            The parameter's nominal value (SI).

        Returns
        -------
        tuple of float
            (min, max), relative to ``nominal`` for the kinds whose range is.
        """
        if self.relative_to_nominal:
            scale = abs(nominal) if nominal != 0.0 or self.minimum >= 0.0 else 1.0  # a signed kind about 0
            return self.minimum * scale, self.maximum * scale
        return self.minimum, self.maximum

    def fmu_name(self, mode: int) -> str:
        """FMU name of this per-mode kind for 1-based mode number ``mode``.

        Parameters
        ----------
        mode : int
            The 1-based mode number.

        Returns
        -------
        str
            The FMU's parameter name, e.g. ``damping_mode_3``.
        """
        if not self.per_mode:
            raise MaceError(f"{self.name} parameters are not per mode")
        return f"{self.fmu_prefix}{mode}"

    def set_name(self, label: str) -> str:
        """Parameter-set name of this per-mode kind for the modes labelled ``label``.

        Parameters
        ----------
        label : str
            The modes' label, e.g. ``"1st Z bending"``.

        Returns
        -------
        str
            The parameter-set name, e.g. ``damping:1st Z bending``.
        """
        if not self.per_mode:
            raise MaceError(f"{self.name} parameters are not per mode")
        return f"{self.set_prefix}{label}"

    def named(self, element: str) -> str:
        """The name (set's and FMU's alike) of this kind's parameter of a named element: ``MODULUS.named("lexan_end")``
        -> ``E_lexan_end``, ``DELAY.named("gyro_bus_y")`` -> ``delay_gyro_bus_y``.

        Parameters
        ----------
        element : str
            The element's name (a material, spring, mass, sensor or actuator).

        Returns
        -------
        str
            The parameter's name.
        """
        if self.per_mode or not self.set_prefix or self.set_prefix != self.fmu_prefix:
            raise MaceError(f"{self.name} parameters are not named after an element")
        return f"{self.set_prefix}{element}"


MODULUS = ParameterKind("modulus", "E_", "E_", "Pa", 0.7, 1.5, relative_to_nominal=True,
                        description="Young's modulus of a MAT1 card")
SPRING = ParameterKind("spring", "k_", "k_", "N/m", 0.7, 1.5, relative_to_nominal=True,
                       description="stiffness of a CELAS2 card")
MASS = ParameterKind("mass", "m_", "m_", "kg", 0.7, 1.5, relative_to_nominal=True,
                     description="mass of a CONM2 card, its inertias scaled with it")
DELAY = ParameterKind("delay", "delay_", "delay_", "s", 0.0, 1.0, description="time delay of a channel")
GAIN = ParameterKind("gain", "", "", "1", -1000.0, 1000.0, relative_to_nominal=True,
                     exact_names=MappingProxyType({"K_a": "V/deg", "K_r": "V/(deg/s)", "K_f": "1", "K_b": "1"}),
                     description="servo loop gain", per_actuator=True)
DAMPING = ParameterKind("damping", "damping:", "damping_mode_", "1", 0.0, 1.0, per_mode=True,
                        description="open-loop modal damping ratio")
FREQUENCY_SCALE = ParameterKind("frequency_scale", "frequency_scale:", "frequency_scale_mode_", "1", 0.1, 10.0,
                                per_mode=True, description="factor on an open-loop natural frequency")

KINDS: tuple[ParameterKind, ...] = (MODULUS, SPRING, MASS, DELAY, GAIN, DAMPING, FREQUENCY_SCALE)
#: the servo gains' names and what they are
SERVO_GAINS = MappingProxyType({"K_a": "gimbal_angle_gain", "K_r": "gimbal_rate_gain", "K_f": "wheel_forward_gain",
                                "K_b": "wheel_backward_gain"})


#: prefix of the calculated parameters an FMU reports each mode's natural frequency [Hz] in, after reanalysis
#: and frequency scale (not a parameter anyone sets: a calculated one)
FREQUENCY_OUTPUT_PREFIX = "frequency_mode_"


def frequency_output_name(mode: int) -> str:
    """The FMU's calculated parameter of 1-based mode ``mode``'s natural frequency [Hz], ``frequency_mode_<k>``."""
    return f"{FREQUENCY_OUTPUT_PREFIX}{mode}"


def is_frequency_output(name: str) -> bool:
    """Whether ``name`` is an FMU's calculated natural frequency (:func:`frequency_output_name`)."""
    rest = name.removeprefix(FREQUENCY_OUTPUT_PREFIX)
    return rest != name and rest.isdigit()


def _match(name: str, *, in_fmu: bool) -> ParameterKind | None:
    """The kind whose name (exact) or prefix ``name`` carries, in an FMU's spelling or a set's."""
    for kind in KINDS:
        if name in kind.exact_names or (kind.per_actuator and split_loop_name(name)[1]):
            return kind
        prefix = kind.fmu_prefix if in_fmu else kind.set_prefix
        rest = name[len(prefix):]
        # an FMU's per-mode name ends in the mode number; a set's in a mode label
        if prefix and name.startswith(prefix) and rest and (rest.isdigit() or not (in_fmu and kind.per_mode)):
            return kind
    return None


def kind_of_set_name(name: str) -> ParameterKind | None:
    """The kind of a parameter-set name (``E_lexan_end``, ``damping:1st Z bending``), None if unknown.

    Parameters
    ----------
    name : str
        A parameter-set name.

    Returns
    -------
    ParameterKind or None
        Its kind: prefix, unit and valid range.
    """
    return _match(name, in_fmu=False)


def kind_of_fmu_name(name: str) -> ParameterKind | None:
    """The kind of an FMU parameter name (``E_lexan_end``, ``damping_mode_14``), None if unknown.

    Parameters
    ----------
    name : str
        An FMU parameter name.

    Returns
    -------
    ParameterKind or None
        Its kind: prefix, unit and valid range.
    """
    return _match(name, in_fmu=True)


def kind_of_name(name: str) -> ParameterKind | None:
    """The kind of a parameter name in either spelling, a set's or an FMU's (``damping:1st Z bending`` and
    ``damping_mode_14`` alike), None if unknown: what a parameter set takes.

    Parameters
    ----------
    name : str
        A parameter name.

    Returns
    -------
    ParameterKind or None
        Its kind: prefix, unit and valid range.
    """
    return kind_of_set_name(name) or kind_of_fmu_name(name)


@dataclass(frozen=True)
class ModeReference:
    """The mode a per-mode parameter name addresses: by label (a set's spelling) or by number (an FMU's)."""

    kind: ParameterKind  #: DAMPING or FREQUENCY_SCALE
    label: str | None = None  #: the mode label of ``damping:<label>``, None for a name by number
    number: int | None = None  #: the 1-based mode number of ``damping_mode_<k>``, None for a name by label


def mode_reference(name: str) -> ModeReference | None:
    """The kind and the mode of a per-mode name in either spelling (``damping:1st Z bending`` -> label
    "1st Z bending", ``damping_mode_14`` -> number 14); None for a name that is not per mode.

    Parameters
    ----------
    name : str
        A parameter name.

    Returns
    -------
    ModeReference or None
        Its kind and the mode's label or number.
    """
    kind = kind_of_fmu_name(name)
    if kind is not None and kind.per_mode:
        return ModeReference(kind, number=int(name[len(kind.fmu_prefix):]))
    kind = kind_of_set_name(name)
    if kind is not None and kind.per_mode:
        return ModeReference(kind, label=name[len(kind.set_prefix):])
    return None


def mode_number(name: str) -> int:
    """1-based mode number of a per-mode FMU parameter name (``frequency_scale_mode_7`` -> 7)."""
    kind = kind_of_fmu_name(name)
    if kind is None or not kind.per_mode:
        raise MaceError(f"{name!r} is not a per-mode FMU parameter name")
    return int(name[len(kind.fmu_prefix):])


def mode_label(name: str) -> str:
    """Mode label of a per-mode parameter-set name (``damping:1st Z bending`` -> ``1st Z bending``)."""
    kind = kind_of_set_name(name)
    if kind is None or not kind.per_mode:
        raise MaceError(f"{name!r} is not a per-mode parameter-set name")
    return name[len(kind.set_prefix):]


def unit_of(kind: ParameterKind, name: str) -> str:
    """SI unit of parameter ``name`` of ``kind`` (a gain's unit is its own, one loop's that of its symbol)."""
    return kind.exact_names.get(split_loop_name(name)[0], kind.unit)


def split_loop_name(name: str) -> tuple[str, str]:
    """(gain symbol, actuator) of a servo gain's name: ``K_a`` -> ("K_a", ""), the shared gain;
    ``K_a_gimbal_z`` -> ("K_a", "gimbal_z"), the gain of that actuator's loop alone; ("", "") for any
    other name."""
    for symbol in GAIN.exact_names:
        if name == symbol:
            return symbol, ""
        if name.startswith(symbol + "_") and len(name) > len(symbol) + 1:
            return symbol, name[len(symbol) + 1:]
    return "", ""


def declared_range(name: str, nominal: float, *, frequency_hz: float | None = None) -> tuple[float, float]:
    """[min, max] an FMU declares and enforces for its parameter ``name`` with nominal value ``nominal``.

    ``frequency_hz`` (a frequency scale's mode, nominal) raises the scale's minimum so that the mode
    stays above :data:`ZERO_HZ`. Names of no kind are unbounded.

    Parameters
    ----------
    name : str
        An FMU parameter name.
    nominal : float
        Its nominal value [SI].
    frequency_hz : float, optional
        For a frequency scale: its mode's nominal frequency [Hz].

    Returns
    -------
    tuple of float
        (minimum, maximum) [SI]; (-inf, inf) for names of no kind.
    """
    kind = kind_of_fmu_name(name)
    if kind is None:
        return -math.inf, math.inf
    low, high = kind.range_for(nominal)
    if kind is FREQUENCY_SCALE and frequency_hz is not None and frequency_hz != 0.0:
        # a scale that would land the mode just on the cluster's edge is refused: keep a 1e-9 margin
        low = max(low, ZERO_HZ / abs(frequency_hz) * (1.0 + 1e-9))
    return low, high
