"""Volts-volts input-output models of the 1-g and 0-g structures, assembled from modelica_like blocks.

Block diagram (thesis 3.4-3.7, Appendix C abcdmace/gimcon3):

    commands -> actuator delays (Table 4.5) -> [wheel speed loops | gimbal servos] -> actuator
    gains [N m/V] -> structure (modal, eq. 3.6) -> sensor gains [V/unit] -> Bessel filters on
    the analog channels -> extra gyro delays (Table 4.6) -> outputs [V]

Wheel speed loops (eq. 3.18): torque command = K_f (u - K_b tach). Gimbal servos (eq. 3.19-3.20):
v = K_a (r - theta) - K_r dtheta/dt on the encoder angle and rate in degrees, so a gimbal input
is a commanded relative angle (1 V = 1 deg) and the computational delay sits inside the loop.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import Sequence, TypeVar

import control as ct
import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.damping import modal_damping
from mace_fmu.iomodel.frf import frequency_response
from mace_fmu.iomodel.instruments import (SPEED_LOOP_GAINS, Instruments, check_accelerometers_have_mass,
                                          load_instruments, resolve_bar_gauges)
from mace_fmu.iomodel.modal_ss import ModalPlant, modal_plant
from mace_fmu.iomodel.model_options import ModelledElectronics, SignalSelection
from mace_fmu.iomodel.motion import motion_unit, parse_motion_output
from mace_fmu.iomodel.source import ModalSource
from mace_fmu.parameters.kinds import (DAMPING, DELAY, FREQUENCY_SCALE, SERVO_GAINS, ParameterKind, mode_number,
                                       split_loop_name)
from mace_fmu.parameters.per_mode import resolve_mode_names
from mace_fmu.parameters.sets import ParameterSet, naming_the_file
from mace_fmu.structure.file import SourceConfiguration
from mace_fmu.util.frequency import ZERO_HZ
from mace_fmu.util.threads import single_blas_thread
from modelica_like import PD, Gain, LowPassFilter, PadeDelay, StateSpace, Sum, System

DEG_PER_RAD = 180.0 / np.pi
_Source = TypeVar("_Source", bound=ModalSource)  #: a modal source (each is a frozen dataclass)


@dataclass(frozen=True)
class VoltsModel:
    """A volts-volts model and what it was built from."""

    system: ct.StateSpace  #: named inputs [V] and outputs [V]; states "block.state"
    diagram: System  #: the modelica_like block diagram (to_modelica() writes it as Modelica)
    plant: ModalPlant  #: the physical modal model inside
    #: the modes the model was built from: the deck route's, or NASTRAN's (a ModalStructure, no FE)
    structure_modes: ModalSource
    instruments: Instruments  #: actuators, sensors, electronics, loops and damping it was built with
    electronics: ModelledElectronics  #: which electronics the model contains, and how
    parameters: ParameterSet | None = None  #: the parameter set it was built with (None: the deck's and file's)

    @property
    def configuration(self) -> SourceConfiguration:
        """"1g" or "0g": the deck's structure the model is of ("modes": NASTRAN's modes)."""
        return self.structure_modes.configuration

    @property
    def signal_units(self) -> dict[str, str]:
        """Every input's and output's unit at the model boundary: "V", or a force input's "N" / "N m" and a
        physical output's unit ("m/s^2", "m", "rad", ...) where the structure file gives no gain; grid motion
        outputs in m or rad."""
        units = {a.name: a.input_unit for a in self.instruments.actuators}
        units |= {x.name: x.output_unit for x in self.instruments.sensors}
        for name in self.system.output_labels:
            motion = parse_motion_output(name)
            if motion is not None:
                units[name] = motion_unit(motion[1])
        return {name: units[name] for name in (*self.system.input_labels, *self.system.output_labels)}

    @property
    def grid_ids(self) -> tuple[int, ...]:
        """Every grid of the model's structure (the ones whose motion can be an output)."""
        return self.structure_modes.grid_ids

    def frequency_response(self, frequencies_hz: np.ndarray) -> np.ndarray:
        """H[k, output, input] [V/V] at ``frequencies_hz`` [Hz], all channels at once.

        The Bessel filters and the gyro delays sit in series on the outputs, outside every
        loop: the core (structure, servos, actuator delays; distinct eigenvalues) goes through
        one eigen-decomposition, and each output's filters are evaluated as scalar transfer
        functions and multiplied in. The full model's 13 identical Bessel filters would make
        its eigenvectors ill-conditioned.
        """
        core = self._core
        h = frequency_response(core, frequencies_hz)
        analog = set(self.instruments.analog_sensor_names)
        for o, name in enumerate(core.output_labels):
            if name in analog:
                h[:, o, :] *= self._output_filter(name, frequencies_hz)[:, None]
        ins, outs = list(core.input_labels), list(core.output_labels)
        i = [ins.index(n) for n in self.system.input_labels]
        o = [outs.index(n) for n in self.system.output_labels]
        return h[:, o][:, :, i]

    @cached_property
    def _core(self) -> ct.StateSpace:
        """The model without its output filters (built once per model)."""
        el = self.instruments.electronics
        quiet = replace(self.instruments, electronics=replace(el, sensor_delays_s={k: 0.0 for k in el.sensor_delays_s}))
        return build_diagram(self.plant, quiet, electronics=replace(self.electronics, bessel="none")).compile()

    def _output_filter(self, sensor: str, frequencies_hz: np.ndarray) -> np.ndarray:
        """Anti-aliasing filter and delay of one analog output channel, evaluated exactly."""
        el = self.instruments.electronics
        extra = el.sensor_delays_s.get(sensor, 0.0) if self.electronics.delays else 0.0
        response = np.ones(len(frequencies_hz), dtype=complex)
        if self.electronics.bessel == "full":
            response *= frequency_response(LowPassFilter("f", el.filter_order, el.filter_cutoff_hz,
                                                         family=el.filter_kind).lti(), frequencies_hz)[:, 0, 0]
        delay = extra + (el.filter_equivalent_delay_s if self.electronics.bessel == "delay" else 0.0)
        if delay > 0.0:
            pade = PadeDelay("d", delay, self.electronics.pade_order).lti()
            response *= frequency_response(pade, frequencies_hz)[:, 0, 0]
        return response


