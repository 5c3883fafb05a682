"""Real eigenvectors from a NASTRAN punch file (``.pch``: DISPLACEMENT(PUNCH) or VECTOR(PUNCH) in SOL 103).

Each mode is a block of 80-column lines (columns 73-80 a line counter)::

    $EIGENVECTOR
    $REAL OUTPUT
    $SUBCASE ID =           1
    $EIGENVALUE =  8.2327765E+06  MODE =     1
             2       G      1.500483E-18     -3.315288E-03      1.857573E-02
    -CONT-                  5.360878E-18     -3.055872E-02     -5.453943E-03

a grid's T1 T2 T3 on its line and R1 R2 R3 on the continuation, in the grid's displacement (CD) system.
A punch file carries no generalized masses and no geometry. Scalar and extra points (type S, E) are
left out, as in the OP2 reader.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.nastran_modes.file_modes import FileModes

_EIGENVALUE = re.compile(r"^\$EIGENVALUE\s*=\s*(\S+)\s+MODE\s*=\s*(\d+)")
_SUBCASE = re.compile(r"^\$SUBCASE ID\s*=\s*(\d+)")


def read_punch_modes(path: Path, *, subcase: int | None) -> FileModes:
    """The real eigenvectors of one subcase of the punch file at ``path`` (the only one when None).

    MaceError (one line: file, line, block) for a file without real eigenvectors, complex ones, a line that
    is not a number where one belongs, or a grid whose rotations (the -CONT- line) are missing.
    """
    lines = path.read_text(encoding="latin-1").splitlines()
    modes: dict[int, list[tuple[int, float, dict[int, np.ndarray]]]] = {}
    skipped: set[int] = set()
    kind = ""
    current_subcase = 1
    vectors: dict[int, np.ndarray] | None = None
    k = 0
    while k < len(lines):
        text = lines[k][:72].rstrip()
        k += 1
        if text.startswith("$"):
            vectors = None
            if text.startswith(("$EIGENVECTOR", "$DISPLACEMENTS", "$VELOCITY", "$ACCELERATION", "$SPCF", "$ELEMENT")):
                kind = text[1:].strip()
            elif text.startswith(("$REAL-IMAGINARY", "$MAGNITUDE-PHASE")):
                if kind == "EIGENVECTOR":
                    raise MaceError(f"{path}:{k}: $EIGENVECTOR block: complex eigenvectors (expected real ones: "
                                    "the punch of a SOL 103 run)")
            elif match := _SUBCASE.match(text):
                current_subcase = int(match.group(1))
            elif (match := _EIGENVALUE.match(text)) and kind == "EIGENVECTOR":
                vectors = {}
                modes.setdefault(current_subcase, []).append(
                    (int(match.group(2)), _number(path, k, match.group(1), "$EIGENVALUE"), vectors))
            continue
        if vectors is None or not text.strip():
            continue
        fields = text.split()
        if fields[0] == "-CONT-":
            continue  # a continuation of a scalar point's line or of a block not read
        gid, point_type = _integer(path, k, fields[0]), fields[1] if len(fields) > 1 else ""
        if point_type != "G":
            skipped.add(gid)
            continue
        rotations = lines[k][:72].split() if k < len(lines) else []
        if not rotations or rotations[0] != "-CONT-":
            raise MaceError(f"{path}:{k + 1}: $EIGENVECTOR block, grid {gid}: expected the -CONT- line with R1 R2 "
                            "R3 after the grid's T1 T2 T3 line")
        if len(fields) != 5 or len(rotations) != 4:
            raise MaceError(f"{path}:{k}: $EIGENVECTOR block, grid {gid}: {len(fields) - 2} and {len(rotations) - 1} "
                            "components (expected T1 T2 T3 on the grid's line and R1 R2 R3 on its -CONT- line)")
        vectors[gid] = np.array([_number(path, k, v, f"grid {gid}") for v in fields[2:5]]
                                + [_number(path, k + 1, v, f"grid {gid}") for v in rotations[1:4]])
        k += 1
    if not modes and not any(line.startswith("$") for line in lines):
        raise MaceError(f"{path}: a text file without a punch file's $ lines ($TITLE, $EIGENVECTOR, ...): neither a "
                        "punch file nor an OP2 (expected a binary OP2 or the punch file of a SOL 103 run, whatever "
                        "the file's name)")
    return _assemble(path, modes, skipped, subcase)


def _assemble(path: Path, modes: dict[int, Any], skipped: set[int], subcase: int | None) -> FileModes:
    if not modes:
        raise MaceError(f"{path}: no $EIGENVECTOR block with $REAL OUTPUT (expected the punch of a SOL 103 run: "
                        "DISPLACEMENT(PUNCH)=ALL in the case control)")
    if subcase is None:
        if len(modes) > 1:
            raise MaceError(f"{path}: eigenvectors of subcases {sorted(modes)} (expected one: choose it with subcase=)")
        subcase = next(iter(modes))
    if subcase not in modes:
        raise MaceError(f"{path}: no eigenvectors of subcase {subcase} (the file has subcases {sorted(modes)})")
    blocks = modes[subcase]
    grid_ids = np.array(sorted(blocks[0][2]), dtype=int)
    columns = []
    for mode, _, vectors in blocks:
        if sorted(vectors) != list(grid_ids):
            raise MaceError(f"{path}: $EIGENVECTOR block of mode {mode}: its grids differ from those of mode "
                            f"{blocks[0][0]} (expected the same {len(grid_ids)} grids in every mode)")
        columns.append(np.array([vectors[g] for g in grid_ids]))
    return FileModes(source=path, subcase=subcase, grid_ids=grid_ids, vectors=np.stack(columns, axis=2), frame="cd",
                     mode_numbers=np.array([b[0] for b in blocks]), eigenvalues=np.array([b[1] for b in blocks]),
                     generalized_masses=None, skipped_points=tuple(sorted(skipped)), geometry=None,
                     where="$EIGENVECTOR blocks", eigenvalues_from="$EIGENVALUE lines")


def _number(path: Path, line: int, text: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise MaceError(f"{path}:{line}: {where}: {text!r} is not a number (expected a real such as "
                        "1.234567E-03)") from None


def _integer(path: Path, line: int, text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise MaceError(f"{path}:{line}: $EIGENVECTOR block: {text!r} is not a grid ID (expected an integer, or "
                        "-CONT-)") from None
