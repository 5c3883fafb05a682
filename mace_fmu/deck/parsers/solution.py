"""Parsers of the cards that steer a solution: GRAV and LOAD, EIGRL and EIGR, NLPARM, and PARAM.

Field layouts and defaults are those of the cards' entries in the MSC Nastran Quick Reference Guide (QRG).
"""

from __future__ import annotations

import re

from mace_fmu.deck.cards import Eigr, Eigrl, Grav, Load, Nlparm, Param, Source
from mace_fmu.deck.fields import Fields, parse_int, parse_real
from mace_fmu.deck.parsers.layouts import vec


def grav(f: Fields, src: Source) -> Grav:
    """GRAV (QRG): SID CID A N1 N2 N3 MB: acceleration A along direction N in system CID."""
    sid = f.ident(1, "SID")
    cid = f.integer(2, "CID", 0, minimum=0)
    scale = f.real(3, "A")
    direction = vec(f, 4, ("N1", "N2", "N3"))
    if f.integer(7, "MB", 0, minimum=-1) > 0:
        raise f.error(f"expected -1 or 0, got {f.text(7)!r}", 7, "MB")
    f.end(7)
    if direction == (0.0, 0.0, 0.0):
        raise f.error("direction vector is zero (expected N1, N2, N3 not all 0.0)", 4, "N1-N3", 6)
    return Grav(sid=sid, cid=cid, scale=scale, direction=direction, source=src)


def load(f: Fields, src: Source) -> Load:
    """LOAD (QRG): SID S S1 L1 S2 L2 ...: the sets Li scaled by Si, all scaled by S."""
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


def eigrl(f: Fields, src: Source) -> Eigrl:
    """EIGRL (QRG): SID V1 V2 ND MSGLVL: modes in [V1, V2] Hz, at most ND of them."""
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


_EIGR_METHODS = ("LAN", "AHOU", "HOU", "MHOU", "GIV", "MGIV", "INV", "SINV")


def eigr(f: Fields, src: Source) -> Eigr:
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


def nlparm(f: Fields, src: Source) -> Nlparm:
    """NLPARM (QRG): ID NINC DT KMETHOD KSTEP MAXITER CONV INTOUT; EPSU EPSP EPSW MAXDIV ... LSTOL."""
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


def param(f: Fields, src: Source) -> Param:
    """PARAM (QRG): N V1 V2 (WTMASS must be a positive number)."""
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