def _check(condition: bool, message: str) -> None:
    """A bad request is a MaceError (a ValueError too), with the message the CLI prints as is."""
    if not condition:
        raise MaceError(message)


def build_diagram(plant: ModalPlant, instruments: Instruments, *,
                  electronics: ModelledElectronics = ModelledElectronics()) -> System:
    """The modelica_like System of one volts-volts model (see the module docstring).

    Parameters
    ----------
    plant : ModalPlant
        The structure's modal state space (generalised forces in, sensor units out).
    instruments : Instruments
        Gains, filters, delays and servo constants of the structure file.
    electronics : ModelledElectronics
        Which of the electronics the diagram contains.

    Returns
    -------
    System
        The block diagram; ``compile()`` gives its ``control.StateSpace``.
    """
    el, sv = instruments.electronics, instruments.servos
    act_names = [a.name for a in instruments.actuators]
    sen_names = [x.name for x in instruments.sensors]
    for name, value in list(el.actuator_delays_s.items()) + list(el.sensor_delays_s.items()):
        _check(value >= 0.0, f"delay of {name} must be >= 0 s, got {value}")

    s = System("mace_volts")
    ss = plant.system
    s.add(StateSpace("structure", ss.A, ss.B, ss.C, ss.D, inputs=list(ss.input_labels), outputs=list(ss.output_labels),
                     states=list(ss.state_labels)))
    s.add(Gain("actuator_gain", np.diag([a.gain for a in instruments.actuators]), inputs=act_names, outputs=act_names))
    s.connect("actuator_gain.y", "structure.u")
    s.add(Gain("sensor_gain", np.diag([x.gain for x in instruments.sensors]), inputs=sen_names, outputs=sen_names))
    if plant.static_correction is None:
        for name in sen_names:
            s.connect(f"structure.y[{name}]", f"sensor_gain.u[{name}]")
    else:  # the residual flexibility beside the modes: a constant block the FMUs carry as they are
        s.add(Gain("residual_flexibility", plant.static_correction, inputs=act_names, outputs=sen_names))
        s.add(Sum("static_correction", signs=(1, 1), size=len(sen_names), signals=sen_names))
        s.connect("actuator_gain.y", "residual_flexibility.u")
        for name in sen_names:
            s.connect(f"structure.y[{name}]", f"static_correction.u1[{name}]")
            s.connect(f"residual_flexibility.y[{name}]", f"static_correction.u2[{name}]")
            s.connect(f"static_correction.y[{name}]", f"sensor_gain.u[{name}]")
    _sensor_channels(s, instruments, electronics=electronics)
    for n in plant.motion_outputs:  # grid motion for animation [m, rad]: straight from the structure
        s.expose_output(n, f"structure.y[{n}]")

    drives = _actuator_delays(s, instruments, electronics=electronics)
    for n in act_names:  # in actuator order, which is the order of the model's inputs
        if electronics.servos and n in sv.wheels:
            _wheel_loop(s, drives, instruments, wheel=n, tach=sv.wheels[n])
        elif electronics.servos and n in sv.gimbals:
            _gimbal_servo(s, drives, instruments, gimbal=n, encoder=sv.gimbals[n])
        else:
            _feed(s, drives, name=n, signal_in=None)
    return s


