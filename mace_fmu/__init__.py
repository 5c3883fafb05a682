"""mace-fmu: a NASTRAN deck of a flexible, actively controlled structure to modes, volts-volts models and FMUs.

The names a user starts with, in the order of the data flow (imported on first use, so that
``import mace_fmu`` stays cheap)::

    deck = mace_fmu.read_deck("my.bdf")                       # the deck as NASTRAN reads it
    modes = mace_fmu.compute_modes(deck, structure="0g")      # modes [Hz], labelled
    model = mace_fmu.volts_model("0g", structure_file="my.toml")  # volts in, volts out
    mace_fmu.export_fmu(model, out_dir="fmus")                # an FMU (native: FMI 2 or 3; or kind="pythonfmu")
"""

from __future__ import annotations

import importlib
from typing import Any

#: public name -> the module that defines it
_PUBLIC = {
    "read_deck": "mace_fmu.deck.reader",
    "load_structure_file": "mace_fmu.structure",
    "compute_modes": "mace_fmu.pipeline",
    "volts_model": "mace_fmu.iomodel.volts",
    "ParameterSet": "mace_fmu.parameters",
    "export_fmu": "mace_fmu.fmu.export",
    "export_controller_fmu": "mace_fmu.fmu.controller",
    "DiscreteController": "mace_fmu.fmu.controller",
    "write_ssp": "mace_fmu.ssp",
    "fmu_problem": "mace_fmu.updating.fmu_problem",
    "update_fmu": "mace_fmu.updating.fmu_update",
    "MaceError": "mace_fmu.errors",
}

__all__ = sorted(_PUBLIC)


def __getattr__(name: str) -> Any:
    if name not in _PUBLIC:
        raise AttributeError(f"module 'mace_fmu' has no attribute {name!r}")
    return getattr(importlib.import_module(_PUBLIC[name]), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
