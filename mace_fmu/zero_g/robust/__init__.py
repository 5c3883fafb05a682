"""Robustness of a compensator designed on the nominal 0-g model: closed around the 0-g FMU over its
declared parameter bounds (corners and a seeded Monte Carlo sample), on the Dask runner."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.zero_g.robust.box import ParameterBox, read_box
    from mace_fmu.zero_g.robust.design import RobustDesign, design_compensator
    from mace_fmu.zero_g.robust.loop import LoopSpec
    from mace_fmu.zero_g.robust.study import RobustStudy, robust_0g_study
    from mace_fmu.zero_g.robust.summary import format_summary
    from mace_fmu.zero_g.robust.sweep import SweepResult, robust_sweep

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "robust_0g_study": "study",
    "RobustStudy": "study",
    "robust_sweep": "sweep",
    "SweepResult": "sweep",
    "design_compensator": "design",
    "RobustDesign": "design",
    "LoopSpec": "loop",
    "read_box": "box",
    "ParameterBox": "box",
    "format_summary": "summary",
})
