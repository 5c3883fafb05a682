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
from mace_fmu.parameters.kinds import kind_of_set_name, mode_label
from mace_fmu.parameters.sets import ParameterSet

_BUILT_IN = ("modulus", "spring", "mass", "frequency_scale")


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
    return SplitParameters(built_in=ParameterSet(physical, parameters.provenance) if physical else None,
                           start_values=ParameterSet(rest, parameters.provenance))


def fmu_start_values(parameters: ParameterSet, *, mode_labels: Sequence[str],
                     fmu_parameters: Sequence[str]) -> dict[str, float]:
    """The FMU variable values that give the set's damping ratios, frequency scales, delays and gains.

    Parameters
    ----------
    parameters
        Values by set name (``damping:<label>``, ``frequency_scale:<label>``, ``delay_<channel>``, ``K_a`` ...).
    mode_labels
        The FMU's open-loop mode labels, mode 1 first (a label names every mode that carries it).
    fmu_parameters
        The FMU's tunable parameter names.

    Returns
    -------
    dict
        FMU variable name -> value [SI]; a label becomes ``damping_mode_<k>`` / ``frequency_scale_mode_<k>``
        of each mode k that carries it. A MaceError names a set entry the FMU has nothing for.
    """
    available = set(fmu_parameters)
    out: dict[str, float] = {}
    for name, value in parameters.values.items():
        kind = kind_of_set_name(name)
        if kind is not None and kind.per_mode:
            label = mode_label(name)
            targets = [kind.fmu_name(k + 1) for k, x in enumerate(mode_labels) if x == label]
            targets = [t for t in targets if t in available]
            if not targets:
                raise MaceError(f"parameter {name!r}: the FMU has no mode labelled {label!r} with such a parameter")
            out.update({t: value for t in targets})
        elif name in available:
            out[name] = value
        else:
            raise MaceError(f"parameter {name!r}: the FMU has no parameter of that name")
    return out
