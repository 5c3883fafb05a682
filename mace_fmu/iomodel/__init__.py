"""Input-output models: instruments, the modal plant, the volts-volts block diagram (servos, filters,
delays), its parameters, poles and frequency responses."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

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
    "ParametricSystem": "parametric",
    "frequency_response": "frf",
    "ClosedLoopPole": "poles",
    "closed_loop_poles": "poles",
    "bode_report": "bode",
})
