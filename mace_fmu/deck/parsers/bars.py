"""Parsers of the line elements and what they are made of.

CBAR and CBEAM (pin flags and offsets refused), their PBAR/PBARL and PBEAM/PBEAML properties (constant
sections only), CROD, CONROD and PROD, and the MAT1 material they all name. Field layouts and defaults are
those of the cards' entries in the MSC Nastran Quick Reference Guide (QRG).
"""

from __future__ import annotations

import math
import re
from typing import Any

from mace_fmu.deck.cards import CBar, CBeam, Mat1, PBar, PBeam, PRod, Rod, Source
from mace_fmu.deck.fields import Fields, parse_int, parse_real
from mace_fmu.deck.parsers.layouts import vec
from mace_fmu.deck.sections import SECTIONS, section_properties


def _orientation(f: Fields, ga: int, gb: int) -> tuple[tuple[float, float, float] | None, int | None]:
    """(v, G0) of a CBAR or CBEAM from fields 5-7."""
    v: tuple[float, float, float] | None = None
    g0: int | None = None
    # NASTRAN: an integer X1 with X2, X3 blank is the orientation grid G0.
    if parse_int(f.text(5)) is not None and not f.text(6) and not f.text(7):
        g0 = f.integer(5, "G0", minimum=1)
        if g0 in (ga, gb):
            raise f.error(f"G0 is grid {g0}, an end of the {f.raw.name.lower()[1:]} (expected a third grid)", 5,
                          "G0")
    elif not (f.text(5) or f.text(6) or f.text(7)):
        raise f.error("orientation is blank (expected G0 or X1, X2, X3)", 5, "X1-X3", 7)
    else:
        v = vec(f, 5, ("X1", "X2", "X3"))
        if v == (0.0, 0.0, 0.0):
            raise f.error("orientation vector is zero (expected a vector off the bar axis)", 5, "X1-X3", 7)
    return v, g0


def _offt(f: Fields, v: Any, g0: int | None, name: str) -> bool:
    """CBAR/CBEAM field 9 (QRG OFFT): True when the orientation vector is in the basic system.

    OFFT is three letters: the system of the orientation vector (G: GA's displacement system, B: basic), then
    those of the end-A and end-B offsets (G, B or O: element). mace-fmu refuses offsets, so only the first letter
    matters. An integer 1 (vector) or 2 (G0) is the F flag of older NASTRAN decks, which MSC Nastran still
    reads: MSC's own test deck pt145 (tests/data/nastran/pt145) ran with a 1 there.
    """
    text = f.text(8).upper()
    if not text or (text == "1" and v is not None) or (text == "2" and g0 is not None):
        return False
    if not re.fullmatch(r"[GB][GBO][GBO]", text):
        raise f.error(f"expected blank, a code such as GGG or BGG (orientation G or B, offsets G, B or O), or the "
                      f"old flag 1 (vector) / 2 (G0), got {f.text(8)!r}", 8, name)
    return text[0] == "B" and v is not None


def _two_node_beam(f: Fields, offt_name: str) -> dict[str, Any]:
    """The fields CBAR and CBEAM share (EID PID GA GB orientation OFFT; PA PB W1A ... W3B), without pin
    flags or offsets (mace-fmu models neither), as keyword arguments of their records."""
    eid = f.ident(1, "EID")
    pid = f.integer(2, "PID", eid, minimum=1)
    ga, gb = f.integer(3, "GA", minimum=1), f.integer(4, "GB", minimum=1)
    if ga == gb:
        raise f.error(f"GA and GB are both grid {ga} (expected two different grids)", 3, "GA, GB", 4)
    v, g0 = _orientation(f, ga, gb)
    basic = _offt(f, v, g0, offt_name)
    for d, name in ((9, "PA"), (10, "PB")):
        if f.text(d) not in ("", "0"):
            raise f.error(f"pin flags are not supported by mace-fmu (got {f.text(d)!r}, expected blank or 0)", d, name)
    for d, name in enumerate(("W1A", "W2A", "W3A", "W1B", "W2B", "W3B"), start=11):
        if f.text(d) and f.real(d, name, 0.0) != 0.0:  # blank (the usual) is 0.0: skip the parse
            raise f.error(f"offsets are not supported by mace-fmu (got {f.text(d)!r}, expected blank or 0.0)", d, name)
    return dict(id=eid, pid=pid, ga=ga, gb=gb, v=v, g0=g0, orientation_basic=basic)


