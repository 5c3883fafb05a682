"""Models updated from test data (thesis chapter 4), by use:

- :mod:`mace_fmu.updating.engine`: measured data, costs (modal, frequency response, time response),
  sensitivities, selection, the staged update, convergence tests, uncertainty and identifiability;
- :mod:`mace_fmu.updating.modal`: the modal-test route: modes identified from measured FRFs, paired by MAC,
  and the modal update of any deck's structure-file parameters (thesis 4.2);
- :mod:`mace_fmu.updating.mace`: the MACE update of thesis 4.5;
- :mod:`mace_fmu.updating.fmu`: the update of any FMU against measured data files, and test planning;
- :mod:`mace_fmu.updating.sample`: the two-mass sample problem of thesis 4.3;
- :mod:`mace_fmu.updating.files`: measured-data files (time histories, FRFs, channel maps).

The engine knows nothing of the others; the public names of all of them are here."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.updating.engine.convergence import ConvergenceReport, convergence_report
    from mace_fmu.updating.engine.inclusion import ModelFamily
    from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory, read_measured_modes
    from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateResult, UpdateSettings, update
    from mace_fmu.updating.engine.uncertainty import StageUncertainty, stage_uncertainty
    from mace_fmu.updating.fmu.planning import Candidate, TestDesign, plan_tests, read_test_plan
    from mace_fmu.updating.fmu.problem import FmuProblem, FmuUpdateRequest
    from mace_fmu.updating.fmu.update import fmu_parameters, update_fmu
    from mace_fmu.updating.mace.update import MaceUpdate, run_mace_update
    from mace_fmu.updating.modal.identify import Identification, identify_modes
    from mace_fmu.updating.modal.update import ModalUpdate, run_modal_update
    from mace_fmu.updating.sample.problem import run_sample_problem
    from mace_fmu.updating.sample.two_mass import TwoMassSystem

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "update": "engine.solve",
    "UpdateSettings": "engine.solve",
    "UpdateResult": "engine.solve",
    "Stage": "engine.solve",
    "Bounds": "engine.solve",
    "ModelFamily": "engine.inclusion",
    "update_fmu": "fmu.update",
    "fmu_parameters": "fmu.update",
    "FmuProblem": "fmu.problem",
    "FmuUpdateRequest": "fmu.problem",
    "run_mace_update": "mace.update",
    "MaceUpdate": "mace.update",
    "identify_modes": "modal.identify",
    "Identification": "modal.identify",
    "run_modal_update": "modal.update",
    "ModalUpdate": "modal.update",
    "run_sample_problem": "sample.problem",
    "convergence_report": "engine.convergence",
    "ConvergenceReport": "engine.convergence",
    "stage_uncertainty": "engine.uncertainty",
    "plan_tests": "fmu.planning",
    "read_test_plan": "fmu.planning",
    "TestDesign": "fmu.planning",
    "Candidate": "fmu.planning",
    "StageUncertainty": "engine.uncertainty",
    "read_measured_modes": "engine.measured",
    "TimeHistory": "engine.measured",
    "MeasuredFrf": "engine.measured",
    "TwoMassSystem": "sample.two_mass",
})
