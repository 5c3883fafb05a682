"""Parsers of scalar springs and lumped masses: CELAS1/CELAS2 and PELAS, CMASS1/CMASS2 and PMASS, CONM1 and CONM2.

Field layouts and defaults are those of the cards' entries in the MSC Nastran Quick Reference Guide (QRG).
"""

from __future__ import annotations

import numpy as np

from mace_fmu.deck.cards import Celas2, Conm1, Conm2, PMass, ScalarMass, Source
from mace_fmu.deck.fields import Fields
from mace_fmu.deck.parsers.layouts import two_groups, vec


def _scalar_ends(f: Fields, first: int) -> tuple[int, int, int | None, int | None]:
    g1, c1 = f.integer(first, "G1", minimum=1), f.component(first + 1, "C1")
    # QRG (CELAS1, CMASS1, CMASS2): zero or blank G2 and C2 make a grounded terminal
    grounded = f.text(first + 2) in ("", "0") and f.text(first + 3) in ("", "0")
    g2, c2 = (None, None) if grounded else (f.integer(first + 2, "G2", minimum=1), f.component(first + 3, "C2"))
    if (g1, c1) == (g2, c2):
        raise f.error(f"both ends are DOF {g1}-{c1} (expected two different DOFs, or G2 and C2 blank for a "
                      "grounded element)", first + 2, "G2, C2", first + 3)
    f.end(first + 3)
    return g1, c1, g2, c2


def celas2(f: Fields, src: Source) -> Celas2:
    """CELAS2 (QRG): EID K G1 C1 G2 C2 GE S (G2 and C2 blank: a grounded spring)."""
    eid = f.ident(1, "EID")
    k = f.real(2, "K")
    g1, c1 = f.integer(3, "G1", minimum=1), f.component(4, "C1")
    grounded = not (f.text(5) or f.text(6))
    g2, c2 = (None, None) if grounded else (f.integer(5, "G2", minimum=1), f.component(6, "C2"))
    if (g1, c1) == (g2, c2):
        raise f.error(f"both ends are DOF {g1}-{c1} (expected two different DOFs, or G2 and C2 blank for a "
                      "grounded spring)", 5, "G2, C2", 6)
    f.real(7, "GE", None)
    f.real(8, "S", None)
    f.end(8)
    return Celas2(id=eid, k=k, g1=g1, c1=c1, g2=g2, c2=c2, source=src)


def celas1(f: Fields, src: Source) -> tuple[int, int, int, int, int | None, int | None]:
    """CELAS1 (QRG): EID PID G1 C1 G2 C2 (PID defaults to EID); becomes a CELAS2 once its PELAS is known."""
    eid = f.ident(1, "EID")
    pid = f.integer(2, "PID", eid, minimum=1)
    g1, c1, g2, c2 = _scalar_ends(f, 3)
    return eid, pid, g1, c1, g2, c2


def pelas(f: Fields, src: Source) -> tuple[tuple[int, float, Source], ...]:
    """PELAS (QRG): up to two PIDi Ki GEi Si groups; (PID, K, source) each."""
    out = []
    for k, d in two_groups(f, "PID1 K1", "PID1"):
        pid = f.integer(d, f"PID{k}", minimum=1)
        f.label = f"PELAS {pid}"
        out.append((pid, f.real(d + 1, f"K{k}"), src))
        f.real(d + 2, f"GE{k}", None)
        f.real(d + 3, f"S{k}", None)
    f.end(8)
    return tuple(out)


def cmass1(f: Fields, src: Source) -> ScalarMass:
    """CMASS1 (QRG): EID PID G1 C1 G2 C2 (PID defaults to EID)."""
    eid = f.ident(1, "EID")
    pid = f.integer(2, "PID", eid, minimum=1)
    g1, c1, g2, c2 = _scalar_ends(f, 3)
    return ScalarMass(id=eid, mass=None, pid=pid, g1=g1, c1=c1, g2=g2, c2=c2, source=src, card="CMASS1")


