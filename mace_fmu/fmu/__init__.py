"""FMUs of the volts-volts models (native C runtime: FMI 2 CS and ME, FMI 3 CS; or pythonfmu), a
discrete controller as an FMU, checks of written FMUs, and FMU simulation."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.fmu.archive import check_fmu
    from mace_fmu.fmu.controller import DiscreteController, export_controller_fmu
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.fmu.naming import fmu_model_name
    from mace_fmu.fmu.parametric import ParametricModel, parametric_model
    from mace_fmu.fmu.simulate import FmuRun, simulate_input_response
    from mace_fmu.fmu.validation import validate_fmu

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "export_fmu": "export",
    "DiscreteController": "controller",
    "export_controller_fmu": "controller",
    "check_fmu": "archive",
    "simulate_input_response": "simulate",
    "FmuRun": "simulate",
    "fmu_model_name": "naming",
    "ParametricModel": "parametric",
    "parametric_model": "parametric",
    "validate_fmu": "validation",
})
