"""Which model pole is which measured mode: by label pattern, then by frequency."""

from __future__ import annotations

import fnmatch
import functools
from typing import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from mace_fmu.iomodel.poles import ClosedLoopPole

#: poles this close to critical damping are real (servo and speed-loop lags), no vibration mode
REAL_POLE_DAMPING = 0.999
_NO_MATCH = 1e6  # assignment cost of a pole whose label does not match: taken only when nothing else can be


@functools.lru_cache(maxsize=65536)
def label_matches(label: str, pattern: str) -> bool:
    """Whether a pole label matches a pattern ("a|b": either of two fnmatch patterns); cached, as an
    update pairs the same few dozen labels thousands of times."""
    return any(fnmatch.fnmatchcase(label, pat) for pat in pattern.split("|"))


#: weight of the damping tie-break (squared log ratio of damping ratios) against squared relative frequency
#: differences: it decides between partners equally far in frequency, never against a real difference
_DAMPING_TIE_BREAK = 1e-6


def pair_poles(patterns: Sequence[tuple[str, float]], poles: Sequence[ClosedLoopPole], *,
               damping: Sequence[float | None] | None = None) -> list[int | None]:
    """For each (label pattern, frequency [Hz]), the index of its pole, or None when no pole matches.

    A pole can be a measured mode's when its label matches the pattern ("a|b": either) and it is
    no real pole; among those, one pole per mode is chosen so that the sum of squared relative
    frequency differences is least (an optimal assignment, not the nearest pole mode by mode:
    a greedy choice swaps partners of closely spaced modes, such as the violin families, at the
    slightest shift, and makes a cost built on the pairing jump). ``damping`` (each mode's damping
    ratio, or None) breaks ties: two modes listed at one frequency (Table 4.7's two 3rd violins
    at 21.58 Hz) would otherwise take their poles in whichever order round-off favours.
    """
    if not patterns:
        return []
    cost = np.full((len(patterns), len(poles)), _NO_MATCH)
    for i, (pattern, hz) in enumerate(patterns):
        for j, p in enumerate(poles):
            if p.damping < REAL_POLE_DAMPING and label_matches(p.label, pattern):
                cost[i, j] = ((p.frequency_hz - hz) / hz) ** 2
                zeta = damping[i] if damping is not None else None
                if zeta is not None and zeta > 0 and 0 < p.damping < REAL_POLE_DAMPING:
                    cost[i, j] += _DAMPING_TIE_BREAK * np.log(p.damping / zeta) ** 2
    rows, cols = linear_sum_assignment(cost)
    out: list[int | None] = [None] * len(patterns)
    for i, j in zip(rows, cols):
        if cost[i, j] < _NO_MATCH:
            out[i] = int(j)
    return out
