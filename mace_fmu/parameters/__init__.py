"""Model parameters: one record per kind (unit, valid range, name in a set and in an FMU) and the
frozen, provenance-carrying parameter set every stage takes (SI units, TOML in and out)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use
    from mace_fmu.parameters.kinds import KINDS, ParameterKind, declared_range, kind_of_fmu_name, kind_of_set_name
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
})
