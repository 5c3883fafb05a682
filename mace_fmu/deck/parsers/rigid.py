"""Parsers of the rigid elements: RBAR and RBE2 (rigid links) and RBE3 (a weighted-average interpolation).

Field layouts and defaults are those of the cards' entries in the MSC Nastran Quick Reference Guide (QRG).
"""

from __future__ import annotations

from mace_fmu.deck.cards import Interpolation, Rigid, Source
from mace_fmu.deck.fields import Fields, parse_int


def rbar(f: Fields, src: Source) -> Rigid:
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


def rbe2(f: Fields, src: Source) -> Rigid:
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


def rbe3(f: Fields, src: Source) -> Interpolation:
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
