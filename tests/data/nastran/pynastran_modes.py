"""Write what pyNastran reads from an OP2's real eigenvectors as pynastran_modes.csv (run once per model).

Usage (in an environment of its own: pyNastran pins numpy < 2, which mace-fmu does not use):
    python -m venv /tmp/pyn && /tmp/pyn/bin/pip install pyNastran==1.4.1
    /tmp/pyn/bin/python pynastran_modes.py MODEL.op2 OUT_DIR

OUT_DIR/pynastran_modes.csv: one row per mode and grid, the eigenvector as pyNastran holds it (in each grid's
CD system) and, when the OP2 has its geometry, as pyNastran's transform_displacements_to_global puts it in basic.
OUT_DIR/pynastran_eigenvalues.csv: mode, eigenvalue and generalized mass of pyNastran's LAMA (when present),
else the eigenvalue of each vector's header. (Grid positions are not taken from pyNastran: for gpsc1's CORD2C,
whose RID is another system, pyNastran 1.4.1 puts the 18 grids given in it elsewhere than NASTRAN's own BGPDT
does; the tests use the BGPDT.) This is the independent reader the tests compare ours with.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pyNastran
from pyNastran.op2.op2_geom import read_op2_geom


def main(op2: str, out: str) -> None:
    model = read_op2_geom(op2, debug=None, build_dataframe=False)
    (subcase, vectors), = model.eigenvectors.items()
    raw = np.array(vectors.data, dtype=float)  # (n_modes, n_grid, 6) in the CD systems
    grids = vectors.node_gridtype[:, 0]
    basic = None
    if model.nodes:
        model.cross_reference()
        index = model.get_displacement_index()
        if index:  # empty when every grid's CD is basic
            xyz_cid0 = model.get_xyz_in_coord(cid=0)
            model.transform_displacements_to_global(index[2], model.coords, xyz_cid0=xyz_cid0)
        basic = np.array(model.eigenvectors[subcase].data, dtype=float)
    header = f"# pyNastran {pyNastran.__version__} reading {Path(op2).name} (subcase {subcase})\n"
    rows = ["mode,grid," + ",".join(f"cd_{c}" for c in ("t1", "t2", "t3", "r1", "r2", "r3"))
            + ("," + ",".join(f"basic_{c}" for c in ("t1", "t2", "t3", "r1", "r2", "r3")) if basic is not None else "")]
    for m, mode in enumerate(vectors.modes):
        for g, gid in enumerate(grids):
            values = list(raw[m, g]) + (list(basic[m, g]) if basic is not None else [])
            rows.append(f"{mode},{gid}," + ",".join(f"{v:.9g}" for v in values))
    Path(out, "pynastran_modes.csv").write_text(header + "\n".join(rows) + "\n")
    lines = [header.rstrip(), "mode,eigenvalue,generalized_mass"]
    if model.eigenvalues:
        (lama,) = model.eigenvalues.values()
        lines += [f"{m},{e:.9g},{g:.9g}" for m, e, g in zip(lama.mode, lama.eigenvalues, lama.generalized_mass)]
    else:
        lines += [f"{m},{e:.9g}," for m, e in zip(vectors.modes, vectors.eigns)]
    Path(out, "pynastran_eigenvalues.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main(*sys.argv[1:])
