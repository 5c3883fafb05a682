"""Actuators, sensors, electronics, servos and damping of a structure, read from its data file.

Every actuator and sensor is a named weighted sum of (grid, component) DOFs, components in the
grid's displacement (CD) system, so nothing indexes a mode-shape vector by position.
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Mapping

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fe.dofs import DofMap, cd_component_vector
from mace_fmu.parameters.kinds import SERVO_GAINS
from mace_fmu.structure.file import StructureFile, bundled_structure_path, load_structure_file
from modelica_like.filters import LOWPASS_KINDS, lowpass_realization

if TYPE_CHECKING:
    from mace_fmu.iomodel.source import ModalSource

SensorKind = Literal["displacement", "rate", "acceleration"]
#: the sensor kinds a structure file may name: a bar strain gauge is a displacement sensor whose weights
#: the deck's bar gives (fe/bar_strain.py); an acceleration sensor (an accelerometer, or an angular one) reads
#: the second derivative of its DOFs, with a feedthrough from the actuators (iomodel/modal_core.py)
SENSOR_KINDS = ("displacement", "rate", "acceleration", "bar_strain")
Dof = tuple[int, int, float]  #: (grid, component 1-6 in CD, weight)


@dataclass(frozen=True)
class BarGauge:
    """Where a strain gauge sits: a CBAR, a position along it and a fibre of its section."""

    bar: int  #: CBAR ID
    position: float  #: along the bar from end A, as a fraction of its length (0: end A, 1: end B)
    fiber_y_m: float  #: fibre offset from the centroid along the element y axis [m]
    fiber_z_m: float  #: fibre offset along the element z axis [m]


@dataclass(frozen=True)
class Actuator:
    """An input: the generalised force ``gain`` x input on its DOFs [N, N m].

    The input is in volts where the structure file gives a ``gain`` [N or N m per V] or a ``sensitivity``
    [V per N] (gain = 1 / sensitivity), else the force itself (``input_unit`` "N" or "N m", gain 1).
    """

    name: str  #: input name
    description: str  #: what it does, for reports and FMU descriptions
    dofs: tuple[Dof, ...]  #: (grid, component in CD, weight): the generalised force of one physical unit
    gain: float  #: [N m / V] (Table 3.11); 1 for an input in N or N m
    input_unit: str = "V"  #: the input's unit at the model boundary: "V", or "N" / "N m" for a force input


@dataclass(frozen=True)
class Sensor:
    """An output: the weighted DOFs (displacement) or their rate, times ``gain`` volts per unit."""

    name: str  #: output name
    description: str  #: what it reads, for reports and FMU descriptions
    kind: SensorKind  #: "displacement", "rate" or "acceleration" of its DOFs
    dofs: tuple[Dof, ...]  #: (grid, component in CD, weight) read (for a bar gauge: filled in from its bar)
    gain: float  #: [V per strain, per rad/s, ...] (Table 3.12, notch DC gains of Table 3.13)
    unit: str = ""  #: the physical quantity's unit: rad, m, rad/s, m/s, or "strain" (given in the structure file)
    #: a bar strain gauge: its ``dofs`` come from the deck's bar (:func:`resolve_bar_gauges`); None otherwise
    gauge: BarGauge | None = None
    #: the output's unit at the model boundary: "V" (a ``gain`` or ``sensitivity`` given), else ``unit`` (gain 1)
    output_unit: str = "V"


@dataclass(frozen=True)
class Electronics:
    """Filters and delays between the structure and the control computer (thesis 3.5, 4.5)."""

    filter_order: int  #: poles of the analog anti-aliasing low-pass on each analog sensor (0: none)
    filter_cutoff_hz: float  #: its -3.01 dB frequency [Hz]
    filter_equivalent_delay_s: float  #: the Pade stand-in for the filter (Fig. 3.18 for MACE's Bessel) [s]
    analog_sensors: tuple[str, ...]  #: sensor names behind the filter
    sensor_delays_s: Mapping[str, float]  #: extra delays (Table 4.6)
    actuator_delays_s: Mapping[str, float]  #: computational delays (Table 4.5)
    filter_kind: str = "bessel"  #: the low-pass family: "bessel" (MACE's) or "butterworth"


#: the gain symbols of each kind of local loop, as the FMU names its parameters
SPEED_LOOP_GAINS = ("K_f", "K_b")
POSITION_LOOP_GAINS = ("K_a", "K_r")
#: structure-file key of each symbol in a loop's own table ([servos] wheels / gimbals entries)
LOOP_GAIN_KEYS = {"K_f": "forward_gain", "K_b": "backward_gain", "K_a": "angle_gain", "K_r": "rate_gain"}


@dataclass(frozen=True)
class Servos:
    """Local loops: wheel speed (eq. 3.18) and gimbal angle (eq. 3.19-3.20).

    Every loop of a kind shares that kind's gains unless the structure file gives the loop its own
    (``loop_gains``); a loop with its own gains gets its own FMU parameters, ``K_f_<actuator>`` and so on.
    """

    wheel_forward_gain: float  #: K_f, shared by the speed loops
    wheel_backward_gain: float  #: K_b, shared by the speed loops
    wheels: Mapping[str, str]  #: wheel actuator -> its tachometer
    gimbal_angle_gain: float  #: K_a [V / deg], shared by the position loops
    gimbal_rate_gain: float  #: K_r [V / (deg/s)], shared by the position loops
    gimbals: Mapping[str, str]  #: gimbal actuator -> its encoder
    #: actuator -> {symbol: value}: the gains a loop has of its own ("K_f", "K_b" or "K_a", "K_r")
    loop_gains: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def shared_gain(self, symbol: str) -> float:
        """The shared gain ``symbol`` ("K_f", "K_b", "K_a" or "K_r") of the loops without their own."""
        return getattr(self, SERVO_GAINS[symbol])

    def gain(self, actuator: str, symbol: str) -> float:
        """The gain ``symbol`` ("K_f", "K_b", "K_a" or "K_r") of the loop closed on ``actuator``."""
        return self.loop_gains.get(actuator, {}).get(symbol, self.shared_gain(symbol))

    def parameter_name(self, actuator: str, symbol: str) -> str:
        """The FMU parameter that carries this gain: ``K_f`` when shared, ``K_f_<actuator>`` when the loop's own."""
        return f"{symbol}_{actuator}" if symbol in self.loop_gains.get(actuator, {}) else symbol


