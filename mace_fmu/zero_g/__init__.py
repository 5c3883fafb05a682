"""The 0-g prediction handed to control designers before flight data (thesis 5.3, Table 5.3): the
updated nominal 0-g model with frequency bounds, its tables, and the robustness of a compensator over
those bounds (:mod:`mace_fmu.zero_g.robust`)."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

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