def _sensor_channels(s: System, instruments: Instruments, *, electronics: ModelledElectronics) -> None:
    """The sensor outputs [V]: the analog channels through the Bessel filter (or its equivalent delay) and the
    extra gyro delays, the digital ones straight from their gains."""
    el = instruments.electronics
    analog = list(instruments.analog_sensor_names)
    extra = {n: (el.sensor_delays_s.get(n, 0.0) if electronics.delays else 0.0) for n in analog}
    source = {x.name: f"sensor_gain.y[{x.name}]" for x in instruments.sensors}
    if electronics.bessel == "full" and analog:  # a structure whose file names no analog sensors has no filter
        block = el.filter_kind  # "bessel" (MACE's) or "butterworth"
        s.add(LowPassFilter(block, el.filter_order, el.filter_cutoff_hz, size=len(analog), signals=analog,
                            family=el.filter_kind))
        for n in analog:
            s.connect(source[n], f"{block}.u[{n}]")
            source[n] = f"{block}.y[{n}]"
    net = {n: extra[n] + (el.filter_equivalent_delay_s if electronics.bessel == "delay" else 0.0) for n in analog}
    for n in analog:
        if net[n] > 0.0:
            s.add(PadeDelay(f"delay_{n}", net[n], electronics.pade_order))
            s.connect(source[n], f"delay_{n}.u")
            source[n] = f"delay_{n}.y"
    for n, signal in source.items():
        s.expose_output(n, signal)


#: an actuator's computational delay block as (its input, its output), (None, None) without one
_Drive = tuple[str | None, str | None]


def _actuator_delays(s: System, instruments: Instruments, *, electronics: ModelledElectronics) -> dict[str, _Drive]:
    """Each actuator's computational delay block (Table 4.5), added to ``s``."""
    drives = {}
    for a in instruments.actuators:
        d = instruments.electronics.actuator_delays_s.get(a.name, 0.0) if electronics.delays else 0.0
        if d > 0.0:
            s.add(PadeDelay(f"delay_{a.name}", d, electronics.pade_order))
            drives[a.name] = (f"delay_{a.name}.u", f"delay_{a.name}.y")
        else:
            drives[a.name] = (None, None)
    return drives


def _feed(s: System, drives: dict[str, _Drive], *, name: str, signal_in: str | None) -> None:
    """Route ``signal_in`` (None: the system input ``name``) through the delay to the actuator gain."""
    delay_in, delay_out = drives[name]
    target = f"actuator_gain.u[{name}]" if delay_in is None else delay_in
    if signal_in is None:
        s.expose_input(name, target)
    else:
        s.connect(signal_in, target)
    if delay_in is not None:
        s.connect(delay_out, f"actuator_gain.u[{name}]")


