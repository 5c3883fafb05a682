"""The finite-element core: bars, beams, springs and masses assembled (sparse), constrained, preloaded
by gravity (linear or large displacement) and solved for labelled modes with mass properties."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.fe.assembly import FEModel, assemble
    from mace_fmu.fe.constraints import Constraints, build_constraints
    from mace_fmu.fe.dofs import DofMap
    from mace_fmu.fe.labels import label_modes
    from mace_fmu.fe.modal import Modes, solve_modes
    from mace_fmu.fe.modes import DEFAULT_MAX_HZ, MassProperties, StructureModes, compute_modes
    from mace_fmu.fe.pairing import mac_matrix, pair_by_mac
    from mace_fmu.fe.preload import Preload, large_displacement_preload, linear_preload
    from mace_fmu.util.frequency import ZERO_HZ

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
