"""NASTRAN's own normal modes (SOL 103 OP2 or punch files) as the FE core's Modes: any structure NASTRAN
can model (shells, solids), modal parameters only."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.nastran_modes.reading import NastranModes, read_nastran_modes

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "read_nastran_modes": "reading",
    "NastranModes": "reading",
})