def _wheel_loop(s: System, drives: dict[str, _Drive], instruments: Instruments, *, wheel: str, tach: str) -> None:
    """eq. 3.18: v = K_f (u - K_b tach); the command delay is outside the analog loop."""
    sv = instruments.servos
    s.add(Sum(f"speed_{wheel}", signs=(1, -1)))
    s.add(Gain(f"kb_{wheel}", sv.gain(wheel, "K_b")))
    s.add(Gain(f"kf_{wheel}", sv.gain(wheel, "K_f")))
    s.connect(f"sensor_gain.y[{tach}]", f"kb_{wheel}.u")
    s.connect(f"kb_{wheel}.y", f"speed_{wheel}.u2")
    s.connect(f"speed_{wheel}.y", f"kf_{wheel}.u")
    delay_in, delay_out = drives[wheel]
    if delay_in is None:
        s.expose_input(wheel, f"speed_{wheel}.u1")
    else:
        s.expose_input(wheel, delay_in)
        s.connect(delay_out, f"speed_{wheel}.u1")
    s.connect(f"kf_{wheel}.y", f"actuator_gain.u[{wheel}]")


def _gimbal_servo(s: System, drives: dict[str, _Drive], instruments: Instruments, *, gimbal: str,
                  encoder: str) -> None:
    """eq. 3.20 with encoder angle and rate in degrees: v = K_a (r - theta) + K_r (-dtheta); the computational
    delay sits inside the loop."""
    sv = instruments.servos
    s.add(Gain(f"angle_deg_{gimbal}", DEG_PER_RAD))
    s.add(Gain(f"rate_deg_{gimbal}", -DEG_PER_RAD))
    s.add(Sum(f"error_{gimbal}", signs=(1, -1)))
    s.add(PD(f"servo_{gimbal}", kp=sv.gain(gimbal, "K_a"), kd=sv.gain(gimbal, "K_r")))
    s.connect(f"structure.y[{encoder}_angle]", f"angle_deg_{gimbal}.u")
    s.connect(f"structure.y[{encoder}]", f"rate_deg_{gimbal}.u")
    s.connect(f"angle_deg_{gimbal}.y", f"error_{gimbal}.u2")
    s.connect(f"error_{gimbal}.y", f"servo_{gimbal}.x")
    s.connect(f"rate_deg_{gimbal}.y", f"servo_{gimbal}.dx")
    s.expose_input(gimbal, f"error_{gimbal}.u1")
    _feed(s, drives, name=gimbal, signal_in=f"servo_{gimbal}.y")


