"""OP2 files made from the public ones of tests/data/nastran with one thing changed: their tables read with the
package's record layer (mace_fmu.nastran_modes.fortran), edited, and written back in the layout it documents
(an OP2 without the dated header, as PARAM,POST,-2 writes it; each data record in one block).

Only the tables a test keeps are written (the eigenvectors, LAMA, DYNAMICS, GEOM1): the reader reads no other.
``tests/nastran_modes/test_what_the_file_says.py`` checks first that a file written back unchanged gives the
same modes, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mace_fmu.nastran_modes.fortran import Op2Records

#: the tables the modes reader reads
KEPT = ("OUG", "BOUG", "OPHIG", "BOPHIG", "LAMA", "DYNAMIC", "GEOM1")


@dataclass
class Op2Table:
    """One table as it is written back: its name, header record and sub-records (raw bytes)."""

    name: str
    header: bytes
    records: list[bytes]


def read_tables(path: Path) -> tuple[str, list[Op2Table]]:
    """(byte order "<" or ">", the tables the modes reader reads) of the OP2 at ``path``."""
    records = Op2Records(path, path.read_bytes())
    kept = [Op2Table(t.name, t.header, list(t.records)) for t in records.tables(lambda n: n.startswith(KEPT))
            if t.name.startswith(KEPT)]
    return records.endian, kept


def write_op2(path: Path, tables: list[Op2Table], endian: str) -> Path:
    """The tables as an OP2 at ``path``: Fortran blocks framed by their length, markers as one-word blocks."""
    order = "little" if endian == "<" else "big"
    out = bytearray()

    def block(data: bytes) -> None:
        out.extend(len(data).to_bytes(4, order, signed=True) + data + len(data).to_bytes(4, order, signed=True))

    def marker(value: int) -> None:
        block(value.to_bytes(4, order, signed=True))

    def record(data: bytes) -> None:
        marker(len(data) // 4)
        block(data)

    for table in tables:
        record(table.name.encode("latin-1").ljust(8))
        marker(-1)
        record(np.zeros(7, dtype=endian + "i4").tobytes())  # the trailer: the reader passes over it
        for value in (-2, 1, 0):
            marker(value)
        record(table.header)
        k = -3
        for data in table.records:
            for value in (k, 1, 0):
                marker(value)
            if data:
                record(data)
            k -= 1
        for value in (k, 1, 0, 0):
            marker(value)
    marker(0)
    path.write_bytes(bytes(out))
    return path


def table(tables: list[Op2Table], name: str) -> Op2Table:
    """The first table called ``name``."""
    return next(t for t in tables if t.name == name)


def words(data: bytes, endian: str, kind: str = "i4") -> np.ndarray:
    """A writable copy of a record's words."""
    return np.frombuffer(data, dtype=endian + kind).copy()
