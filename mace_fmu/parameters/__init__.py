"""Model parameters: one record per kind (unit, valid range, name in a set and in an FMU), the
frozen, provenance-carrying parameter set every stage takes (SI units, TOML in and out), and the
per-mode names of a set resolved against a model's modes (by label or by number, either spelling)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.parameters.kinds import (KINDS, ModeReference, ParameterKind, declared_range, kind_of_fmu_name,
                                           kind_of_name, kind_of_set_name, mode_reference)
    from mace_fmu.parameters.per_mode import label_mode_names, resolve_mode_names
    from mace_fmu.parameters.sets import ParameterNames, ParameterSet, Provenance, load_parameter_names, parameter_names

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "ParameterSet": "sets",
    "Provenance": "sets",
    "ParameterNames": "sets",
    "parameter_names": "sets",
    "load_parameter_names": "sets",
    "ParameterKind": "kinds",
    "KINDS": "kinds",
    "declared_range": "kinds",
    "kind_of_set_name": "kinds",
    "kind_of_fmu_name": "kinds",
    "kind_of_name": "kinds",
    "ModeReference": "kinds",
    "mode_reference": "kinds",
    "resolve_mode_names": "per_mode",
    "label_mode_names": "per_mode",
})
