"""NASTRAN's automatic constraint of singular DOFs (PARAM,AUTOSPC): DOFs with neither stiffness nor mass.

A grid attached to nothing, or the rotations of a grid that only rods and springs reach, have
zero stiffness: the static solution is singular and the eigen-solution finds nothing but a
zero-mass, zero-stiffness null space. NASTRAN constrains such DOFs automatically (AUTOSPC = YES,
its default in the modal solutions) and lists them; so does this. A deck that sets
PARAM,AUTOSPC,NO (as the MACE deck does) keeps every DOF, and a singular DOF is then an error
naming it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mace_fmu.deck.cards import Deck
from mace_fmu.fe.constraints import Constraints

#: a diagonal entry at most this fraction of the largest counts as zero
RELATIVE_ZERO = 1e-12


def autospc_enabled(deck: Deck) -> bool:
    """PARAM,AUTOSPC of the deck: on unless set to NO (NASTRAN's default for the modal solutions)."""
    param = deck.params.get("AUTOSPC")
    return param is None or str(param.values[0]).strip().upper() != "NO"


def constrain_singular_dofs(constraints: Constraints, stiffness, mass=None
                            ) -> tuple[Constraints, tuple[tuple[int, int], ...]]:
    """``constraints`` without the independent DOFs that have zero stiffness (and zero mass, when ``mass``
    is given), and those DOFs as (grid, component)."""
    k = constraints.reduce_sparse(stiffness).diagonal()
    singular = np.abs(k) <= RELATIVE_ZERO * max(float(np.abs(k).max()), 1e-300)
    if mass is not None:
        m = constraints.reduce_sparse(mass).diagonal()
        singular &= np.abs(m) <= RELATIVE_ZERO * max(float(np.abs(m).max()), 1e-300)
    if not singular.any():
        return constraints, ()
    keep = np.flatnonzero(~singular)
    removed = tuple(constraints.independent[i] for i in np.flatnonzero(singular))
    return replace(constraints, transform=constraints.transform[:, keep],
                   independent=tuple(constraints.independent[i] for i in keep)), removed


def describe_dofs(dofs: tuple[tuple[int, int], ...]) -> str:
    """'grid 99 (1-6), grid 7 (4, 5)': DOFs grouped by grid, for reports and messages."""
    by_grid: dict[int, list[int]] = {}
    for g, c in dofs:
        by_grid.setdefault(int(g), []).append(int(c))
    parts = []
    for g, comps in sorted(by_grid.items()):
        comps = sorted(comps)
        text = "1-6" if comps == [1, 2, 3, 4, 5, 6] else ", ".join(map(str, comps))
        parts.append(f"grid {g} ({text})")
    return ", ".join(parts)
