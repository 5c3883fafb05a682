"""Where a measured DOF is on the model: the model DOFs (grid, component, weight) a test's channel reads.

A channel's DOFs come from, in this order: a DOF map (TOML, ``"<channel>" = [[grid, component, weight], ...]``),
the modes file's own ``at`` (written by ``mace-fmu ema --structure``), the structure file's sensor of that name (its
``dofs``), or the name itself when it is a node and direction as UFF files name channels ("101+Z", "7-RX").
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Mapping, Sequence

from mace_fmu.errors import MaceError
from mace_fmu.updating.modal.modes_file import Dof, MeasuredDof
from mace_fmu.util.textfile import read_toml

#: a channel named by node and direction, as the UFF reader names channels without ID lines
NODE_DIRECTION = re.compile(r"^(\d+)([+-])(X|Y|Z|RX|RY|RZ)$")
_COMPONENT = {"X": 1, "Y": 2, "Z": 3, "RX": 4, "RY": 5, "RZ": 6}


def dofs_of_name(name: str) -> tuple[Dof, ...] | None:
    """((grid, component, +-1),) of a node-and-direction name ("101+Z" -> ((101, 3, 1.0),)), else None."""
    m = NODE_DIRECTION.match(name.strip())
    if not m:
        return None
    return ((int(m.group(1)), _COMPONENT[m.group(3)], 1.0 if m.group(2) == "+" else -1.0),)


def read_dof_map(path: str | Path) -> dict[str, tuple[Dof, ...]]:
    """A DOF map: ``"<channel>" = [[grid, component, weight], ...]`` per channel (TOML)."""
    data = read_toml(path, what="DOF map")
    out = {}
    for name, value in data.items():
        ok = isinstance(value, list) and value and all(
            isinstance(x, list) and len(x) == 3 and isinstance(x[0], int) and isinstance(x[1], int)
            and 1 <= x[1] <= 6 and isinstance(x[2], (int, float)) and not isinstance(x[2], bool) for x in value)
        if not ok:
            raise MaceError(f"{path}: {name!r} = {value!r}, expected [[grid, component 1-6, weight], ...]")
        out[name] = tuple((int(g), int(c), float(w)) for g, c, w in value)
    return out


def resolve_dofs(dofs: Sequence[MeasuredDof], *, sensors: Mapping[str, tuple[Dof, ...]] | None = None,
                 dof_map: Mapping[str, tuple[Dof, ...]] | None = None, source: str = "") -> tuple[tuple[Dof, ...], ...]:
    """The model DOFs each measured DOF reads (see the module docstring); a channel none of them places is an
    error that names it and the ways to place it."""
    out = []
    for d in dofs:
        found = ((dof_map or {}).get(d.name) or d.at or (sensors or {}).get(d.name) or dofs_of_name(d.name))
        if not found:
            raise MaceError(f"{source + ': ' if source else ''}measured DOF {d.name!r}: where is it on the model? "
                            "Not a sensor of the structure file, no node and direction (e.g. '101+Z'), not in a DOF map "
                            "(--dof-map FILE: \"<channel>\" = [[grid, component, weight]])")
        out.append(tuple(found))
    return tuple(out)


def driving_points(inputs: Sequence[str], outputs: Sequence[str], *,
                   actuators: Mapping[str, tuple[Dof, ...]] | None = None,
                   sensors: Mapping[str, tuple[Dof, ...]] | None = None) -> dict[str, str]:
    """Input -> the output measured at its DOF: the same name ("101+X" both), the same node and direction, or an
    actuator and a sensor of the structure file on the same DOFs with the same weights."""
    out = {}
    for i in inputs:
        place = (actuators or {}).get(i) or dofs_of_name(i)
        for o in outputs:
            there = (sensors or {}).get(o) or dofs_of_name(o)
            if o == i or (place and there and sorted(place) == sorted(there)):
                out[i] = o
                break
    return out
