"""Cross-reference checks of a deck: the IDs cards name, MPC dependent DOFs, bar geometry, selected sets.

Each problem is a DeckError at the card (or, for a selection, the subcase) that names what is wrong.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mace_fmu.deck.cards import CBar, CBeam, Deck, Mpc
from mace_fmu.deck.fields import TEMPERATURE, Selections
from mace_fmu.deck.geometry import Frame, bar_orientations, coordinate_frames, grid_positions
from mace_fmu.errors import DeckError


def _fail(card: Any, label: str, field: str | None, message: str) -> DeckError:
    return DeckError(message, file=card.source.file, line=card.source.line, card=label, field=field)


def _need(key: int | None, table: Any, card: Any, label: str, field: str, noun: str, expected: str) -> None:
    if key is not None and key not in table:
        raise _fail(card, label, field, f"{noun} {key} is not defined (expected {expected})")


def check_deck(deck: Deck) -> None:
    """Cross references, MPC dependent DOFs and bar geometry of a deck (also one changed in code).

    Parameters
    ----------
    deck : Deck
        The deck, as read or as changed since.

    Raises
    ------
    DeckError
        The first problem found, at the card that has it.
    """
    frames = coordinate_frames(deck)
    grid, coord = ("grid", "a GRID ID"), ("coordinate system", "0 or a CORD2R or CORD1R ID")
    for g in deck.grids.values():
        _need(g.cp, frames, g, f"GRID {g.id}", "field 3 (CP)", *coord)
        _need(g.cd, frames, g, f"GRID {g.id}", "field 7 (CD)", *coord)
    for name, elements, properties, expected in (("CBAR", deck.bars, deck.pbars, "a PBAR ID"),
                                                 ("CBEAM", deck.beams, deck.pbeams, "a PBEAM or PBEAML ID")):
        grids = deck.grids
        if all(b.pid in properties and b.ga in grids and b.gb in grids and (b.g0 is None or b.g0 in grids)
               for b in elements.values()):
            continue  # the usual case, without a label per bar (a large deck has 80,000)
        for b in elements.values():
            label = f"{name} {b.id}"
            _need(b.pid, properties, b, label, "field 3 (PID)", "property", expected)
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
            for k, gid in enumerate(spc.grids, start=1):
                _need(gid, deck.grids, spc, f"SPC1 {sid}", f"grid list (G{k})", *grid)
    for gr in deck.gravs.values():
        _need(gr.cid, frames, gr, f"GRAV {gr.sid}", "field 3 (CID)", *coord)
    for ld in deck.loads.values():
        for k, (_, lset) in enumerate(ld.terms, start=1):
            _need(lset, {**deck.static_loads, **deck.gravs}, ld, f"LOAD {ld.sid}", f"L{k}", "load set",
                  "a GRAV, FORCE, MOMENT or PLOAD SID")
    if (grdpnt := deck.params.get("GRDPNT")) is not None:
        value = grdpnt.values[0]
        if not isinstance(value, int) or value < -1:
            raise _fail(grdpnt, "PARAM GRDPNT", "field 3 (V1)", f"expected -1, 0 or a GRID ID, got {value!r}")
        _need(value if value > 0 else None, deck.grids, grdpnt, "PARAM GRDPNT", "field 3 (V1)", *grid)
    _check_mpc_dofs(deck)
    _check_bars(deck, frames)


def _check_new_elements(deck: Deck, grid: tuple[str, str]) -> None:
    """Cross references of PBEAM, CROD/CONROD, CMASS1/2, RBAR/RBE2 and their properties."""
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
    for prod in deck.prods.values():
        _need(prod.mid, deck.mat1s, prod, f"PROD {prod.id}", "field 3 (MID)", "material", "a MAT1 ID")
    for m in deck.scalar_masses.values():
        label = f"{m.card} {m.id}"
        if m.pid is not None:
            _need(m.pid, deck.pmasses, m, label, "field 3 (PID)", "property", "a PMASS ID")
        _need(m.g1, deck.grids, m, label, "field 4 (G1)", *grid)
        _need(m.g2, deck.grids, m, label, "field 6 (G2)", *grid)
    for conm in deck.conm1s.values():
        _need(conm.grid, deck.grids, conm, f"CONM1 {conm.id}", "field 3 (G)", *grid)
        _need(conm.cid if conm.cid > 0 else None, coordinate_frames(deck), conm, f"CONM1 {conm.id}", "field 4 (CID)",
              "coordinate system", "0 or a CORD2R or CORD1R ID")
    for rigid in deck.rigids.values():
        _need(rigid.independent, deck.grids, rigid, f"{rigid.card} {rigid.id}", "independent grid", *grid)
        for k, (gid, _) in enumerate(rigid.dependent, start=1):
            _need(gid, deck.grids, rigid, f"{rigid.card} {rigid.id}", f"dependent grid {k}", *grid)
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


def _check_bars(deck: Deck, frames: dict[int, Frame]) -> None:
    """Bars need a length and an orientation vector off their axis (positions in basic). Checked for all
    bars at once (a 100k-DOF deck has 70k bars), then the first offender in deck order is reported."""
    pos = grid_positions(deck, frames)
    bars: tuple[CBar | CBeam, ...] = (*deck.bars.values(), *deck.beams.values())
    if bars:
        axis = np.array([pos[b.gb] for b in bars]) - np.array([pos[b.ga] for b in bars])
        v = bar_orientations(deck, bars, pos, frames)
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
            "LOAD": (("loads", "gravs", "static_loads"), "a LOAD, GRAV, FORCE, MOMENT or PLOAD set ID"),
            "NLPARM": (("nlparms",), "an NLPARM ID"),
            "METHOD": (("eigrls", "eigrs"), "an EIGRL or EIGR set ID")}


def check_selections(deck: Deck, selections: Selections) -> None:
    """Sets selected by the subcases (or by the global case when there are none) must exist.

    Parameters
    ----------
    deck : Deck
        The deck the case control belongs to.
    selections : Selections
        The case control's set selections with their lines, by subcase (0: the global case).

    Raises
    ------
    DeckError
        A selected SPC, MPC, LOAD, NLPARM or METHOD set that the bulk data does not define.
    """
    cases = list(deck.subcases) or ([0] if deck.global_case is not None else [])
    dependent = [(n, where) for n, _, where in deck.skipped if n == "MATT1"]
    for cid in cases:
        if TEMPERATURE in selections[cid] and dependent:
            value, line = selections[cid][TEMPERATURE]
            raise DeckError(f"material temperatures {value} are selected, and MATT1 (first at {dependent[0][1]}) makes "
                            "a material depend on them: mace-fmu models temperature-independent materials (expected "
                            "no TEMP(MATERIAL) or TEMP(BOTH) selection, or no MATT1)", file=deck.path, line=line,
                            card=f"SUBCASE {cid}" if cid else "global case control", field="TEMP")
        for key, (value, line) in selections[cid].items():
            if key in _TARGETS and not any(value in getattr(deck, t) for t in _TARGETS[key][0]):
                raise DeckError(f"{key} set {value} is not defined (expected {_TARGETS[key][1]})", file=deck.path,
                                line=line, card=f"SUBCASE {cid}" if cid else "global case control", field=key)
