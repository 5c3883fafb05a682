"""FMUs of the volts-volts models (native C runtime: FMI 2 CS and ME, FMI 3 CS; or pythonfmu), a
discrete controller as an FMU, checks of written FMUs, and FMU simulation."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "export_fmu": "export",
    "export_pythonfmu": "export",
    "export_native_fmu": "mace_fmu.fmu.native.export",
    "DiscreteController": "controller",
    "export_controller_fmu": "controller",
    "check_fmu": "archive",
    "simulate_input_response": "simulate",
    "FmuRun": "simulate",
    "fmu_model_name": "naming",
})
