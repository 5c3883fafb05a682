"""Write the decks of this folder (run once; the decks are committed, with MYSTRAN's .F06 for each).

Usage: python make_decks.py OUT_FOLDER

Small-field fixed format, which MYSTRAN and NASTRAN both read. Where MYSTRAN 17.0.0 does not take a form NASTRAN
does (provenance.toml lists them), the deck uses an equivalent one; tests/fe/test_card_closed_forms.py checks the
other forms on variants of these decks.
"""

from __future__ import annotations

import pathlib
import sys


def card(*fields):
    """One card, continuation lines after every 8 data fields (fixed small field, left-justified)."""
    fields = ["" if f is None else str(f) for f in fields]
    for f in fields:
        assert len(f) <= 8, f
    lines, head, rest = [], fields[0], fields[1:]
    first, rest = rest[:8], rest[8:]
    lines.append(head.ljust(8) + "".join(f.ljust(8) for f in first))
    while rest:
        chunk, rest = rest[:8], rest[8:]
        lines.append(" " * 8 + "".join(f.ljust(8) for f in chunk))
    return "\n".join(line.rstrip() for line in lines)


def deck(title, comments, cards, case="SPC = 1\nMETHOD = 1\n"):
    head = [f"$ {c}" for c in comments]
    return "\n".join(head + ["SOL 103", "CEND", f"TITLE = {title}", "ECHO = NONE", case.rstrip(), "BEGIN BULK"]
                     + cards + ["ENDDATA", ""])


def crod():
    # ten CRODs along u = (1, 2, 2)/3, 0.3 m each; grids in basic, displacement system 1 has x along u
    cards = [card("EIGRL", 1, None, None, 12),
             card("CORD2R", 1, None, "0.", "0.", "0.", "2.", "-1.", "0.", "1.", "2.", "2."),
             card("MAT1", 1, "7.0E10", None, ".33", "2700."),
             card("PROD", 1, 1, "1.0E-4", "2.0E-9"),
             card("SPC1", 1, 123456, 1)]
    for k in range(11):
        cards.append(card("GRID", k + 1, None, f"{0.1 * k:.1f}", f"{0.2 * k:.1f}", f"{0.2 * k:.1f}", 1, 2356))
    for k in range(10):
        cards.append(card("CROD", 10 + k + 1, 1, k + 1, k + 2))
    for k in range(1, 11):  # point masses with a polar inertia about the rod's axis (system 1 x)
        cards.append(card("CONM2", 100 + k + 1, k + 1, 1, ".05", None, None, None, None, "1.0E-5"))
    return deck("CROD CHAIN ALONG (1,2,2)/3, AXIAL AND TORSION",
                ["Ten CRODs (PROD A 1.0E-4 m^2, J 2.0E-9 m^4; MAT1 E 7.0E10 Pa, nu 0.33, rho 2700 kg/m^3), 0.3 m",
                 "each, along (1,2,2)/3 from grid 1 (clamped); displacement system 1 has x along the rods, so PS 2356",
                 "leaves each grid's axial (1) and torsional (4) motion. CONM2 0.05 kg, I11 1.0E-5 kg m^2 in system 1",
                 "on grids 2-11."], cards)


def scalar():
    cards = [card("EIGR", 1, "GIV", None, None, None, 7),
             card("PELAS", 1, "1.0E4"), card("PELAS", 2, "2.0E4"),
             card("PELAS", 3, "1.5E4"), card("PELAS", 4, "3.0E4"),  # one per card: MYSTRAN 17 reads only the first
             card("PMASS", 11, "1.0"), card("PMASS", 12, "2.0"), card("PMASS", 13, ".5")]
    for g in range(1, 7):
        cards.append(card("GRID", g, None, f"{float(g - 1):.1f}", "0.", "0.", None, 3456 if g == 6 else 23456))
    cards.append(card("GRID", 7, None, "6.0", "0.", "0.", None, 123456))  # ground: MYSTRAN needs G2 on CELAS1
    springs = [(11, 1, 1, 1, 7, 1), (12, 2, 1, 1, 2, 1), (13, 3, 2, 1, 3, 1), (14, 2, 3, 1, 4, 1),
               (15, 4, 4, 1, 5, 1), (16, 1, 5, 1, 6, 2), (17, 3, 6, 2, 7, 2), (18, 4, 6, 1, 4, 1)]
    cards += [card("CELAS1", *s) for s in springs]
    masses = [(21, 11, 1, 1), (22, 12, 2, 1), (23, 11, 3, 1), (24, 13, 4, 1), (25, 12, 5, 1), (26, 13, 6, 1)]
    cards += [card("CMASS1", *m) for m in masses]
    cards.append(card("CONM2", 27, 6, None, ".5"))  # MYSTRAN 17 puts a CMASS1 on a grid's component 1 whatever C1 is
    return deck("CELAS1 PELAS CMASS1 PMASS NETWORK",
                ["Scalar springs (CELAS1 on PELAS) and masses (CMASS1 on PMASS) on the x of grids 1-6 and the y of",
                 "grid 6 (every other component fixed by PS): springs between two DOFs, one from an x to a y, two to",
                 "the clamped grid 7 (MYSTRAN 17 takes neither a blank G2 on CELAS1 nor a second grid on CMASS1, and puts",
                 "a CMASS1 on component 1 whatever its C1: the y of grid 6 gets its mass from a 0.5 kg CONM2, the x of",
                 "grid 6 0.5 kg from it and 0.5 kg from CMASS1 26)."], cards, case="METHOD = 1\n")


