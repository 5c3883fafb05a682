"""The updating engine (thesis 4.2): measured data, linear models as the costs read them, costs,
sensitivities, parameter selection, the staged least-squares update, convergence tests and uncertainty.

It knows nothing of MACE or of FMUs: the MACE update (:mod:`mace_fmu.updating.mace`), the FMU update
(:mod:`mace_fmu.updating.fmu`) and the sample problem (:mod:`mace_fmu.updating.sample`) build on it.
Its public names are also on :mod:`mace_fmu.updating`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.updating.engine.convergence import ConvergenceReport, convergence_report
    from mace_fmu.updating.engine.inclusion import ModelFamily
    from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory, read_measured_modes
    from mace_fmu.updating.engine.models import PoleModel, SimulatedModel
    from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateResult, UpdateSettings, update
    from mace_fmu.updating.engine.uncertainty import StageUncertainty, stage_uncertainty

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "ConvergenceReport": "convergence",
    "convergence_report": "convergence",
    "ModelFamily": "inclusion",
    "MeasuredFrf": "measured",
    "TimeHistory": "measured",
    "read_measured_modes": "measured",
    "SimulatedModel": "models",
    "PoleModel": "models",
    "Bounds": "solve",
    "Stage": "solve",
    "UpdateResult": "solve",
    "UpdateSettings": "solve",
    "update": "solve",
    "StageUncertainty": "uncertainty",
    "stage_uncertainty": "uncertainty",
})
