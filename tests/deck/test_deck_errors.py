"""Broken decks: each must raise one DeckError at the right line, naming the card and the problem."""

from __future__ import annotations

from pathlib import Path

import pytest

from mace_fmu.deck import DeckError, read_deck, read_deck_text
from mace_fmu.errors import MaceError


def sf(name: str, *fields: object) -> str:
    """One small-field line: field 1 and data fields, 8 columns each."""
    return "".join(f"{str(x):<8}" for x in (name, *fields)).rstrip()


def lf(name: str, *fields: object) -> str:
    """One large-field line: field 1 (8 columns) and data fields of 16 columns."""
    return f"{name:<8}" + "".join(f"{str(x):<16}" for x in fields).rstrip()


def text(*lines: str) -> str:
    return "\n".join(lines) + "\n"


# Lines 1-5: a valid model. Cards appended to it start at line 6.
BASE = (
    sf("GRID", 1, "", "0.0", "0.0", "0.0"),
    sf("GRID", 2, "", "1.0", "0.0", "0.0"),
    sf("MAT1", 1, "7.0E10", "", "0.3", "2700.0"),
    sf("PBAR", 1, 1, "1.0E-4", "1.0E-9", "2.0E-9", "3.0E-9"),
    sf("CBAR", 10, 1, 1, 2, "0.0", "0.0", "1.0"),
)


def base(*lines: str) -> str:
    return text(*BASE, *lines)


def case(control: str, *bulk: str) -> str:
    """Executive control (line 1), CEND (line 2), case control from line 3, then BASE + bulk."""
    return f"SOL 106\nCEND\n{control}\nBEGIN BULK\n" + text(*BASE, *bulk) + "ENDDATA\n"


CORD_LINE2 = sf("", "1.0", "0.0", "0.0")

