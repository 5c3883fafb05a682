"""Robustness of a compensator designed on the nominal 0-g model: closed around the 0-g FMU over its
declared parameter bounds (corners and a seeded Monte Carlo sample), on the Dask runner."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

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
