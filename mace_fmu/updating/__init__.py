"""Models updated from test data (thesis chapter 4): the engine (stages, bounds, convergence tests),
cost functions (modal, frequency response, time response), uncertainty and identifiability, the MACE
update, the two-mass sample problem, and the update of any FMU against measured data files."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

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
