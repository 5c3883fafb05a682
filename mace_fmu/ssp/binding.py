"""Which part of a parameter set is built into a plant FMU and which part an SSV binds to it.

Moduli and spring stiffnesses change the finite-element model: an FMU applies them only by
first-order reanalysis in its modal basis, so an SSP package builds them into the FMU with a full
re-solve (as ``mace-fmu export --parameters`` does). Frequency scales are built in too: the FMU's
``frequency_scale_mode_<k>`` is relative to the model it was built from, and Table 5.3's bounds
(its min/max) are relative to the nominal model, so the FMU is built at the nominal scales and its
own scales stay 1 within 1 -+ bound. Damping ratios, delays and servo gains are exact as FMU
parameters: they become the SSV's start values, so the package's model equals
``volts_model(compute_modes(..., parameters=set))`` and a colleague can change them without rebuilding.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from mace_fmu.errors import MaceError
from mace_fmu.parameters.kinds import KindName
from mace_fmu.parameters.per_mode import resolve_mode_names
from mace_fmu.parameters.sets import ParameterSet

_BUILT_IN: tuple[KindName, ...] = ("modulus", "spring", "mass", "frequency_scale")


@dataclass(frozen=True)
class SplitParameters:
    """A set split into what an FMU build takes and what its SSV binds."""

    built_in: ParameterSet | None  #: moduli, springs, masses, frequency scales (with the set's provenance); None if none
    start_values: ParameterSet  #: damping ratios, delays, servo gains


def split_parameters(parameters: ParameterSet | None) -> SplitParameters:
    """Split ``parameters`` into the part built into the FMU and the part an SSV binds (module docstring)."""
    if parameters is None:
        return SplitParameters(built_in=None, start_values=ParameterSet({}))
    physical = parameters.of_kind(*_BUILT_IN)
    rest = {n: v for n, v in parameters.values.items() if n not in physical}
    # both halves keep the file they came from: an error in either names it
    source = parameters.source
    return SplitParameters(built_in=ParameterSet(physical, parameters.provenance, source=source) if physical else None,
                           start_values=ParameterSet(rest, parameters.provenance, source=source))


def fmu_start_values(parameters: ParameterSet, *, mode_labels: Sequence[str],
                     fmu_parameters: Sequence[str]) -> dict[str, float]:
    """The FMU variable values that give the set's damping ratios, frequency scales, delays and gains.

    Parameters
    ----------
    parameters
        Values by name (``damping:<label>`` or ``damping_mode_<k>``, ``frequency_scale:<label>`` or
        ``frequency_scale_mode_<k>``, ``delay_<channel>``, ``K_a`` ...).
    mode_labels
        The FMU's open-loop mode labels, mode 1 first (a label names every mode that carries it).
    fmu_parameters
        The FMU's tunable parameter names.

    Returns
    -------
    dict
        FMU variable name -> value [SI]; a label becomes ``damping_mode_<k>`` / ``frequency_scale_mode_<k>``
        of each mode k that carries it (:func:`~mace_fmu.parameters.per_mode.resolve_mode_names`). A MaceError
        names the set's file and an entry the FMU has nothing for.
    """
    available = set(fmu_parameters)
    out = resolve_mode_names(parameters.values, mode_labels=mode_labels, model="plant FMU", source=parameters.source,
                             available=available)
    for name in out:
        if name not in available:
            where = f"{parameters.source}: " if parameters.source else ""
            raise MaceError(f"{where}parameter {name!r}: the FMU has no parameter of that name")
    return out