@single_blas_thread
def volts_model(modes: ModalSource, *, parameters: ParameterSet | None = None,
                instruments: Instruments | None = None, electronics: ModelledElectronics = ModelledElectronics(),
                signals: SignalSelection = SignalSelection(), max_hz: float | None = None) -> VoltsModel:
    """Volts-volts model of the structure whose modes are given: actuator volts in, sensor volts out.

    Inputs: gimbal commands (relative angle, 1 V = 1 deg, with servos; motor volts without), wheel speed
    commands and active strut volts. Outputs: the sensors in volts (MACE: 20), then any grid motion.
    The modes fix the structure (deck, structure file, 1-g or 0-g, preload, moduli); the records say
    which electronics are modelled and which signals are kept.

    Parameters
    ----------
    modes : ModalSource
        The modes of the 1-g or 0-g structure (:func:`~mace_fmu.fe.modes.compute_modes`), or NASTRAN's modes
        (:func:`~mace_fmu.iomodel.modal_source.modal_structure`: modal parameters only, no moduli).
    parameters : ParameterSet, optional
        Delays [s] (defaults: Tables 4.5 and 4.6 from the structure file), servo gains, and open-loop
        damping ratios and frequency scales by mode label (as in ``modes.labels``, e.g. "1st Z bending").
        By default the set the modes were computed with; a set given here replaces it, and its moduli
        [Pa] and spring stiffnesses [N/m], if any, must be those the modes were computed with.
    instruments : Instruments, optional
        Replaces the structure file's actuators, sensors, electronics, servos and damping.
    electronics : ModelledElectronics
        Servo loops closed or open, the Bessel filters as filters, as a delay or left out, the time
        delays on or off and their Pade order (default: all of it, order 3).
    signals : SignalSelection
        The inputs and outputs kept (default: all) and the grids whose motion [m, rad] is added as
        outputs (default: none).
    max_hz : float, optional
        Highest retained mode [Hz] (default: every mode given).

    Returns
    -------
    VoltsModel
        ``system`` (a ``control.StateSpace`` with named signals and states), the block diagram, the
        modal plant, the modes and the instruments it was built from.

    Raises
    ------
    MaceError
        For a request that contradicts itself or names what the model lacks, saying what is allowed.

    Examples
    --------
    >>> from mace_fmu import SignalSelection, compute_modes, volts_model
    >>> modes = compute_modes(configuration="0g", max_hz=5.0)
    >>> model = volts_model(modes, signals=SignalSelection(inputs=["gimbal_secondary_z"], outputs=["gyro_payload_z"]))
    >>> model.system.ninputs, model.system.noutputs
    (1, 1)
    """
    _check(callable(getattr(modes, "instrument_file", None)),  # a ModalSource (the protocol's members are not run)
           f"modes must be the StructureModes of compute_modes(...), got {type(modes).__name__} (or NASTRAN's modes: "
           "the ModalStructure of modal_structure(...))")
    _check(isinstance(electronics, ModelledElectronics),
           f"electronics must be a ModelledElectronics record, got {type(electronics).__name__}")
    _check(isinstance(signals, SignalSelection),
           f"signals must be a SignalSelection record, got {type(signals).__name__}")
    if parameters is None:
        parameters = modes.parameters
    else:
        modes.check_computed_with(parameters)
    configuration = modes.configuration
    instruments = _source_instruments(modes, instruments, parameters)
    with naming_the_file(parameters):
        instruments = apply_parameters(instruments, parameters, modes.labels, configuration=configuration)
        modes = scale_frequencies(modes, parameters, configuration=configuration)
    flexible = modes.frequencies_hz[np.abs(modes.frequencies_hz) >= ZERO_HZ]
    _check(len(flexible) > 0, f"the {configuration} modes have no flexible mode (the highest is at "
                              f"{np.max(modes.frequencies_hz):.3g} Hz); compute more: compute_modes(..., max_hz=...)")
    if max_hz is None:
        max_hz = float(np.max(modes.frequencies_hz))
    _check(max_hz >= flexible.min(),
           f"max_hz = {max_hz} Hz is below the first flexible mode ({flexible.min():.3f} Hz); allowed: >= that")
    zeta = modal_damping(modes.labels, modes.rank_frequencies_hz, instruments.damping)
    grids = modes.modes.dofs.grid_ids
    inputs, outputs = signals.inputs, signals.outputs
    motion_grids = grids if signals.motion_grids == "all" else signals.motion_grids
    if outputs is not None:  # only grids whose motion is asked for: the others' states would go unread
        named = {parse_motion_output(n)[0] for n in outputs if parse_motion_output(n) is not None}
        motion_grids = [g for g in motion_grids if g in named]
    unknown = sorted(set(motion_grids) - set(grids))
    _check(not unknown, f"motion_grids: grid(s) {unknown} are not in the {configuration} model; it has grids "
                        f"{grids[0]}..{grids[-1]} ({len(grids)} in all)")
    plant = modal_plant(modes.modes, instruments, zeta, max_hz=max_hz, motion_grids=list(motion_grids),
                        static_correction=modes.static_correction(instruments))
    diagram = build_diagram(plant, instruments, electronics=electronics)
    system = diagram.compile()
    return VoltsModel(system=select_signals(system, inputs=inputs, outputs=outputs), diagram=diagram, plant=plant,
                      structure_modes=modes, instruments=instruments, electronics=electronics,
                      parameters=parameters if parameters is not None and len(parameters) else None)


