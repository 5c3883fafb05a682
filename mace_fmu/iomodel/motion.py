"""Names and units of grid motion outputs (``grid_<id>_<tx|ty|tz|rx|ry|rz>``, basic axes).

Kept apart from the state-space code so that readers of these names, such as the viewer, do
not import python-control.
"""

from __future__ import annotations

import re

#: Components of a grid's motion output, in DOF order (NASTRAN T1 T2 T3 R1 R2 R3), basic axes.
MOTION_COMPONENTS = ("tx", "ty", "tz", "rx", "ry", "rz")
_MOTION_NAME = re.compile(rf"grid_(\d+)_({'|'.join(MOTION_COMPONENTS)})")


def motion_output_name(grid: int, component: str) -> str:
    """Output name of one motion component of a grid, e.g. ``grid_1001_ty``."""
    return f"grid_{grid}_{component}"


def parse_motion_output(name: str) -> tuple[int, str] | None:
    """(grid, component) of a motion output name; None for any other signal."""
    match = _MOTION_NAME.fullmatch(name)
    return (int(match.group(1)), match.group(2)) if match else None


def motion_unit(component: str) -> str:
    """SI unit of a motion component: metres for translations, radians for rotations."""
    return "m" if component.startswith("t") else "rad"
