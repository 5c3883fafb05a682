"""What a deck does not say about its structure (the structure file), and the 1-g (suspended) and
0-g (suspension removed) structures built from a deck and that file."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.structure.build import Structure, apply_overrides, build_structure, remove_suspension
    from mace_fmu.structure.file import (STRUCTURE_FILE_TABLES, Configuration, StructureFile, StructureSpec,
                                         bundled_deck_path, bundled_structure_path, load_structure_file,
                                         structure_file_for)

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "StructureFile": "file",
    "StructureSpec": "file",
    "Configuration": "file",
    "STRUCTURE_FILE_TABLES": "file",
    "load_structure_file": "file",
    "structure_file_for": "file",
    "bundled_deck_path": "file",
    "bundled_structure_path": "file",
    "Structure": "build",
    "build_structure": "build",
    "apply_overrides": "build",
    "remove_suspension": "build",
})
