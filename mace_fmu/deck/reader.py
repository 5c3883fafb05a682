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

from mace_fmu.deck.cards import (CBar, Celas2, Conm2, Cord2R, Deck, Eigrl, Grav, Grid, Load, Mat1, Mpc, MpcTerm,
                                 Nlparm, Param, PBar, Source, Spc1)
from mace_fmu.deck.fields import (Fields, Selections, case_control, check_text, parse_int, parse_real, split_cards,
                                  split_sections)
from mace_fmu.deck.geometry import axes_from_points, bar_orientation, coordinate_frames, grid_positions
from mace_fmu.errors import DeckError


def read_deck(path: str | os.PathLike[str]) -> Deck:
    """Read and validate the deck in file ``path``."""
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
    """Read and validate a deck given as text; ``name`` stands for the file in error messages."""
    # Split on newlines only, so that line numbers match what an editor shows.
    physical = text.removeprefix("\ufeff").split("\n")  # a byte-order mark, which some editors write
    if physical and physical[-1] == "":
        physical.pop()
    lines = [(number, line.rstrip("\r")) for number, line in enumerate(physical, start=1)]
    check_text(lines, name)
    case, bulk = split_sections(lines, name)
    global_case, subcases, selections = case_control(case, name) if case is not None else (None, {}, {})
    raw_cards = _cards_with_includes(bulk, name, stack=(os.path.abspath(name),))
    if not raw_cards:
        raise DeckError("no bulk data cards (expected GRID, CBAR and the other cards before ENDDATA)", file=name,
                        line=min(bulk[-1][0] + 1, lines[-1][0]) if bulk else lines[-1][0])
    tables, skipped = _bulk_tables(raw_cards, name)
    deck = Deck(path=name, subcases=subcases, global_case=global_case, skipped=skipped, **tables)
    _validate(deck, selections)
    return deck


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
})


# ----------------------------------------------------------------------------------------------
# Cards

def _vec(f: Fields, d: int, names: tuple[str, str, str]) -> tuple[float, float, float]:
    return (f.real(d, names[0], 0.0), f.real(d + 1, names[1], 0.0), f.real(d + 2, names[2], 0.0))


def _grid(f: Fields, src: Source) -> Grid:
    gid = f.ident(1, "ID")
    cp = f.integer(2, "CP", 0, minimum=0)
    xyz = _vec(f, 3, ("X1", "X2", "X3"))
    cd = f.integer(6, "CD", 0, minimum=0)
    ps = f.components(7, "PS", "")
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


def _cbar(f: Fields, src: Source) -> CBar:
    eid = f.ident(1, "EID")
    pid = f.integer(2, "PID", eid, minimum=1)
    ga, gb = f.integer(3, "GA", minimum=1), f.integer(4, "GB", minimum=1)
    if ga == gb:
        raise f.error(f"GA and GB are both grid {ga} (expected two different grids)", 3, "GA, GB", 4)
    v: tuple[float, float, float] | None = None
    g0: int | None = None
    # NASTRAN: an integer X1 with X2, X3 blank is the orientation grid G0.
    if parse_int(f.text(5)) is not None and not f.text(6) and not f.text(7):
        g0 = f.integer(5, "G0", minimum=1)
        if g0 in (ga, gb):
            raise f.error(f"G0 is grid {g0}, an end of the bar (expected a third grid)", 5, "G0")
    elif not (f.text(5) or f.text(6) or f.text(7)):
        raise f.error("orientation is blank (expected G0 or X1, X2, X3)", 5, "X1-X3", 7)
    else:
        v = _vec(f, 5, ("X1", "X2", "X3"))
        if v == (0.0, 0.0, 0.0):
            raise f.error("orientation vector is zero (expected a vector off the bar axis)", 5, "X1-X3", 7)
    offt = f.word(8, "OFFT", "GGG")
    if offt != "GGG":
        raise f.error(f"OFFT {offt!r} is not supported by mace-fmu (expected blank or GGG)", 8, "OFFT")
    for d, name in ((9, "PA"), (10, "PB")):
        if f.text(d) not in ("", "0"):
            raise f.error(f"pin flags are not supported by mace-fmu (got {f.text(d)!r}, expected blank or 0)", d, name)
    for d, name in enumerate(("W1A", "W2A", "W3A", "W1B", "W2B", "W3B"), start=11):
        if f.real(d, name, 0.0) != 0.0:
            raise f.error(f"offsets are not supported by mace-fmu (got {f.text(d)!r}, expected blank or 0.0)", d, name)
    f.end(16)
    return CBar(id=eid, pid=pid, ga=ga, gb=gb, v=v, g0=g0, source=src)


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


