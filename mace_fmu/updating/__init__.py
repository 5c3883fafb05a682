"""Models updated from test data (thesis chapter 4): the engine (stages, bounds, convergence tests),
cost functions (modal, frequency response, time response), uncertainty and identifiability, the MACE
update, the two-mass sample problem, and the update of any FMU against measured data files."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.updating.convergence import ConvergenceReport, convergence_report
    from mace_fmu.updating.data import FrequencyResponseData, TimeHistory, read_measured_modes
    from mace_fmu.updating.fmu_problem import FmuProblem
    from mace_fmu.updating.fmu_update import fmu_parameters, update_fmu
    from mace_fmu.updating.inclusion import ModelFamily
    from mace_fmu.updating.mace_update import MaceUpdate, run_mace_update
    from mace_fmu.updating.planning import Candidate, TestDesign, plan_tests, read_test_plan
    from mace_fmu.updating.sample import run_sample_problem
    from mace_fmu.updating.solve import Bounds, Stage, UpdateResult, UpdateSettings, update
    from mace_fmu.updating.two_mass import TwoMassSystem
    from mace_fmu.updating.uncertainty import StageUncertainty, stage_uncertainty

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "update": "solve",
    "UpdateSettings": "solve",
    "UpdateResult": "solve",
    "Stage": "solve",
    "Bounds": "solve",
    "ModelFamily": "inclusion",
    "update_fmu": "fmu_update",
    "fmu_parameters": "fmu_update",
    "FmuProblem": "fmu_problem",
    "run_mace_update": "mace_update",
    "MaceUpdate": "mace_update",
    "run_sample_problem": "sample",
    "convergence_report": "convergence",
    "ConvergenceReport": "convergence",
    "stage_uncertainty": "uncertainty",
    "plan_tests": "planning",
    "read_test_plan": "planning",
    "TestDesign": "planning",
    "Candidate": "planning",
    "StageUncertainty": "uncertainty",
    "read_measured_modes": "data",
    "TimeHistory": "data",
    "FrequencyResponseData": "data",
    "TwoMassSystem": "two_mass",
})
