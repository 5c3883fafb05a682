"""The finite-element core: bars, beams, springs and masses assembled (sparse), constrained, preloaded
by gravity (linear or large displacement) and solved for labelled modes with mass properties."""

from __future__ import annotations

from mace_fmu.util.lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "compute_modes": "modes",
    "StructureModes": "modes",
    "MassProperties": "modes",
    "DEFAULT_MAX_HZ": "modes",
    "FEModel": "assembly",
    "assemble": "assembly",
    "Modes": "modal",
    "solve_modes": "modal",
    "ZERO_HZ": "mace_fmu.util.frequency",
    "Preload": "preload",
    "linear_preload": "preload",
    "large_displacement_preload": "preload",
    "label_modes": "labels",
    "DofMap": "dofs",
    "Constraints": "constraints",
    "build_constraints": "constraints",
    "mac_matrix": "pairing",
    "pair_by_mac": "pairing",
})
