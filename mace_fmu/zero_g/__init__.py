"""The 0-g prediction handed to control designers before flight data (thesis 5.3, Table 5.3): the
updated nominal 0-g model with frequency bounds, its tables, and the robustness of a compensator over
those bounds (:mod:`mace_fmu.zero_g.robust`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.zero_g.nominal import BoundRule, ZeroGPrediction, ZeroGRow, predict_zero_g
    from mace_fmu.zero_g.table import format_table, read_frequency_bounds, table_5_3, write_prediction

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "predict_zero_g": "nominal",
    "ZeroGPrediction": "nominal",
    "ZeroGRow": "nominal",
    "BoundRule": "nominal",
    "write_prediction": "table",
    "read_frequency_bounds": "table",
    "format_table": "table",
    "table_5_3": "table",
})
