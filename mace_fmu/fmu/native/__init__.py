"""The native FMUs: one C runtime for FMI 2 and FMI 3, its model descriptions, its resource file of
model arrays, and its compilation (gcc; mingw-w64 for Windows where installed)."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "export_native_fmu": "export",
    "write_native_fmu": "export",
    "compile_runtime": "compile",
    "fmu_variables": "model_description",
    "FmuVariable": "model_description",
})