_PARSERS: dict[str, Callable[[Fields, Source], Any]] = {
    "GRID": _grid, "CORD2R": _cord2r, "CBAR": _cbar, "PBAR": _pbar, "MAT1": _mat1, "CONM2": _conm2,
    "CELAS2": _celas2, "MPC": _mpc, "SPC1": _spc1, "SPC": _spc, "GRAV": _grav, "LOAD": _load, "EIGRL": _eigrl,
    "NLPARM": _nlparm, "PARAM": _param}
_TABLES = {"GRID": "grids", "CORD2R": "coords", "CBAR": "bars", "PBAR": "pbars", "MAT1": "mat1s",
           "CONM2": "conm2s", "CELAS2": "celas2s", "GRAV": "gravs", "LOAD": "loads", "EIGRL": "eigrls",
           "NLPARM": "nlparms", "PARAM": "params"}
_ELEMENTS = ("CBAR", "CONM2", "CELAS2")  # one ID namespace in NASTRAN


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
    for raw in raw_cards:
        if raw.name in NON_STRUCTURAL and raw.name not in _PARSERS:
            continue
        parser = _PARSERS[raw.name]
        card = parser(Fields(raw, file), Source(raw.file or file, raw.line))
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
        key = card.name if raw.name == "PARAM" else card.sid if hasattr(card, "sid") else card.id
        table = tables[_TABLES[raw.name]]
        if key in table:
            raise DeckError(f"{raw.name} {key} defined twice: line {table[key].source.line} and line {raw.line}",
                            file=raw.file or file, line=raw.line, card=f"{raw.name} {key}")
        if raw.name in _ELEMENTS:
            if key in elements:
                kind, other = elements[key]
                raise DeckError(f"element ID {key} is used twice: {kind} at line {other.source.line} and {raw.name} "
                                f"at line {raw.line} (CBAR, CONM2 and CELAS2 share one ID namespace)",
                                file=raw.file or file, line=raw.line, card=f"{raw.name} {key}")
            elements[key] = (raw.name, card)
        table[key] = card
    # MSC rule: grids of a THRU range that do not exist are skipped.
    for index, item in thru:
        group = sets["spc1s"][item.card.sid]
        grids = tuple(g for g in sorted(tables["grids"]) if item.first <= g <= item.last)
        if not grids:
            raise DeckError(f"no GRID exists in {item.first} THRU {item.last} (expected at least one)", file=file,
                            line=item.card.source.line, card=f"SPC1 {item.card.sid}", field="fields 4-6 (G1 THRU G2)")
        group[index] = replace(item.card, grids=grids)
    report = tuple((n, len(rs), f"{rs[0].file or file}:{rs[0].line}") for n, rs in sorted(skipped.items()))
    return {**tables, **{name: {sid: tuple(cards) for sid, cards in group.items()} for name, group in sets.items()}}, \
        report


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
    """Bars need a length and an orientation vector off their axis (positions in basic)."""
    pos = grid_positions(deck, frames)
    for b in deck.bars.values():
        axis = pos[b.gb] - pos[b.ga]
        length = float(np.linalg.norm(axis))
        if length < 1e-9:
            raise _fail(b, f"CBAR {b.id}", "fields 4-5 (GA, GB)", f"zero length: grids {b.ga} and {b.gb} are both "
                        f"at {tuple(round(float(x), 9) for x in pos[b.ga])} (expected distinct positions)")
        v = bar_orientation(deck, b, pos, frames)
        where = "field 6 (G0)" if b.g0 is not None else "fields 6-8 (X1-X3)"
        if np.linalg.norm(np.cross(axis, v)) <= 1e-6 * length * np.linalg.norm(v):
            raise _fail(b, f"CBAR {b.id}", where, "orientation vector is parallel to the bar axis (expected a "
                        "vector that defines the element x-y plane)")


_TARGETS = {"SPC": (("spc1s",), "an SPC1 set ID"), "MPC": (("mpcs",), "an MPC set ID"),
            "LOAD": (("loads", "gravs"), "a LOAD or GRAV set ID"), "NLPARM": (("nlparms",), "an NLPARM ID"),
            "METHOD": (("eigrls",), "an EIGRL set ID")}


def _check_selections(deck: Deck, selections: Selections) -> None:
    """Sets selected by the subcases (or by the global case when there are none) must exist."""
    cases = list(deck.subcases) or ([0] if deck.global_case is not None else [])
    for cid in cases:
        for key, (value, line) in selections[cid].items():
            if key in _TARGETS and not any(value in getattr(deck, t) for t in _TARGETS[key][0]):
                raise DeckError(f"{key} set {value} is not defined (expected {_TARGETS[key][1]})", file=deck.path,
                                line=line, card=f"SUBCASE {cid}" if cid else "global case control", field=key)