def _source_instruments(modes: ModalSource, instruments: Instruments | None,
                        parameters: ParameterSet | None) -> Instruments:
    """The instruments of the modes' structure (its structure file's unless given), bar gauges resolved as the source
    gives them and accelerometers checked against its mass, after checking that the set's physical parameters are
    ones the source can have."""
    if instruments is None:
        instruments = load_instruments(modes.instrument_file())
    instruments = resolve_bar_gauges(instruments, modes)
    check_accelerometers_have_mass(instruments, mass=modes.mass, dof_map=modes.modes.dofs,
                                   cd_frames=modes.modes.cd_frames, transform=modes.constraint_transform)
    with naming_the_file(parameters):  # the moduli and springs must name cards
        modes.check_parameters(parameters)
    return instruments


def apply_parameters(instruments: Instruments, parameters: ParameterSet | None, mode_labels: Sequence[str], *,
                     configuration: str = "") -> Instruments:
    """Instruments with the set's delays [s], servo gains and damping ratios replaced.

    Names are checked against the instrument file and ``mode_labels``; a MaceError names the
    entry and what is allowed. A damping ratio is named by mode label (``damping:<label>``: every mode
    with the label) or by mode number (``damping_mode_<k>``, 1-based in ``mode_labels``' order, as the
    FMU names it); both resolve to the modes (:func:`~mace_fmu.parameters.per_mode.resolve_mode_names`).
    A damping ratio whose mode label the structure lacks is skipped only when the set was made for the
    other structure (its provenance says so): a 1-g set carries the damping of suspension and violin
    modes, which the 0-g structure does not have; a mode number of such a set is refused.

    Parameters
    ----------
    instruments : Instruments
        The structure's instruments and electronics.
    parameters : ParameterSet or None
        The set whose delays [s], servo gains and damping ratios apply (None: no change).
    mode_labels : sequence of str
        The structure's mode labels in mode order, which damping names refer to.
    configuration : str
        "1g" or "0g": the structure the instruments are for.

    Returns
    -------
    Instruments
        A copy with the set's values.

    Raises
    ------
    MaceError
        A name the instruments or the modes do not have.
    """
    if parameters is None:
        return instruments
    el, sv = instruments.electronics, instruments.servos
    actuators, sensors = dict(el.actuator_delays_s), dict(el.sensor_delays_s)
    for name, value in parameters.of_kind("delay").items():
        channel = name.removeprefix(DELAY.set_prefix)
        table = actuators if channel in actuators else sensors if channel in sensors else None
        if table is None:
            raise MaceError(f"parameter {name!r}: no delayed channel {channel!r}; known: "
                            f"{', '.join(DELAY.set_prefix + c for c in [*actuators, *sensors])}")
        _check_range(name, value, DELAY)
        table[channel] = value
    gains, loop_gains = {}, {actuator: dict(own) for actuator, own in sv.loop_gains.items()}
    for name, value in parameters.of_kind("gain").items():
        symbol, actuator = split_loop_name(name)
        if not actuator:
            gains[SERVO_GAINS[symbol]] = value
            continue
        loops = sv.wheels if symbol in SPEED_LOOP_GAINS else sv.gimbals
        if actuator not in loops:
            raise MaceError(f"parameter {name!r}: no {'speed' if loops is sv.wheels else 'position'} loop on an "
                            f"actuator {actuator!r}; loops: {', '.join(loops) or 'none'}")
        loop_gains.setdefault(actuator, {})[symbol] = value
    given = parameters.of_kind("damping")
    for name, value in given.items():
        _check_range(name, value, DAMPING)
    damping = {mode_number(name): value for name, value in resolve_mode_names(
        given, mode_labels=mode_labels, model=f"{configuration} structure", source=parameters.source,
        other_structure=_other_structure(parameters, configuration)).items()}
    return replace(instruments, electronics=replace(el, actuator_delays_s=actuators, sensor_delays_s=sensors),
                   servos=replace(sv, **gains, loop_gains=loop_gains),
                   damping=replace(instruments.damping, by_mode={**instruments.damping.by_mode, **damping}))


