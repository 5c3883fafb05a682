"""Updating any FMU against measured data: the FMU as the model inside a cost, the problem as a user
states it, the update, test planning and the known-truth test article. Its public names are also on
:mod:`mace_fmu.updating`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.updating.fmu.planning import Candidate, TestDesign, plan_tests, read_test_plan
    from mace_fmu.updating.fmu.problem import FmuProblem, FmuUpdateRequest
    from mace_fmu.updating.fmu.update import fmu_parameters, update_fmu

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "Candidate": "planning",
    "TestDesign": "planning",
    "plan_tests": "planning",
    "read_test_plan": "planning",
    "FmuProblem": "problem",
    "FmuUpdateRequest": "problem",
    "fmu_parameters": "update",
    "update_fmu": "update",
})