def rbe3():
    a, b = 0.4, 0.25
    corners = [(1, a, b, 0.0), (2, -a, b, 0.05), (3, -a, -b, 0.0), (4, a, -b, -0.1)]
    cards = [card("EIGR", 1, "GIV", None, None, None, 12)]
    for g, x, y, z in corners:
        cards.append(card("GRID", g, None, f"{x:.2f}", f"{y:.2f}", f"{z:.2f}", None, 456))
    cards.append(card("GRID", 10, None, ".1", "-.05", ".2"))
    cards.append(card("GRID", 99, None, "0.", "0.", "0.", None, 123456))  # ground: MYSTRAN needs G2 on CELAS2
    kxyz = [("1.0E4", "2.0E4", "3.0E4"), ("1.5E4", "1.0E4", "2.5E4"), ("2.0E4", "1.5E4", "2.0E4"),
            ("1.0E4", "3.0E4", "3.5E4")]
    for (g, *_), ks in zip(corners, kxyz):
        for c, k in enumerate(ks, start=1):
            cards.append(card("CELAS2", 100 + 10 * g + c, k, g, c, 99, c))
        cards.append(card("CONM2", 200 + g, g, None, ".2"))
    cards.append(card("CONM2", 300, 10, None, "5.0", None, None, None, None,
                      ".4", ".02", ".7", "-.03", ".01", ".9"))
    # unequal weights: grids 1 and 3 weigh 1.0, grids 2 and 4 weigh 2.5
    cards.append(card("RBE3", 400, None, 10, 123456, "1.0", 123, 1, 3, "2.5", 123, 2, 4))
    return deck("RBE3 OVER FOUR SPRUNG CORNERS",
                ["A 5 kg CONM2 (full inertia) on grid 10, the reference of an RBE3 over the translations of four",
                 "corner grids (weights 1.0 and 2.5, the reference off their centroid and plane); each corner on three",
                 "grounded CELAS2 springs and a 0.2 kg CONM2."], cards, case="METHOD = 1\n")


def cord1r():
    # CORD1R 9 through grids 91-93 (92 given in the rotated CORD2R 5); the beam's grids are in system 9. GRID cards in
    # ascending ID order: MYSTRAN 17.0.0 puts a CONM2 on the wrong grid when a higher-numbered GRID comes first.
    cards = [card("EIGRL", 1, None, None, 8),
             card("CORD2R", 5, None, "0.", "0.", "0.", ".3", ".4", ".866", "1.", ".2", ".1"),
             card("CORD1R", 9, 91, 92, 93),
             card("MAT1", 1, "7.0E10", None, ".33", "2700."),
             card("PBAR", 1, 1, "7.0E-4", "4.0E-8", "9.0E-8", "1.0E-8"),
             card("SPC1", 1, 123456, 1)]
    for k in range(9):
        cards.append(card("GRID", k + 1, 9, "0.", "0.", f"{0.25 * k:.2f}", 9))
    cards += [card("GRID", 91, None, "1.", "2.", "3.", None, 123456),
              card("GRID", 92, 5, ".2", "-.4", "1.1", None, 123456),
              card("GRID", 93, None, "2.", "2.5", "3.5", None, 123456),
              card("GRID", 95, None, "1.40", "0.04", "2.00", None, 123456),
              card("GRID", 98, None, "0.", "0.", "0.", None, 123456)]  # ground: MYSTRAN needs G2 on CELAS2
    for k in range(8):
        cards.append(card("CBAR", k + 1, 1, k + 1, k + 2, "1.", "0.", "0."))
    cards += [card("CELAS2", 50, "1.0E3", 9, 1, 98, 1), card("CELAS2", 51, "4.0E3", 9, 2, 98, 2),
              card("CONM2", 60, 9, None, ".5"), card("CONROD", 70, 9, 95, 1, "1.0E-7")]
    return deck("CANTILEVER IN A CORD1R SYSTEM",
                ["Eight CBARs along z of CORD1R 9 (origin grid 91, z towards grid 92 given in CORD2R 5, x-z plane",
                 "through grid 93); grids located and displaced in system 9; tip springs along x and y of system 9, and a",
                 "CONROD across from the tip to grid 95 (basic, clamped, about 1 m off the tip between x and y of",
                 "system 9), which makes the modes depend on where system 9 is and how it is turned."],
                cards)


def pbarl(kind, dims, orient):
    cards = [card("EIGRL", 1, None, None, 8),
             card("MAT1", 1, "7.0E10", None, ".33", "2700."),
             card("PBARL", 1, 1, None, kind, None, None, None, None, *dims),
             card("SPC1", 1, 123456, 1)]
    n, length = 20, 4.0
    for k in range(n + 1):
        cards.append(card("GRID", k + 1, None, f"{length * k / n:.2f}", "0.", "0."))
    for k in range(n):
        cards.append(card("CBAR", k + 1, 1, k + 1, k + 2, *orient))
    return deck(f"CANTILEVER ON A PBARL {kind}",
                [f"Twenty CBARs, 4 m along x, clamped at grid 1, PBARL {kind} {' '.join(dims)} (MAT1 E 7.0E10 Pa,",
                 f"nu 0.33, rho 2700 kg/m^3), orientation vector ({', '.join(orient)})."], cards)


def main(out: pathlib.Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    decks = {"crod": crod(), "scalar_springs_masses": scalar(), "rbe3": rbe3(), "cord1r": cord1r(),
             "pbarl_tube": pbarl("TUBE", (".03", ".025"), ("0.", "1.", "1.")),
             "pbarl_box": pbarl("BOX", (".06", ".03", ".003", ".002"), ("0.", ".6", ".8"))}
    for name, text in decks.items():
        (out / f"{name}.bdf").write_text(text)


if __name__ == "__main__":
    main(pathlib.Path(sys.argv[1]))
