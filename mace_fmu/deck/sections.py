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

from mace_fmu.errors import MaceError


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


def _tube(dims: tuple[float, ...]) -> SectionProperties:
    outer, inner = dims
    if not outer > inner:
        raise MaceError(f"DIM2 (inner radius {inner:g}) is not below DIM1 (outer radius {outer:g})")
    area = math.pi * (outer**2 - inner**2)
    i = math.pi * (outer**4 - inner**4) / 4.0
    # K1 = K2 = 0.5: what MSC Nastran writes for a TUBE (message 4379 of MSC's fmondsp run in the pyNastran
    # repository, models/aero/fmondsp.f06: PBEAML 1, TUBE 0.2 / 0.195 -> A 6.2047E-03, I 1.2103E-04, J 2.4206E-04,
    # K1 K2 5.0000E-01)
    return SectionProperties(area=area, i1=i, i2=i, i12=0.0, j=2.0 * i, k1=0.5, k2=0.5)


def _box(dims: tuple[float, ...]) -> SectionProperties:
    # QRG figure: DIM1 the width (along element z), DIM2 the height (along element y), DIM3 the thickness of the
    # flanges (top and bottom), DIM4 that of the webs (sides).
    width, height, t_flange, t_web = dims
    if not (width > 2.0 * t_web and height > 2.0 * t_flange):
        raise MaceError(f"the walls fill the box (expected DIM1 > 2 DIM4 and DIM2 > 2 DIM3, got {width:g}, "
                        f"{height:g}, {t_flange:g}, {t_web:g})")
    inner_w, inner_h = width - 2.0 * t_web, height - 2.0 * t_flange
    area = width * height - inner_w * inner_h
    i1 = (width * height**3 - inner_w * inner_h**3) / 12.0
    i2 = (height * width**3 - inner_h * inner_w**3) / 12.0
    # Bredt's thin-walled torsion constant on the wall mid-lines, and shear factors = the area of the walls
    # parallel to the shear over A. Both are the values MSC Nastran writes (message 4379 of fmondsp.f06, see
    # _tube): PBEAML 5, BOX 0.6 0.2 0.0025 0.0025 -> A 3.9750E-03, I1 3.2346E-05, I2 1.7702E-04, J 8.7582E-05,
    # K1 2.4528E-01, K2 7.4843E-01; PBEAML 6, BOX 0.05 0.5 0.001 0.001 -> K1 9.0876E-01, K2 8.7591E-02.
    j = (2.0 * t_flange * t_web * (width - t_web) ** 2 * (height - t_flange) ** 2
         / (width * t_web + height * t_flange - t_web**2 - t_flange**2))
    k1 = 2.0 * t_web * inner_h / area
    k2 = 2.0 * t_flange * inner_w / area
    return SectionProperties(area=area, i1=i1, i2=i2, i12=0.0, j=j, k1=k1, k2=k2)


#: section type -> (number of dimensions, property function). NASTRAN also writes a warping constant CW on the
#: PBEAM it makes from a BOX PBEAML; it acts only through a CBEAM's warping scalar points SA, SB (QRG CBEAM),
#: which mace-fmu refuses, so it is not computed.
SECTIONS = {"ROD": (1, _rod), "TUBE": (2, _tube), "BOX": (4, _box)}


def section_properties(kind: str, dims: tuple[float, ...]) -> SectionProperties:
    """A, I1, I2, I12, J, K1, K2 of PBARL/PBEAML section ``kind`` with dimensions ``dims`` [m].

    Raises KeyError for a type not in :data:`SECTIONS` and MaceError for a wrong number of dimensions.
    """
    count, function = SECTIONS[kind]
    if len(dims) != count:
        raise MaceError(f"{kind} has {count} dimension(s), got {len(dims)}")
    return function(dims)
