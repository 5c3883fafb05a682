"""Strict reader for the subset of NASTRAN bulk data that mace-fmu understands.

Every problem is a DeckError pointing at ``file:line``, the card and the field; nothing is guessed.
Field positions follow fields.py: data field 1 is field 2 of a card's first line.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from mace_fmu.deck.cards import (CBar, CBeam, Celas2, Conm1, Conm2, Cord1R, Cord2R, Deck, Eigr, Eigrl, Grav, Grid,
                                 Interpolation, Load, Mat1, Mpc, MpcTerm, Nlparm, Param, PBar, PBeam, PMass, PRod,
                                 Rigid, Rod, ScalarMass, SetUnion, Source, Spc1)
from mace_fmu.deck.fields import (Fields, Selections, case_control, check_text, parse_int, parse_real, split_cards,
                                  split_sections)
from mace_fmu.deck.sections import SECTIONS, section_properties
from mace_fmu.deck.geometry import axes_from_points, bar_orientation, coordinate_frames, grid_positions
from mace_fmu.errors import DeckError


def read_deck(path: str | os.PathLike[str]) -> Deck:
    """Read and validate the NASTRAN bulk-data deck in file ``path`` (INCLUDE files relative to it).

    Parameters
    ----------
    path : str or path-like
        The deck (``.bdf``, ``.dat``, ``.nas``): free, small or large field.

    Returns
    -------
    Deck
        Every card we model as a frozen record, with the file and line it came from; cards that do not
        change mass or stiffness are read past and listed in ``Deck.skipped``.

    Raises
    ------
    DeckError
        With the file, line, card and field, and what was expected; every card we cannot model is
        listed at once.
    """
    name = os.fspath(path)
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise DeckError("no such file", file=name, line=0) from None
    except OSError as exc:
        raise DeckError(f"cannot read the deck file ({exc.strerror})", file=name, line=0) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        raise DeckError(f"byte 0x{data[exc.start]:02x} at column {exc.start - line_start + 1} is not text (expected "
                        "an ASCII or UTF-8 text file)", file=name, line=data.count(b"\n", 0, exc.start) + 1) from None
    return read_deck_text(text, name=name)


def read_deck_text(text: str, *, name: str = "<string>") -> Deck:
    """Read and validate a deck given as text; ``name`` stands for the file in error messages.

    Parameters
    ----------
    text : str
        The bulk data (and case control) as a NASTRAN deck file would hold it.
    name : str
        What error messages call the text.

    Returns
    -------
    Deck
        The validated cards.

    Raises
    ------
    DeckError
        A malformed or inconsistent card: the message names ``name``, the line, the card and the field.
    """
    # Split on newlines only, so that line numbers match what an editor shows.
    physical = text.removeprefix("\ufeff").split("\n")  # a byte-order mark, which some editors write
    if physical and physical[-1] == "":
        physical.pop()
    lines = [(number, line.rstrip("\r")) for number, line in enumerate(physical, start=1)]
    check_text(lines, name)
    case, bulk = split_sections(lines, name)
    global_case, subcases, selections = case_control(case, name) if case is not None else (None, {}, {})
    # A second BEGIN BULK line repeats the section's start; NASTRAN reads past it (bah_plane.bdf and
    # ha144ds.bdf of tests/data/nastran have one and ran), and so does this reader.
    bulk = [(number, text) for number, text in bulk if not _BEGIN_BULK.fullmatch(text.split("$", 1)[0].strip())]
    raw_cards = _cards_with_includes(bulk, name, stack=(os.path.abspath(name),))
    if not raw_cards:
        raise DeckError("no bulk data cards (expected GRID, CBAR and the other cards before ENDDATA)", file=name,
                        line=min(bulk[-1][0] + 1, lines[-1][0]) if bulk else lines[-1][0])
    tables, skipped = _bulk_tables(raw_cards, name)
    deck = Deck(path=name, subcases=subcases, global_case=global_case, skipped=skipped, **tables)
    _validate(deck, selections)
    return deck


_BEGIN_BULK = re.compile(r"BEGIN\s*BULK", re.IGNORECASE)
_INCLUDE = re.compile(r"^\s*INCLUDE\s*'([^']+)'\s*$", re.IGNORECASE)


def _cards_with_includes(lines: list, file: str, *, stack: tuple[str, ...]) -> list:
    """The bulk cards of ``lines`` with each ``INCLUDE 'path'`` replaced by the cards of that file (a path
    relative to the including file's folder, nested INCLUDEs too); every card keeps its own file and line."""
    out, segment = [], []

    def flush() -> None:
        for raw in split_cards(segment, file):
            raw.file = file
            out.append(raw)
        segment.clear()

    for number, text in lines:
        head = text.split("$", 1)[0]
        if not head.strip().upper().startswith("INCLUDE"):
            segment.append((number, text))
            continue
        match = _INCLUDE.match(head)
        if not match:
            raise DeckError("expected INCLUDE 'path' (the path in single quotes on one line)", file=file, line=number,
                            card="INCLUDE")
        flush()
        target = Path(match.group(1))
        if not target.is_absolute():
            target = Path(file).parent / target
        resolved = os.path.abspath(target)
        if resolved in stack:
            raise DeckError(f"INCLUDE {match.group(1)!r} is circular: {' -> '.join(stack)} -> {resolved}", file=file,
                            line=number, card="INCLUDE")
        try:
            included = target.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise DeckError(f"INCLUDE {match.group(1)!r}: no such file ({target})", file=file, line=number,
                            card="INCLUDE") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise DeckError(f"INCLUDE {match.group(1)!r}: cannot read {target} ({exc})", file=file, line=number,
                            card="INCLUDE") from None
        physical = included.removeprefix("\ufeff").split("\n")
        numbered = [(k, line.rstrip("\r")) for k, line in enumerate(physical, start=1)]
        check_text(numbered, str(target))
        out += _cards_with_includes(numbered, str(target), stack=stack + (resolved,))
    flush()
    return out


#: cards that change neither mass nor stiffness (loads, frequencies, output sets, aerodynamics, ...): read
#: past and reported, never an error; any other card we cannot model is one
NON_STRUCTURAL = frozenset({
    "USET", "USET1", "FORCE", "FORCE1", "FORCE2", "MOMENT", "MOMENT1", "MOMENT2", "PLOAD", "PLOAD1", "PLOAD2",
    "PLOAD4", "TEMP", "TEMPD", "DAREA", "DLOAD", "RLOAD1", "RLOAD2", "TLOAD1", "TLOAD2", "TABLED1", "TABLED2",
    "TABLED3", "TABLED4", "FREQ", "FREQ1", "FREQ2", "FREQ3", "FREQ4", "FREQ5", "TSTEP", "TSTEPNL", "RANDPS",
    "SET1", "SET2", "SET3", "CAERO1", "CAERO2", "PAERO1", "PAERO2", "SPLINE1", "SPLINE2", "SPLINE4", "SPLINE5",
    "AERO", "AEROS", "MKAERO1", "MKAERO2", "FLFACT", "FLUTTER", "AESTAT", "AESURF", "TRIM", "DESVAR", "DRESP1",
    "DCONSTR", "DVPREL1", "DOPTPRM", "EIGC", "TABDMP1", "PLOTEL", "ECHOOFF", "ECHOON",
    # SUPORT only names the DOFs along which NASTRAN's modal solution computes the rigid-body modes (printed as
    # 0.0 Hz); with a statically determinate set, as NASTRAN requires, the elastic modes are those of the
    # unsupported structure, which is what mace-fmu solves (its rigid-body modes come out near 0 Hz).
    "SUPORT", "SUPORT1",
    # gust, random-response and monitor-point data of the aeroelastic solutions
    "GUST", "TABRND1", "MONPNT1", "MONPNT3",
})


# ----------------------------------------------------------------------------------------------
# Cards

def _vec(f: Fields, d: int, names: tuple[str, str, str]) -> tuple[float, float, float]:
    return (f.real(d, names[0], 0.0), f.real(d + 1, names[1], 0.0), f.real(d + 2, names[2], 0.0))


def _grid(f: Fields, src: Source, defaults: tuple[int, int, str] = (0, 0, "")) -> Grid:
    """GRID; blank CP, CD and PS take the GRDSET values ``defaults`` (QRG GRDSET), else 0, 0 and none."""
    gid = f.ident(1, "ID")
    cp = f.integer(2, "CP", defaults[0], minimum=0)
    xyz = _vec(f, 3, ("X1", "X2", "X3"))
    cd = f.integer(6, "CD", defaults[1], minimum=0)
    ps = f.components(7, "PS", defaults[2])
    f.blank(8, "SEID")
    f.end(8)
    return Grid(id=gid, cp=cp, xyz=xyz, cd=cd, ps=ps, source=src)


def _cord2r(f: Fields, src: Source) -> Cord2R:
    cid = f.ident(1, "CID")
    rid = f.integer(2, "RID", 0, minimum=0)
    a, b, c = _vec(f, 3, ("A1", "A2", "A3")), _vec(f, 6, ("B1", "B2", "B3")), _vec(f, 9, ("C1", "C2", "C3"))
    f.end(11)
    try:
        axes_from_points(np.array(a), np.array(b), np.array(c))
    except ValueError as exc:
        raise f.error(str(exc), 3, "A, B, C", 11) from None
    return Cord2R(id=cid, rid=rid, a=a, b=b, c=c, source=src)


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
        v = _vec(f, 5, ("X1", "X2", "X3"))
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


def _two_node_beam(f: Fields, offt_name: str) -> dict:
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


def _cbar(f: Fields, src: Source) -> CBar:
    fields = _two_node_beam(f, "OFFT")
    f.end(16)
    return CBar(**fields, source=src)


def _pbar(f: Fields, src: Source) -> PBar:
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


def _mat1(f: Fields, src: Source) -> Mat1:
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


def _conm2(f: Fields, src: Source) -> Conm2:
    eid = f.ident(1, "EID")
    grid = f.integer(2, "G", minimum=1)
    cid = f.integer(3, "CID", 0, minimum=-1)
    mass = f.real(4, "M")
    offset = _vec(f, 5, ("X1", "X2", "X3"))
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
    return Conm2(id=eid, grid=grid, cid=cid, mass=mass, offset=offset, inertia=inertia,  # type: ignore[arg-type]
                 source=src)


def _celas2(f: Fields, src: Source) -> Celas2:
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


def _mpc(f: Fields, src: Source) -> Mpc:
    sid = f.ident(1, "SID")
    terms: list[MpcTerm] = []
    for base in range(0, max(len(f), 8), 8):
        if base:
            f.blank(base + 1, "unused")
        for d in (base + 2, base + 5):
            texts = (f.text(d), f.text(d + 1), f.text(d + 2))
            if not any(texts):
                continue
            k = len(terms) + 1
            for offset, what in enumerate(("grid", "component", "coefficient")):
                if not texts[offset]:
                    raise f.error(f"MPC term {k} is incomplete: {what} blank (expected G, C and A)", d + offset,
                                  f"{'GCA'[offset]}{k}")
            terms.append(MpcTerm(grid=f.integer(d, f"G{k}", minimum=1), component=f.component(d + 1, f"C{k}"),
                                 coefficient=f.real(d + 2, f"A{k}")))
        f.blank(base + 8, "unused")
    if not terms:
        raise f.error("MPC has no terms (expected G1 C1 A1 ...)", 2, "G1")
    if terms[0].coefficient == 0.0:
        raise f.error("the dependent term has coefficient 0.0 (expected a non-zero A1)", 4, "A1")
    return Mpc(sid=sid, terms=tuple(terms), source=src)


@dataclass(frozen=True)
class _Thru:
    """SPC1 in the G1 THRU G2 form; grids are filled in once all GRIDs are known."""

    card: Spc1
    first: int
    last: int


def _spc1(f: Fields, src: Source) -> Spc1 | _Thru:
    sid = f.ident(1, "SID")
    comps = f.components(2, "C")
    if f.text(4).upper() == "THRU":
        first, last = f.integer(3, "G1", minimum=1), f.integer(5, "G2", minimum=1)
        f.end(5)
        if last < first:
            raise f.error(f"G2 = {last} is below G1 = {first} (expected G1 THRU G2 with G1 <= G2)", 5, "G2")
        return _Thru(Spc1(sid=sid, components=comps, grids=(), source=src), first, last)
    grids = tuple(f.integer(d, f"G{d - 2}", minimum=1) for d in range(3, len(f) + 1) if f.text(d))
    if not grids:
        raise f.error("no grids listed (expected G1 ...)", 3, "G1")
    return Spc1(sid=sid, components=comps, grids=grids, source=src)


def _spc(f: Fields, src: Source) -> tuple[Spc1, ...]:
    """SPC: up to two (grid, components, enforced value) triples; a fixed DOF only (the value must be 0),
    stored as SPC1 entries of the same set."""
    sid = f.ident(1, "SID")
    out = []
    for k, d in enumerate((2, 5), start=1):
        if not f.text(d):
            if k == 1:
                raise f.error("no grid (expected G1 C1 D1)", 2, "G1")
            continue
        grid = f.integer(d, f"G{k}", minimum=1)
        comps = f.components(d + 1, f"C{k}")
        if f.real(d + 2, f"D{k}", 0.0) != 0.0:
            raise f.error("an enforced displacement is not supported (expected D blank or 0.0: a fixed DOF)",
                          d + 2, f"D{k}")
        out.append(Spc1(sid=sid, components=comps, grids=(grid,), source=src))
    f.end(7)
    return tuple(out)


def _grav(f: Fields, src: Source) -> Grav:
    sid = f.ident(1, "SID")
    cid = f.integer(2, "CID", 0, minimum=0)
    scale = f.real(3, "A")
    direction = _vec(f, 4, ("N1", "N2", "N3"))
    if f.integer(7, "MB", 0, minimum=-1) > 0:
        raise f.error(f"expected -1 or 0, got {f.text(7)!r}", 7, "MB")
    f.end(7)
    if direction == (0.0, 0.0, 0.0):
        raise f.error("direction vector is zero (expected N1, N2, N3 not all 0.0)", 4, "N1-N3", 6)
    return Grav(sid=sid, cid=cid, scale=scale, direction=direction, source=src)


def _load(f: Fields, src: Source) -> Load:
    sid = f.ident(1, "SID")
    scale = f.real(2, "S")
    terms: list[tuple[float, int]] = []
    for d in range(3, len(f) + 1, 2):
        if f.text(d) or f.text(d + 1):
            k = (d - 1) // 2
            term = (f.real(d, f"S{k}"), f.integer(d + 1, f"L{k}", minimum=1))
            if term[1] in (t[1] for t in terms):
                raise f.error(f"load set {term[1]} is listed twice (expected unique Li)", d + 1, f"L{k}")
            terms.append(term)
    if not terms:
        raise f.error("no load sets listed (expected S1 L1 ...)", 3, "S1")
    return Load(sid=sid, scale=scale, terms=tuple(terms), source=src)


def _eigrl(f: Fields, src: Source) -> Eigrl:
    sid = f.ident(1, "SID")
    v1, v2, nd = f.real(2, "V1", None), f.real(3, "V2", None), f.integer(4, "ND", None, minimum=1)
    msglvl = f.integer(5, "MSGLVL", 0, minimum=0)
    if v1 is None and v2 is None and nd is None:
        raise f.error("V1, V2 and ND are all blank (expected a frequency range or a number of modes)", 2,
                      "V1, V2, ND", 4)
    if v1 is not None and v2 is not None and v2 <= v1:
        raise f.error(f"V2 = {f.text(3)} is not above V1 = {f.text(2)} (expected V1 < V2)", 3, "V2")
    if v2 is not None and v2 <= 0.0:
        raise f.error(f"V2 = {f.text(3)} (expected an upper frequency > 0.0 Hz)", 3, "V2")
    return Eigrl(sid=sid, v1=v1, v2=v2, nd=nd, msglvl=msglvl, source=src)


def _nlparm(f: Fields, src: Source) -> Nlparm:
    nid = f.ident(1, "ID")
    ninc = f.integer(2, "NINC", 10, minimum=1)
    f.real(3, "DT", None)
    kmethod = f.word(4, "KMETHOD", "AUTO", ("AUTO", "SEMI", "ITER"))
    kstep = f.integer(5, "KSTEP", None, minimum=-1)
    max_iter = f.integer(6, "MAXITER", 25)
    if max_iter == 0:
        raise f.error("MAXITER is 0 (expected a non-zero integer)", 6, "MAXITER")
    conv = f.word(7, "CONV", "PW")
    if not re.fullmatch(r"[UPWV]+", conv):
        raise f.error(f"expected a combination of U, P, W (and V), got {conv!r}", 7, "CONV")
    f.word(8, "INTOUT", None, ("YES", "NO", "ALL"))
    eps_u, eps_p, eps_w = (f.real(d, name, 0.01, above=0.0) for d, name in ((9, "EPSU"), (10, "EPSP"), (11, "EPSW")))
    for d, name in ((12, "MAXDIV"), (13, "MAXQN"), (14, "MAXLS")):
        f.integer(d, name, None)
    f.real(15, "FSTRESS", None)
    f.real(16, "LSTOL", None)
    return Nlparm(id=nid, ninc=ninc, kmethod=kmethod, kstep=kstep, max_iter=max_iter, conv=conv, eps_u=eps_u,
                  eps_p=eps_p, eps_w=eps_w, source=src)


def _param_value(text: str) -> int | float | str:
    as_int, as_real = parse_int(text), parse_real(text)
    return as_int if as_int is not None else as_real if as_real is not None else text.upper()


def _param(f: Fields, src: Source) -> Param:
    name = f.word(1, "N")
    f.label = f"PARAM {name}"
    if not f.text(2):
        raise f.error("required field is blank (expected a value)", 2, "V1")
    f.end(3)
    values = tuple(_param_value(f.text(d)) for d in (2, 3) if f.text(d))
    if name == "WTMASS" and (len(values) != 1 or isinstance(values[0], str) or not values[0] > 0):
        raise f.error(f"WTMASS {f.text(2)!r} must be a positive number (the factor on every mass, e.g. 0.00259 "
                      "for a deck in lbf and inches)", 2, "V1")
    return Param(name=name, values=values, source=src)


# ----------------------------------------------------------------------------------------------
# Beams, rods, scalar masses, rigid elements, EIGR: what public NASTRAN decks use beyond the MACE deck. Field layouts and defaults are those of
# the cards' entries in the MSC Nastran Quick Reference Guide (QRG).

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


def _pbarl(f: Fields, src: Source) -> PBar:
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


def _pbeaml(f: Fields, src: Source) -> PBeam:
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


def _pbeam(f: Fields, src: Source) -> PBeam:
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


def _cbeam(f: Fields, src: Source) -> CBeam:
    """CBEAM (QRG): EID PID GA GB X1 X2 X3 (or G0) OFFT/BIT; PA PB W1A ... W3B; SA SB. Without offsets, pin
    flags or scalar points (mace-fmu models none of them)."""
    fields = _two_node_beam(f, "OFFT/BIT")
    for d, name in ((17, "SA"), (18, "SB")):
        f.blank(d, name)
    f.end(18)
    return CBeam(**fields, source=src)


def _rod_ends(f: Fields, first: int) -> tuple[int, int]:
    ga, gb = f.integer(first, "G1", minimum=1), f.integer(first + 1, "G2", minimum=1)
    if ga == gb:
        raise f.error(f"G1 and G2 are both grid {ga} (expected two different grids)", first, "G1, G2", first + 1)
    return ga, gb


def _crod(f: Fields, src: Source) -> Rod:
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


def _conrod(f: Fields, src: Source) -> Rod:
    """CONROD (QRG): EID G1 G2 MID A J C NSM."""
    eid = f.ident(1, "EID")
    ga, gb = _rod_ends(f, 2)
    mid = f.integer(4, "MID", minimum=1)
    area, j, nsm = _rod_values(f, 5)
    f.end(8)
    return Rod(id=eid, ga=ga, gb=gb, pid=None, mid=mid, area=area, j=j, nsm=nsm, source=src, card="CONROD")


def _prod(f: Fields, src: Source) -> PRod:
    """PROD (QRG): PID MID A J C NSM."""
    pid = f.ident(1, "PID")
    mid = f.integer(2, "MID", minimum=1)
    area, j, nsm = _rod_values(f, 3)
    f.end(6)
    return PRod(id=pid, mid=mid, area=area, j=j, nsm=nsm, source=src)


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


def _cmass1(f: Fields, src: Source) -> ScalarMass:
    """CMASS1 (QRG): EID PID G1 C1 G2 C2 (PID defaults to EID)."""
    eid = f.ident(1, "EID")
    pid = f.integer(2, "PID", eid, minimum=1)
    g1, c1, g2, c2 = _scalar_ends(f, 3)
    return ScalarMass(id=eid, mass=None, pid=pid, g1=g1, c1=c1, g2=g2, c2=c2, source=src, card="CMASS1")


def _cmass2(f: Fields, src: Source) -> ScalarMass:
    """CMASS2 (QRG): EID M G1 C1 G2 C2."""
    eid = f.ident(1, "EID")
    mass = f.real(2, "M")
    g1, c1, g2, c2 = _scalar_ends(f, 3)
    return ScalarMass(id=eid, mass=mass, pid=None, g1=g1, c1=c1, g2=g2, c2=c2, source=src)


def _pmass(f: Fields, src: Source) -> tuple[PMass, ...]:
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


def _rbar(f: Fields, src: Source) -> Rigid:
    """RBAR (QRG): EID GA GB CNA CNB CMA CMB ALPHA. With CMA and CMB blank every DOF not in CNA or CNB is
    dependent (QRG remark). mace-fmu takes the common form: all six DOFs of one end independent, components
    of the other end dependent."""
    eid = f.ident(1, "EID")
    ga, gb = f.integer(2, "GA", minimum=1), f.integer(3, "GB", minimum=1)
    if ga == gb:
        raise f.error(f"GA and GB are both grid {ga} (expected two different grids)", 2, "GA, GB", 3)
    cna, cnb = f.components(4, "CNA", ""), f.components(5, "CNB", "")
    cma, cmb = f.components(6, "CMA", ""), f.components(7, "CMB", "")
    f.real(8, "ALPHA", None)
    f.end(8)
    if not cma and not cmb:  # QRG: the DOFs not independent are dependent
        cma = "".join(c for c in "123456" if c not in cna)
        cmb = "".join(c for c in "123456" if c not in cnb)
    if cna == "123456" and not cnb and not cma:
        independent, dependent = ga, ((gb, cmb),)
    elif cnb == "123456" and not cna and not cmb:
        independent, dependent = gb, ((ga, cma),)
    else:
        raise f.error(f"CNA {cna or 'blank'}, CNB {cnb or 'blank'}, CMA {cma or 'blank'}, CMB {cmb or 'blank'} is "
                      "not supported by mace-fmu (expected all six DOFs of one end independent, e.g. CNA 123456 "
                      "and the rest blank)", 4, "CNA-CMB", 7)
    if not dependent[0][1]:
        raise f.error("no dependent DOF (expected CMA or CMB)", 6, "CMA, CMB", 7)
    return Rigid(id=eid, card="RBAR", independent=independent, dependent=dependent, source=src)


def _rbe2(f: Fields, src: Source) -> Rigid:
    """RBE2 (QRG): EID GN CM GM1 GM2 ... (an optional real ALPHA, and TREF, after the last grid): components
    CM of every GMi follow grid GN rigidly."""
    eid = f.ident(1, "EID")
    gn = f.integer(2, "GN", minimum=1)
    cm = f.components(3, "CM")
    grids: list[int] = []
    d = 4
    while d <= len(f):
        text = f.text(d)
        if text and parse_int(text) is None:  # ALPHA (then TREF): thermal only, after the grid list
            f.real(d, "ALPHA")
            f.real(d + 1, "TREF", None)
            f.end(d + 1)
            break
        if text:
            grid = f.integer(d, f"GM{len(grids) + 1}", minimum=1)
            if grid == gn or grid in grids:
                raise f.error(f"grid {grid} is {'GN' if grid == gn else 'listed twice'} (expected distinct "
                              "dependent grids other than GN)", d, f"GM{len(grids) + 1}")
            grids.append(grid)
        d += 1
    if not grids:
        raise f.error("no dependent grid (expected GM1 ...)", 4, "GM1")
    return Rigid(id=eid, card="RBE2", independent=gn, dependent=tuple((g, cm) for g in grids), source=src)


def _rbe3(f: Fields, src: Source) -> Interpolation:
    """RBE3 (QRG): EID, blank, REFGRID, REFC, then groups WTi Ci Gi,1 Gi,2 ...; optional "UM" (dependent
    DOFs moved to the independent grids) and "ALPHA" sections after them. mace-fmu takes translational
    independent components (Ci within 123): NASTRAN weights rotational ones with a characteristic length
    whose definition its Guide leaves open, and UM sets, both refused."""
    eid = f.ident(1, "EID")
    f.blank(2, "blank")
    reference = f.integer(3, "REFGRID", minimum=1)
    reference_components = f.components(4, "REFC")
    groups: list[tuple[float, str, tuple[int, ...]]] = []
    d = 5
    while d <= len(f):
        text = f.text(d)
        if not text:
            d += 1
            continue
        if text.upper() == "UM":
            raise f.error("a UM section (dependent DOFs on the independent grids) is not supported by mace-fmu "
                          "(expected the reference grid's REFC as the only dependent DOFs)", d, "UM")
        if text.upper() == "ALPHA":  # thermal expansion only: read and left
            f.real(d + 1, "ALPHA")
            f.end(d + 1)
            break
        k = len(groups) + 1
        weight = f.real(d, f"WT{k}", above=0.0)
        components = f.components(d + 1, f"C{k}")
        if set(components) - set("123"):
            raise f.error(f"C{k} = {components}: rotational independent components are not supported by mace-fmu "
                          "(expected translations, digits 1-3)", d + 1, f"C{k}")
        grids: list[int] = []
        d += 2
        while d <= len(f) and (not f.text(d) or parse_int(f.text(d)) is not None):
            if f.text(d):
                grid = f.integer(d, f"G{k},{len(grids) + 1}", minimum=1)
                if grid == reference:
                    raise f.error(f"grid {grid} is REFGRID (expected independent grids other than the reference)",
                                  d, f"G{k},{len(grids) + 1}")
                grids.append(grid)
            d += 1
        if not grids:
            raise f.error(f"no grid after WT{k} and C{k} (expected G{k},1 ...)", d - 1, f"G{k},1")
        groups.append((weight, components, tuple(grids)))
    if not groups:
        raise f.error("no independent grids (expected WT1, C1, G1,1 ...)", 5, "WT1")
    return Interpolation(id=eid, reference=reference, reference_components=reference_components,
                         groups=tuple(groups), source=src)


_EIGR_METHODS = ("LAN", "AHOU", "HOU", "MHOU", "GIV", "MGIV", "INV", "SINV")


def _eigr(f: Fields, src: Source) -> Eigr:
    """EIGR (QRG): SID METHOD F1 F2 NE ND; NORM G C. Any method gives the same roots; mace-fmu keeps those
    in [F1, F2] (when given), at most ND of them."""
    sid = f.ident(1, "SID")
    method = f.word(2, "METHOD", None, _EIGR_METHODS) or "LAN"
    f1, f2 = f.real(3, "F1", None), f.real(4, "F2", None)
    ne, nd = f.integer(5, "NE", None, minimum=0), f.integer(6, "ND", None, minimum=0)
    f.blank(7, "unused")
    f.blank(8, "unused")
    norm = f.word(9, "NORM", "MASS", ("MASS", "MAX", "POINT"))
    f.integer(10, "G", None, minimum=1)
    f.integer(11, "C", None, minimum=0)
    f.end(11)
    if f1 is not None and f2 is not None and f2 < f1:
        raise f.error(f"F2 = {f.text(4)} is below F1 = {f.text(3)} (expected F1 <= F2)", 4, "F2")
    return Eigr(sid=sid, method=method, f1=f1, f2=f2, ne=ne, nd=nd or None, norm=norm, source=src)


def _two_groups(f: Fields, expected: str, first_name: str) -> list[tuple[int, int]]:
    """(group number 1 or 2, first field) of each four-field group present on a card that carries up to
    two (CORD1R, PELAS, ...); the first is required."""
    present = [(k, d) for k, d in ((1, 1), (2, 5)) if any(f.text(d + i) for i in range(4))]
    if not present or present[0][0] != 1:
        raise f.error(f"required field is blank (expected {expected})", 1, first_name)
    return present


def _cord1r(f: Fields, src: Source) -> tuple[Cord1R, ...]:
    """CORD1R (QRG): up to two CIDi G1i G2i G3i groups."""
    out = []
    for k, d in _two_groups(f, "CID1 G1A G2A G3A", "CIDA"):
        cid = f.integer(d, f"CID{'AB'[k - 1]}", minimum=1)
        f.label = f"CORD1R {cid}"
        grids = tuple(f.integer(d + i, f"G{i}{'AB'[k - 1]}", minimum=1) for i in (1, 2, 3))
        if len(set(grids)) < 3:
            raise f.error(f"grids {grids} are not three different grids", d + 1, "G1-G3", d + 3)
        out.append(Cord1R(id=cid, g1=grids[0], g2=grids[1], g3=grids[2], source=src, field=d + 1))
    f.end(8)
    return tuple(out)


def _grdset(f: Fields, src: Source) -> tuple[int, int, str]:
    """GRDSET (QRG): defaults of GRID's CP (field 3), CD (field 7) and PS (field 8)."""
    f.blank(1, "unused")
    cp = f.integer(2, "CP", 0, minimum=0)
    for d in (3, 4, 5):
        f.blank(d, "unused")
    cd = f.integer(6, "CD", 0, minimum=0)
    ps = f.components(7, "PS", "")
    f.blank(8, "SEID")
    f.end(8)
    return cp, cd, ps


def _celas1(f: Fields, src: Source) -> tuple[int, int, int, int, int | None, int | None]:
    """CELAS1 (QRG): EID PID G1 C1 G2 C2 (PID defaults to EID); becomes a CELAS2 once its PELAS is known."""
    eid = f.ident(1, "EID")
    pid = f.integer(2, "PID", eid, minimum=1)
    g1, c1, g2, c2 = _scalar_ends(f, 3)
    return eid, pid, g1, c1, g2, c2


def _pelas(f: Fields, src: Source) -> tuple[tuple[int, float, Source], ...]:
    """PELAS (QRG): up to two PIDi Ki GEi Si groups; (PID, K, source) each."""
    out = []
    for k, d in _two_groups(f, "PID1 K1", "PID1"):
        pid = f.integer(d, f"PID{k}", minimum=1)
        f.label = f"PELAS {pid}"
        out.append((pid, f.real(d + 1, f"K{k}"), src))
        f.real(d + 2, f"GE{k}", None)
        f.real(d + 3, f"S{k}", None)
    f.end(8)
    return tuple(out)


def _conm1(f: Fields, src: Source) -> Conm1:
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
    return Conm1(id=eid, grid=grid, cid=cid, matrix=tuple(values), source=src)  # type: ignore[arg-type]


def _spcadd(f: Fields, src: Source) -> SetUnion:
    """SPCADD / MPCADD (QRG): SID S1 S2 ...: the union of the listed sets."""
    sid = f.ident(1, "SID")
    sets = tuple(f.integer(d, f"S{d - 1}", minimum=1) for d in range(2, len(f) + 1) if f.text(d))
    if not sets:
        raise f.error("no sets listed (expected S1 ...)", 2, "S1")
    if sid in sets:
        k = sets.index(sid)
        raise f.error(f"set {sid} lists itself (expected other set IDs)", 2 + k, f"S{k + 1}")
    return SetUnion(sid=sid, card=f.raw.name, sets=sets, source=src)


_PARSERS: dict[str, Callable[[Fields, Source], Any]] = {
    "GRID": _grid, "CORD2R": _cord2r, "CBAR": _cbar, "PBAR": _pbar, "MAT1": _mat1, "CONM2": _conm2,
    "CELAS2": _celas2, "MPC": _mpc, "SPC1": _spc1, "SPC": _spc, "GRAV": _grav, "LOAD": _load, "EIGRL": _eigrl,
    "NLPARM": _nlparm, "PARAM": _param, "PBARL": _pbarl, "PBEAML": _pbeaml, "PBEAM": _pbeam, "CBEAM": _cbeam,
    "CROD": _crod, "CONROD": _conrod, "PROD": _prod, "CMASS1": _cmass1, "CMASS2": _cmass2, "PMASS": _pmass,
    "RBAR": _rbar, "RBE2": _rbe2, "EIGR": _eigr, "GRDSET": _grdset, "CELAS1": _celas1, "PELAS": _pelas,
    "CONM1": _conm1, "SPCADD": _spcadd, "MPCADD": _spcadd, "CORD1R": _cord1r, "RBE3": _rbe3}
_TABLES = {"GRID": "grids", "CORD2R": "coords", "CBAR": "bars", "PBAR": "pbars", "MAT1": "mat1s",
           "CONM2": "conm2s", "CELAS2": "celas2s", "GRAV": "gravs", "LOAD": "loads", "EIGRL": "eigrls",
           "NLPARM": "nlparms", "PARAM": "params", "PBARL": "pbars", "PBEAML": "pbeams", "PBEAM": "pbeams",
           "CBEAM": "beams", "CROD": "rods", "CONROD": "rods", "PROD": "prods", "CMASS1": "scalar_masses",
           "CMASS2": "scalar_masses", "PMASS": "pmasses", "RBAR": "rigids", "RBE2": "rigids", "EIGR": "eigrs",
           "CONM1": "conm1s", "CORD1R": "coords", "RBE3": "interpolations"}
#: one element ID namespace in NASTRAN. CONM2 has its own: MSC Nastran ran HA144D with CBAR 100 and CONM2 100
#: (its sorted bulk echo is in the .f06 of tests/data/nastran/ha144ds), so a deck may reuse a CBAR's ID on a CONM2
_ELEMENTS = ("CBAR", "CELAS1", "CELAS2", "CBEAM", "CROD", "CONROD", "CMASS1", "CMASS2", "RBAR", "RBE2", "RBE3")


def _bulk_tables(raw_cards: list, file: str) -> tuple[dict[str, dict], tuple]:
    """Cards keyed by ID (MPC and SPC1 by set ID), with duplicates rejected, and the non-structural cards
    read past ((name, count, first file:line) each)."""
    tables: dict[str, dict] = {attr: {} for attr in _TABLES.values()}
    sets: dict[str, dict[int, list]] = {"mpcs": {}, "spc1s": {}}
    elements: dict[int, tuple[str, Any]] = {}
    thru: list[tuple[int, _Thru]] = []
    unknown: dict[str, list] = {}
    skipped: dict[str, list] = {}
    for raw in raw_cards:
        if raw.name not in _PARSERS:
            (skipped if raw.name in NON_STRUCTURAL else unknown).setdefault(raw.name, []).append(raw)
    if unknown:  # every card we cannot model, once each: card, count, first line
        (name, first), *_ = sorted(((n, rs[0]) for n, rs in unknown.items()), key=lambda t: (t[1].file, t[1].line))
        if len(unknown) == 1 and len(unknown[name]) == 1:
            message = f"unknown card {name!r} (supported: {', '.join(sorted(_PARSERS))})"
        else:
            listed = ", ".join(f"{n} ({len(rs)}x, first at {rs[0].file or file}:{rs[0].line})"
                               for n, rs in sorted(unknown.items(), key=lambda t: (t[1][0].file, t[1][0].line)))
            message = (f"cards this reader cannot model: {listed} (supported: {', '.join(sorted(_PARSERS))}; "
                       f"read past without a word, as changing neither mass nor stiffness: "
                       f"{', '.join(sorted(NON_STRUCTURAL))})")
        raise DeckError(message, file=first.file or file, line=first.line, card=name)
    grdsets = [raw for raw in raw_cards if raw.name == "GRDSET"]
    if len(grdsets) > 1:
        raise DeckError(f"GRDSET defined twice: line {grdsets[0].line} and line {grdsets[1].line} (expected at most "
                        "one)", file=grdsets[1].file or file, line=grdsets[1].line, card="GRDSET")
    defaults = _grdset(Fields(grdsets[0], file), Source(grdsets[0].file or file, grdsets[0].line)) if grdsets \
        else (0, 0, "")
    celas1s: list[tuple[Any, Source]] = []
    pelas: dict[int, tuple[float, Source]] = {}
    unions: dict[str, dict[int, SetUnion]] = {"SPCADD": {}, "MPCADD": {}}
    for raw in raw_cards:
        if (raw.name in NON_STRUCTURAL and raw.name not in _PARSERS) or raw.name == "GRDSET":
            continue
        parser = _PARSERS[raw.name]
        src = Source(raw.file or file, raw.line)
        card = _grid(Fields(raw, file), src, defaults) if raw.name == "GRID" else parser(Fields(raw, file), src)
        if raw.name == "PELAS":
            for pid, k, where in card:
                if pid in pelas:
                    raise DeckError(f"PELAS {pid} defined twice: line {pelas[pid][1].line} and line {raw.line}",
                                    file=src.file, line=raw.line, card=f"PELAS {pid}")
                pelas[pid] = (k, where)
            continue
        if raw.name in unions:
            if card.sid in unions[raw.name]:
                raise DeckError(f"{raw.name} {card.sid} defined twice: line {unions[raw.name][card.sid].source.line} "
                                f"and line {raw.line}", file=src.file, line=raw.line, card=f"{raw.name} {card.sid}")
            unions[raw.name][card.sid] = card
            continue
        if raw.name == "CELAS1":
            eid = card[0]
            if eid in elements:
                kind, other = elements[eid]
                raise DeckError(f"element ID {eid} is used twice: {kind} at line {other.source.line} and CELAS1 at "
                                f"line {raw.line} ({', '.join(_ELEMENTS)} share one ID namespace)", file=src.file,
                                line=raw.line, card=f"CELAS1 {eid}")
            celas1s.append((card, src))
            elements[eid] = ("CELAS1", Celas2(id=eid, k=0.0, g1=card[2], c1=card[3], g2=card[4], c2=card[5],
                                             source=src))
            continue
        if raw.name == "SPC":  # one or two fixed DOFs: SPC1 entries of the same set
            for entry in card:
                sets["spc1s"].setdefault(entry.sid, []).append(entry)
            continue
        if raw.name in ("MPC", "SPC1"):
            sid = card.card.sid if isinstance(card, _Thru) else card.sid
            group = sets["mpcs" if raw.name == "MPC" else "spc1s"].setdefault(sid, [])
            if isinstance(card, _Thru):
                thru.append((len(group), card))
            group.append(card)
            continue
        for card in card if raw.name in ("PMASS", "CORD1R") else (card,):  # several on one card
            _store(raw, card, tables, elements, file)
    _resolve_thru(tables, sets, thru, file)
    for (eid, pid, g1, c1, g2, c2), src in celas1s:  # CELAS1 + PELAS = CELAS2 (QRG)
        if pid not in pelas:
            raise DeckError(f"property {pid} is not defined (expected a PELAS ID)", file=src.file, line=src.line,
                            card=f"CELAS1 {eid}", field="field 3 (PID)")
        if eid in tables["celas2s"]:
            raise DeckError(f"element ID {eid} is used twice: CELAS2 at line {tables['celas2s'][eid].source.line} and "
                            f"CELAS1 at line {src.line}", file=src.file, line=src.line, card=f"CELAS1 {eid}")
        tables["celas2s"][eid] = Celas2(id=eid, k=pelas[pid][0], g1=g1, c1=c1, g2=g2, c2=c2, source=src)
    _union_sets(sets, unions)
    report = tuple((n, len(rs), f"{rs[0].file or file}:{rs[0].line}") for n, rs in sorted(skipped.items()))
    return {**tables, **{name: {sid: tuple(cards) for sid, cards in group.items()} for name, group in sets.items()}}, \
        report


def _store(raw: Any, card: Any, tables: dict, elements: dict, file: str) -> None:
    """Put ``card`` in its table, refusing a second card with its key (or its element ID)."""
    key = card.name if raw.name == "PARAM" else card.sid if hasattr(card, "sid") else card.id
    table = tables[_TABLES[raw.name]]
    if key in table:
        # (PBAR and PBARL share one ID table, as do PBEAM and PBEAML, CROD and CONROD, CMASS1 and CMASS2)
        raise DeckError(f"{raw.name} {key} defined twice: line {table[key].source.line} and line {raw.line}",
                        file=raw.file or file, line=raw.line, card=f"{raw.name} {key}")
    if raw.name in _ELEMENTS:
        if key in elements:
            kind, other = elements[key]
            raise DeckError(f"element ID {key} is used twice: {kind} at line {other.source.line} and {raw.name} "
                            f"at line {raw.line} ({', '.join(_ELEMENTS)} share one ID namespace)",
                            file=raw.file or file, line=raw.line, card=f"{raw.name} {key}")
        elements[key] = (raw.name, card)
    table[key] = card


def _union_sets(sets: dict[str, dict[int, list]], unions: dict[str, dict]) -> None:
    """SPCADD / MPCADD: the set is the union of the listed SPC1/SPC (MPC) sets, which must exist and may not
    themselves be SPCADD (MPCADD) sets (QRG)."""
    for name, table, what in (("SPCADD", "spc1s", "an SPC or SPC1 set ID"), ("MPCADD", "mpcs", "an MPC set ID")):
        for sid, card in unions[name].items():
            if sid in sets[table]:
                raise DeckError(f"set {sid} is both an {name} and a set of {'SPC/SPC1' if name == 'SPCADD' else 'MPC'} "
                                f"cards (expected a new set ID; first such card at line "
                                f"{sets[table][sid][0].source.line})", file=card.source.file, line=card.source.line,
                                card=f"{name} {sid}", field="field 2 (SID)")
        for sid, card in unions[name].items():
            merged: list = []
            for k, s in enumerate(card.sets, start=1):
                if s not in sets[table] or s in unions[name]:
                    raise DeckError(f"set {s} is not defined (expected {what})", file=card.source.file,
                                    line=card.source.line, card=f"{name} {sid}", field=f"S{k}")
                merged += sets[table][s]
            sets[table][sid] = merged


def _resolve_thru(tables: dict, sets: dict, thru: list, file: str) -> None:
    """MSC rule: grids of a THRU range that do not exist are skipped."""
    for index, item in thru:
        group = sets["spc1s"][item.card.sid]
        grids = tuple(g for g in sorted(tables["grids"]) if item.first <= g <= item.last)
        if not grids:
            raise DeckError(f"no GRID exists in {item.first} THRU {item.last} (expected at least one)", file=file,
                            line=item.card.source.line, card=f"SPC1 {item.card.sid}", field="fields 4-6 (G1 THRU G2)")
        group[index] = replace(item.card, grids=grids)


# ----------------------------------------------------------------------------------------------
# Cross-card validation

def _fail(card: Any, label: str, field: str | None, message: str) -> DeckError:
    return DeckError(message, file=card.source.file, line=card.source.line, card=label, field=field)


def _need(key: int | None, table: Any, card: Any, label: str, field: str, noun: str, expected: str) -> None:
    if key is not None and key not in table:
        raise _fail(card, label, field, f"{noun} {key} is not defined (expected {expected})")


def _validate(deck: Deck, selections: Selections) -> None:
    """Cross references, MPC dependent DOFs, bar geometry and case-control selections."""
    check_deck(deck)
    _check_selections(deck, selections)


def check_deck(deck: Deck) -> None:
    """Cross references, MPC dependent DOFs and bar geometry of a deck (also one changed in code)."""
    frames = coordinate_frames(deck)
    grid, coord = ("grid", "a GRID ID"), ("coordinate system", "0 or a CORD2R ID")
    for g in deck.grids.values():
        _need(g.cp, frames, g, f"GRID {g.id}", "field 3 (CP)", *coord)
        _need(g.cd, frames, g, f"GRID {g.id}", "field 7 (CD)", *coord)
    for b in deck.bars.values():
        label = f"CBAR {b.id}"
        _need(b.pid, deck.pbars, b, label, "field 3 (PID)", "property", "a PBAR ID")
        for key, field in ((b.ga, "field 4 (GA)"), (b.gb, "field 5 (GB)"), (b.g0, "field 6 (G0)")):
            _need(key, deck.grids, b, label, field, *grid)
    for p in deck.pbars.values():
        _need(p.mid, deck.mat1s, p, f"PBAR {p.id}", "field 3 (MID)", "material", "a MAT1 ID")
    for m in deck.conm2s.values():
        _need(m.grid, deck.grids, m, f"CONM2 {m.id}", "field 3 (G)", *grid)
        _need(m.cid if m.cid > 0 else None, frames, m, f"CONM2 {m.id}", "field 4 (CID)", *coord)
    for s in deck.celas2s.values():
        _need(s.g1, deck.grids, s, f"CELAS2 {s.id}", "field 4 (G1)", *grid)
        _need(s.g2, deck.grids, s, f"CELAS2 {s.id}", "field 6 (G2)", *grid)
    _check_new_elements(deck, grid)
    for sid, eqs in deck.mpcs.items():
        for eq in eqs:
            for k, t in enumerate(eq.terms, start=1):
                _need(t.grid, deck.grids, eq, f"MPC {sid}", f"term {k} (G{k})", *grid)
    for sid, spcs in deck.spc1s.items():
        for spc in spcs:
            for k, g in enumerate(spc.grids, start=1):
                _need(g, deck.grids, spc, f"SPC1 {sid}", f"grid list (G{k})", *grid)
    for gr in deck.gravs.values():
        _need(gr.cid, frames, gr, f"GRAV {gr.sid}", "field 3 (CID)", *coord)
    for ld in deck.loads.values():
        for k, (_, lset) in enumerate(ld.terms, start=1):
            _need(lset, deck.gravs, ld, f"LOAD {ld.sid}", f"L{k}", "load set", "a GRAV SID")
    if (grdpnt := deck.params.get("GRDPNT")) is not None:
        value = grdpnt.values[0]
        if not isinstance(value, int) or value < -1:
            raise _fail(grdpnt, "PARAM GRDPNT", "field 3 (V1)", f"expected -1, 0 or a GRID ID, got {value!r}")
        _need(value if value > 0 else None, deck.grids, grdpnt, "PARAM GRDPNT", "field 3 (V1)", *grid)
    _check_mpc_dofs(deck)
    _check_bars(deck, frames)


def _check_new_elements(deck: Deck, grid: tuple[str, str]) -> None:
    """Cross references of CBEAM, CROD/CONROD, CMASS1/2, RBAR/RBE2 and their properties."""
    for b in deck.beams.values():
        label = f"CBEAM {b.id}"
        _need(b.pid, deck.pbeams, b, label, "field 3 (PID)", "property", "a PBEAM or PBEAML ID")
        for key, field in ((b.ga, "field 4 (GA)"), (b.gb, "field 5 (GB)"), (b.g0, "field 6 (G0)")):
            _need(key, deck.grids, b, label, field, *grid)
    for p in deck.pbeams.values():
        _need(p.mid, deck.mat1s, p, f"{'PBEAML' if p.section else 'PBEAM'} {p.id}", "field 3 (MID)", "material",
              "a MAT1 ID")
    for r in deck.rods.values():
        label, first = f"{r.card} {r.id}", (4 if r.card == "CROD" else 3)
        if r.pid is not None:
            _need(r.pid, deck.prods, r, label, "field 3 (PID)", "property", "a PROD ID")
        else:
            _need(r.mid, deck.mat1s, r, label, "field 5 (MID)", "material", "a MAT1 ID")
        _need(r.ga, deck.grids, r, label, f"field {first} (G1)", *grid)
        _need(r.gb, deck.grids, r, label, f"field {first + 1} (G2)", *grid)
    for p in deck.prods.values():
        _need(p.mid, deck.mat1s, p, f"PROD {p.id}", "field 3 (MID)", "material", "a MAT1 ID")
    for m in deck.scalar_masses.values():
        label = f"{m.card} {m.id}"
        if m.pid is not None:
            _need(m.pid, deck.pmasses, m, label, "field 3 (PID)", "property", "a PMASS ID")
        _need(m.g1, deck.grids, m, label, "field 4 (G1)", *grid)
        _need(m.g2, deck.grids, m, label, "field 6 (G2)", *grid)
    for m in deck.conm1s.values():
        _need(m.grid, deck.grids, m, f"CONM1 {m.id}", "field 3 (G)", *grid)
        _need(m.cid if m.cid > 0 else None, coordinate_frames(deck), m, f"CONM1 {m.id}", "field 4 (CID)",
              "coordinate system", "0 or a CORD2R ID")
    for r in deck.rigids.values():
        _need(r.independent, deck.grids, r, f"{r.card} {r.id}", "independent grid", *grid)
        for k, (g, _) in enumerate(r.dependent, start=1):
            _need(g, deck.grids, r, f"{r.card} {r.id}", f"dependent grid {k}", *grid)
    for e in deck.interpolations.values():
        _need(e.reference, deck.grids, e, f"RBE3 {e.id}", "field 4 (REFGRID)", *grid)
        for k, (_, _, grids) in enumerate(e.groups, start=1):
            for j, g in enumerate(grids, start=1):
                _need(g, deck.grids, e, f"RBE3 {e.id}", f"G{k},{j}", *grid)


def _check_mpc_dofs(deck: Deck) -> None:
    """Within one set, a dependent DOF may appear in no other equation (NASTRAN's m-set rule)."""
    for sid, eqs in deck.mpcs.items():
        dependent_of: dict[tuple[int, int], Mpc] = {}
        used_in: dict[tuple[int, int], Mpc] = {}  # first equation with the DOF in any term
        for eq in eqs:
            dofs = [(t.grid, t.component) for t in eq.terms]
            # Reported at the later of the two equations, where a sequential reader sees the clash.
            clash = [(dof, dependent_of[dof], eq) for dof in dofs if dof in dependent_of]
            clash += [(dofs[0], eq, used_in[dofs[0]])] if dofs[0] in used_in else []
            if clash:
                (grid, comp), dep, other = clash[0]
                again = "is used again at" if other is eq else "is also used in the equation at"
                raise _fail(eq, f"MPC {sid}", None, f"DOF {grid}-{comp} is the dependent DOF of the equation at "
                            f"line {dep.source.line} and {again} line {other.source.line}")
            dependent_of[dofs[0]] = eq
            for dof in dofs:
                used_in.setdefault(dof, eq)


def _check_bars(deck: Deck, frames: dict) -> None:
    """Bars need a length and an orientation vector off their axis (positions in basic). Checked for all
    bars at once (a 100k-DOF deck has 70k bars), then the first offender in deck order is reported."""
    pos = grid_positions(deck, frames)
    bars = (*deck.bars.values(), *deck.beams.values())
    if bars:
        axis = np.array([pos[b.gb] for b in bars]) - np.array([pos[b.ga] for b in bars])
        v = np.array([bar_orientation(deck, b, pos, frames) for b in bars])
        length = np.linalg.norm(axis, axis=1)
        short = length < 1e-9
        parallel = ~short & (np.linalg.norm(np.cross(axis, v), axis=1) <= 1e-6 * length * np.linalg.norm(v, axis=1))
        bad = np.flatnonzero(short | parallel)
        if bad.size:
            b = bars[bad[0]]
            name = "CBEAM" if isinstance(b, CBeam) else "CBAR"
            if short[bad[0]]:
                raise _fail(b, f"{name} {b.id}", "fields 4-5 (GA, GB)", f"zero length: grids {b.ga} and {b.gb} are "
                            f"both at {tuple(round(float(x), 9) for x in pos[b.ga])} (expected distinct positions)")
            where = "field 6 (G0)" if b.g0 is not None else "fields 6-8 (X1-X3)"
            raise _fail(b, f"{name} {b.id}", where, "orientation vector is parallel to the bar axis (expected a "
                        "vector that defines the element x-y plane)")
    for r in deck.rods.values():
        if np.linalg.norm(pos[r.gb] - pos[r.ga]) < 1e-9:
            first = 4 if r.card == "CROD" else 3
            raise _fail(r, f"{r.card} {r.id}", f"fields {first}-{first + 1} (G1, G2)", f"zero length: grids {r.ga} "
                        f"and {r.gb} are both at {tuple(round(float(x), 9) for x in pos[r.ga])} (expected distinct "
                        "positions)")


_TARGETS = {"SPC": (("spc1s",), "an SPC1 set ID"), "MPC": (("mpcs",), "an MPC set ID"),
            "LOAD": (("loads", "gravs"), "a LOAD or GRAV set ID"), "NLPARM": (("nlparms",), "an NLPARM ID"),
            "METHOD": (("eigrls", "eigrs"), "an EIGRL or EIGR set ID")}


def _check_selections(deck: Deck, selections: Selections) -> None:
    """Sets selected by the subcases (or by the global case when there are none) must exist."""
    cases = list(deck.subcases) or ([0] if deck.global_case is not None else [])
    for cid in cases:
        for key, (value, line) in selections[cid].items():
            if key in _TARGETS and not any(value in getattr(deck, t) for t in _TARGETS[key][0]):
                raise DeckError(f"{key} set {value} is not defined (expected {_TARGETS[key][1]})", file=deck.path,
                                line=line, card=f"SUBCASE {cid}" if cid else "global case control", field=key)
