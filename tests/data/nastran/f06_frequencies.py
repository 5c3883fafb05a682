"""Write NASTRAN's natural frequencies from an .f06 file as reference_frequencies.toml (run once per deck).

Usage: python f06_frequencies.py F06 SOURCE PROGRAM OUT.toml

F06: the .f06 file NASTRAN wrote for the deck; SOURCE: where it is published (repository, commit, path);
PROGRAM: the NASTRAN version named in the .f06's page headers. The first "R E A L   E I G E N V A L U E S"
table is used (for a run with residual vectors: the table before augmentation, which holds the eigenvalues
of the structure itself). The CYCLES column is copied as printed, so the file holds NASTRAN's own digits.
"""

from __future__ import annotations

import sys


def first_eigenvalue_table(lines: list[str]) -> tuple[int, list[tuple[int, str]]]:
    """(1-based line of the table's title, [(mode number, CYCLES text)]) of the first real eigenvalue table."""
    for start, line in enumerate(lines):  # noqa: B007  (start: where the loop stopped)
        if "R E A L   E I G E N V A L U E S" in line:
            break
    else:
        raise SystemExit("no real eigenvalue table in the file")
    rows = []
    k = start + 1
    while "MODE" not in lines[k]:
        k += 1
    for line in lines[k + 2:]:
        parts = line.split()
        # MODE NO., EXTRACTION ORDER, EIGENVALUE, RADIANS, CYCLES, GENERALIZED MASS, GENERALIZED STIFFNESS
        if len(parts) != 7 or not parts[0].isdigit():
            break
        rows.append((int(parts[0]), parts[4]))
    return start + 1, rows


def write_reference(out: str, *, script: str, source: str, program: str, where: str,
                    cycles: list[tuple[int, str]]) -> None:
    """reference_frequencies.toml: where NASTRAN's frequencies were copied from and the CYCLES values as text."""
    text = [
        f"# NASTRAN's natural frequencies of this deck, copied once from its {script}",
        f'source = "{source}"',
        f'program = "{program}"',
        where,
        "# CYCLES column, mode 1 first [Hz]",
        "cycles = [",
        *(f"    {value},  # mode {mode}" for mode, value in cycles),
        "]",
    ]
    with open(out, "w", encoding="utf-8") as handle:
        handle.write("\n".join(text) + "\n")


def main(argv: list[str]) -> None:
    f06, source, program, out = argv
    lines = open(f06, encoding="latin-1").read().splitlines()
    title_line, rows = first_eigenvalue_table(lines)
    write_reference(out, script=".f06 by tests/data/nastran/f06_frequencies.py", source=source, program=program,
                    where=f"table_line = {title_line}  # line of the first REAL EIGENVALUES table in that .f06",
                    cycles=rows)


if __name__ == "__main__":
    main(sys.argv[1:])
