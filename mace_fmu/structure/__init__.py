"""What a deck does not say about its structure (the structure file), and the 1-g (suspended) and
0-g (suspension removed) structures built from a deck and that file."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

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