@dataclass(frozen=True)
class ViolinFamily:
    order: int
    cables: frozenset[int]
    zeta: tuple[float, ...]


@dataclass(frozen=True)
class DampingTable:
    """Open-loop modal damping ratios by mode label (Table 4.7 measurement model), and a parameter set's by mode."""

    default: float
    zero_frequency: float
    by_label: Mapping[str, float]
    violin_families: tuple[ViolinFamily, ...]
    #: 1-based mode number -> ratio: a parameter set's damping ratios, either spelling resolved to the modes
    #: (mace_fmu.parameters.per_mode); before the labels, as a set's value overrides the file's
    by_mode: Mapping[int, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Instruments:
    """Everything between the FE modes and the volts-volts model."""

    actuators: tuple[Actuator, ...]  #: the inputs, in input order
    sensors: tuple[Sensor, ...]  #: the outputs, in output order
    electronics: Electronics  #: filters and delays
    servos: Servos  #: local loops (wheel speed, gimbal servos)
    damping: DampingTable  #: open-loop modal damping ratios by mode label
    source: str  #: the structure file they come from

    def actuator(self, name: str) -> Actuator:
        return _by_name(self.actuators, name, "actuator")

    def sensor(self, name: str) -> Sensor:
        return _by_name(self.sensors, name, "sensor")

    @property
    def analog_sensor_names(self) -> tuple[str, ...]:
        """Sensors behind a Bessel filter, in output order."""
        return tuple(s.name for s in self.sensors
                     if any(fnmatch.fnmatchcase(s.name, pat) for pat in self.electronics.analog_sensors))


def _by_name(items, name: str, what: str):
    for item in items:
        if item.name == name:
            return item
    raise MaceError(f"unknown {what} {name!r}; known: {', '.join(i.name for i in items)}")


#: a DOF whose mass is below this fraction of the largest is massless (round-off of assembled lumped masses)
MASSLESS_FRACTION = 1e-12


def influence_vector(dofs: tuple[Dof, ...], dof_map: DofMap, cd_frames: np.ndarray) -> np.ndarray:
    """Row vector over the basic DOFs that forms sum(weight * u(grid, component in CD))."""
    vec = np.zeros(dof_map.size)
    for grid, comp, weight in dofs:
        vec += weight * cd_component_vector(dof_map, cd_frames, grid, comp)
    return vec


def _number(entry: Mapping[str, Any], key: str, where: str, default: float | None = None) -> float:
    value = entry.get(key, default)
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise MaceError(f"{where}: {key} must be a number, got {value!r}")
    return float(value)


def _bar_gauge(entry: Mapping[str, Any], where: str) -> BarGauge:
    """``bar = ID``, ``position = 0..1`` (default 0.5), ``fiber = [y, z]`` [m] of a bar_strain sensor."""
    if "dofs" in entry or "wheels" in entry:
        raise MaceError(f"{where}: a bar_strain sensor takes bar, position and fiber, not dofs (its bar gives them)")
    bar, fiber = entry.get("bar"), entry.get("fiber")
    if not isinstance(bar, int) or isinstance(bar, bool):
        raise MaceError(f"{where}: bar must be a CBAR ID (an integer), got {bar!r}")
    if not (isinstance(fiber, list) and len(fiber) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in fiber)):
        raise MaceError(f"{where}: fiber must be [y, z], the gauge's offset [m] from the section centroid in "
                        f"element axes, got {fiber!r}")
    position = _number(entry, "position", where, default=0.5)
    if not 0.0 <= position <= 1.0:
        raise MaceError(f"{where}: position must be in [0, 1] (a fraction of the bar's length from end A), got "
                        f"{position}")
    return BarGauge(bar=bar, position=position, fiber_y_m=float(fiber[0]), fiber_z_m=float(fiber[1]))


