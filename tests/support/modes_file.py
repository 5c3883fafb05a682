"""NASTRAN's modes for the tests of the [modes] route: public OP2 runs with a structure file naming them, and
a deck's modes in the reader's form (``read_nastran_modes``'s NastranModes) where a test needs the FE as well
(a direct solve of K, M to compare with, or a residual flexibility from K^-1).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mace_fmu.fe.modal import Modes
from mace_fmu.fe.modes import StructureModes
from support.paths import ROOT


@dataclass(frozen=True)
class ReadModes:
    """The fields of ``mace_fmu.nastran_modes.NastranModes``."""

    modes: Modes
    eigenvalues: np.ndarray
    generalized_masses: np.ndarray
    normalisation: str
    grid_positions: dict[int, np.ndarray] | None
    source: Path
    units: str


def read_modes_of(fe: StructureModes, source: Path) -> ReadModes:
    """``fe``'s modes as the reader would return them from the file ``source``."""
    m = fe.modes
    positions = {g: fe.model.positions[fe.model.dofs.grid_index(g)] for g in m.dofs.grid_ids}
    return ReadModes(modes=Modes(frequencies_hz=m.frequencies_hz, shapes=m.shapes, dofs=m.dofs, cd_frames=m.cd_frames),
                     eigenvalues=(2 * np.pi * m.frequencies_hz) ** 2, generalized_masses=np.ones(len(m)),
                     normalisation="MASS", grid_positions=positions, source=source, units="SI")


DATA = ROOT / "tests" / "data" / "nastran"
#: model -> (OP2, geometry deck, force DOF, sensor DOF): DOFs as (grid, component in CD)
RUNS = {
    "plate_py": ("plate_py/plate_py.op2", "plate_py/plate_py.dat", (231, 3), (116, 3)),
    "solid_shell_bar": ("solid_shell_bar/mode_solid_shell_bar.op2", "solid_shell_bar/mode_solid_shell_bar.bdf",
                        (21, 2), (13, 1)),
}


def op2_structure_file(tmp_path: Path, run: str, *, zeta: float = 0.015) -> Path:
    """A structure file whose [modes] table names the OP2 and the deck of one of RUNS, with a force and two sensors
    (displacement and acceleration) on its two DOFs."""
    op2, deck, force, sensor = RUNS[run]
    text = f"""
[modes]
file = "{(DATA / op2).as_posix()}"
geometry = "{(DATA / deck).as_posix()}"

[[actuators]]
name = "shaker"
description = "force"
dofs = [[{force[0]}, {force[1]}, 1.0]]

[[sensors]]
name = "displacement"
description = "displacement sensor"
kind = "displacement"
dofs = [[{sensor[0]}, {sensor[1]}, 1.0]]

[[sensors]]
name = "accelerometer"
description = "accelerometer"
kind = "acceleration"
dofs = [[{sensor[0]}, {sensor[1]}, 1.0]]

[damping]
default = {zeta}
"""
    path = tmp_path / f"{run}.toml"
    path.write_text(text)
    return path
