"""What both FMU kinds (pythonfmu and native) say about a model: units, summary, default experiment."""

from __future__ import annotations

from pathlib import Path

from mace_fmu.iomodel.motion import motion_unit, parse_motion_output
from mace_fmu.iomodel.volts import VoltsModel
from mace_fmu.parameters.kinds import is_frequency_output, kind_of_fmu_name, unit_of

DEFAULT_EXPERIMENT = {"startTime": "0.0", "stopTime": "10.0", "stepSize": "0.002"}


def variable_unit(name: str, causality: str) -> str | None:
    """Unit of an FMU variable: V for inputs and outputs, m/rad for motion outputs, SI for parameters."""
    motion = parse_motion_output(name)
    if motion is not None:
        return motion_unit(motion[1])
    if causality in ("input", "output"):
        return "V"
    kind = kind_of_fmu_name(name)
    if kind is not None:
        return unit_of(kind, name)
    return "Hz" if is_frequency_output(name) else None


def model_summary(model: VoltsModel) -> str:
    """One-line description of a volts-volts model for an FMU's model description."""
    structure, sys_ = model.structure_modes.structure, model.system
    kind = structure.configuration
    # "MACE <kind>" names the bundled structure only (hosts and `view response` read it); another deck is
    # named by its file
    from mace_fmu.structure.file import is_bundled_deck

    who = "MACE" if is_bundled_deck(structure.deck) else Path(structure.deck.path).stem
    built = f"; parameter set {model.parameters.describe()}" if model.parameters is not None else ""
    return f"{who} {kind} volts-volts model: {sys_.nstates} states; {model.electronics.describe()}{built}"
