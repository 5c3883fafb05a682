"""Default bounds of an update's parameters, by parameter kind (thesis eq. 4.18's plausible change, gamma)."""

from __future__ import annotations

from typing import Mapping, Sequence

from mace_fmu.parameters.kinds import DAMPING, DELAY, MASS, MODULUS, SPRING, kind_of_name
from mace_fmu.updating.engine.solve import Bounds


def default_bounds(names: Sequence[str], start: Mapping[str, float]) -> dict[str, Bounds]:
    """Range and plausible change (eq. 4.18's gamma) by kind, relative to the start value: moduli
    and concentrated masses x0.5-1.5 (10 %), springs x0.2-5 (50 %), delays x0.2-3 (50 %), damping ratios x0.1-4,
    at most 0.95 (100 %), servo gains, frequency scales and any other name x0.2-5 (50 %).

    The kind is read from either spelling, a parameter set's (``damping:1st Z bending``) or an FMU's
    (``damping_mode_3``): an FMU's damping ratio read as a set's name had no kind, and took the others' x0.2-5."""
    out = {}
    for n in names:
        v = start[n]
        kind = kind_of_name(n)
        if kind is MODULUS or kind is MASS:
            out[n] = Bounds(0.5 * v, 1.5 * v, gamma_percent=10.0)
        elif kind is SPRING:
            out[n] = Bounds(0.2 * v, 5.0 * v, gamma_percent=50.0)
        elif kind is DELAY:
            out[n] = Bounds(0.2 * v, 3.0 * v, gamma_percent=50.0)
        elif kind is DAMPING:
            out[n] = Bounds(0.1 * v, min(4.0 * v, 0.95), gamma_percent=100.0)
        else:
            out[n] = Bounds(min(0.2 * v, 5 * v), max(0.2 * v, 5 * v), gamma_percent=50.0)
    return out
