"""The record layer of an OP2 file: Fortran unformatted blocks grouped into NASTRAN's tables.

An OP2 is a sequence of Fortran records, each framed by its length in bytes before and after. NASTRAN
writes a table as: its name (a record of two words, announced by the marker 2), the marker -1 and a
7-word trailer, the markers -2, 1, 0 and a header record, then sub-records, each announced by the
markers -k, 1, 0 (k = 3, 4, ...; a matrix's columns by -k, 1, 1) and ended by a last marker 0. A data
record is announced by its length in words and may be split into several blocks, each announced by its
own (positive) length; a marker is a one-word record. The file itself may open with a header (marker 3:
date, tape code, version, then markers -1, 0) or go straight to the first table (marker 2). Layout as
documented in MSC's DMAP Programmer's Guide ("OUTPUT2") and as pyNastran reads it (op2_reader.py).

Both byte orders are read; the word size is 4 bytes (32-bit OP2; 64-bit files are refused by name).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Literal
from pathlib import Path

from mace_fmu.errors import MaceError


@dataclass(frozen=True)
class Table:
    """One OP2 table: its name, header record and sub-records (raw bytes, in file order)."""

    name: str  #: the table's name, e.g. "OUGV1", "LAMA", "GEOM1S"
    header: bytes  #: the record after the markers -2, 1, 0
    records: tuple[bytes, ...]  #: the sub-records announced by -3, -4, ... (empty when not kept)


class Op2Records:
    """Reads the tables of one OP2 file held in memory, with messages naming file, table and record."""

    def __init__(self, path: Path, data: bytes) -> None:
        self.path = path
        self.data = data
        self.pos = 0
        self.table: str | None = None  #: the table being read (None: the file header, or between tables)
        self.record = "the file header's first record"
        if len(data) < 12:
            self.fail(f"the file is {len(data)} bytes long (expected an OP2 file: Fortran records of "
                      "NASTRAN's tables)")
        little, big = int.from_bytes(data[:4], "little"), int.from_bytes(data[:4], "big")
        if little == 4:
            self.endian = "<"
        elif big == 4:
            self.endian = ">"
        elif 8 in (little, big):
            self.fail("a 64-bit OP2 (8-byte words) is not read (expected a 32-bit OP2: write it with the default "
                      "OUTPUT2 word size)")
        else:
            self.fail(f"the file does not start with a Fortran record of one word (found a length of {little} "
                      "bytes): not an OP2 file")
        self.order: Literal["little", "big"] = "little" if self.endian == "<" else "big"

    # --- errors -------------------------------------------------------------------------------------
    def fail(self, problem: str) -> None:
        """Raise the one-line MaceError naming the file, the table and the record being read."""
        where = f"table {self.table}, {self.record}" if self.table else self.record
        raise MaceError(f"{self.path}: {where}: {problem}")

    # --- blocks, markers and records -------------------------------------------------------------------
    def _block(self) -> bytes:
        """The next Fortran block's content (its two length words checked)."""
        start = self.pos
        if start + 4 > len(self.data):
            self.fail(f"the file ends at byte {len(self.data)} (expected another Fortran record: truncated file)")
        length = int.from_bytes(self.data[start:start + 4], self.order, signed=True)
        end = start + 4 + length
        if length < 0 or end + 4 > len(self.data):
            self.fail(f"a Fortran record of {length} bytes at byte {start} runs past the end of the file "
                      f"({len(self.data)} bytes: truncated file)")
        closing = int.from_bytes(self.data[end:end + 4], self.order, signed=True)
        if closing != length:
            self.fail(f"the Fortran record at byte {start} opens with length {length} and closes with {closing} "
                      "(corrupted file)")
        self.pos = end + 4
        return self.data[start + 4:end]

    def _peek_marker(self) -> int | None:
        """The value of the next block when it is a one-word marker, else None; the position is kept."""
        if self.pos + 12 > len(self.data):
            return None
        if int.from_bytes(self.data[self.pos:self.pos + 4], self.order, signed=True) != 4:
            return None
        return int.from_bytes(self.data[self.pos + 4:self.pos + 8], self.order, signed=True)

    def marker(self, expected: int | None = None) -> int:
        """The next marker (a one-word record); MaceError when it is not ``expected``."""
        block = self._block()
        if len(block) != 4:
            self.fail(f"found a record of {len(block)} bytes where a one-word marker"
                      + (f" ({expected})" if expected is not None else "") + " belongs (corrupted file)")
        value = int.from_bytes(block, self.order, signed=True)
        if expected is not None and value != expected:
            self.fail(f"found the marker {value} where {expected} belongs (corrupted file)")
        return value

    def logical_record(self, *, continued: bool = True, counted: bool = True) -> bytes:
        """A data record: its length in words, then its blocks (a long record comes in several; the file
        header's records come in one, ``continued=False``, since a positive marker follows them). ``counted=False``
        for a table that is skipped: a matrix's column blocks count their words in their own way."""
        parts = []
        words = self.marker()
        while True:
            if words <= 0:
                self.fail(f"found the marker {words} where the length of a data record belongs (corrupted file)")
            block = self._block()
            if counted and len(block) != 4 * words:
                self.fail(f"a data record of {len(block)} bytes was announced as {words} words (corrupted file)")
            parts.append(block)
            following = self._peek_marker()
            if not continued or following is None or following <= 0:
                return b"".join(parts)
            words = self.marker()

    # --- the file -------------------------------------------------------------------------------------
    def _file_header(self) -> None:
        first = self._peek_marker()
        if first == 2:  # PARAM,POST,-2 style: straight to the first table
            return
        if first != 3:
            self.fail(f"the file opens with the marker {first} (expected 3, a dated header, or 2, a table name)")
        for self.record in ("the file header's date record", "the file header's tape code record"):
            self.logical_record(continued=False)
        self.record = "the file header's version record"
        self.logical_record()  # MSC 2014 and later add a second block to it
        self.record = "the end of the file header"
        self.marker(-1)
        self.marker(0)

    def tables(self, keep: Callable[[str], bool]) -> Iterator[Table]:
        """Every table in file order; the sub-records of those for which ``keep(name)`` holds."""
        self._file_header()
        previous = "the file header"
        while True:
            self.table, self.record = None, f"the name record of the table after {previous}"
            following = self._peek_marker()
            if following is None and self.pos >= len(self.data):
                return  # no closing marker: the file ends after the last table
            if following == 0:
                self.marker(0)
                return
            name = self.logical_record()[:8].decode("latin-1").strip()
            self.table = name or "(unnamed)"
            self.record = "the trailer (record 1)"
            self.marker(-1)
            self.logical_record()
            self.record = "the header (record 2)"
            for value in (-2, 1, 0):
                self.marker(value)
            header = self.logical_record()
            kept = keep(name)
            records = []
            k = -3
            while True:
                self.record = f"record {-k}"
                self.marker(k)
                self.marker(1)
                self.marker()  # 0 for a table's record, 1 for a matrix column
                following = self._peek_marker()
                if following == 0:
                    self.marker(0)
                    break
                # a negative marker: an empty record (the next one's k follows at once)
                record = (self.logical_record(counted=kept) if following is None or following > 0 else b"")
                if kept:
                    records.append(record)
                k -= 1
            previous = f"table {name}"
            yield Table(name=name, header=header, records=tuple(records))
