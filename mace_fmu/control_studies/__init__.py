"""Modelling for control (thesis Appendix A): how good must a model be for LQG design?

- ``lqg``: LQG design on a model and its closed-loop cost on another (the evaluation system);
- ``stiffness_sensitivity``: A.1, cost of designing on mismodelled stiffnesses (two-mass system);
- ``cantilever``: A.2's aluminium cantilever from the FE core (beam elements), as a modal model;
- ``reduced_order``: A.2, balanced reduction to 4 modes and its update under the closed-loop cost;
- ``figures``: the contour and transfer-function PNGs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.control_studies.cantilever import cantilever_model
    from mace_fmu.control_studies.lqg import LqgDesign, LqgWeights, design_lqg
    from mace_fmu.control_studies.reduced_order import reduced_order_study
    from mace_fmu.control_studies.stiffness_sensitivity import sensitivity_map

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "design_lqg": "lqg",
    "LqgWeights": "lqg",
    "LqgDesign": "lqg",
    "sensitivity_map": "stiffness_sensitivity",
    "cantilever_model": "cantilever",
    "reduced_order_study": "reduced_order",
})
