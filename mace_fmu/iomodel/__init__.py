"""Input-output models: instruments, the modal plant, the volts-volts block diagram (servos, filters,
delays), its parameters, poles and frequency responses; their modal source is a deck's modes or NASTRAN's
(a structure file's ``[modes]`` table: :func:`modal_structure`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.iomodel.bode import bode_report
    from mace_fmu.iomodel.frf import frequency_response
    from mace_fmu.iomodel.instruments import Actuator, Instruments, Sensor, load_instruments
    from mace_fmu.iomodel.modal_ss import ModalPlant, modal_plant
    from mace_fmu.iomodel.modal_source import ModalStructure, modal_structure
    from mace_fmu.iomodel.model_options import ModelledElectronics, SignalSelection
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.poles import ClosedLoopPole, closed_loop_poles
    from mace_fmu.iomodel.volts import VoltsModel, apply_parameters, scale_frequencies, select_signals, volts_model

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "VoltsModel": "volts",
    "volts_model": "volts",
    "apply_parameters": "volts",
    "scale_frequencies": "volts",
    "select_signals": "volts",
    "ModelledElectronics": "model_options",
    "SignalSelection": "model_options",
    "Instruments": "instruments",
    "load_instruments": "instruments",
    "Actuator": "instruments",
    "Sensor": "instruments",
    "ModalPlant": "modal_ss",
    "modal_plant": "modal_ss",
    "ModalStructure": "modal_source",
    "modal_structure": "modal_source",
    "ParametricSystem": "parametric",
    "frequency_response": "frf",
    "ClosedLoopPole": "poles",
    "closed_loop_poles": "poles",
    "bode_report": "bode",
})
