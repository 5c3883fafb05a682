"""Truncated, corrupted and unsuitable OP2 files: one line naming the file, the table and the record."""

from __future__ import annotations

import re

import numpy as np
import pytest
from support.nastran_results import NASTRAN, op2_path

from mace_fmu.errors import MaceError
from mace_fmu.nastran_modes import read_nastran_modes

ONE_LINE = re.compile(r"^(?P<file>\S+): table (?P<table>\S+), (?P<record>[^:]+): (?P<problem>.+)$")


def _error(path) -> re.Match:
    with pytest.raises(MaceError) as caught:
        read_nastran_modes(path)
    message = str(caught.value)
    assert "\n" not in message
    match = ONE_LINE.match(message)
    assert match, message
    assert match["file"] == str(path)
    return match


def _table_offset(data: bytes, name: bytes) -> int:
    """Where a table's name record is (the 8 characters after its 2-word length)."""
    return data.index(b"\x08\x00\x00\x00" + name.ljust(8))


@pytest.mark.parametrize("table, into", [("OUGV1", 900), ("OUGV1", 5_000), ("LAMA", 300), ("GEOM1", 200)])
def test_a_file_cut_inside_a_table_names_it_and_the_record(tmp_path, table, into):
    data = op2_path("beam_modes_op2").read_bytes()
    cut = _table_offset(data, table.encode()) + into
    path = tmp_path / "cut.op2"
    path.write_bytes(data[:cut])
    match = _error(path)
    assert match["table"] == table
    assert re.fullmatch(r"record \d+( \(.*\))?|the trailer \(record 1\)|the header \(record 2\)", match["record"])
    assert "truncated file" in match["problem"]


def test_a_file_cut_inside_its_header(tmp_path):
    path = tmp_path / "cut.op2"
    path.write_bytes(op2_path("beam_modes_op2").read_bytes()[:50])
    with pytest.raises(MaceError, match=rf"^{re.escape(str(path))}: the file header's tape code record: a Fortran "
                                        r"record of 28 bytes at byte 44 runs past the end of the file \(50 bytes: "
                                        r"truncated file\)$"):
        read_nastran_modes(path)


def test_a_corrupted_record_length_names_the_table_and_record(tmp_path):
    data = bytearray(op2_path("solid_shell_bar").read_bytes())
    start = _table_offset(bytes(data), b"OUGV1") + 4000
    # the next Fortran record after ``start``: a length word repeated after its record
    pos = start
    while True:
        length = int.from_bytes(data[pos:pos + 4], "little")
        if 4 <= length < 10_000 and int.from_bytes(data[pos + 4 + length:pos + 8 + length], "little") == length:
            break
        pos += 4
    data[pos + 4 + length:pos + 8 + length] = (length + 4).to_bytes(4, "little")
    path = tmp_path / "corrupt.op2"
    path.write_bytes(bytes(data))
    match = _error(path)
    assert match["table"] == "OUGV1"
    assert f"opens with length {length} and closes with {length + 4} (corrupted file)" in match["problem"]


def test_complex_or_sort2_vectors_are_refused(tmp_path):
    """An eigenvector IDENT whose words per point say complex (14, format 2) is refused, naming the record."""
    data = bytearray(op2_path("solid_shell_bar").read_bytes())
    words = np.frombuffer(bytes(data), "<i4")
    start = _table_offset(bytes(data), b"OUGV1") // 4
    # the IDENT: approach 2 (x 10 + device), table code 7, element type 0; then format 1 and 8 words at 9, 10
    ident = next(i for i in range(start, len(words) - 10)
                 if words[i] // 10 == 2 and words[i + 1] == 7 and words[i + 2] == 0 and words[i + 9] == 8)
    words = words.copy()
    words[ident + 8], words[ident + 9] = 2, 14
    path = tmp_path / "complex.op2"
    path.write_bytes(words.tobytes())
    match = _error(path)
    assert match["table"] == "OUGV1" and match["record"] == "record 3 (the IDENT of a vector)"
    assert "14 words per point in format 2 (expected real ones" in match["problem"]


def test_a_static_run_is_said_to_hold_static_displacements():
    """models/plate/plate.op2 (SOL 101): asking it for DISPLACEMENT(PLOT)=ALL, as the message once did, changes
    nothing; what the file holds does."""
    match = _error(NASTRAN / "plate_static" / "plate.op2")
    assert match["table"] == "OUGV1" and match["record"] == "its IDENT records"
    assert match["problem"] == ("no real eigenvectors of a normal-modes run in the file: it holds static "
                                "displacements (SOL 101) in OUGV1 (expected the OP2 of a SOL 103 run: its normal "
                                "modes)")


def test_a_subcase_that_is_not_in_the_file():
    with pytest.raises(MaceError, match=r"gpsc1\.op2: table OUGV1, its IDENT records: no eigenvectors of subcase 2 \(the file "
                                        r"has subcases \[1\]\)"):
        read_nastran_modes(op2_path("gpsc1"), subcase=2)


def test_files_that_are_not_32_bit_op2(tmp_path):
    wide = tmp_path / "wide.op2"
    wide.write_bytes((8).to_bytes(4, "little") + (3).to_bytes(8, "little") + (8).to_bytes(4, "little"))
    with pytest.raises(MaceError, match=r"wide\.op2: the file header's first record: a 64-bit OP2 \(8-byte words\) is "
                                        "not read"):
        read_nastran_modes(wide)
    missing = tmp_path / "none.op2"
    with pytest.raises(MaceError, match=r"none\.op2: no such file"):
        read_nastran_modes(missing)
