"""What the stages share: atomic file writes, text files read with errors that name them, progress
reports, the Dask runner for many model runs, one BLAS thread for small matrices, numbers as text."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.util.atomic import write_text_atomic
    from mace_fmu.util.progress import ProgressCallback, Step
    from mace_fmu.util.runner import DaskRunner
    from mace_fmu.util.textfile import read_toml

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "DaskRunner": "runner",
    "ProgressCallback": "progress",
    "Step": "progress",
    "read_toml": "textfile",
    "write_text_atomic": "atomic",
})