def cmass2(f: Fields, src: Source) -> ScalarMass:
    """CMASS2 (QRG): EID M G1 C1 G2 C2."""
    eid = f.ident(1, "EID")
    mass = f.real(2, "M")
    g1, c1, g2, c2 = _scalar_ends(f, 3)
    return ScalarMass(id=eid, mass=mass, pid=None, g1=g1, c1=c1, g2=g2, c2=c2, source=src)


def pmass(f: Fields, src: Source) -> tuple[PMass, ...]:
    """PMASS (QRG): up to four PIDi Mi pairs."""
    out = []
    for k, d in enumerate((1, 3, 5, 7), start=1):
        if not (f.text(d) or f.text(d + 1)):
            if k == 1:
                raise f.error("required field is blank (expected PID1 M1)", 1, "PID1")
            continue
        pid = f.integer(d, f"PID{k}", minimum=1)
        f.label = f"PMASS {pid}"
        out.append(PMass(id=pid, mass=f.real(d + 1, f"M{k}"), source=src))
    f.end(8)
    return tuple(out)


def conm2(f: Fields, src: Source) -> Conm2:
    """CONM2 (QRG): EID G CID M X1 X2 X3; I11 I21 I22 I31 I32 I33 (a positive semi-definite inertia)."""
    eid = f.ident(1, "EID")
    grid = f.integer(2, "G", minimum=1)
    cid = f.integer(3, "CID", 0, minimum=-1)
    mass = f.real(4, "M")
    offset = vec(f, 5, ("X1", "X2", "X3"))
    f.blank(8, "unused")
    names = ("I11", "I21", "I22", "I31", "I32", "I33")
    inertia = tuple(f.real(d, name, 0.0) for d, name in enumerate(names, start=9))
    f.end(14)
    for d, name, value in ((4, "M", mass), (9, "I11", inertia[0]), (11, "I22", inertia[2]), (13, "I33", inertia[5])):
        if value < 0.0:
            raise f.error(f"negative {'mass' if name == 'M' else 'inertia'} {f.text(d)!r} (expected >= 0.0)", d, name)
    i11, i21, i22, i31, i32, i33 = inertia
    matrix = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
    smallest = float(np.linalg.eigvalsh(matrix)[0])
    if smallest < -1e-12 * max(i11 + i22 + i33, np.finfo(float).tiny):
        raise f.error(f"the inertia matrix is not positive semi-definite (eigenvalue {smallest:.3g} kg m^2; expected "
                      "products of inertia small enough that I11 I22 >= I21^2 and so on)", 9, "I11-I33", 14)
    return Conm2(id=eid, grid=grid, cid=cid, mass=mass, offset=offset, inertia=inertia,
                 source=src)


def conm1(f: Fields, src: Source) -> Conm1:
    """CONM1 (QRG): EID G CID M11 M21 M22 M31 M32 M33; M41 ... M66: the lower triangle of a symmetric 6x6 mass
    matrix in system CID at grid G."""
    eid = f.ident(1, "EID")
    grid = f.integer(2, "G", minimum=1)
    cid = f.integer(3, "CID", 0, minimum=0)
    values, names = [], []
    d = 4
    for row in range(1, 7):
        for col in range(1, row + 1):
            names.append(f"M{row}{col}")
            values.append(f.real(d, names[-1], 0.0))
            d += 1
    f.end(d - 1)
    matrix = np.zeros((6, 6))
    matrix[np.tril_indices(6)] = values
    matrix = matrix + np.tril(matrix, -1).T
    smallest = float(np.linalg.eigvalsh(matrix)[0])
    if smallest < -1e-12 * max(float(np.abs(matrix).max()), np.finfo(float).tiny):
        raise f.error(f"the mass matrix is not positive semi-definite (eigenvalue {smallest:.3g})", 4, "M11-M66",
                      d - 1)
    return Conm1(id=eid, grid=grid, cid=cid, matrix=tuple(values), source=src)
