"""Decks that must read: the three field formats, continuations, numbers, case control, geometry."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.paths import ROOT

from mace_fmu.deck import Deck, DeckError, read_deck, read_deck_text
from mace_fmu.deck.fields import parse_real
from mace_fmu.deck.geometry import bar_orientation, coordinate_frames, grid_positions


def sf(name: str, *fields: object) -> str:
    """One small-field line: field 1 and data fields, 8 columns each."""
    return "".join(f"{str(x):<8}" for x in (name, *fields)).rstrip()


def lf(name: str, *fields: object) -> str:
    """One large-field line: field 1 (8 columns) and data fields of 16 columns."""
    return f"{name:<8}" + "".join(f"{str(x):<16}" for x in fields).rstrip()


def deck(*lines: str) -> Deck:
    return read_deck_text("\n".join(lines) + "\n")


MAT = sf("MAT1", 1, "7.0E10", "", "0.3")

# A minimal valid model: two grids, one bar, its property and material.
BAR = [
    sf("GRID", 1, "", "0.0", "0.0", "0.0"),
    sf("GRID", 2, "", "1.0", "0.0", "0.0"),
    sf("MAT1", 1, "7.0E10", "", "0.3", "2700.0"),
    sf("PBAR", 1, 1, "1.0E-4", "1.0E-9", "2.0E-9", "3.0E-9"),
    sf("CBAR", 10, 1, 1, 2, "0.0", "0.0", "1.0"),
]


def test_small_field_model() -> None:
    d = deck(*BAR)
    assert d.path == "<string>"
    assert d.grids[2].xyz == (1.0, 0.0, 0.0) and d.grids[2].cp == 0 and d.grids[2].cd == 0 and d.grids[2].ps == ""
    assert d.grids[2].source.line == 2 and str(d.grids[2].source) == "<string>:2"
    assert d.mat1s[1].e == 7.0e10 and d.mat1s[1].g is None and d.mat1s[1].nu == 0.3 and d.mat1s[1].rho == 2700.0
    p = d.pbars[1]
    assert (p.mid, p.area, p.i1, p.i2, p.j, p.nsm, p.i12) == (1, 1.0e-4, 1.0e-9, 2.0e-9, 3.0e-9, 0.0, 0.0)
    assert p.stress_points == (None,) * 8 and p.k1 is None and p.k2 is None
    b = d.bars[10]
    assert (b.pid, b.ga, b.gb, b.v, b.g0) == (1, 1, 2, (0.0, 0.0, 1.0), None)
    assert d.subcases == {} and d.global_case is None


def test_defaults_and_case_insensitive_names() -> None:
    d = deck(sf("grid", 7), sf("Grid", 8, "", "1.0", "", "", "", "2131"), sf("cbar", 3, "", 7, 8, "0.0", "1.0"),
             sf("pbar", 3, 1), sf("MAT1", 1, "", "1.0E9"))
    assert d.grids[7].xyz == (0.0, 0.0, 0.0)
    assert d.grids[8].ps == "123"  # sorted, unique
    assert d.bars[3].pid == 3  # PID defaults to EID
    assert d.bars[3].v == (0.0, 1.0, 0.0)  # blank X3 = 0.0
    assert d.pbars[3].area == 0.0 and d.mat1s[1].e is None and d.mat1s[1].g == 1.0e9


def test_large_field_grid_with_star_continuation() -> None:
    d = deck(lf("GRID*", 5, 0, "1.25", "-2.5"), lf("*", "3.75", 0, 246), lf("GRID*", 6, "", "1.0D-3", ""),
             lf("*", "4.99-12"))
    assert d.grids[5].xyz == (1.25, -2.5, 3.75) and d.grids[5].ps == "246"
    assert d.grids[6].xyz == (1.0e-3, 0.0, 4.99e-12)
    assert d.grids[6].source.line == 3


def test_large_field_name_with_blanks_before_the_star_as_nastran_punches_it() -> None:
    """``GRID   *``: the same card as ``GRID*``, as NASTRAN punches ``DESVAR *`` in models/aero/cpmopt.pch of pyNastran
    (that file as published: tests/deck/test_published_decks.py)."""
    d = deck("GRID   *               5               0            1.25            -2.5",
             "*                   3.75               0")
    assert d.grids[5].xyz == (1.25, -2.5, 3.75)


def test_case_control_subcase_with_an_equals_sign() -> None:
    """``SUBCASE=1`` (MSC.NASTRAN 2006 accepted it; modele_petite_zone.dat of pyNastran's models)."""
    text = "SOL 103\nCEND\nMETHOD = 1\nSUBCASE=1\n  SPC = 7\nSUBCASE = 2\n  SPC = 7\nBEGIN BULK\n" + "\n".join(
        [sf("GRID", 1), sf("SPC1", 7, 123456, 1), sf("EIGRL", 1, "", "", 5)]) + "\nENDDATA\n"
    d = read_deck_text(text, name="petite.dat")
    assert sorted(d.subcases) == [1, 2] and d.subcases[1].spc == 7


def test_a_load_selection_of_a_static_load_set_is_read_and_the_1g_preload_refuses_it() -> None:
    """``LOAD = 7`` naming a FORCE set directly, or a LOAD card combining one (NASTRAN runs both:
    models/frame_three_bars/bar1.dat of pyNastran): the 0-g modes take no load; the 1-g preload, which takes
    gravity only, says which set it met."""
    from mace_fmu.errors import MaceError
    from mace_fmu.fe.modes import compute_modes

    bulk = [sf("GRID", 1), sf("GRID", 2, "", "1.0"), sf("MAT1", 1, "7.0+10", "", "0.3", "2700.0"),
            sf("PBAR", 1, 1, "1.0-4", "1.0-8", "1.0-8", "2.0-8"), sf("CBAR", 1, 1, 1, 2, "0.0", "0.0", "1.0"),
            sf("SPC1", 1, 123456, 1), sf("EIGRL", 1, "", "", 3), sf("FORCE", 7, 2, "", "10.0", "0.0", "0.0", "-1.0"),
            sf("LOAD", 8, "1.0", "2.0", 7)]
    for load in (7, 8):
        d = read_deck_text(f"SOL 103\nCEND\nSPC = 1\nMETHOD = 1\nLOAD = {load}\nBEGIN BULK\n" + "\n".join(bulk)
                           + "\nENDDATA\n", name="bar1.dat")
        assert d.static_loads == {7: ("FORCE",)}
        assert compute_modes(d, configuration="0g").frequencies_hz[0] > 0
        with pytest.raises(MaceError, match=f"load set {load}: set 7 is a FORCE set; the 1-g preload takes gravity "
                                            "loads only"):
            compute_modes(d, configuration="1g")


@pytest.mark.parametrize("selection, refused", [("", False), ("TEMP(LOAD) = 3", False),
                                                ("TEMP(MATERIAL) = 3", True), ("TEMPERATURE = 3", True)])
def test_matt1_tablem1_and_dti_are_read_past_unless_the_materials_temperatures_are_selected(selection, refused):
    """MATT1, TABLEM1 and DTI (satk/pn_mwe_s-solution_1.dat of pyNastran's models): they change nothing unless the
    case control selects material temperatures (TEMP(MATERIAL), or TEMP(BOTH) as a plain TEMP means)."""
    bulk = [sf("GRID", 1), sf("GRID", 2, "", "1.0"), sf("MAT1", 1, "7.0+10", "", "0.3", "2700.0"),
            sf("MATT1", 1, 5), sf("TABLEM1", 5), ",20.0,1.0,100.0,0.9,ENDT",
            sf("DTI", "UNITS", 1, "KG", "N", "S", "M"),
            sf("PBAR", 1, 1, "1.0-4", "1.0-8", "1.0-8", "2.0-8"), sf("CBAR", 1, 1, 1, 2, "0.0", "0.0", "1.0"),
            sf("SPC1", 1, 123456, 1), sf("EIGRL", 1, "", "", 3)]
    text = (f"SOL 103\nCEND\nSPC = 1\nMETHOD = 1\n{selection}\nBEGIN BULK\n" + "\n".join(bulk)
            + "\nENDDATA\n")
    if refused:
        with pytest.raises(DeckError, match=r"pn_mwe.dat:5: global case control, TEMP: material temperatures 3 are "
                                            r"selected, and MATT1 \(first at pn_mwe.dat:\d+\) makes a material"):
            read_deck_text(text, name="pn_mwe.dat")
    else:
        d = read_deck_text(text, name="pn_mwe.dat")
        assert {name for name, *_ in d.skipped} >= {"MATT1", "TABLEM1", "DTI"}


def test_replication_lines_are_named_as_such_and_a_refusal_stays_short() -> None:
    """NASTRAN's ``=`` / ``==`` shorthand was listed as an unknown card; a deck of many foreign elements gave a
    refusal of 1.5 kB. Now: the shorthand by name, and at most six cards listed before "and N more"."""
    head = "BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\n"
    with pytest.raises(DeckError, match=r"x.bdf:4: =: a replication line '=' \(2 in all; NASTRAN's '=' and '==' "):
        read_deck_text(head + "=,*1,,=,=\n=,*1,,=,=\nENDDATA\n", name="x.bdf")
    foreign = "".join(f"{name},{k},1,1,2\n" for k, name in enumerate(
        ("CQUAD4", "CTRIA3", "CHEXA", "CPENTA", "CTETRA", "CSHEAR", "CBUSH", "CGAP", "CVISC", "CDAMP1"), start=1))
    with pytest.raises(DeckError) as refused:
        read_deck_text(head + foreign + "ENDDATA\n", name="x.bdf")
    text = str(refused.value)
    assert "CSHEAR (1x, first at line 9) and 4 more (supported: CBAR" in text and "CBUSH" not in text
    assert len(text) < 700


def test_free_field_with_continuations() -> None:
    d = deck("GRID,1,,0.0,0.0,0.0", "GRID,2,,1.0,0.0,0.0", "grid,3,,0.0,1.0,0.0",
             "CONM2,20,1,,2.5,0.1,,,,+C1",
             "+C1,1.0,,2.0,,,3.0",
             "MPC,5,1,1,1.0,2,1,-1.0",
             ",,3,1,0.5",
             "PARAM,POST,0")
    m = d.conm2s[20]
    assert (m.grid, m.cid, m.mass, m.offset) == (1, 0, 2.5, (0.1, 0.0, 0.0))
    assert m.inertia == (1.0, 0.0, 2.0, 0.0, 0.0, 3.0)
    terms = d.mpcs[5][0].terms
    assert [(t.grid, t.component, t.coefficient) for t in terms] == [(1, 1, 1.0), (2, 1, -1.0), (3, 1, 0.5)]
    assert d.params["POST"].values == (0,)


def test_free_field_large_card() -> None:
    d = deck("GRID*,4,,1.0,2.0,*G4", "*G4,3.0,,5")
    assert d.grids[4].xyz == (1.0, 2.0, 3.0) and d.grids[4].ps == "5"


def test_tab_separated_small_field() -> None:
    d = deck("GRID\t9\t\t1.0\t2.0\t3.0", "GRID\t10\t0\t1.5\t\t-2.0E-1\t0")
    assert d.grids[9].xyz == (1.0, 2.0, 3.0)
    assert d.grids[10].xyz == (1.5, 0.0, -0.2)


@pytest.mark.parametrize("text, value", [
    ("1.0", 1.0), ("1.", 1.0), (".5", 0.5), ("-1.0E-5", -1.0e-5), ("1.0e5", 1.0e5), ("1.0D-3", 1.0e-3),
    ("4.99-12", 4.99e-12), ("1.5+3", 1.5e3), ("+.5E+2", 50.0), ("-7.d2", -700.0),
    ("7", None), ("1.2.3", None), ("1.0E", None), ("E5", None), ("", None), ("nan", None)])
def test_real_numbers(text: str, value: float | None) -> None:
    assert parse_real(text) == value


def test_plain_reals_read_as_nastrans_grammar_reads_them() -> None:
    """Strings of digits, signs, points and E's (the ones parse_real gives to Python's float first), 30,000 at
    random: each is read as NASTRAN's grammar of a real reads it (a decimal point, an E/D or implicit exponent),
    the grammar applied on its own."""
    from mace_fmu.deck import fields

    def by_grammar(text: str) -> float | None:
        m = fields._REAL.fullmatch(text)
        return None if m is None else float(f"{m.group(1)}e{m.group(2) or m.group(3) or '0'}")

    rng = np.random.default_rng(7)
    alphabet = np.array(list("0123456789.+-eE"))
    weights = np.array([3.0] * 10 + [4.0, 1.0, 1.0, 1.0, 1.0])
    for _ in range(30_000):
        text = "".join(rng.choice(alphabet, size=rng.integers(1, 9), p=weights / weights.sum()))
        assert parse_real(text) == by_grammar(text), text



def test_the_plain_bar_route_reads_what_the_checked_route_reads_and_nothing_it_refuses() -> None:
    """CBARs and CBEAMs read without the field-by-field checks (the one-line card with a vector or G0) give the
    record the checked route gives, and a card that route refuses never passes: 20,000 cards of fields drawn at
    random from valid and invalid IDs, reals, words and blanks, on one line or two, read as either card."""
    from mace_fmu.deck.fields import Fields, RawCard
    from mace_fmu.deck.parsers import bars

    rng = np.random.default_rng(11)
    ids = ["1", "2", "7", "12"] * 6 + ["0", "-3", "", "1.0", "A", "\u0663"]  # mostly valid: both routes are drawn
    reals = ["0.0", "1.0", "-2.5e-1", "1.", "4.99-12", "0.", "-0.0"] * 3 + ["", "0", "3", "1.0e999", "x", "7"]
    tails = [""] * 12 + ["GGG", "BGG", "1", "2", "0"]
    plain = 0
    for _ in range(20_000):
        fields = [str(rng.choice(ids)) for _ in range(4)] + [str(rng.choice(reals)) for _ in range(3)]
        if rng.random() < 0.2:  # field 5 the G0 of the two ends' or another grid
            fields[4:7] = [fields[int(rng.integers(2, 4))] if rng.random() < 0.3 else "9", "", ""]
        fields.append(str(rng.choice(tails)))
        if rng.random() < 0.1:  # a continuation: pin flags and offsets, blank or not
            fields += [str(rng.choice(["", "", "0", "1", "0.0", "2.5"])) for _ in range(8)]
        quick = bars._plain_two_node_beam(fields)
        for name, offt, last in (("CBAR", "OFFT", 16), ("CBEAM", "OFFT/BIT", 18)):
            f = Fields(RawCard(name, 1, fields=fields, lines=[1] * len(fields)), "deck.bdf")
            try:
                checked = bars._two_node_beam(f, offt)
                f.end(last)  # a CBEAM's SA and SB (fields 17-18) lie beyond these cards
            except DeckError:
                assert quick is None, fields
                continue
            if quick is not None:
                plain += 1
                assert quick == checked, fields
    assert plain > 1000  # the draw reaches the route it tests


def test_implicit_exponent_in_cards() -> None:
    d = deck(sf("PBAR", 5, 5, "7.92E-6", "4.99-12", "4.99-12", "9.98-12"), sf("MAT1", 5, "198.2E9", "", "1.0D-1"))
    assert d.pbars[5].i1 == 4.99e-12 and d.pbars[5].j == pytest.approx(9.98e-12, rel=1e-15)
    assert d.mat1s[5].nu == pytest.approx(0.1)


def test_pbar_first_continuation_is_stress_points_not_shear_factors() -> None:
    d = deck(sf("PBAR", 1, 1, "2.56E-4", "2.14E-8", "2.14E-8", "4.27E-8"), sf("", "0.54921", "0.54921"), MAT)
    p = d.pbars[1]
    assert p.stress_points == (0.54921, 0.54921, None, None, None, None, None, None)
    assert p.k1 is None and p.k2 is None and p.i12 == 0.0


def test_pbar_second_continuation_gives_shear_factors() -> None:
    d = deck(sf("PBAR", 1, 1, "2.56E-4", "2.14E-8", "2.14E-8", "4.27E-8", "0.1", "", "+P1"),
             sf("+P1", "0.01", "0.02", "", "", "", "", "", "-0.01", "+P2"),
             sf("+P2", "0.85", "0.9", "1.0E-9"), MAT)
    p = d.pbars[1]
    assert p.nsm == 0.1
    assert p.stress_points == (0.01, 0.02, None, None, None, None, None, -0.01)
    assert (p.k1, p.k2, p.i12) == (0.85, 0.9, 1.0e-9)


def test_short_parent_line_is_padded_before_continuation() -> None:
    # The parent stops after NSM; the continuation still starts at data field 9 (C1).
    d = deck(sf("PBAR", 1, 1, "1.0"), "+", sf("+", "0.5", "0.6"), MAT)
    assert d.pbars[1].stress_points == (None,) * 8
    assert (d.pbars[1].k1, d.pbars[1].k2) == (0.5, 0.6)


def test_mpc_with_continuations_and_sets() -> None:
    grids = [sf("GRID", g, "", f"{g}.0") for g in range(1, 6)]
    d = deck(*grids,
             sf("MPC", 5, 1, 1, "1.0", 2, 1, "-0.5"),
             sf("", "", 3, 1, "-0.25", 4, 1, "-0.25"),
             sf("", "", 5, 2, "1.0E-3"),
             sf("MPC", 5, 2, 3, "1.0", 3, 3, "-1.0"),
             sf("MPC", 6, 1, 1, "1.0", 2, 1, "-1.0"))
    first, second = d.mpcs[5]
    assert [(t.grid, t.component, t.coefficient) for t in first.terms] == [
        (1, 1, 1.0), (2, 1, -0.5), (3, 1, -0.25), (4, 1, -0.25), (5, 2, 1.0e-3)]
    assert first.sid == 5 and first.source.line == 6 and second.source.line == 9
    assert [t.grid for t in second.terms] == [2, 3]
    assert len(d.mpcs[6]) == 1


def test_spc1_lists_thru_and_continuations() -> None:
    grids = [sf("GRID", g) for g in (1, 2, 3, 5, 8, 9)]
    d = deck(*grids,
             sf("SPC1", 1, 321, 1, 2, 3, 5, 8, 9),
             sf("", 1),
             sf("SPC1", 1, 456, 2, "THRU", 7),
             sf("SPC1", 2, 1123456, 9))
    listed, thru = d.spc1s[1]
    assert listed.components == "123" and listed.grids == (1, 2, 3, 5, 8, 9, 1)
    assert thru.components == "456" and thru.grids == (2, 3, 5)  # grids 4, 6, 7 do not exist: skipped (MSC)
    assert d.spc1s[2][0].components == "123456"


def test_conm2_inertia_on_continuation() -> None:
    d = deck(sf("GRID", 3), sf("CONM2", 1, 3, "", "0.17033", "0.0", "0.01", "0.0"),
             sf("", "4.21E-5", "", "4.60E-5", "", "", "4.60E-5"),
             sf("CONM2", 2, 3, 0, "1.0"), sf("", "1.0", "0.1", "2.0", "0.2", "0.3", "3.0"))
    assert d.conm2s[1].inertia == (4.21e-5, 0.0, 4.60e-5, 0.0, 0.0, 4.60e-5)
    assert d.conm2s[1].offset == (0.0, 0.01, 0.0)
    assert d.conm2s[2].inertia == (1.0, 0.1, 2.0, 0.2, 0.3, 3.0)


def test_loads_springs_eigrl_nlparm_params() -> None:
    d = deck(sf("GRID", 1), sf("GRID", 2),
             sf("CELAS2", 11, "16.9878", 1, 2), sf("CELAS2", 12, "1.0E3", 1, 6, 2, 6),
             sf("GRAV", 9999, "", "9.807", "0.0", "-1.0"),
             sf("GRAV", 9998, 0, "1.0", "1.0"),
             sf("LOAD", 100, "1.0", "1.0", 9999, "0.5", 9998),
             sf("EIGRL", 1, "-1.0", "250.", 200, 3),
             sf("EIGRL", 2, "", "", 10),
             sf("NLPARM", 1, 1),
             sf("NLPARM", 10, 20, "", "iter", 1, 25, "w"),
             sf("", "", "", "1.5E-4"),
             sf("PARAM", "GRDPNT", 2), sf("PARAM", "autospc", "no"), sf("PARAM", "WTMASS", "1.0"),
             "PARAM,DBCCONV,XL")
    assert d.celas2s[11].g2 is None and d.celas2s[11].c2 is None and d.celas2s[11].c1 == 2
    assert (d.celas2s[12].g2, d.celas2s[12].c2, d.celas2s[12].k) == (2, 6, 1.0e3)
    assert d.gravs[9999].direction == (0.0, -1.0, 0.0) and d.gravs[9999].scale == 9.807 and d.gravs[9999].cid == 0
    assert d.loads[100].scale == 1.0 and d.loads[100].terms == ((1.0, 9999), (0.5, 9998))
    assert (d.eigrls[1].v1, d.eigrls[1].v2, d.eigrls[1].nd, d.eigrls[1].msglvl) == (-1.0, 250.0, 200, 3)
    assert (d.eigrls[2].v1, d.eigrls[2].v2, d.eigrls[2].nd, d.eigrls[2].msglvl) == (None, None, 10, 0)
    n1, n10 = d.nlparms[1], d.nlparms[10]
    assert (n1.ninc, n1.kmethod, n1.kstep, n1.max_iter, n1.conv, n1.eps_u, n1.eps_p, n1.eps_w) == (
        1, "AUTO", None, 25, "PW", 0.01, 0.01, 0.01)
    assert (n10.ninc, n10.kmethod, n10.kstep, n10.max_iter, n10.conv, n10.eps_u, n10.eps_w) == (
        20, "ITER", 1, 25, "W", 0.01, 1.5e-4)
    assert d.params["GRDPNT"].values == (2,) and d.params["AUTOSPC"].values == ("NO",)
    assert d.params["WTMASS"].values == (1.0,) and d.params["DBCCONV"].values == ("XL",)
    assert isinstance(d.params["WTMASS"].values[0], float) and d.params["GRDPNT"].name == "GRDPNT"


CASE_DECK = """\
SOL 106
TIME 2000
CEND
TITLE = test $ comment
METHOD = 1
LABEL = global label
spc=51
SUBCASE 1
  LABEL = Gravity preload, mechanisms locked
  SPC = 52
  MPC=5
  LOAD = 100
  NLPARM = 10
  DISP = ALL
SUBCASE 2
$ PARAM,EIGEN,1
  mpc = 5
  NLPARM = 1
BEGIN BULK
{bulk}
ENDDATA
this text after ENDDATA is ignored: FOO BAR 1.2.3
"""


def test_case_control_subcases_inherit_global_values() -> None:
    bulk = "\n".join([sf("GRID", 1), sf("GRID", 2), sf("SPC1", 51, 123456, 1), sf("SPC1", 52, 123, 1),
                      sf("MPC", 5, 1, 1, "1.0", 2, 1, "-1.0"), sf("GRAV", 100, "", "9.81", "0.0", "-1.0"),
                      sf("NLPARM", 10), sf("NLPARM", 1), sf("EIGRL", 1, "", "", 5)])
    d = read_deck_text(CASE_DECK.format(bulk=bulk), name="mace.bdf")
    g = d.global_case
    assert g is not None and (g.id, g.spc, g.mpc, g.load, g.nlparm, g.method, g.label) == (
        0, 51, None, None, None, 1, "global label")
    s1, s2 = d.subcases[1], d.subcases[2]
    assert (s1.spc, s1.mpc, s1.load, s1.nlparm, s1.method) == (52, 5, 100, 10, 1)
    assert s1.label == "Gravity preload, mechanisms locked" and s1.source == d.subcases[1].source
    assert s1.source.line == 8 and s1.source.file == "mace.bdf"
    assert (s2.spc, s2.mpc, s2.load, s2.nlparm, s2.method, s2.label) == (51, 5, None, 1, 1, "global label")
    assert list(d.subcases) == [1, 2]


def test_case_control_without_subcase_goes_to_global_case() -> None:
    d = read_deck_text("CEND\nSPC = 1\nBEGIN BULK\n" + sf("GRID", 1) + "\n" + sf("SPC1", 1, 1, 1) + "\nENDDATA")
    assert d.subcases == {} and d.global_case is not None and d.global_case.spc == 1


def test_begin_bulk_without_executive_control_and_spacing() -> None:
    d = read_deck_text("  begin   bulk  \n" + sf("GRID", 1) + "\nenddata\n")
    assert list(d.grids) == [1] and d.global_case is not None and d.subcases == {}


def test_comments_mid_line_and_blank_lines() -> None:
    d = deck("$ full-line comment", "", sf("GRID", 1, "", "1.0") + "  $ X2 X3 blank",
             "GRID    2               2.0$3.0 is inside the comment", "   ", "GRID,3,,4.0 $,5.0",
             sf("PBAR", 1, 1, "1.0") + " $ no continuation", "$ a comment between parent and continuation",
             sf("", "0.5"), MAT)
    assert d.grids[1].xyz == (1.0, 0.0, 0.0) and d.grids[2].xyz == (2.0, 0.0, 0.0)
    assert d.grids[3].xyz == (4.0, 0.0, 0.0)
    assert d.pbars[1].stress_points[0] == 0.5


def test_bulk_only_file_with_and_without_enddata() -> None:
    d = deck(*BAR)
    assert len(d.grids) == 2
    d = deck(*BAR, "ENDDATA", "GARBAGE after the end")
    assert len(d.bars) == 1


def test_element_ids_of_different_types_may_differ() -> None:
    d = deck(*BAR, sf("CONM2", 11, 1, "", "1.0"), sf("CELAS2", 12, "1.0", 2, 3))
    assert set(d.bars) | set(d.conm2s) | set(d.celas2s) == {10, 11, 12}


def test_cord2r_chain_positions() -> None:
    # System 1: origin (1, 0, 0), x = basic Y, z = basic Z (so y = -basic X).
    # System 2, given in system 1: origin (0, 0, 2)_1 = (1, 0, 2), z along x_1 = basic Y,
    # C - A along z_1 so x_2 = basic Z, y_2 = z_2 x x_2 = basic X.
    d = deck(sf("CORD2R", 2, 1, "0.0", "0.0", "2.0", "1.0", "0.0", "2.0"), sf("", "0.0", "0.0", "3.0"),
             sf("CORD2R", 1, "", "1.0", "0.0", "0.0", "1.0", "0.0", "1.0"), sf("", "1.0", "1.0", "0.0"),
             sf("GRID", 10, 2, "1.0", "2.0", "3.0"),
             sf("GRID", 11, 1, "1.0", "2.0", "3.0"),
             sf("GRID", 12, 0, "1.0", "2.0", "3.0"))
    frames = coordinate_frames(d)
    np.testing.assert_allclose(frames[1][0], [1.0, 0.0, 0.0])
    np.testing.assert_allclose(frames[1][1], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(frames[2][0], [1.0, 0.0, 2.0])
    np.testing.assert_allclose(frames[2][1], [[0, 1, 0], [0, 0, 1], [1, 0, 0]], atol=1e-15)
    pos = grid_positions(d)
    np.testing.assert_allclose(pos[10], [3.0, 3.0, 3.0], atol=1e-15)  # (1,0,2) + 1 Z + 2 X + 3 Y
    np.testing.assert_allclose(pos[11], [-1.0, 1.0, 3.0], atol=1e-15)  # (1,0,0) + 1 Y - 2 X + 3 Z
    np.testing.assert_allclose(pos[12], [1.0, 2.0, 3.0])


def test_cord2r_skew_axes_are_orthonormal() -> None:
    d = deck(sf("CORD2R", 3, 0, "0.0", "0.0", "0.0", "-0.70715", "0.57729", "-0.40827"), sf("", "0.0", "1.0", "0.0"))
    rot = coordinate_frames(d)[3][1]
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)
    np.testing.assert_allclose(rot[:, 2], np.array([-0.70715, 0.57729, -0.40827]) / np.linalg.norm([-0.70715, 0.57729,
                                                                                                   -0.40827]))


def test_orientation_vector_in_cd_system_and_by_g0() -> None:
    # Grid 1 measures displacements in system 1 (x = basic Y). The bar lies along basic X, so
    # v = (1, 0, 0) would be parallel to it in basic, but in system 1 it is basic Y: valid.
    d = deck(sf("CORD2R", 1, "", "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), sf("", "0.0", "1.0", "0.0"),
             sf("GRID", 1, "", "0.0", "0.0", "0.0", 1), sf("GRID", 2, "", "2.0", "0.0", "0.0"),
             sf("GRID", 3, "", "0.0", "0.0", "5.0"),
             sf("MAT1", 1, "7.0E10"), sf("PBAR", 1, 1, "1.0"),
             sf("CBAR", 1, 1, 1, 2, "1.0", "0.0", "0.0"),
             sf("CBAR", 2, 1, 2, 1, 3))
    frames = coordinate_frames(d)
    pos = grid_positions(d, frames)
    np.testing.assert_allclose(bar_orientation(d, d.bars[1], pos, frames), [0.0, 1.0, 0.0], atol=1e-15)
    assert d.bars[2].g0 == 3 and d.bars[2].v is None
    np.testing.assert_allclose(bar_orientation(d, d.bars[2], pos, frames), [-2.0, 0.0, 5.0])


def test_all_bars_oriented_at_once_against_the_closed_form() -> None:
    """bar_orientations (every bar at once, what the check and the assembly use), a mix of vectors in GA's CD
    system, in basic (OFFT BGG) and by G0, against the closed form: system 1's axes are x = basic Y,
    y = -basic X, z = basic Z, so (1, 0, 0) there is (0, 1, 0) in basic and (0.3, 0, 1) is (0, 0.3, 1); a G0
    gives pos(G0) - pos(GA)."""
    from mace_fmu.deck.geometry import bar_orientations

    d = deck(sf("CORD2R", 1, "", "0.0", "0.0", "0.0", "0.0", "0.0", "1.0"), sf("", "0.0", "1.0", "0.0"),
             sf("GRID", 1, "", "0.0", "0.0", "0.0", 1), sf("GRID", 2, "", "2.0", "0.0", "0.0"),
             sf("GRID", 3, "", "0.0", "0.0", "5.0"), sf("GRID", 4, "", "1.0", "1.0", "0.0", 1),
             sf("MAT1", 1, "7.0E10"), sf("PBAR", 1, 1, "1.0"),
             sf("CBAR", 1, 1, 1, 2, "1.0", "0.0", "0.0"), sf("CBAR", 2, 1, 2, 1, 3),
             sf("CBAR", 3, 1, 1, 2, "0.0", "1.0", "0.0", "BGG"), sf("CBAR", 4, 1, 4, 3, "0.3", "0.0", "1.0"),
             sf("CBAR", 5, 1, 2, 3, "0.0", "1.0", "0.0"), sf("CBAR", 6, 1, 4, 2, 3))
    frames = coordinate_frames(d)
    pos = grid_positions(d, frames)
    bars = list(d.bars.values())
    expected = np.array([[0.0, 1.0, 0.0], [-2.0, 0.0, 5.0], [0.0, 1.0, 0.0], [0.0, 0.3, 1.0], [0.0, 1.0, 0.0],
                         [-1.0, -1.0, 5.0]])
    np.testing.assert_allclose(bar_orientations(d, bars, pos, frames), expected, rtol=0, atol=1e-14)
    assert bar_orientations(d, [], pos, frames).shape == (0, 3)


def test_read_deck_from_file(tmp_path: Path) -> None:
    path = tmp_path / "model.bdf"
    path.write_text("SOL 103\nCEND\nSUBCASE 4\nBEGIN BULK\n" + "\n".join(BAR) + "\nENDDATA\n")
    d = read_deck(path)
    assert d.path == str(path) and len(d.bars) == 1 and d.grids[1].source.file == str(path)
    assert list(d.subcases) == [4]


def test_error_message_format() -> None:
    err = DeckError("grid 999 is not defined (expected a GRID ID)", file="deck.bdf", line=123, card="CBAR 41",
                    field="field 5 (GB)")
    assert str(err) == "deck.bdf:123: CBAR 41, field 5 (GB): grid 999 is not defined (expected a GRID ID)"
    assert (err.file, err.line, err.card, err.field) == ("deck.bdf", 123, "CBAR 41", "field 5 (GB)")
    assert str(DeckError("no card", file="x", line=1)) == "x:1: no card"
    assert isinstance(err, ValueError)


def test_bundled_mace_deck_reads() -> None:
    path = ROOT / "mace_fmu" / "data" / "mace_em.bdf"
    if not path.exists():
        pytest.skip("bundled deck not present")
    d = read_deck(path)
    assert d.grids and d.bars and d.pbars and d.mpcs and set(d.subcases) == {1, 2}
    assert all(p.k1 is None and p.k2 is None for p in d.pbars.values())  # only C1/C2 are printed
