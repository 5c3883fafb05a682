"""A test oracle: NASTRAN's real eigenvalue table and eigenvector printout, read from an .f06 as printed.

Independent of mace_fmu.nastran_modes (it reads the text NASTRAN printed, not the binary tables); the numbers
keep NASTRAN's 7 printed digits.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class PrintedModes:
    """The first REAL EIGENVALUES table and the REAL EIGENVECTOR printout of an .f06."""

    modes: np.ndarray  #: mode numbers of the eigenvalue table
    eigenvalues: np.ndarray  #: [rad^2/s^2]
    cycles: np.ndarray  #: [Hz]
    generalized_masses: np.ndarray
    vectors: dict[int, dict[int, np.ndarray]]  #: mode -> grid -> T1 T2 T3 R1 R2 R3 in the grid's CD system


def read_f06_modes(path: Path) -> PrintedModes:
    lines = path.read_text(encoding="latin-1").splitlines()
    start = next(k for k, line in enumerate(lines) if "R E A L   E I G E N V A L U E S" in line)
    rows = []
    for line in lines[start + 1:]:
        parts = line.split()
        if len(parts) == 7 and parts[0].isdigit() and parts[1].isdigit():
            rows.append([float(p) for p in parts])
        elif rows:
            break
    table = np.array(rows)
    vectors: dict[int, dict[int, np.ndarray]] = {}
    mode = None
    for line in lines:
        if "R E A L   E I G E N V E C T O R   N O ." in line:
            mode = int(line.split()[-1])
            vectors.setdefault(mode, {})
            continue
        if line.startswith("1"):  # a new page: the printout goes on only under a new heading
            mode = None
            continue
        parts = line.split()
        if mode is not None and len(parts) == 8 and parts[0].isdigit() and parts[1] == "G":
            vectors[mode][int(parts[0])] = np.array([float(p) for p in parts[2:]])
    return PrintedModes(modes=table[:, 0].astype(int), eigenvalues=table[:, 2], cycles=table[:, 4],
                        generalized_masses=table[:, 5], vectors=vectors)