def _boundary(entry: Mapping[str, Any], where: str, *, physical_unit: str, is_input: bool) -> tuple[float, str]:
    """(gain, unit at the model boundary) of an instrument: volts with a ``gain`` or a ``sensitivity`` [V per
    physical unit], else the physical quantity itself with gain 1."""
    if "gain" in entry and "sensitivity" in entry:
        raise MaceError(f"{where}: give gain or sensitivity, not both")
    if "sensitivity" in entry:
        sensitivity = _number(entry, "sensitivity", where)
        if not (math.isfinite(sensitivity) and sensitivity > 0):
            raise MaceError(f"{where}: sensitivity must be > 0 V per {physical_unit}, got {sensitivity:g}")
        return (1.0 / sensitivity if is_input else sensitivity), "V"
    if "gain" in entry:
        gain = _number(entry, "gain", where)
        if not (math.isfinite(gain) and gain != 0):
            raise MaceError(f"{where}: gain must be a finite number other than 0, got {gain:g}")
        return gain, "V"
    if physical_unit == "physical unit":
        raise MaceError(f"{where}: its DOFs mix translations and rotations, so its {'input' if is_input else 'output'}"
                        " has no single unit: give a gain (volts at the model boundary)")
    return 1.0, physical_unit


def _dof_units(dofs: tuple[Dof, ...], *, translation: str, rotation: str) -> str:
    """``translation`` or ``rotation`` when every DOF is one kind (components 1-3 or 4-6), else "physical unit"
    (a weighted sum of both has no single unit)."""
    if all(c >= 4 for _, c, _ in dofs):
        return rotation
    return translation if all(c <= 3 for _, c, _ in dofs) else "physical unit"


def force_unit(dofs: tuple[Dof, ...]) -> str:
    """The unit of an actuator's generalised force on ``dofs``: N, N m, or "physical unit" for a mix."""
    return _dof_units(dofs, translation="N", rotation="N m")


def _actuator(entry: Mapping[str, Any], path: Path) -> Actuator:
    where = f"{path} actuator {entry['name']}"
    dofs = _dofs(entry, where)
    gain, unit = _boundary(entry, where, is_input=True, physical_unit=force_unit(dofs))
    return Actuator(name=entry["name"], description=entry["description"], dofs=dofs, gain=gain, input_unit=unit)


