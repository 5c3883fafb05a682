"""Rebuild the deck NASTRAN ran from the case-control and sorted bulk-data echoes of its .f06 (run once per deck).

Usage: python f06_echo.py F06 SOURCE OUT.bdf

Some public runs are published as the .f06 only (pyNastran's nlfltr/case2/buckled.f06). With ECHO=SORT the
.f06 holds every case-control line and every bulk-data card NASTRAN read, each in the 80 columns of its card
image after its count ("   12-        CBEAM   ..."); the executive control is not echoed, so the rebuilt deck
starts with ``SOL 103`` (the eigenvalue table says the run was a normal-modes run) and ``CEND``. The card
images are copied as printed, continuation names included; nothing else is changed.
tests/fe/test_nastran_decks.py rebuilds the deck from the .f06 again and checks it equals the stored file.
"""

from __future__ import annotations

import re
import sys

CASE_TITLE = "C A S E    C O N T R O L   D E C K   E C H O"
BULK_TITLE = "S O R T E D   B U L K   D A T A   E C H O"
CASE_LINE = re.compile(r" {10,}\d+      ")  #: "                  2      TITLE = ..." (the text from column 26)
BULK_LINE = re.compile(r" +\d+-        ")  #: "                   12-        CBEAM ..." (the card from column 31)


def deck_from_echo(text: str, source: str) -> str:
    """The deck text rebuilt from the echoes of the .f06 ``text``; ``source`` names the .f06 in its header."""
    case: list[str] = []
    bulk: list[str] = []
    part = None
    for line in text.splitlines():
        if CASE_TITLE in line:
            part = case
        elif BULK_TITLE in line:
            part = bulk
        elif part is bulk and line.strip() == "ENDDATA":
            break
        elif part is case and CASE_LINE.match(line):
            case.append(line[25:].rstrip())
        elif part is bulk and BULK_LINE.match(line):
            bulk.append(line[30:].rstrip())
    if not case or not bulk:
        raise SystemExit("no case-control or sorted bulk-data echo in the file (expected a run with ECHO=SORT)")
    header = [f"$ rebuilt by tests/data/nastran/f06_echo.py from the echoes in {source}",
              "$ (executive control not echoed: SOL 103, CEND)", "SOL 103", "CEND"]
    if not any(line.strip().upper().startswith("BEGIN BULK") for line in case):
        case.append("BEGIN BULK")
    return "\n".join(header + case + bulk + ["ENDDATA"]) + "\n"


def main(argv: list[str]) -> None:
    f06, source, out = argv
    with open(f06, encoding="latin-1") as handle:
        text = handle.read()
    with open(out, "w", encoding="utf-8", newline="\n") as handle:
        handle.write(deck_from_echo(text, source))


if __name__ == "__main__":
    main(sys.argv[1:])
