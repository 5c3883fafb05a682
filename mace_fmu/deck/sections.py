"""Section properties NASTRAN derives from PBARL / PBEAML dimensions.

NASTRAN replaces each PBARL by a PBAR and each PBEAML by a PBEAM (user information message 4379,
"THE USER SUPPLIED PBARL BULK DATA ENTRIES ARE REPLACED BY THE FOLLOWING PBAR ENTRIES") before it
builds any matrix; this module computes those replacement values. The dimension names and the
section shapes are those of the PBARL / PBEAML figures of the MSC Nastran Quick Reference Guide.

Only the section types whose NASTRAN values (including the shear factors NASTRAN gives them, which
the Guide does not tabulate) have been checked against a NASTRAN run are listed; any other type is
refused by the reader rather than guessed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class SectionProperties:
    """What NASTRAN writes on the replacement PBAR / PBEAM."""

    area: float  #: A [m^2]
    i1: float  #: I1 [m^4]
    i2: float  #: I2 [m^4]
    i12: float  #: I12 [m^4]
    j: float  #: torsion constant [m^4]
    k1: float  #: shear area factor, plane 1
    k2: float  #: shear area factor, plane 2


def _rod(dims: tuple[float, ...]) -> SectionProperties:
    (r,) = dims
    area = math.pi * r * r
    i = math.pi * r**4 / 4.0
    # K1 = K2 = 0.9: the value NASTRAN writes on the PBAR/PBEAM replacing a ROD PBARL/PBEAML (message 4379 of
    # the beam_modes run in tests/data/nastran/beam_modes/beam_modes.f06: A 3.1416, I 0.7854, J 1.5708, K 0.9).
    return SectionProperties(area=area, i1=i, i2=i, i12=0.0, j=2.0 * i, k1=0.9, k2=0.9)


#: section type -> (number of dimensions, property function)
SECTIONS = {"ROD": (1, _rod)}


def section_properties(kind: str, dims: tuple[float, ...]) -> SectionProperties:
    """A, I1, I2, I12, J, K1, K2 of PBARL/PBEAML section ``kind`` with dimensions ``dims`` [m].

    Raises KeyError for a type not in :data:`SECTIONS` and ValueError for a wrong number of dimensions.
    """
    count, function = SECTIONS[kind]
    if len(dims) != count:
        raise ValueError(f"{kind} has {count} dimension(s), got {len(dims)}")
    return function(dims)
