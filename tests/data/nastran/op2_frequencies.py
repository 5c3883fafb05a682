"""Write NASTRAN's natural frequencies from an .op2 file as reference_frequencies.toml (run once per deck).

Usage: python op2_frequencies.py OP2 SOURCE PROGRAM OUT.toml

For a run published with its .op2 only. NASTRAN's real eigenvalue table (LAMA) holds one record of seven
4-byte words per mode: mode number, extraction order (integers), then eigenvalue, radians, cycles,
generalized mass and generalized stiffness (reals). The file is scanned for the run of consecutive records
numbered 1, 2, 3, ... whose words agree with each other as those of a LAMA record must (radians^2 =
eigenvalue, cycles = radians / 2 pi, generalized stiffness = eigenvalue x generalized mass), so no OP2 reader
(and none of mace-fmu's code) is involved. The CYCLES words are written with the 8 significant digits a
4-byte real holds.
"""

from __future__ import annotations

import math
import struct
import sys

RECORD = struct.Struct("<2i5f")  #: mode, order, eigenvalue, radians, cycles, generalized mass, generalized stiffness


def _is_lama(words: tuple) -> bool:
    mode, order, eigenvalue, radians, cycles, mass, stiffness = words
    if not (mode >= 1 and order >= 1 and eigenvalue > 0.0 and mass > 0.0):
        return False
    return (math.isclose(radians**2, eigenvalue, rel_tol=1e-5)
            and math.isclose(2 * math.pi * cycles, radians, rel_tol=1e-5)
            and math.isclose(stiffness, eigenvalue * mass, rel_tol=1e-5))


def lama_cycles(data: bytes) -> tuple[int, list[float]]:
    """(byte offset of the table, [cycles of mode 1, 2, ...]) of the first LAMA run in ``data``."""
    for start in range(0, len(data) - RECORD.size, 4):
        cycles = []
        offset = start
        while offset + RECORD.size <= len(data):
            words = RECORD.unpack_from(data, offset)
            if words[0] != len(cycles) + 1 or not _is_lama(words):
                break
            cycles.append(words[4])
            offset += RECORD.size
        if cycles:
            return start, cycles
    raise SystemExit("no real eigenvalue records in the file")


def main(argv: list[str]) -> None:
    from f06_frequencies import write_reference  # this folder's sibling script (run as a script from here)

    op2, source, program, out = argv
    with open(op2, "rb") as handle:
        start, cycles = lama_cycles(handle.read())
    write_reference(out, script=".op2 by tests/data/nastran/op2_frequencies.py", source=source, program=program,
                    where=f"table_offset = {start}  # byte offset of the first real eigenvalue record in that .op2",
                    cycles=[(mode, f"{value:.8g}") for mode, value in enumerate(cycles, start=1)])


if __name__ == "__main__":
    main(sys.argv[1:])