def _sensor(entry: Mapping[str, Any], path: Path) -> Sensor:
    where = f"{path} sensor {entry['name']}"
    kind = entry["kind"]
    if kind not in SENSOR_KINDS:
        raise MaceError(f"{path}: sensor {entry['name']}: kind must be one of {', '.join(map(repr, SENSOR_KINDS))}, "
                        f"got {kind!r}")
    if kind == "bar_strain":
        unit = str(entry.get("unit") or "strain")
        gain, output_unit = _boundary(entry, where, physical_unit=unit, is_input=False)
        return Sensor(name=entry["name"], description=entry["description"], kind="displacement", dofs=(),
                      gain=gain, unit=unit, gauge=_bar_gauge(entry, where), output_unit=output_unit)
    dofs = _dofs(entry, where)
    unit = str(entry.get("unit") or _sensor_unit(kind, dofs))
    gain, output_unit = _boundary(entry, where, physical_unit=unit, is_input=False)
    return Sensor(name=entry["name"], description=entry["description"], kind=kind, dofs=dofs, gain=gain, unit=unit,
                  output_unit=output_unit)


def check_accelerometers_have_mass(instruments: Instruments, *, mass, transform, dof_map: DofMap,
                                   cd_frames: np.ndarray) -> None:
    """A MaceError naming the structure file, the sensor and the actuator when an acceleration sensor reads a
    DOF without mass that a force input pushes on a DOF without mass.

    Where it matters: a massless DOF's motion is the static response to the others and to the forces on it,
    so its acceleration carries the second derivative of a force applied to massless DOFs. That part has no
    modal form (each retained mode adds to the direct feedthrough without converging), so the model would
    silently depend on how many modes it keeps. An accelerometer on a massless grid driven only through
    massive DOFs reads a proper signal and is accepted.

    Parameters
    ----------
    instruments : Instruments
        The structure's actuators and sensors.
    mass : sparse or dense matrix or None
        The mass matrix on the basic DOFs [kg, kg m^2] (None: none to check against, NASTRAN's modes).
    transform : sparse matrix or None
        The constraints' T (basic = T @ independent); None: every DOF independent.
    dof_map : DofMap
        The basic DOFs' (grid, component) order.
    cd_frames : numpy.ndarray
        (n_grid, 3, 3) displacement-system axes (the instruments' components are in CD).
    """
    accelerometers = [s for s in instruments.sensors if s.kind == "acceleration"]
    if not accelerometers or not instruments.actuators or mass is None:
        return

    def independent(dofs: tuple[Dof, ...]) -> np.ndarray:
        row = influence_vector(dofs, dof_map, cd_frames)
        return np.asarray(transform.T @ row if transform is not None else row).ravel()

    reduced = transform.T @ mass @ transform if transform is not None else mass
    diagonal = np.asarray(reduced.diagonal()).ravel()
    massless = diagonal <= MASSLESS_FRACTION * max(float(np.max(np.abs(diagonal), initial=0.0)), 1e-300)
    pushing = [a for a in instruments.actuators if np.any(independent(a.dofs)[massless] != 0.0)]
    for sensor in accelerometers:
        read = np.flatnonzero((independent(sensor.dofs) != 0.0) & massless)
        if read.size and pushing:
            grids = sorted({g for g, _, _ in sensor.dofs})
            raise MaceError(
                f"{instruments.source}: sensor {sensor.name!r} (kind = \"acceleration\") reads grid "
                f"{', '.join(map(str, grids))} where a DOF carries no mass, and actuator {pushing[0].name!r} pushes a "
                "DOF without mass: that acceleration follows the force's second derivative, which no modal model "
                "holds; give the grid the accelerometer's own mass (a CONM2) or read the acceleration where there "
                "is mass")


def resolve_bar_gauges(instruments: Instruments, source: ModalSource) -> Instruments:
    """``instruments`` with every bar strain gauge's DOF weights computed from its bar, as the modal source gives
    them (:meth:`~mace_fmu.iomodel.source.ModalSource.bar_strain_weights`: a deck's bar, or a refusal)."""
    if not any(s.gauge is not None and not s.dofs for s in instruments.sensors):
        return instruments
    sensors = []
    for s in instruments.sensors:
        if s.gauge is not None and not s.dofs:
            try:
                dofs = source.bar_strain_weights(bar_id=s.gauge.bar, position=s.gauge.position,
                                                 fiber_y_m=s.gauge.fiber_y_m, fiber_z_m=s.gauge.fiber_z_m)
            except MaceError as exc:
                raise MaceError(f"{instruments.source} sensor {s.name}: {exc}") from None
            s = replace(s, dofs=dofs)
        sensors.append(s)
    return replace(instruments, sensors=tuple(sensors))