def _other_structure(parameters: ParameterSet, configuration: str) -> str:
    """The structure ``parameters`` were made for when it is not ``configuration`` (their provenance), else ""."""
    prov = parameters.provenance
    return prov.configuration if prov is not None and prov.configuration not in ("", configuration) else ""


def _check_range(name: str, value: float, kind: ParameterKind) -> None:
    """A MaceError unless ``value`` lies in the range every parameter of ``kind`` has (the FMUs' own; for the
    kinds whose range does not depend on a nominal value: delays, damping ratios, frequency scales)."""
    low, high = kind.minimum, kind.maximum
    if not low <= value <= high:
        unit = "" if kind.unit == "1" else f" {kind.unit}"
        raise MaceError(f"parameter {name!r} = {value:g} is outside [{low:g}, {high:g}]{unit}, the range of every "
                        f"{kind.name.replace('_', ' ')} parameter")


def scale_frequencies(modes: _Source, parameters: ParameterSet | None, *, configuration: str = "") -> _Source:
    """``modes`` with each frequency scale of the set multiplying its modes' frequencies [Hz]: ``frequency_scale:<label>``
    every mode with the label, ``frequency_scale_mode_<k>`` mode k (1-based, as the FMU names it).

    Shapes are kept: the scale is a modal adjustment of the open-loop model (thesis 5.3), not an FE
    change. A set made for the other structure (its provenance says so) scales nothing: an updated
    nominal 0-g set leaves the 1-g model's frequencies alone, as the thesis never changes them.
    Labels are checked as for damping ratios (:func:`apply_parameters`); a scale must be > 0.

    Parameters
    ----------
    modes : ModalSource
        The structure's modes (a dataclass: a deck's or NASTRAN's).
    parameters : ParameterSet or None
        The set whose ``frequency_scale:<label>`` entries apply (None: no change).
    configuration : str
        "1g" or "0g": the structure the modes are of.

    Returns
    -------
    ModalSource
        A copy with the scaled frequencies [Hz].

    Raises
    ------
    MaceError
        A label the modes do not have, or a scale that is not > 0.
    """
    scales = parameters.of_kind("frequency_scale") if parameters is not None else {}
    if not scales or _other_structure(parameters, configuration):
        return modes
    for name, value in scales.items():
        _check_range(name, value, FREQUENCY_SCALE)
    frequencies = np.array(modes.frequencies_hz, dtype=float)
    for name, value in resolve_mode_names(scales, mode_labels=modes.labels, model=f"{configuration} structure",
                                          source=parameters.source).items():
        frequencies[mode_number(name) - 1] *= value
    scaled = replace(modes.modes, frequencies_hz=frequencies)
    return replace(modes, modes=scaled)  # type: ignore[type-var]  # every modal source is a dataclass


def select_signals(system: ct.StateSpace, *, inputs: Sequence[str] | None = None,
                   outputs: Sequence[str] | None = None) -> ct.StateSpace:
    """The channels ``inputs`` -> ``outputs`` (by name) of a model; None keeps them all.

    Parameters
    ----------
    system : control.StateSpace
        A model with named signals.
    inputs, outputs : sequence of str, optional
        The channels to keep, by name (None: all).

    Returns
    -------
    control.StateSpace
        The sub-model, signals named as before.

    Raises
    ------
    MaceError
        A name the model does not have.
    """
    ins, outs = list(system.input_labels), list(system.output_labels)
    for name in inputs or ():
        _check(name in ins, f"unknown input signal {name!r}; allowed: {', '.join(ins)}")
    for name in outputs or ():
        _check(name in outs, f"unknown output signal {name!r}; allowed: {', '.join(outs)}")
    if inputs is None and outputs is None:
        return system
    i = [ins.index(n) for n in (inputs or ins)]
    o = [outs.index(n) for n in (outputs or outs)]
    return ct.ss(system.A, system.B[:, i], system.C[o], system.D[np.ix_(o, i)], inputs=[ins[k] for k in i],
                 outputs=[outs[k] for k in o], states=list(system.state_labels), name=system.name)
