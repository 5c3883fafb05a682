"""The ``[modes]`` table of a structure file: NASTRAN's normal modes instead of a deck.

A structure file with ``[modes]`` describes a structure known by the modes NASTRAN computed (a
SOL 103 OP2 or punch file), not by a deck this tool solves::

    [modes]
    file = "plate.op2"                  # NASTRAN's eigenvectors (OP2 or .pch), relative to this file
    subcase = 1                          # optional: the SOL 103 subcase (default: the only one)
    geometry = "plate.bdf"               # optional: the deck, read for drawing only (grids, element edges)
    residual_flexibility = "resflex.csv" # optional: static correction for the modes not in the file
    normalisation = "mass"               # optional: the vectors are mass-normalised, for a file that cannot show it

Paths are relative to the structure file's folder. Everything else in the file (actuators, sensors,
electronics, servos, damping) means what it means for a deck; the damping table's labels are
``"mode 1"``, ``"mode 2"``, ... (the modes' order in the file).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mace_fmu.errors import MaceError
from mace_fmu.structure.file import StructureFile, _where
from mace_fmu.util.textfile import read_text

#: the keys of a ``[modes]`` table and what each holds
MODES_KEYS = {
    "file": "NASTRAN's normal modes: a SOL 103 OP2 or punch (.pch) file",
    "subcase": "the SOL 103 subcase whose modes to take (default: the file's only one)",
    "geometry": "a deck whose grids and elements are drawn (read for drawing only; no FE is built)",
    "residual_flexibility": "a CSV of the static flexibility of the modes not in the file, between instrument DOFs",
    "normalisation": "\"mass\": the vectors are mass-normalised, stated for a file without generalized masses (no LAMA "
                     "table, a punch file) whose vectors look normalised otherwise",
}


@dataclass(frozen=True)
class ModesTable:
    """What a structure file's ``[modes]`` table says, its paths resolved against the file's folder."""

    file: Path  #: NASTRAN's normal modes (OP2 or punch)
    subcase: int | None  #: the SOL 103 subcase (None: the file's only one)
    geometry: Path | None  #: a deck read for drawing only (None: nothing to draw but what the modes file gives)
    residual_flexibility: Path | None  #: static correction CSV (None: none)
    source: Path  #: the structure file
    normalisation: str | None = None  #: "mass": the user states the vectors are mass-normalised (None: not stated)


def modes_table(file: StructureFile) -> ModesTable | None:
    """The ``[modes]`` table of a structure file, checked; None when the file has none (a deck's structure file).

    Parameters
    ----------
    file : StructureFile
        The structure file, read (:func:`~mace_fmu.structure.file.load_structure_file`).

    Returns
    -------
    ModesTable or None
        The modes file, subcase, drawing geometry and residual flexibility, paths resolved.

    Raises
    ------
    MaceError
        One line naming the structure file, its line and the key that is wrong, and what was expected.
    """
    if not file.has("modes"):
        return None
    table = file.tables["modes"]
    text = read_text(file.path, what="structure")
    where = _where(file.path, text, "modes")
    if not isinstance(table, dict):
        raise MaceError(f"{where}: expected a table with the keys {', '.join(MODES_KEYS)}, got {table!r}")
    unknown = sorted(set(table) - set(MODES_KEYS))
    if unknown:
        raise MaceError(f"{where}: unknown key {unknown[0]!r}; [modes] takes "
                        + "; ".join(f"{k} ({v})" for k, v in MODES_KEYS.items()))
    if "file" not in table:
        raise MaceError(f"{where}: needs file = \"<NASTRAN's modes>.op2\" (or a .pch punch file)")
    subcase = table.get("subcase")
    if subcase is not None and (isinstance(subcase, bool) or not isinstance(subcase, int) or subcase < 1):
        raise MaceError(f"{where}: subcase must be a positive integer (a SUBCASE ID), got {subcase!r}")
    normalisation = table.get("normalisation")
    if normalisation is not None and normalisation != "mass":
        raise MaceError(f"{where}: normalisation must be \"mass\" (the statement that the file's vectors are "
                        f"mass-normalised), got {normalisation!r}")
    folder = file.path.parent

    def path_of(key: str, *, must_exist: bool = True) -> Path | None:
        value = table.get(key)
        if value is None:
            return None
        if not isinstance(value, str) or not value.strip():
            raise MaceError(f"{where}: {key} must be a file name (a string), got {value!r}")
        path = (folder / value).resolve() if not Path(value).is_absolute() else Path(value)
        if must_exist and not path.is_file():
            raise MaceError(f"{where}: {key} = {value!r}: no such file {path}")
        return path

    modes_file = path_of("file")
    assert modes_file is not None  # the table has a file (checked above)
    return ModesTable(file=modes_file, subcase=subcase, geometry=path_of("geometry"),
                      residual_flexibility=path_of("residual_flexibility"), source=file.path,
                      normalisation=normalisation)