def _dofs(entry: Mapping[str, Any], where: str) -> tuple[Dof, ...]:
    """DOF list from ``dofs = [[grid, comp, w], ...]`` or ``wheels = [[wheel, base, w], ...]``."""
    if "dofs" in entry:
        rows = entry["dofs"]
        out = [(int(g), int(c), float(w)) for g, c, w in rows]
    elif "wheels" in entry:
        # A wheel is spun about its CD z axis (component 6) relative to its base.
        out = []
        for wheel, base, w in entry["wheels"]:
            out += [(int(wheel), 6, float(w)), (int(base), 6, -float(w))]
    else:
        raise MaceError(f"{where}: needs 'dofs' or 'wheels'")
    for g, c, _ in out:
        if not 1 <= c <= 6:
            raise MaceError(f"{where}: component {c} of grid {g} is not 1-6")
    return tuple(out)


#: open-loop damping ratio of every flexible mode when the structure file gives no [damping] table
DEFAULT_DAMPING = 0.01


def _sensor_unit(kind: str, dofs: tuple[Dof, ...]) -> str:
    """The unit a sensor reads when its structure file gives none: rad or m (per s for a rate sensor, per
    s^2 for an acceleration sensor), from its DOFs' components (a weighted sum of rotations reads radians)."""
    base = _dof_units(dofs, translation="m", rotation="rad")
    per = {"rate": "/s", "acceleration": "/s^2"}.get(kind, "")
    return f"{base}{per}" if base != "physical unit" else base


def _electronics(table: Mapping[str, Any], path: object) -> Electronics:
    """[electronics] of a structure file. The filter: ``filter_kind`` ("bessel", the default, or
    "butterworth"), ``filter_order``, ``filter_cutoff_hz`` and ``filter_equivalent_delay_s`` (the
    delay that stands in for the filter with ``bessel="delay"``; default: the filter's group delay
    at 0 Hz, sum of -Re(p) / |p|^2 over its poles). ``bessel_order``, ``bessel_cutoff_hz`` and
    ``bessel_equivalent_delay_s`` are the same keys for a Bessel filter (the older spelling)."""
    kind = str(table.get("filter_kind", "bessel"))
    if kind not in LOWPASS_KINDS:
        raise MaceError(f"{path}: [electronics] filter_kind must be one of {', '.join(LOWPASS_KINDS)}, got {kind!r}")
    order = int(table.get("filter_order", table.get("bessel_order", 0)))
    cutoff_hz = float(table.get("filter_cutoff_hz", table.get("bessel_cutoff_hz", 0.0)))
    delay = table.get("filter_equivalent_delay_s", table.get("bessel_equivalent_delay_s"))
    if delay is None and order > 0 and cutoff_hz > 0:
        a = lowpass_realization(kind, order, cutoff_hz)[0]
        poles = np.linalg.eigvals(a)
        delay = float(np.sum(-poles.real / np.abs(poles) ** 2))
    return Electronics(filter_kind=kind, filter_order=order, filter_cutoff_hz=cutoff_hz,
                       filter_equivalent_delay_s=float(delay or 0.0),
                       analog_sensors=tuple(table.get("analog_sensors", ())),
                       sensor_delays_s=dict(table.get("gyro_delays_s", {})),
                       actuator_delays_s=dict(table.get("actuator_delays_s", {})))