def _plain_two_node_beam(fields: list[str]) -> dict[str, Any] | None:
    """What :func:`_two_node_beam` returns for the usual one-line CBAR or CBEAM (EID PID GA GB, then a G0 or a vector
    of reals; OFFT and every later field blank), read without its field-by-field checks: 80,000 bars of a
    large deck took 0.5 s through them. None for any other card, which the checked route reads or refuses
    with its message, so nothing this accepts differs from what that route would return."""
    if len(fields) != 8 or fields[7]:
        return None
    eid, pid, ga, gb, x1, x2, x3 = fields[:7]
    if not (eid.isdecimal() and pid.isdecimal() and ga.isdecimal() and gb.isdecimal()):
        return None
    eid_, pid_, ga_, gb_ = int(eid), int(pid), int(ga), int(gb)
    if min(eid_, pid_, ga_, gb_) < 1 or ga_ == gb_:
        return None
    v, g0 = None, None
    if x1.isdecimal() and not x2 and not x3:
        g0 = int(x1)
        if g0 < 1 or g0 in (ga_, gb_):
            return None
    else:
        components = []
        for text in (x1, x2, x3):
            value = parse_real(text) if text else 0.0
            if value is None or not math.isfinite(value):
                return None
            components.append(value)
        v = tuple(components)
        if v == (0.0, 0.0, 0.0):
            return None
    return dict(id=eid_, pid=pid_, ga=ga_, gb=gb_, v=v, g0=g0, orientation_basic=False)


def cbar(f: Fields, src: Source) -> CBar:
    """CBAR (QRG): EID PID GA GB X1 X2 X3 (or G0) OFFT; PA PB W1A ... W3B, without pin flags or offsets."""
    plain = _plain_two_node_beam(f.raw.fields)
    if plain is not None:
        return CBar(**plain, source=src)
    fields = _two_node_beam(f, "OFFT")
    f.end(16)
    return CBar(**fields, source=src)


def cbeam(f: Fields, src: Source) -> CBeam:
    """CBEAM (QRG): EID PID GA GB X1 X2 X3 (or G0) OFFT/BIT; PA PB W1A ... W3B; SA SB. Without offsets, pin
    flags or scalar points (mace-fmu models none of them)."""
    plain = _plain_two_node_beam(f.raw.fields)
    if plain is not None:
        return CBeam(**plain, source=src)
    fields = _two_node_beam(f, "OFFT/BIT")
    for d, name in ((17, "SA"), (18, "SB")):
        f.blank(d, name)
    f.end(18)
    return CBeam(**fields, source=src)


def pbar(f: Fields, src: Source) -> PBar:
    """PBAR (QRG): PID MID A I1 I2 J NSM; the stress points C1 ... F2; K1 K2 I12."""
    pid = f.ident(1, "PID")
    mid = f.integer(2, "MID", minimum=1)
    area, i1, i2, j, nsm = (f.real(d, name, 0.0) for d, name in enumerate(("A", "I1", "I2", "J", "NSM"), start=3))
    for d, name, value in ((3, "A", area), (4, "I1", i1), (5, "I2", i2), (6, "J", j), (7, "NSM", nsm)):
        if value < 0.0:
            raise f.error(f"negative value {f.text(d)!r} (expected >= 0.0)", d, name)
    f.blank(8, "unused")
    # First continuation: stress recovery points only; the shear factors are on the second.
    points = tuple(f.real(d, n, None) for d, n in enumerate(("C1", "C2", "D1", "D2", "E1", "E2", "F1", "F2"), 9))
    k1, k2 = f.real(17, "K1", None, minimum=0.0), f.real(18, "K2", None, minimum=0.0)
    i12 = f.real(19, "I12", 0.0)
    f.end(19)
    if i12 != 0.0 and not i1 * i2 > i12 * i12:  # NASTRAN's rule for a product of inertia
        raise f.error(f"I1 = {i1:g}, I2 = {i2:g} and I12 = {i12:g} give I1 I2 <= I12^2 (expected I1 I2 > I12^2)",
                      19, "I12")
    return PBar(id=pid, mid=mid, area=area, i1=i1, i2=i2, j=j, nsm=nsm, stress_points=points, k1=k1, k2=k2,
                i12=i12, source=src)


def _section_dims(f: Fields, first: int, kind: str) -> tuple[tuple[float, ...], float, int]:
    """(DIM1..DIMn, NSM, last field used) of a PBARL/PBEAML section starting at data field ``first``."""
    if kind not in SECTIONS:
        raise f.error(f"section type {kind!r} is not supported by mace-fmu (supported: "
                      f"{', '.join(sorted(SECTIONS))})", 4, "TYPE")
    count = SECTIONS[kind][0]
    dims = tuple(f.real(first + k, f"DIM{k + 1}", above=0.0) for k in range(count))
    nsm = f.real(first + count, "NSM", 0.0, minimum=0.0)
    try:
        section_properties(kind, dims)
    except ValueError as exc:
        raise f.error(f"{kind}: {exc}", first, f"DIM1-DIM{count}", first + count - 1) from None
    return dims, nsm, first + count


