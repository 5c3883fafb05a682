"""What the stages share: atomic file writes, text files read with errors that name them, progress
reports, the Dask runner for many model runs, one BLAS thread for small matrices, numbers as text."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "DaskRunner": "runner",
    "ProgressCallback": "progress",
    "Step": "progress",
    "read_toml": "textfile",
    "write_text_atomic": "atomic",
})
