"""The native FMUs: one C runtime for FMI 2 and FMI 3, its model descriptions, its resource file of
model arrays, and its compilation for Linux, Windows and macOS on x86-64 and ARM (zig)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.fmu.native.compile import compile_runtime
    from mace_fmu.fmu.native.model_description import FmuVariable, fmu_variables

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "compile_runtime": "compile",
    "fmu_variables": "model_description",
    "FmuVariable": "model_description",
})