def pbarl(f: Fields, src: Source) -> PBar:
    """PBARL (QRG): PID MID GROUP TYPE; DIM1 ... DIMn NSM on the continuations. NASTRAN replaces it by a PBAR
    with the section's A, I1, I2, J and shear factors (sections.py); the stress points do not matter here."""
    pid = f.ident(1, "PID")
    mid = f.integer(2, "MID", minimum=1)
    group = f.text(3).upper() or "MSCBML0"
    if group != "MSCBML0":  # the QRG's default group; other groups are user-defined sections
        raise f.error(f"GROUP {f.text(3)!r} is not supported by mace-fmu (expected blank or MSCBML0)", 3, "GROUP")
    kind = f.word(4, "TYPE")
    for d in range(5, 9):
        f.blank(d, "unused")
    dims, nsm, last = _section_dims(f, 9, kind)
    f.end(last)
    p = section_properties(kind, dims)
    return PBar(id=pid, mid=mid, area=p.area, i1=p.i1, i2=p.i2, j=p.j, nsm=nsm, stress_points=(), k1=p.k1,
                k2=p.k2, i12=p.i12, source=src, section=kind)


def pbeam(f: Fields, src: Source) -> PBeam:
    """PBEAM (QRG) of constant section: PID MID A I1 I2 I12 J NSM; the stress points (C1 ... F2); optionally
    the end-B station (SO X/XB=1.0 and the end-A values, or blanks meaning them); then K1 K2 S1 S2 NSI(A)
    NSI(B) CW(A) CW(B). K1, K2 default to 1.0 (QRG); shear relief, warping, non-structural inertia and
    neutral-axis offsets must be blank or 0.0 (mace-fmu does not model them)."""
    pid = f.ident(1, "PID")
    mid = f.integer(2, "MID", minimum=1)
    names = ("A", "I1", "I2", "I12", "J", "NSM")
    values = [f.real(3 + k, name, 0.0) for k, name in enumerate(names)]
    for k, name in enumerate(names):
        if name != "I12" and values[k] < 0.0:
            raise f.error(f"negative value {f.text(3 + k)!r} (expected >= 0.0)", 3 + k, name)
    area, i1, i2, i12, j, nsm = values
    d = 17  # after the stress points of end A (data fields 9-16)
    if f.text(d).upper() in ("YES", "YESA", "NO"):  # the end-B station
        xxb = f.real(d + 1, "X/XB")
        if xxb != 1.0:
            raise f.error(f"intermediate stations (X/XB = {xxb:g}) are not supported by mace-fmu (expected only the "
                          "end-B station, X/XB = 1.0)", d + 1, "X/XB")
        for k, name in enumerate(names):
            if f.real(d + 2 + k, name, values[k]) != values[k]:
                raise f.error("end B differs from end A: tapered beams are not supported by mace-fmu (expected the "
                              "end-A value or blank)", d + 2 + k, name)
        d += 16 if f.text(d).upper() == "YES" else 8  # SO = YES: end B's stress points follow
    k1, k2 = f.real(d, "K1", 1.0, minimum=0.0), f.real(d + 1, "K2", 1.0, minimum=0.0)
    for k, name in enumerate(("S1", "S2", "NSI(A)", "NSI(B)", "CW(A)", "CW(B)", "M1(A)", "M2(A)", "M1(B)", "M2(B)",
                              "N1(A)", "N2(A)", "N1(B)", "N2(B)"), start=d + 2):
        if f.real(k, name, 0.0) != 0.0:
            raise f.error(f"{name} is not supported by mace-fmu (expected blank or 0.0)", k, name)
    f.end(d + 15)
    if i12 != 0.0 and not i1 * i2 > i12 * i12:
        raise f.error("I1 I2 <= I12^2 (expected I1 I2 > I12^2)", 6, "I12")
    return PBeam(id=pid, mid=mid, area=area, i1=i1, i2=i2, i12=i12, j=j, nsm=nsm, k1=k1, k2=k2, source=src)