BROKEN = [
    # --- line structure and field formats
    pytest.param(base(sf("CQUAD4", 1, 1, 1, 2, 3, 4)), 6, "CQUAD4", "unknown card 'CQUAD4' (supported: CBAR",
                 id="unknown-card"),
    pytest.param(text(sf("", "1.0", "2.0"), *BASE), 1, "", "has no card before it", id="continuation-first"),
    pytest.param(text(sf("+C1", 1)), 1, "", "has no card before it", id="plus-continuation-first"),
    pytest.param("SOL 103\nCEND\nBEGIN BULK\n" + text(*BASE), 8, "", "BEGIN BULK at line 3 has no ENDDATA",
                 id="missing-enddata"),
    # a free-field line longer than a card image goes on in implicit continuations, whose fields 10 and 1 are
    # continuation markers: a datum there would be shifted to another field, so it is refused
    pytest.param(base("GRID,3,,1.0,2.0,3.0,,,,1,2"), 6, "GRID", "free-field line: '1' (item 10 of the line) falls in "
                 "field 10 of card image 1, a continuation field", id="free-field-too-many"),
    pytest.param(base("GRID*,3,,1.0,2.0,3.0"), 6, "GRID", "free-field line: '3.0' (item 6 of the line) falls in field "
                 "10 of card image 1, a continuation field", id="free-large-too-many"),
    pytest.param(base(sf("GRID", 3, "", "1.2.3")), 6, "GRID 3", "field 4 (X1): expected a real number, got '1.2.3'",
                 id="bad-real"),
    pytest.param(base(sf("GRID", 3, "", "1.0", "7")), 6, "GRID 3",
                 "expected a real number with a decimal point, got '7'", id="integer-in-real-field"),
    pytest.param(base(sf("CBAR", 11, "1.0", 1, 2, "0.0", "0.0", "1.0")), 6, "CBAR 11",
                 "field 3 (PID): expected an integer >= 1, got '1.0'", id="real-in-integer-field"),
    pytest.param(base(sf("GRID", "3.0")), 6, "GRID", "field 2 (ID): expected an integer >= 1, got '3.0'",
                 id="real-id"),
    pytest.param(base(sf("CONM2", 20, 1)), 6, "CONM2 20", "field 5 (M): required field is blank",
                 id="missing-required"),
    pytest.param(base(sf("GRID", 3, "", "1.0E999")), 6, "GRID 3", "out of range", id="real-overflow"),
    pytest.param(base(lf("GRID*", 3, 0, "1.0", "2.0"), lf("*", "3.0.0")), 7, "GRID 3",
                 "field 6 (X3): expected a real number, got '3.0.0'", id="large-field-continuation"),
    pytest.param(base(lf("GRID*", 3, 0, "1.0", "2.0"), sf("+", "3.0")), 7, "GRID",
                 "small-field continuation after an odd number of large-field lines", id="large-then-small"),
    pytest.param(base(sf("GRID", 3, "", "", "", "", "", "", 5)), 6, "GRID 3", "field 9 (SEID): expected a blank",
                 id="grid-seid"),
    pytest.param(base(sf("GRID", 3), sf("", "1.0")), 7, "GRID 3", "unexpected value '1.0'", id="extra-field"),
    # --- duplicates
    pytest.param(base(sf("GRID", 1, "", "5.0")), 6, "GRID 1", "GRID 1 defined twice: line 1 and line 6",
                 id="duplicate-grid"),
    pytest.param(base(sf("CBEAM", 10, 1, 1, 2, "0.0", "1.0", "0.0")), 6, "CBEAM 10",
                 "element ID 10 is used twice: CBAR at line 5 and CBEAM at line 6", id="duplicate-element-id"),
    pytest.param(base(sf("CELAS2", 11, "1.0", 1, 1), sf("CBAR", 11, 1, 1, 2, "0.0", "1.0")), 7, "CBAR 11",
                 "element ID 11 is used twice: CELAS2 at line 6 and CBAR at line 7", id="duplicate-celas2-cbar"),
    pytest.param(base("PARAM,POST,0", sf("PARAM", "POST", -1)), 7, "PARAM POST", "defined twice",
                 id="duplicate-param"),
    # --- references
    pytest.param(base(sf("CBAR", 11, 1, 1, 999, "0.0", "0.0", "1.0")), 6, "CBAR 11",
                 "field 5 (GB): grid 999 is not defined (expected a GRID ID)", id="missing-grid-cbar"),
    pytest.param(base(sf("CBAR", 11, 1, 1, 2, 77)), 6, "CBAR 11", "field 6 (G0): grid 77 is not defined",
                 id="missing-g0"),
    pytest.param(base(sf("CBAR", 11, 7, 1, 2, "0.0", "0.0", "1.0")), 6, "CBAR 11",
                 "property 7 is not defined (expected a PBAR ID)", id="missing-pbar"),
    pytest.param(base(sf("PBAR", 2, 9, "1.0")), 6, "PBAR 2", "material 9 is not defined (expected a MAT1 ID)",
                 id="missing-mat1"),
    pytest.param(base(sf("GRID", 3, 5, "1.0")), 6, "GRID 3", "field 3 (CP): coordinate system 5 is not defined (expected 0 or a CORD2R or CORD1R ID)",
                 id="missing-cp"),
    pytest.param(base(sf("GRID", 3, "", "1.0", "", "", 6)), 6, "GRID 3",
                 "field 7 (CD): coordinate system 6 is not defined", id="missing-cd"),
    pytest.param(base(sf("CONM2", 20, 1, 4, "1.0")), 6, "CONM2 20", "coordinate system 4 is not defined",
                 id="missing-conm2-cid"),
    pytest.param(base(sf("CONM2", 20, 3, "", "1.0")), 6, "CONM2 20", "grid 3 is not defined", id="missing-conm2-grid"),
    pytest.param(base(sf("CELAS2", 20, "1.0", 1, 1, 77, 1)), 6, "CELAS2 20", "field 6 (G2): grid 77 is not defined",
                 id="missing-celas2-g2"),
    pytest.param(base(sf("MPC", 5, 1, 1, "1.0"), sf("", "", 42, 1, "-1.0")), 6, "MPC 5", "grid 42 is not defined",
                 id="missing-mpc-grid"),
    pytest.param(base(sf("SPC1", 1, 123, 1, 2, 42)), 6, "SPC1 1", "grid 42 is not defined", id="missing-spc1-grid"),
    pytest.param(base(sf("SPC1", 1, 123, 50, "THRU", 60)), 6, "SPC1 1", "no GRID exists in 50 THRU 60",
                 id="spc1-thru-empty"),
    pytest.param(base(sf("GRAV", 1, 3, "9.81", "0.0", "0.0", "-1.0")), 6, "GRAV 1",
                 "coordinate system 3 is not defined", id="missing-grav-cid"),
    pytest.param(base(sf("GRAV", 1, "", "9.81", "0.0", "0.0", "-1.0"), sf("LOAD", 100, "1.0", "1.0", 1, "1.0", 5)),
                 7, "LOAD 100", "load set 5 is not defined (expected a GRAV, FORCE, MOMENT or PLOAD SID)", id="load-missing-grav"),
    # --- coordinate systems
    pytest.param(base(sf("CORD2R", 1, 2, "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), CORD_LINE2,
                      sf("CORD2R", 2, 1, "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), CORD_LINE2),
                 6, "CORD2R 1", "RID chain 1 -> 2 -> 1 is a cycle", id="cord2r-cycle"),
    pytest.param(base(sf("CORD2R", 3, 3, "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), CORD_LINE2), 6, "CORD2R 3",
                 "RID chain 3 -> 3 is a cycle", id="cord2r-self-reference"),
    pytest.param(base(sf("CORD2R", 1, 4, "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), CORD_LINE2), 6, "CORD2R 1",
                 "field 3 (RID): coordinate system 4 is not defined", id="cord2r-missing-rid"),
    pytest.param(base(sf("CORD2R", 1, "", "1.0", "2.0", "3.0", "1.0", "2.0", "3.0"), CORD_LINE2), 6, "CORD2R 1",
                 "points A and B coincide", id="cord2r-a-equals-b"),
    pytest.param(base(sf("CORD2R", 1, "", "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), sf("", "0.0", "0.0", "5.0")),
                 6, "CORD2R 1", "point C lies on the line AB", id="cord2r-c-on-axis"),
    # --- MPC
    pytest.param(base(sf("MPC", 5, 1, 1, "1.0", 2, 1, "-1.0"), sf("MPC", 5, 2, 2, "1.0", 1, 1, "-1.0")), 7, "MPC 5",
                 "DOF 1-1 is the dependent DOF of the equation at line 6 and is used again at line 7",
                 id="mpc-dependent-used-as-independent"),
    pytest.param(base(sf("MPC", 5, 1, 1, "1.0", 2, 1, "-1.0"), sf("MPC", 5, 2, 1, "1.0", 1, 2, "-1.0")), 7, "MPC 5",
                 "DOF 2-1 is the dependent DOF of the equation at line 7 and is also used in the equation at line 6",
                 id="mpc-independent-made-dependent"),
    pytest.param(base(sf("MPC", 5, 1, 2, "1.0", 2, 2, "-1.0"), sf("MPC", 6, 1, 2, "1.0"),
                      sf("MPC", 5, 1, 2, "2.0", 2, 3, "-1.0")), 8, "MPC 5",
                 "DOF 1-2 is the dependent DOF of the equation at line 6 and is used again at line 8",
                 id="mpc-dependent-twice"),
    pytest.param(base(sf("MPC", 5, 1, 1, "1.0", 2, "", "-1.0")), 6, "MPC 5",
                 "MPC term 2 is incomplete: component blank", id="mpc-incomplete-term"),
    pytest.param(base(sf("MPC", 5, 1, 1, "1.0"), sf("", "", 2, 1)), 7, "MPC 5",
                 "MPC term 2 is incomplete: coefficient blank", id="mpc-incomplete-continuation"),
    pytest.param(base(sf("MPC", 5, 1, 7, "1.0")), 6, "MPC 5", "expected a single component digit 1-6, got '7'",
                 id="mpc-component-7"),
    pytest.param(base(sf("MPC", 5, 1, 0, "1.0")), 6, "MPC 5", "component 0 (scalar point) is not supported",
                 id="mpc-component-0"),
    pytest.param(base(sf("MPC", 5, 1, 1, "1.0"), sf("", 2, 2, 1, "1.0")), 7, "MPC 5",
                 "continuation 1 field 2 (unused): expected a blank field, got '2'", id="mpc-continuation-field-2"),
    # --- components and other card rules
    pytest.param(base(sf("SPC1", 1, 127, 1)), 6, "SPC1 1", "expected components (digits 1-6), got '127'",
                 id="spc1-component-7"),
    pytest.param(base(sf("CELAS2", 20, "1.0", 1, 7)), 6, "CELAS2 20", "expected a single component digit 1-6",
                 id="celas2-component-7"),
    pytest.param(base(sf("GRID", 3, "", "0.0", "0.0", "0.0"),
                      sf("CBAR", 11, 1, 1, 3, "0.0", "0.0", "1.0")), 7, "CBAR 11", "zero length", id="zero-length-bar"),
    pytest.param(base(sf("CBAR", 11, 1, 1, 2, "2.0", "0.0", "0.0")), 6, "CBAR 11",
                 "orientation vector is parallel to the bar axis", id="orientation-parallel"),
    pytest.param(base(sf("GRID", 3, "", "5.0"), sf("CBAR", 11, 1, 1, 2, 3)), 7, "CBAR 11",
                 "field 6 (G0): orientation vector is parallel", id="g0-on-bar-axis"),
    pytest.param(base(sf("CBAR", 11, 1, 1, 2, "0.0", "0.0", "0.0")), 6, "CBAR 11", "orientation vector is zero",
                 id="orientation-zero"),
    pytest.param(base(sf("CBAR", 11, 1, 1, 2)), 6, "CBAR 11", "orientation is blank", id="orientation-blank"),
    pytest.param(base(sf("CBAR", 11, 1, 2, 2, "0.0", "0.0", "1.0")), 6, "CBAR 11", "GA and GB are both grid 2",
                 id="cbar-ga-equals-gb"),
    pytest.param(base(sf("CBAR", 11, 1, 1, 2, "0.0", "0.0", "1.0"), sf("", 456)), 7, "CBAR 11",
                 "continuation 1 field 2 (PA): pin flags are not supported by mace-fmu", id="cbar-pin-flags"),
    pytest.param(base(sf("CBAR", 11, 1, 1, 2, "0.0", "0.0", "1.0"), sf("", "", "", "0.1")), 7, "CBAR 11",
                 "(W1A): offsets are not supported by mace-fmu", id="cbar-offsets"),
    pytest.param(base(sf("CBAR", 11, 1, 1, 2, "0.0", "0.0", "1.0", "BXG")), 6, "CBAR 11",
                 "field 9 (OFFT): expected blank, a code such as GGG or BGG", id="cbar-offt"),
    pytest.param(base(sf("PBAR", 2, 1, "-1.0E-4")), 6, "PBAR 2", "field 4 (A): negative value '-1.0E-4'",
                 id="negative-area"),
    pytest.param(base(sf("PBAR", 2, 1, "1.0E-4"), sf("", "0.5"), sf("", 1)), 8, "PBAR 2",
                 "continuation 2 field 2 (K1): expected a real number with a decimal point, got '1'",
                 id="pbar-integer-k1"),
    pytest.param(base(sf("MAT1", 2, "", "", "0.3")), 6, "MAT1 2", "E and G are both blank", id="mat1-no-e-no-g"),
    pytest.param(base(sf("MAT1", 2, "7.0E10", "", "0.6")), 6, "MAT1 2", "Poisson's ratio '0.6' is outside (-1, 0.5]",
                 id="mat1-nu"),
    pytest.param(base(sf("CONM2", 20, 1, "", "-1.0")), 6, "CONM2 20", "negative mass '-1.0'", id="conm2-negative-mass"),
    pytest.param(base(sf("CONM2", 20, 1, "", "1.0"), sf("", "1.0", "", "-2.0")), 7, "CONM2 20",
                 "(I22): negative inertia '-2.0'", id="conm2-negative-inertia"),
    pytest.param(base(sf("GRAV", 1, "", "9.81", "0.0", "0.0", "0.0")), 6, "GRAV 1", "direction vector is zero",
                 id="grav-zero-direction"),
    pytest.param(base(sf("GRAV", 1, "", "", "0.0", "0.0", "1.0")), 6, "GRAV 1", "field 4 (A): required field",
                 id="grav-no-scale"),
    pytest.param(base(sf("EIGRL", 1)), 6, "EIGRL 1", "V1, V2 and ND are all blank", id="eigrl-all-blank"),
    pytest.param(base(sf("NLPARM", 1, "", "", "NEWTON")), 6, "NLPARM 1", "expected one of AUTO, SEMI, ITER",
                 id="nlparm-kmethod"),
    pytest.param(base(sf("NLPARM", 1), sf("", "1")), 7, "NLPARM 1", "(EPSU): expected a real number with a decimal",
                 id="nlparm-epsu-integer"),
    pytest.param(base(sf("PARAM", "POST")), 6, "PARAM POST", "field 3 (V1): required field is blank",
                 id="param-no-value"),
    # --- values checked where they are read, whether or not an element uses the card
    pytest.param(base(sf("MAT1", 2, "-7.0E10", "", "0.3")), 6, "MAT1 2",
                 "field 3 (E): value '-7.0E10' is out of range (expected a real number > 0.0)", id="mat1-negative-e"),
    pytest.param(base(sf("MAT1", 2, "7.0E10", "0.0")), 6, "MAT1 2", "field 4 (G): value '0.0' is out of range",
                 id="mat1-zero-g"),
    pytest.param(base(sf("MAT1", 2, "7.0E10", "", "0.3", "-2700.0")), 6, "MAT1 2",
                 "field 6 (RHO): value '-2700.0' is out of range (expected a real number >= 0.0)",
                 id="mat1-negative-rho"),
    pytest.param(base(sf("MAT1", 2, "7.0E10", "", "-1.0")), 6, "MAT1 2", "Poisson's ratio '-1.0' is outside",
                 id="mat1-nu-minus-one"),
    pytest.param(base(sf("PBAR", 2, 1, "1.0E-4", "1.0E-9", "1.0E-9", "1.0E-9", "-0.5")), 6, "PBAR 2",
                 "field 8 (NSM): negative value '-0.5'", id="pbar-negative-nsm"),
    pytest.param(base(sf("PBAR", 2, 1, "1.0E-4", "1.0E-9", "1.0E-9", "-1.0E-9")), 6, "PBAR 2",
                 "field 7 (J): negative value '-1.0E-9'", id="pbar-negative-j"),
    pytest.param(base(sf("PBAR", 2, 1, "1.0E-4", "1.0E-9", "1.0E-9"), sf("+"), sf("+", "", "", "2.0E-9")), 8,
                 "PBAR 2", "(I12): I1 = 1e-09, I2 = 1e-09 and I12 = 2e-09 give I1 I2 <= I12^2", id="pbar-i12"),
    pytest.param(base(sf("PBAR", 2, 1, "1.0E-4", "1.0E-9", "1.0E-9"), sf("+"), sf("+", "-0.5")), 8, "PBAR 2",
                 "(K1): value '-0.5' is out of range (expected a real number >= 0.0)", id="pbar-negative-k1"),
    pytest.param(base(sf("CONM2", 20, 1, "", "1.0"), sf("", "1.0", "2.0", "1.0", "", "", "1.0")), 7, "CONM2 20",
                 "continuation 1 fields 2-7 (I11-I33): the inertia matrix is not positive semi-definite",
                 id="conm2-inertia-not-psd"),
    pytest.param(base(sf("CELAS2", 20, "1.0", 1, 2, 1, 2)), 6, "CELAS2 20", "both ends are DOF 1-2",
                 id="celas2-same-dof"),
    pytest.param(base(sf("CELAS2", 20, "1.0", 1, 2, 2)), 6, "CELAS2 20", "field 7 (C2): required field is blank",
                 id="celas2-g2-without-c2"),
    pytest.param(base(sf("GRAV", 1, "", "9.81", "0.0", "0.0", "-1.0", 2)), 6, "GRAV 1",
                 "field 8 (MB): expected -1 or 0, got '2'", id="grav-mb"),
    pytest.param(base(sf("GRAV", 1, -1, "9.81", "0.0", "0.0", "-1.0")), 6, "GRAV 1",
                 "field 3 (CID): expected an integer >= 0, got '-1'", id="grav-negative-cid"),
    pytest.param(base(sf("EIGRL", 1, "", "-5.0")), 6, "EIGRL 1", "(V2): V2 = -5.0 (expected an upper frequency > 0.0",
                 id="eigrl-negative-v2"),
    pytest.param(base(sf("NLPARM", 1), sf("", "", "", "0.0")), 7, "NLPARM 1",
                 "(EPSW): value '0.0' is out of range (expected a real number > 0.0)", id="nlparm-zero-epsw"),
    pytest.param(base(sf("PARAM", "GRDPNT", 77)), 6, "PARAM GRDPNT", "field 3 (V1): grid 77 is not defined",
                 id="grdpnt-missing-grid"),
    pytest.param(base(sf("PARAM", "GRDPNT", "YES")), 6, "PARAM GRDPNT", "expected -1, 0 or a GRID ID, got 'YES'",
                 id="grdpnt-word"),
    pytest.param(base(sf("CORD2R", 1, -2, "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), CORD_LINE2), 6, "CORD2R 1",
                 "field 3 (RID): expected an integer >= 0, got '-2'", id="cord2r-negative-rid"),
    pytest.param(base(sf("PARAM", "WTMASS", "-0.00259")), 6, "PARAM WTMASS", "WTMASS '-0.00259' must be a positive",
                 id="wtmass"),
    # --- text and sections
    pytest.param("", 1, "", "the file is empty", id="empty-file"),
    pytest.param("$ only a comment\n\n", 2, "", "no bulk data cards", id="comments-only"),
    pytest.param("SOL 103\nCEND\nBEGIN BULK\n$ nothing\nENDDATA\n", 5, "", "no bulk data cards", id="empty-bulk"),
    pytest.param("SOL 103\nCEND\nSPC = 1\n" + text(*BASE), 2, "", "CEND but no BEGIN BULK", id="cend-no-begin-bulk"),
    pytest.param(base(sf("GRID", 3, "", "1.0\x00")), 6, "", "control character U+0000 at column 28",
                 id="nul-character"),
    pytest.param(text(*BASE[:2], "$ comment with an escape \x1b[31m", *BASE[2:]), 3, "",
                 "control character U+001B at column 26", id="escape-in-comment"),
    pytest.param(base(sf("GRID", 3, "", "1.0\u200b")), 6, "GRID 3", "field 4 (X1): expected a real number",
                 id="zero-width-space"),
    pytest.param(base(sf("GRÎD", 3)), 6, "GRÎD", "unknown card 'GRÎD'", id="non-ascii-card-name"),
    pytest.param(base(sf("GRID", 3, "", "1.0", "2.0", "3.0")[:33]), 6, "GRID 3", "field 5 (X2): expected a real number with a decimal point, got '2'",
                 id="truncated-line"),
    # --- case control
    pytest.param("CEND\nSUBCASE 1\nSUBCASE 1\nBEGIN BULK\nENDDATA\n", 3, "SUBCASE 1",
                 "SUBCASE 1 defined twice: line 2 and line 3", id="duplicate-subcase"),
    pytest.param(case("SUBCASE 1\n  SPC = 99", sf("SPC1", 1, 123456, 1)), 4, "SUBCASE 1",
                 "SPC set 99 is not defined (expected an SPC1 set ID)", id="subcase-spc-missing"),
    pytest.param(case("SUBCASE 1\n  MPC = 7\nSUBCASE 2"), 4, "SUBCASE 1", "MPC set 7 is not defined",
                 id="subcase-mpc-missing"),
    pytest.param(case("METHOD = 3\nSUBCASE 1\nSUBCASE 2\n  METHOD = 4", sf("EIGRL", 4, "", "", 10)), 3, "SUBCASE 1",
                 "METHOD set 3 is not defined (expected an EIGRL or EIGR set ID)", id="inherited-method-missing"),
    pytest.param(case("LOAD = 9"), 3, "global case control", "LOAD set 9 is not defined", id="global-load-missing"),
    pytest.param(case("SUBCASE 1\n  NLPARM = 2"), 4, "SUBCASE 1", "NLPARM set 2 is not defined",
                 id="subcase-nlparm-missing"),
    pytest.param(case("SUBCASE 1\n  SPC = ALL"), 4, "SUBCASE 1", "expected a set ID (positive integer), got 'ALL'",
                 id="subcase-spc-not-integer"),
    pytest.param(case("SUBCASE 1\n  SPC = 1\n  spc=2"), 5, "SUBCASE 1", "SPC selected twice: line 4 and line 5",
                 id="subcase-spc-twice"),
    pytest.param(case("SUBCOM 3"), 3, "global case control", "SUBCOM is not supported", id="subcom"),
]


@pytest.mark.parametrize("deck, line, card, phrase", BROKEN)
def test_broken_deck(deck: str, line: int, card: str, phrase: str) -> None:
    with pytest.raises(DeckError) as info:
        read_deck_text(deck)
    err = info.value
    message = str(err)
    assert err.line == line, message
    assert f"<string>:{line}: " in message
    assert card in message and (not card or err.card == card), message
    assert phrase in message
    assert "\n" not in message


def test_error_location_uses_given_name() -> None:
    with pytest.raises(DeckError) as info:
        read_deck_text(base(sf("CBAR", 41, 1, 1, 999, "0.0", "0.0", "1.0")), name="deck.bdf")
    err = info.value
    assert str(err) == "deck.bdf:6: CBAR 41, field 5 (GB): grid 999 is not defined (expected a GRID ID)"
    assert (err.file, err.line, err.card, err.field) == ("deck.bdf", 6, "CBAR 41", "field 5 (GB)")
    assert err.message == "grid 999 is not defined (expected a GRID ID)"
    assert isinstance(err, MaceError) and isinstance(err, ValueError)


def test_cord2r_error_comes_before_bar_checks() -> None:
    # Both the cycle and the (otherwise parallel) bar are wrong: the coordinate system is reported.
    deck = base(sf("CBAR", 11, 1, 1, 2, "2.0", "0.0", "0.0"),
                sf("CORD2R", 1, 1, "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), CORD_LINE2)
    with pytest.raises(DeckError, match="is a cycle"):
        read_deck_text(deck)


def test_read_deck_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "no_such_deck.bdf"
    with pytest.raises(DeckError) as info:
        read_deck(path)
    assert info.value.line == 0
    assert str(info.value) == f"{path}: no such file"


def test_undecodable_bytes_name_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "latin1.bdf"
    path.write_bytes(base(sf("GRID", 3, "", "1.0")).encode() + b"$ r\xe9sum\xe9\n")
    with pytest.raises(DeckError) as info:
        read_deck(path)
    assert info.value.line == 7
    assert str(info.value) == f"{path}:7: byte 0xe9 at column 4 is not text (expected an ASCII or UTF-8 text file)"


def test_utf8_comments_and_byte_order_mark_are_text(tmp_path: Path) -> None:
    path = tmp_path / "utf8.bdf"
    path.write_bytes("\ufeff$ Young's modulus in N/m² — résumé\n".encode() + base().encode())
    assert sorted(read_deck(path).grids) == [1, 2]


def test_structure_errors_name_the_case_control_line() -> None:
    from mace_fmu.structure.build import build_structure

    deck = read_deck_text(case("SUBCASE 1\n  SPC = 1", sf("SPC1", 1, 123456, 1)), name="deck.bdf")
    with pytest.raises(DeckError) as info:
        build_structure(deck, configuration="1g")
    assert str(info.value).startswith("deck.bdf:3: SUBCASE 1: the 1-g structure needs a subcase with a LOAD")
    with pytest.raises(DeckError) as info:
        build_structure(read_deck_text(base(), name="bulk.bdf"), configuration="0g")
    assert str(info.value).startswith("bulk.bdf:1: no case control")


def test_at_least_thirty_broken_decks() -> None:
    assert len(BROKEN) >= 30
