"""The public NASTRAN SOL 103 results the reader is proven on (tests/data/nastran, provenance.toml) and their
independent readings: NASTRAN's own .f06 printout (tests/support/f06_modes.py) and pyNastran 1.4.1, run once
in an environment of its own (tests/data/nastran/pynastran_modes.py wrote the pynastran_*.csv files)."""

from __future__ import annotations

import numpy as np

from support.paths import DATA

NASTRAN = DATA / "nastran"

#: model -> (OP2, f06 or None, what the model is)
MODELS = {
    # SOL 103, MSC: CHEXA, CPENTA, CTETRA, CQUAD4, CTRIA3, CBAR, CBEAM, CROD; 25 grids, 3 modes; no LAMA in the OP2
    "solid_shell_bar": ("mode_solid_shell_bar.op2", "mode_solid_shell_bar.f06"),
    # the General Purpose SpaceCraft: CQUAD4, CTRIA3, CBAR, CONM2; 51 grids, 18 of them given in a CORD2C; 17 modes
    "gpsc1": ("gpsc1.op2", None),
    # SOL SEMODES (103), Femap: a free CQUAD4 plate of 231 grids, 10 modes (6 rigid-body); no geometry, no LAMA
    "plate_py": ("plate_py.op2", None),
    # SOL 103, Simcenter: the CBAR/CBEAM cantilever that the FE core also solves; NORM=MAX (generalized masses != 1)
    "beam_modes_op2": ("beam_modes_m1.op2", "beam_modes.f06"),
}


def op2_path(model: str):
    return NASTRAN / model / MODELS[model][0]


def pynastran_vectors(model: str) -> dict[str, np.ndarray]:
    """pyNastran's reading: columns mode, grid, cd_t1 .. cd_r3[, basic_t1 .. basic_r3] as arrays."""
    path = NASTRAN / model / "pynastran_modes.csv"
    names = path.read_text().splitlines()[1].split(",")
    table = np.loadtxt(path, delimiter=",", skiprows=2)
    return {name: table[:, k] for k, name in enumerate(names)}


def pynastran_eigenvalues(model: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(modes, eigenvalues, generalized masses or None) as pyNastran read them."""
    path = NASTRAN / model / "pynastran_eigenvalues.csv"
    rows = [line.split(",") for line in path.read_text().splitlines()[2:]]
    masses = None if rows[0][2] == "" else np.array([float(r[2]) for r in rows])
    return np.array([int(r[0]) for r in rows]), np.array([float(r[1]) for r in rows]), masses
