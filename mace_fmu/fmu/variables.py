"""What both FMU kinds (pythonfmu and native) say about a model: units, summary, default experiment."""

from __future__ import annotations

from collections.abc import Mapping

from mace_fmu.iomodel.motion import motion_unit, parse_motion_output
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.parameters.kinds import is_frequency_output, kind_of_fmu_name, unit_of

DEFAULT_EXPERIMENT = {"startTime": "0.0", "stopTime": "10.0", "stepSize": "0.002"}


def variable_unit(name: str, causality: str, *, signal_units: Mapping[str, str] | None = None) -> str | None:
    """Unit of an FMU variable: an input's or output's from ``signal_units`` (the model's
    :attr:`~mace_fmu.iomodel.volts.VoltsModel.signal_units`; V where it does not say), m/rad for motion
    outputs, SI for parameters."""
    motion = parse_motion_output(name)
    if motion is not None:
        return motion_unit(motion[1])
    if causality in ("input", "output"):
        return (signal_units or {}).get(name, "V")
    kind = kind_of_fmu_name(name)
    if kind is not None:
        return unit_of(kind, name)
    return "Hz" if is_frequency_output(name) else None


def model_summary(model: VoltsModel) -> str:
    """One-line description of a volts-volts model for an FMU's model description."""
    built = f"; parameter set {model.parameters.describe()}" if model.parameters is not None else ""
    electronics = model.electronics.describe(instruments=model.instruments)
    # "<label> <kind>": hosts and `view response --fmu` read which structure and configuration it is
    title = model.structure_modes.title("volts-volts model")
    return f"{title}: {model.system.nstates} states; {electronics}{built}"