def _servos(table: Mapping[str, Any], path: str) -> Servos:
    """The [servos] table: shared gains, and per loop either the sensor's name (the shared gains) or a
    table ``{ sensor = "...", <gain key> = value, ... }`` whose gains are the loop's own."""
    loops: dict[str, dict[str, str]] = {}
    own: dict[str, dict[str, float]] = {}
    for kind, symbols in (("wheels", SPEED_LOOP_GAINS), ("gimbals", POSITION_LOOP_GAINS)):
        loops[kind] = {}
        for actuator, entry in dict(table.get(kind, {})).items():
            where = f"{path}: [servos] {kind}.{actuator}"
            if isinstance(entry, str):
                loops[kind][actuator] = entry
                continue
            if not isinstance(entry, Mapping) or not isinstance(entry.get("sensor"), str):
                raise MaceError(f"{where}: expected a sensor name or a table with 'sensor' and the loop's own gains")
            keys = {LOOP_GAIN_KEYS[s]: s for s in symbols}
            unknown = sorted(set(entry) - {"sensor", *keys})
            if unknown:
                raise MaceError(f"{where}: unknown key(s) {unknown}; a {kind[:-1]} loop takes 'sensor' and "
                                f"{', '.join(repr(k) for k in keys)}")
            loops[kind][actuator] = entry["sensor"]
            gains = {}
            for key, symbol in keys.items():
                if key in entry:
                    value = entry[key]
                    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                        raise MaceError(f"{where}: {key} must be a finite number, got {value!r}")
                    gains[symbol] = float(value)
            if gains:
                own[actuator] = gains
    return Servos(wheel_forward_gain=float(table.get("wheel_forward_gain", 0.0)),
                  wheel_backward_gain=float(table.get("wheel_backward_gain", 0.0)), wheels=loops["wheels"],
                  gimbal_angle_gain=float(table.get("gimbal_angle_gain", 0.0)),
                  gimbal_rate_gain=float(table.get("gimbal_rate_gain", 0.0)), gimbals=loops["gimbals"],
                  loop_gains=own)


def load_instruments(structure_file: StructureFile | str | Path | None = None) -> Instruments:
    """Instruments, electronics, servos and damping of a structure file (read once; see
    :class:`~mace_fmu.structure.file.StructureFile`), or of the file at a path; default: the bundled mace_em.toml.

    Parameters
    ----------
    structure_file : StructureFile or path, optional
        A structure file, read or to read (default: the bundled mace_em.toml).

    Returns
    -------
    Instruments
        Actuators and sensors (DOFs, gains, kinds), electronics, servos and modal damping.

    Raises
    ------
    MaceError
        A malformed structure file, naming the file, the line and the key.
    """
    if not isinstance(structure_file, StructureFile):
        structure_file = load_structure_file(structure_file if structure_file is not None else bundled_structure_path())
    path, data = structure_file.path, structure_file.tables
    try:
        actuators = tuple(_actuator(a, path) for a in data["actuators"])
        sensors = tuple(_sensor(s, path) for s in data["sensors"])
        # electronics, servos and damping are optional: a structure without them has no filters, no
        # delays, no local loops, and every mode DEFAULT_DAMPING (rigid-body and mechanism modes none)
        el, sv, dm = data.get("electronics", {}), data.get("servos", {}), data.get("damping", {})
        electronics = _electronics(el, path)
        servos = _servos(sv, path)
        damping = DampingTable(default=float(dm.get("default", DEFAULT_DAMPING)),
                               zero_frequency=float(dm.get("zero_frequency", 0.0)),
                               by_label=dict(dm.get("by_label", {})),
                               violin_families=tuple(ViolinFamily(order=int(f["order"]), cables=frozenset(f["cables"]),
                                                                  zeta=tuple(f["zeta"]))
                                                     for f in dm.get("violin_families", ())))
        if el.get("analog_sensors") and not (electronics.filter_order > 0 and electronics.filter_cutoff_hz > 0):
            raise MaceError(f"{path}: [electronics] analog_sensors need filter_order > 0 and filter_cutoff_hz > 0")
    except KeyError as exc:
        raise MaceError(f"{path}: missing table or key {exc}") from None
    inst = Instruments(actuators=actuators, sensors=sensors, electronics=electronics, servos=servos, damping=damping,
                       source=str(path))
    names = [a.name for a in actuators] + [s.name for s in sensors]
    # every name the electronics and the loops refer to must be an instrument of this file
    references = ([("[electronics] gyro_delays_s", name, inst.sensor) for name in electronics.sensor_delays_s]
                  + [("[electronics] actuator_delays_s", name, inst.actuator)
                     for name in electronics.actuator_delays_s])
    for kind, loops in (("wheels", servos.wheels), ("gimbals", servos.gimbals)):
        for actuator, sensor in loops.items():
            references += [(f"[servos] {kind}.{actuator}", actuator, inst.actuator),
                           (f"[servos] {kind}.{actuator}", sensor, inst.sensor)]
    for where, name, look_up in references:
        try:
            look_up(name)
        except MaceError as exc:
            raise MaceError(f"{path}: {where}: {exc}") from None
    if len(set(names)) != len(names):
        raise MaceError(f"{path}: actuator and sensor names must be unique")
    return inst
