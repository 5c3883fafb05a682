"""Decks NASTRAN runs, read as published: what the reader accepts and what it says.

The decks are pyNastran's files, copied unedited into tests/data/nastran (provenance.toml gives each file's
path and git blob id; tests/fe/test_nastran_decks.py checks the bytes). Each test names the NASTRAN feature
the deck uses and asserts what the deck means: the set a LOAD selects, a subcase's selections, the values of
a large-field card, NASTRAN's frequencies where the run has them. Where a test changes a deck (to show a
refusal NASTRAN's own run did not need), it says so and changes it in memory only.
"""

from __future__ import annotations

import re
import shutil
import tomllib

import numpy as np
import pytest
from support.paths import DATA

from mace_fmu.cli import main
from mace_fmu.deck.fields import case_control, split_sections
from mace_fmu.deck.reader import read_deck, read_deck_text
from mace_fmu.errors import DeckError, MaceError
from mace_fmu.fe.modes import compute_modes

NASTRAN = DATA / "nastran"


def _cli(capsys, argv: list[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_bar1_load_selects_a_force_set_directly():
    """models/frame_three_bars/bar1.dat (MSC's Linear Static Analysis User's Guide, problem 4.5): ``LOAD = 1``
    names the FORCE set 1 itself, no LOAD card (it was refused: "LOAD set 1 is not defined"). The 1-g preload,
    which takes gravity only, names the set it met and the deck."""
    path = NASTRAN / "frame_three_bars" / "bar1.dat"
    deck = read_deck(path)
    assert deck.global_case.load == 1 and deck.global_case.label == "POINT LOAD AT GRID POINT 4"
    assert deck.static_loads == {1: ("FORCE",)}
    assert ("FORCE", 1, f"{path}:42") in deck.skipped  # the FORCE card's line
    assert sorted(deck.bars) == [1, 2, 3] and deck.grids[4].xyz == (0.0, 0.0, 1000.0)
    with pytest.raises(MaceError, match=re.escape(f"{path}: load set 1: set 1 is a FORCE set; the 1-g preload takes "
                                                  "gravity loads only (GRAV)")):
        compute_modes(deck, configuration="1g")


def test_bar1_has_no_mass_and_the_modes_say_so(capsys):
    """bar1.dat is a static deck: its MAT1 has no RHO and it has no mass element. Its 0-g modes said "no modes in
    the range asked for, up to 250 Hz": K phi = lambda M phi with M = 0 has no finite root, and
    the message now says why."""
    path = NASTRAN / "frame_three_bars" / "bar1.dat"
    message = (f"{path}: the deck has no mass: no CONM1, CONM2, CMASS1, CMASS2 or PMASS card and no density (RHO) on "
               "its MAT1 cards nor non-structural mass (NSM) on its properties, so it has no vibration modes (expected "
               "RHO on the MAT1 cards, or mass elements)")
    with pytest.raises(MaceError) as caught:
        compute_modes(read_deck(path), configuration="0g")
    assert str(caught.value) == message
    code, _, err = _cli(capsys, ["modes", "0g", "--deck", str(path)])
    assert code == 2 and err == f"mace-fmu: error: {message}\n"


def test_grid_point_forces_load_selects_pload1_cards_directly():
    """models/grid_point_forces/bar_grid_point_forces.bdf (with its INCLUDE cbar_cbeam.blk): subcase 1's
    ``LOAD = 10`` names ten PLOAD1 cards directly; read, and the structure's modes computed."""
    path = NASTRAN / "grid_point_forces" / "bar_grid_point_forces.bdf"
    deck = read_deck(path)
    assert deck.subcases[1].load == 10 and deck.subcases[1].spc == 1
    assert deck.static_loads == {10: ("PLOAD1",)}
    assert ("PLOAD1", 10, f"{path}:46") in deck.skipped
    assert len(deck.bars) == 9 and len(deck.beams) == 1  # from the INCLUDEd file
    assert len(compute_modes(deck, configuration="0g").modes) > 0


def test_modele_petite_zone_subcase_with_an_equals_sign_is_read():
    """models/modele_petite_zone/modele_petite_zone.dat (MSC.NASTRAN 2006): ``SUBCASE=1`` and the selections
    under it are the case control NASTRAN read. The deck's shells (PSHELL, CQUAD4) are outside mace-fmu's
    element set, so reading the whole deck stops at them, in a short message naming them, and not at the
    subcase."""
    path = NASTRAN / "modele_petite_zone" / "modele_petite_zone.dat"
    lines = list(enumerate(path.read_text(encoding="latin-1").splitlines(), start=1))
    case, _ = split_sections(lines, str(path))
    global_case, subcases, _ = case_control(case, str(path))
    assert (global_case.spc, global_case.load) == (2, 2)
    assert list(subcases) == [1] and subcases[1].source.line == 17
    one = subcases[1]
    assert (one.load, one.spc, one.mpc, one.label) == (1, 2, 101106, "chargement")
    with pytest.raises(DeckError, match=re.escape(f"{path}:196: PSHELL: cards this reader cannot model: PSHELL (8x, "
                                                  "first at line 196), CQUAD4 (8x, first at line 199)")) as refused:
        read_deck(path)
    assert "SUBCASE" not in str(refused.value)


def test_modele_petite_zone_refusal_is_short_and_verbose_lists_every_card(capsys):
    path = NASTRAN / "modele_petite_zone" / "modele_petite_zone.dat"
    code, _, err = _cli(capsys, ["modes", "0g", "--deck", str(path)])
    assert code == 2 and err.count("\n") == 2 and err.endswith("  (2 lines more with mace-fmu --verbose ...)\n")
    code, _, err = _cli(capsys, ["--verbose", "modes", "0g", "--deck", str(path)])
    assert code == 2 and "  PSHELL: 8 card(s), first at line 196\n  CQUAD4: 8 card(s), first at line 199" in err


def test_cpmopt_punch_large_field_cards_as_nastran_writes_them(tmp_path):
    """models/aero/cpmopt.pch, NASTRAN's punch of an optimised design: ``DESVAR *`` (blanks between the name and
    the large-field star) and PBAR* cards with blank ``*`` continuations. The punch has no MAT1 (it is meant to
    be INCLUDEd in its deck), so a deck of three MAT1s INCLUDEs the published file: every PBAR field comes out
    as punched, and the three DESVARs are read past as design data."""
    shutil.copy(NASTRAN / "cpmopt" / "cpmopt.pch", tmp_path / "cpmopt.pch")
    materials = "".join(f"MAT1,{mid},1.0+7,,0.3,0.1\n" for mid in (1, 2, 3))
    (tmp_path / "design.bdf").write_text(f"BEGIN BULK\n{materials}INCLUDE 'cpmopt.pch'\nENDDATA\n")
    deck = read_deck(tmp_path / "design.bdf")
    punched = {100: (1, 2.0, 1.73611000e-01, 1.50000006e-01, 5.0e-01),
               101: (2, 3.67486668, 4.25331533e-01, 4.89982224, 1.13421822),
               102: (2, 1.46452260, 1.69504821e-01, 1.95269680, 4.52013195e-01),
               301: (3, 7.76864365e-02, 8.99147987e-03, 1.03581913e-01, 2.39772964e-02)}
    assert {pid: (p.mid, p.area, p.i1, p.i2, p.j) for pid, p in deck.pbars.items()} == punched
    assert ("DESVAR", 3, f"{tmp_path / 'cpmopt.pch'}:11") in deck.skipped


def _satk_reference() -> np.ndarray:
    with open(NASTRAN / "satk" / "reference_frequencies.toml", "rb") as handle:
        return np.array(tomllib.load(handle)["cycles"])


def test_satk_temperature_tables_are_read_past_and_the_modes_are_nastrans(capsys):
    """models/satk/pn_mwe_s-solution_1.dat (Simcenter Nastran 2022.1): a MATT1 with three TABLEM1s and a DTI
    MATALL; no case control selects material temperatures, so they change nothing: read past, said in one line,
    and the three roots of its EIGRL (0.1 to 2000 Hz) are NASTRAN's (its .op2) within 1e-4 (measured 2.4e-5: that run's
    lumped CBAR mass has rotary inertia, tests/fe/test_nastran_decks.py)."""
    path = NASTRAN / "satk" / "pn_mwe_s-solution_1.dat"
    deck = read_deck(path)
    skipped = {name: count for name, count, _ in deck.skipped}
    assert skipped["MATT1"] == 1 and skipped["TABLEM1"] == 3 and skipped["DTI"] == 1
    np.testing.assert_allclose(compute_modes(deck, configuration="0g").frequencies_hz, _satk_reference(), rtol=1e-4)
    code, out, _ = _cli(capsys, ["modes", "0g", "--deck", str(path)])
    read_past = [line for line in out.splitlines() if line.startswith("read past")]
    assert code == 0 and len(read_past) == 1
    assert f"DTI (1x, first at {path}:154), MATT1 (1x, first at {path}:135), TABLEM1 (3x, first at {path}:136)" \
        in read_past[0]


def test_satk_with_material_temperatures_selected_is_refused_naming_the_matt1():
    """The same deck with ``TEMPERATURE(MATERIAL) = 1`` added to its subcase (in memory; NASTRAN would then take
    E, nu and alpha from the TABLEM1s at the temperatures of set 1): mace-fmu models temperature-independent
    materials, so it refuses, naming the selection's line and the MATT1."""
    path = NASTRAN / "satk" / "pn_mwe_s-solution_1.dat"
    text = path.read_text(encoding="latin-1")
    text = text.replace("  METHOD = 103\n", "  METHOD = 103\n  TEMPERATURE(MATERIAL) = 1\n")
    with pytest.raises(DeckError, match=re.escape(
            "satk.dat:61: SUBCASE 3, TEMP: material temperatures 1 are selected, and MATT1 (first at satk.dat:136) "
            "makes a material depend on them: mace-fmu models temperature-independent materials")):
        read_deck_text(text, name="satk.dat")


def test_v10111_replication_lines_are_named_as_such():
    """models/other/v10111.bdf (MSC's conical-shell demo): four lines of NASTRAN's ``=``/``=(n)`` replication
    shorthand. The refusal names the first by what it is (they were listed as unknown cards "=" and "=(7)")."""
    path = NASTRAN / "v10111" / "v10111.bdf"
    with pytest.raises(DeckError) as refused:
        read_deck(path)
    message = str(refused.value)
    assert message.startswith(f"{path}:26: =: a replication line '=' (4 in all; NASTRAN's '=' and '==' shorthand")
    assert "=(7)" not in message and "cannot model" not in message and len(message) < 400 + len(str(path))


def test_buckled_strut_mass_properties_say_the_decks_units_and_the_basic_origin(capsys):
    """nlfltr/buckled (inch-pound-second era MSC deck, WTMASS 1/32.2, PARAM,GRDPNT,0): the mass line names no kg
    or m (the deck states no units) and says the inertia is about the basic origin; the numbers are NASTRAN's
    grid point weight generator's (tests/fe/test_nastran_decks.py checks them to 1e-6)."""
    deck = NASTRAN / "nlfltr_buckled" / "buckled.bdf"
    code, out, _ = _cli(capsys, ["modes", "0g", "--deck", str(deck)])
    line = next(line for line in out.splitlines() if line.startswith("mass "))
    assert code == 0 and line.startswith("mass 7641.6650 (the deck's mass unit), centre of mass [16.55644, 3.00333, "
                                         "-0.09865] (the deck's length unit), inertia about the basic origin: Jxx")
    assert "kg" not in line and " m^2" not in line and "grid None" not in line


def test_an_undefined_displacement_system_names_every_system_card_the_reader_takes():
    """The undefined-CP/CD message lists CORD1R beside CORD2R (it omitted the CORD1R the reader accepts). No
    published deck has an undefined system; bar1.dat's grid 4 is given CD 5 in memory."""
    path = NASTRAN / "frame_three_bars" / "bar1.dat"
    text = path.read_text(encoding="latin-1").replace("GRID    4               0.      0.      1000.           ",
                                                      "GRID    4               0.      0.      1000.   5       ")
    with pytest.raises(DeckError, match=r"bar1.dat:\d+: GRID 4, field 7 \(CD\): coordinate system 5 is not defined "
                                        r"\(expected 0 or a CORD2R or CORD1R ID\)"):
        read_deck_text(text, name="bar1.dat")