def pbeaml(f: Fields, src: Source) -> PBeam:
    """PBEAML (QRG) of constant section: DIM1(A) ... NSM(A); an end-B station, when written, must repeat
    end A (SO, X/XB = 1.0, the same dimensions): tapered beams are refused."""
    pid = f.ident(1, "PID")
    mid = f.integer(2, "MID", minimum=1)
    group = f.text(3).upper() or "MSCBML0"
    if group != "MSCBML0":
        raise f.error(f"GROUP {f.text(3)!r} is not supported by mace-fmu (expected blank or MSCBML0)", 3, "GROUP")
    kind = f.word(4, "TYPE")
    for d in range(5, 9):
        f.blank(d, "unused")
    dims, nsm, last = _section_dims(f, 9, kind)
    d = last + 1
    while any(f.text(k) for k in range(d, len(f) + 1)):  # further stations: SO, X/XB, DIMs, NSM
        f.word(d, "SO", None, ("YES", "YESA", "NO"))
        xxb = f.real(d + 1, "X/XB", minimum=0.0)
        station = tuple(f.real(d + 2 + k, f"DIM{k + 1}", dims[k]) for k in range(len(dims)))
        station_nsm = f.real(d + 2 + len(dims), "NSM", nsm)
        if station != dims or station_nsm != nsm:
            raise f.error(f"the section at X/XB = {xxb:g} differs from end A: tapered beams are not supported by "
                          "mace-fmu (expected the end-A dimensions and NSM)", d + 2, "DIM1-NSM", d + 2 + len(dims))
        d += 3 + len(dims)
    p = section_properties(kind, dims)
    return PBeam(id=pid, mid=mid, area=p.area, i1=p.i1, i2=p.i2, i12=p.i12, j=p.j, nsm=nsm, k1=p.k1, k2=p.k2,
                 source=src, section=kind)


def _rod_ends(f: Fields, first: int) -> tuple[int, int]:
    ga, gb = f.integer(first, "G1", minimum=1), f.integer(first + 1, "G2", minimum=1)
    if ga == gb:
        raise f.error(f"G1 and G2 are both grid {ga} (expected two different grids)", first, "G1, G2", first + 1)
    return ga, gb


def crod(f: Fields, src: Source) -> Rod:
    """CROD (QRG): EID PID G1 G2 (PID defaults to EID)."""
    eid = f.ident(1, "EID")
    pid = f.integer(2, "PID", eid, minimum=1)
    ga, gb = _rod_ends(f, 3)
    f.end(4)
    return Rod(id=eid, ga=ga, gb=gb, pid=pid, mid=None, area=0.0, j=0.0, nsm=0.0, source=src)


def _rod_values(f: Fields, first: int) -> tuple[float, float, float]:
    """A, J, NSM at data fields ``first``, +1, +3 (C, the stress coefficient at +2, does not matter here)."""
    area = f.real(first, "A", 0.0, minimum=0.0)
    j = f.real(first + 1, "J", 0.0, minimum=0.0)
    f.real(first + 2, "C", None)
    nsm = f.real(first + 3, "NSM", 0.0, minimum=0.0)
    return area, j, nsm


def conrod(f: Fields, src: Source) -> Rod:
    """CONROD (QRG): EID G1 G2 MID A J C NSM."""
    eid = f.ident(1, "EID")
    ga, gb = _rod_ends(f, 2)
    mid = f.integer(4, "MID", minimum=1)
    area, j, nsm = _rod_values(f, 5)
    f.end(8)
    return Rod(id=eid, ga=ga, gb=gb, pid=None, mid=mid, area=area, j=j, nsm=nsm, source=src, card="CONROD")


def prod(f: Fields, src: Source) -> PRod:
    """PROD (QRG): PID MID A J C NSM."""
    pid = f.ident(1, "PID")
    mid = f.integer(2, "MID", minimum=1)
    area, j, nsm = _rod_values(f, 3)
    f.end(6)
    return PRod(id=pid, mid=mid, area=area, j=j, nsm=nsm, source=src)


def mat1(f: Fields, src: Source) -> Mat1:
    """MAT1 (QRG): MID E G NU RHO A TREF GE; ST SC SS MCSID (E or G required, both > 0)."""
    mid = f.ident(1, "MID")
    # NASTRAN allows E = G = 0.0; a bar made of it has no stiffness, so mace-fmu asks for > 0.
    e, g, nu = f.real(2, "E", None, above=0.0), f.real(3, "G", None, above=0.0), f.real(4, "NU", None)
    rho = f.real(5, "RHO", 0.0, minimum=0.0)
    for d, name in enumerate(("A", "TREF", "GE", "ST", "SC", "SS"), start=6):
        f.real(d, name, None)
    f.integer(12, "MCSID", None, minimum=0)
    f.end(12)
    if e is None and g is None:
        raise f.error("E and G are both blank (expected at least one of them)", 2, "E, G", 3)
    if nu is not None and not -1.0 < nu <= 0.5:
        raise f.error(f"Poisson's ratio {f.text(4)!r} is outside (-1, 0.5]", 4, "NU")
    return Mat1(id=mid, e=e, g=g, nu=nu, rho=rho, source=src)
