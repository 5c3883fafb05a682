"""Real NASTRAN decks as published, against NASTRAN's own frequencies.

Each folder of tests/data/nastran holds a deck copied unedited from the pyNastran repository (licence in
tests/data/nastran/LICENSE-pyNastran.txt) and reference_frequencies.toml: the CYCLES column of the real
eigenvalue table of the .f06 NASTRAN wrote for it, copied once by tests/data/nastran/f06_frequencies.py (or by
op2_frequencies.py from the .op2, for a run published with that only). One deck, nlfltr/buckled, is published
as its .f06 only: the folder holds that .f06 and the deck f06_echo.py rebuilt from its echoes (checked below).
The decks are read through the public route (read_deck, compute_modes), with the modes their own
EIGRL/EIGR asks for, and every mode is checked against NASTRAN's: 1e-4 relative for the elastic modes,
NASTRAN's printed 7 digits being ~1e-6; rigid-body modes (NASTRAN: below 0.01 Hz) must come out below
1e-3 Hz.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from support.paths import DATA

from mace_fmu.deck.reader import read_deck, read_deck_text
from mace_fmu.errors import DeckError, MaceError
from mace_fmu.fe import assembly
from mace_fmu.fe.modes import compute_modes

NASTRAN = DATA / "nastran"
COMMIT = "1d25a92442a76cd1b24bfd0bd4008644b79322b2"  #: the pyNastran commit of every file (provenance.toml)
RELATIVE = 1e-4  #: elastic modes
RIGID_HZ = 0.01  #: NASTRAN frequencies below this are rigid-body modes
RIGID_TOLERANCE_HZ = 1e-3

#: folder -> (deck file, number of modes its EIGRL/EIGR asks for, what the deck exercises)
DECKS = {
    # SOL 103, Simcenter NASTRAN: 9 CBARs on a PBARL ROD, a CBEAM on a PBEAML ROD, a CONM2, an unused PROD,
    # an unattached grid (AUTOSPC), INCLUDE; EIGRL ND = 10
    "beam_modes": ("beam_modes.dat", 10),
    # SOL 145, MSC Nastran: CBARs with PARAM,COUPMASS,1, CMASS2 on rotations in a CORD2R displacement system,
    # GRID PS, the old CBAR "F" flag; EIGR GIV ND = 6 with F2 = 0.1 Hz
    "pt145": ("pt145.bdf", 6),
    # SOL 145, MSC Nastran: CBAR, CONM2, RBE2 and a chain of four RBARs, two rigid-body modes, INCLUDE,
    # a repeated BEGIN BULK; EIGR LAN ND = 8
    "bah_plane": ("bah_plane.bdf", 8),
    # SOL 103, MSC Nastran (HA144D): CBARs of a massless material, CONM2s (one with a CBAR's ID), six RBARs,
    # SUPORT (3 rigid-body modes), PARAM,WTMASS; EIGR MGIV ND = 24 of which the structure has 21
    "ha144ds": ("ha144ds.bdf", 21),
    # SOL 145, MSC Nastran 2012: the BAH wing of bah_plane as pyNastran's MATLAB example has it (its own copy of
    # the structure, free-field comments after '$'); EIGR LAN ND = 10
    "BAH_Plane": ("BAH_Plane.bdf", 10),
    # SOL 146, MSC Nastran 2014: the same wing in a gust-response run (GUST, RLOAD1, RANDPS, TABRND1, MONPNT3 read
    # past); EIGR LAN ND = 8
    "BAH_Plane_gust": ("BAH_Plane_cont_gust_LINE5000000_10FREQs.bdf", 8),
    # SOL 103, Simcenter Nastran 2022.1 (mm, mN): five CBARs on a PBARL ROD, a CONM2, MATT1/TABLEM1/DTI read past
    # (no material temperatures selected), USET, SPCADD; EIGRL V1 0.1, V2 2000 Hz; NASTRAN's frequencies from its .op2
    "satk": ("pn_mwe_s-solution_1.dat", 3),
}

#: the nlfltr/buckled strut, rebuilt from the echoes of NASTRAN's .f06 (the only published form of the deck)
BUCKLED = NASTRAN / "nlfltr_buckled" / "buckled.bdf"
#: the other folders of decks read as published (here and in tests/deck/test_published_decks.py)
READ_AS_PUBLISHED = ("nlfltr_buckled", "frame_three_bars", "grid_point_forces", "modele_petite_zone", "cpmopt",
                     "v10111")


def reference(folder: str) -> np.ndarray:
    """NASTRAN's frequencies [Hz] of the deck in ``folder``."""
    with open(NASTRAN / folder / "reference_frequencies.toml", "rb") as handle:
        return np.array(tomllib.load(handle)["cycles"], dtype=float)


def check_against_nastran(ours: np.ndarray, nastran: np.ndarray) -> float:
    """Assert mode by mode; the worst relative error of the elastic modes."""
    assert len(ours) == len(nastran), f"{len(ours)} modes, NASTRAN has {len(nastran)}"
    rigid = np.abs(nastran) < RIGID_HZ
    assert np.all(np.abs(ours[rigid]) < RIGID_TOLERANCE_HZ), ours[rigid]
    relative = np.abs(ours[~rigid] - nastran[~rigid]) / nastran[~rigid]
    for mode in np.flatnonzero(~rigid):
        assert ours[mode] == pytest.approx(nastran[mode], rel=RELATIVE), f"mode {mode + 1}"
    return float(relative.max())


@pytest.mark.parametrize("folder", sorted(DECKS))
def test_published_deck_gives_nastrans_frequencies(folder):
    name, asked = DECKS[folder]
    result = compute_modes(read_deck(NASTRAN / folder / name), configuration="0g")
    nastran = reference(folder)[:asked]
    assert len(result.modes) == asked  # the deck's EIGRL/EIGR decides how many
    check_against_nastran(result.frequencies_hz, nastran)


def test_the_decks_are_pynastrans_files_unedited():
    """Every file of every deck folder is byte for byte the pyNastran file named in provenance.toml (its git blob
    id there), or a deck rebuilt from such a file's echo by f06_echo.py, so the decks are read as published."""
    import hashlib
    import importlib.util

    with open(NASTRAN / "provenance.toml", "rb") as handle:
        provenance = tomllib.load(handle)
    files, rebuilt = provenance["files"], provenance["rebuilt"]
    for folder in (*DECKS, *READ_AS_PUBLISHED):
        deck_files = {f"{folder}/{p.name}" for p in (NASTRAN / folder).iterdir()
                      if p.name != "reference_frequencies.toml"}
        assert deck_files <= set(files) | set(rebuilt), deck_files - set(files) - set(rebuilt)
    for name, entry in files.items():
        data = (NASTRAN / name).read_bytes()
        assert hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest() == entry["blob"], name
    spec = importlib.util.spec_from_file_location("f06_echo", NASTRAN / "f06_echo.py")
    f06_echo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(f06_echo)
    for name, entry in rebuilt.items():
        f06 = entry["from"]
        source = f"pyNastran repository (SteveDoyle2/pyNastran) commit {COMMIT}, {files[f06]['source']}"
        again = f06_echo.deck_from_echo((NASTRAN / f06).read_text(encoding="latin-1"), source)
        assert (NASTRAN / name).read_text(encoding="utf-8") == again, name


def test_pt145_every_root_nastran_prints():
    """EIGR GIV finds every root: NASTRAN prints all 30 (vectors for the ND = 6 lowest); all 30 match."""
    result = compute_modes(read_deck(NASTRAN / "pt145" / "pt145.bdf"), configuration="0g", max_hz=1e6)
    check_against_nastran(result.frequencies_hz, reference("pt145"))


def test_coupled_cbar_mass_has_no_torsional_inertia(monkeypatch):
    """With rho (I1 + I2) L torsional inertia in pt145's coupled CBAR mass (mace-fmu's own consistent matrix)
    its first torsion mode (236.4137 Hz in NASTRAN) moves by more than the tolerance: the deck test tells the
    two conventions apart."""
    from mace_fmu.fe import assembly
    from mace_fmu.fe.beam import local_mass

    deck = read_deck(NASTRAN / "pt145" / "pt145.bdf")
    assert compute_modes(deck, configuration="0g").modes.frequencies_hz[1] == pytest.approx(reference("pt145")[1],
                                                                                         rel=RELATIVE)
    monkeypatch.setattr(assembly, "bar_mass", lambda sec, length, kind, deck: local_mass(sec, length, kind))
    with_torsion = compute_modes(deck, configuration="0g").modes.frequencies_hz[1]
    assert abs(with_torsion / reference("pt145")[1] - 1.0) > 2 * RELATIVE


def test_satk_s_residual_is_the_rotary_inertia_of_simcenter_2022_s_lumped_cbar_mass(monkeypatch):
    """satk's bending modes are 2.4e-5 above NASTRAN's (Simcenter Nastran 2022.1), the other decks' within 4.6e-7.
    With rotary inertia rho I L / 2 on each end's bending rotations added to the lumped CBAR mass they come out
    within 1e-7 (measured 1.7e-8); beam_modes (Simcenter 2019.2, CBARs on a PBARL ROD too) then moves 2.3 % off
    its NASTRAN run, so mace-fmu keeps NASTRAN's documented lumped mass (translations only) and satk's residual is
    that difference between the two runs (which switch makes it, version or parameter, is not known here)."""
    original = assembly.bar_mass

    def with_rotary_inertia(sec, length, kind, deck):
        m = original(sec, length, kind, deck).copy()
        for rotation, inertia in ((5, sec.i1), (4, sec.i2)):
            m[rotation, rotation] += sec.rho * inertia * length / 2.0
            m[rotation + 6, rotation + 6] += sec.rho * inertia * length / 2.0
        return m

    monkeypatch.setattr(assembly, "bar_mass", with_rotary_inertia)
    satk = compute_modes(read_deck(NASTRAN / "satk" / "pn_mwe_s-solution_1.dat"), configuration="0g")
    np.testing.assert_allclose(satk.frequencies_hz, reference("satk"), rtol=1e-7)
    beam_modes = compute_modes(read_deck(NASTRAN / "beam_modes" / "beam_modes.dat"), configuration="0g")
    nastran = reference("beam_modes")
    assert np.max(np.abs(beam_modes.frequencies_hz / nastran - 1.0)) > 1e-2


def test_coupled_cbar_mass_is_cosmic_nastrans_bar_matrix():
    """A deck's PARAM,COUPMASS,1 gives the CBAR the coupled mass of COSMIC NASTRAN's BAR element, entry by entry as
    subroutine BARD writes it (nasa/NASTRAN-95 mis/bard.f: M(I,J) times (rho A + NSM) L / 420, the upper triangle
    listed there, no torsional terms); no published run tells its axial terms apart (pt145's 30 roots do not
    move with them), so the NASTRAN source is the reference for those."""
    from types import SimpleNamespace

    from mace_fmu.deck.cards import Param
    from mace_fmu.fe.beam import BeamSection
    from mace_fmu.fe.elements import bar_mass

    coupled_deck = SimpleNamespace(params={"COUPMASS": Param(name="COUPMASS", values=(1,), source=None)})
    sec = BeamSection(area=3.0e-4, i1=2.0e-8, i2=5.0e-8, j=6.0e-8, e=7.0e10, g=2.6e10, rho=2700.0, nsm=0.05)
    length = 0.7
    bl22, bl13, blsq4, blsq3 = 22 * length, 13 * length, 4 * length**2, 3 * length**2
    upper = {(1, 1): 175.0, (1, 7): 35.0, (2, 2): 156.0, (2, 6): bl22, (2, 8): 54.0, (2, 12): -bl13, (3, 3): 156.0,
             (3, 5): -bl22, (3, 9): 54.0, (3, 11): bl13, (5, 5): blsq4, (5, 9): -bl13, (5, 11): -blsq3,
             (6, 6): blsq4, (6, 8): bl13, (6, 12): -blsq3, (7, 7): 175.0, (8, 8): 156.0, (8, 12): -bl22,
             (9, 9): 156.0, (9, 11): bl22, (11, 11): blsq4, (12, 12): blsq4}
    bard = np.zeros((12, 12))
    for (i, j), value in upper.items():
        bard[i - 1, j - 1] = bard[j - 1, i - 1] = value
    bard *= length * (sec.rho * sec.area + sec.nsm) / 420.0
    np.testing.assert_allclose(bar_mass(sec, length, "consistent", coupled_deck), bard, rtol=1e-14, atol=1e-18)


def test_cbeam_lumped_mass_carries_the_torsional_inertia_nastran_reports():
    """beam_modes: NASTRAN's grid point weight generator (in its .f06) gives Ixx = 3.765757E-03 about the
    beam's axis: the CONM2's 2.59E-03 plus rho (I1 + I2) L of the one CBEAM; the CBARs add none."""
    result = compute_modes(read_deck(NASTRAN / "beam_modes" / "beam_modes.dat"), configuration="0g")
    assert result.mass_properties.mass_kg == pytest.approx(2.610514e-02, rel=1e-6)
    assert result.mass_properties.inertia_about_reference_kgm2[0, 0] == pytest.approx(3.765757e-03, rel=1e-6)



def test_cbeams_assembled_all_at_once_have_the_stiffness_of_the_same_cbars():
    """CBEAMs go through the same vectorised geometry as CBARs (ends, lengths, element frames, the distinct
    (property, length) pairs), the CBAR route being the one NASTRAN's decks check: twelve elements of two
    sections and several lengths, oriented by a vector in a rotated CD system, by G0 and by a basic vector
    (OFFT BGG), have the same stiffness as CBEAMs (PBEAM without I12) as CBARs, to rounding."""
    grids = "\n".join(f"GRID,{g},,{x:.1f},{y:.1f},{z:.1f},{cd}" for g, (x, y, z, cd) in enumerate(
        [(0, 0, 0, 0), (1, 0, 0, 7), (2, 0.5, 0, 0), (2, 1.5, 1, 7), (0, 1, 1, 0), (3, 1, 0, 0), (1, 3, 2, 0)],
        start=1))
    connections = [(1, 2), (2, 3), (3, 4), (4, 5), (5, 1), (1, 3), (2, 4), (3, 5), (4, 6), (6, 1), (2, 6), (5, 6)]
    orientations = [",0.0,0.0,1.0,", ",7,,,", ",0.3,1.0,0.2,BGG"]  # grid 7 orients, in no element

    def deck(card: str, prop: str) -> str:
        elements = "\n".join(f"{card},{e},{1 + e % 2},{a},{b}{orientations[e % 3]}"
                              for e, (a, b) in enumerate(connections, start=1))
        return (f"BEGIN BULK\nCORD2R,7,0,0.0,0.0,0.0,0.3,0.2,0.9\n,1.0,0.5,0.1\n{grids}\n{elements}\n"
                f"{prop.format(1, '2.0e-4,3.0e-8,5.0e-8')}\n{prop.format(2, '1.0e-4,2.0e-8,1.0e-8')}\n"
                "MAT1,1,70.0e9,,0.33,2700.0\nENDDATA\n")

    # PBEAM's shear factors default to 1.0 (QRG), PBAR's to none: given here (second continuation)
    pbar = "PBAR,{},1,{},4.0e-8\n,,,,,,,,\n,1.0,1.0"
    bars = assembly.assemble(read_deck_text(deck("CBAR", pbar))).stiffness.toarray()
    beams = assembly.assemble(read_deck_text(deck("CBEAM", "PBEAM,{},1,{},0.0,4.0e-8"))).stiffness.toarray()
    assert np.count_nonzero(bars) > 900  # 12 elements, each coupling 12 DOFs
    np.testing.assert_allclose(beams, bars, rtol=0, atol=1e-12 * np.abs(bars).max())


def test_coupled_cbeam_mass_gives_nastrans_frequencies_of_the_buckled_strut():
    """nlfltr/buckled (MSC/NASTRAN 4/28/98): 71 CBEAMs under PARAM,COUPMASS,1, a CONM2 on an RBE2, SUPORT, WTMASS
    and grids in CORD2R systems. Its EIGRL asks for 50 roots and the .f06 as published holds the first 15: one
    rigid-body mode and 14 elastic modes, all matching (the worst 3.4e-7) with NASTRAN's coupled CBEAM mass
    (consistent bending, lumped axial and torsional mass)."""
    result = compute_modes(read_deck(BUCKLED), configuration="0g")
    assert len(result.modes) == 50
    nastran = reference("nlfltr_buckled")
    assert check_against_nastran(result.frequencies_hz[:len(nastran)], nastran) < 1e-6


def _consistent_pair(total: float) -> np.ndarray:
    return total / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])


@pytest.mark.parametrize("convention", ["axial mass consistent", "torsional mass consistent", "no torsional mass"])
def test_the_buckled_strut_tells_the_coupled_cbeam_conventions_apart(monkeypatch, convention):
    """Each other reading of COUPMASS for CBEAM moves some of the strut's modes by more than the deck test's
    tolerance (measured: 1.0e-3, 16 % and 42 %), so the test above decides the rule."""
    from mace_fmu.fe import elements

    nastrans_rule = elements.beam_mass

    def other(sec, length, kind, deck):
        m = nastrans_rule(sec, length, kind, deck)
        polar = sec.rho * (sec.i1 + sec.i2) * length
        block = {"axial mass consistent": ([0, 6], _consistent_pair(sec.mass_per_length * length)),
                 "torsional mass consistent": ([3, 9], _consistent_pair(polar)),
                 "no torsional mass": ([3, 9], np.zeros((2, 2)))}[convention]
        m[np.ix_(block[0], block[0])] = block[1]
        return m

    monkeypatch.setattr(elements, "beam_mass", other)
    nastran = reference("nlfltr_buckled")
    ours = compute_modes(read_deck(BUCKLED), configuration="0g").frequencies_hz[:len(nastran)]
    elastic = np.abs(nastran) >= RIGID_HZ
    assert np.max(np.abs(ours[elastic] / nastran[elastic] - 1.0)) > 5 * RELATIVE


def test_buckled_strut_mass_properties_are_nastrans_grid_point_weight_generator():
    """PARAM,GRDPNT,0: NASTRAN's grid point weight generator in the strut's .f06 (page 25) prints mass, centre of
    gravity and inertia about the basic origin in weight units (mass / WTMASS); times WTMASS = 0.0310559 they are
    mace-fmu's mass properties of the deck to NASTRAN's 7 digits (measured: within 3e-7)."""
    wtmass = 0.0310559
    mp = compute_modes(read_deck(BUCKLED), configuration="0g").mass_properties
    assert mp.reference_grid is None and np.all(mp.reference_point_m == 0.0)
    assert mp.mass_kg == pytest.approx(2.460616e5 * wtmass, rel=1e-6)
    np.testing.assert_allclose(mp.center_of_mass_m, [1.655644e1, 3.003331e0, -9.864630e-2], rtol=1e-6)
    nastran = wtmass * np.array([[4.231471e7, -3.449106e7, 1.344226e6],
                                 [-3.449106e7, 8.112558e7, 1.092062e6],
                                 [1.344226e6, 1.092062e6, 1.221223e8]])  # the MO matrix's rotational block
    np.testing.assert_allclose(mp.inertia_about_reference_kgm2, nastran, rtol=1e-6)


@pytest.mark.parametrize("kind, dims, nastran", [
    # (A, I1, I2, J, K1, K2) as NASTRAN prints them in user information message 4379, which replaces each
    # PBARL/PBEAML by a PBAR/PBEAM: beam_modes.f06 (Simcenter) for ROD; fmondsp.f06 (MSC, pyNastran's
    # models/aero, a deck with tapered beams that cannot be run here) for TUBE and BOX
    ("ROD", (1.0,), (3.1416e+00, 7.8540e-01, 7.8540e-01, 1.5708e+00, 0.9, 0.9)),
    ("TUBE", (0.2, 0.195), (6.2047e-03, 1.2103e-04, 1.2103e-04, 2.4206e-04, 0.5, 0.5)),
    ("TUBE", (0.4, 0.395), (1.2488e-02, 9.8662e-04, 9.8662e-04, 1.9732e-03, 0.5, 0.5)),
    ("BOX", (0.6, 0.2, 0.0025, 0.0025), (3.9750e-03, 3.2346e-05, 1.7702e-04, 8.7582e-05, 2.4528e-01, 7.4843e-01)),
    ("BOX", (0.05, 0.5, 0.001, 0.001), (1.0960e-03, 2.6809e-05, 6.1877e-07, 2.1819e-06, 9.0876e-01, 8.7591e-02)),
])
def test_pbarl_sections_are_the_pbar_nastran_makes(kind, dims, nastran):
    from mace_fmu.deck.sections import section_properties

    p = section_properties(kind, dims)
    # NASTRAN prints 5 significant digits
    np.testing.assert_allclose((p.area, p.i1, p.i2, p.j, p.k1, p.k2), nastran, rtol=6e-5)


def test_deck_reports_what_it_read_past(tmp_path):
    deck = read_deck(NASTRAN / "bah_plane" / "bah_plane.bdf")
    skipped = {name for name, _, _ in deck.skipped}
    assert {"CAERO1", "SPLINE2", "FLUTTER", "SET1"} <= skipped
    assert len(deck.rigids) == 9 and {r.card for r in deck.rigids.values()} == {"RBAR", "RBE2"}


# ----------------------------------------------------------------------------------------------
# Malformed new cards: one clear error naming file, line, card and field

BASE = """SOL 103
CEND
METHOD = 1
BEGIN BULK
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
MAT1,1,7.e10,,0.3,2700.
EIGRL,1,,,4
{card}
ENDDATA
"""


@pytest.mark.parametrize("card, message", [
    ("PBARL,7,1,,HEXA\n,1.0", r"deck.bdf:9: PBARL 7, field 5 \(TYPE\): section type 'HEXA' is not supported"),
    ("PBARL,7,1,,ROD\n,-1.0", r"deck.bdf:10: PBARL 7, continuation 1 field 2 \(DIM1\): value '-1.0' is out of "
                              r"range \(expected a real number > 0.0\)"),
    ("PBEAML,7,1,,ROD\n,1.0,0.,YES,1.0,2.0", r"deck.bdf:10: PBEAML 7, continuation 1 fields 6-7 \(DIM1-NSM\): the "
                                             r"section at X/XB = 1 differs from end A: tapered beams"),
    ("CBEAM,3,7,1,2,0.,1.,0.\n,,,0.1", r"deck.bdf:10: CBEAM 3, continuation 1 field 4 \(W1A\): offsets are not "
                                       r"supported"),
    ("CMASS2,4,,1,3", r"deck.bdf:9: CMASS2 4, field 3 \(M\): required field is blank"),
    ("RBAR,5,1,2,123,,456", r"deck.bdf:9: RBAR 5, fields 5-8 \(CNA-CMB\): CNA 123, CNB blank, CMA 456"),
    ("RBE2,6,1,123456", r"deck.bdf:9: RBE2 6, field 5 \(GM1\): no dependent grid"),
    ("EIGR,2,QR,0.,10.", r"deck.bdf:9: EIGR 2, field 3 \(METHOD\): expected one of LAN"),
    ("PBARL,7,1,,BOX\n,0.1,0.2,0.11,0.01", r"deck.bdf:10: PBARL 7, continuation 1 fields 2-5 \(DIM1-DIM4\): BOX: "
                                         r"the walls fill the box"),
    ("CROD,8,9,1,1", r"deck.bdf:9: CROD 8, fields 4-5 \(G1, G2\): G1 and G2 are both grid 1"),
    ("GRID,3,,1.,0.,0.\nCONROD,8,2,3,1,0.1", r"deck.bdf:10: CONROD 8, fields 3-4 \(G1, G2\): zero length"),
])
def test_malformed_new_card_is_one_error_naming_file_line_card_and_field(tmp_path, card, message):
    path = tmp_path / "deck.bdf"
    path.write_text(BASE.format(card=card))
    with pytest.raises(DeckError, match=message):
        read_deck(path)


def test_undefined_property_and_rigid_cycle_are_named():
    with pytest.raises(DeckError, match=r"x.bdf:9: CBEAM 3, field 3 \(PID\): property 7 is not defined \(expected "
                                        r"a PBEAM or PBEAML ID\)"):
        read_deck_text(BASE.format(card="CBEAM,3,7,1,2,0.,1.,0."), name="x.bdf")
    deck = read_deck_text(BASE.format(card="RBAR,5,1,2,123456\nRBAR,6,2,1,123456\nCONM2,9,1,,1.0"), name="x.bdf")
    with pytest.raises(MaceError, match=r"x.bdf:10: RBAR 6: dependent DOF 1-1 is already dependent in RBAR 5|"
                                        r"depends on itself"):
        compute_modes(deck, configuration="0g")


# ----------------------------------------------------------------------------------------------
# The other new cards, each against the card it stands for or against a closed form

def _modes(tmp_path, bulk: list[str], name: str, case: str = "SPC = 7\n") -> np.ndarray:
    path = tmp_path / f"{name}.bdf"
    path.write_text(f"SOL 103\nCEND\n{case}METHOD = 1\nBEGIN BULK\nEIGRL,1,,,6\n" + "\n".join(bulk) + "\nENDDATA\n")
    return compute_modes(read_deck(path), configuration="0g").modes.frequencies_hz


def _cantilever(ps: str = "345", grdset: str | None = None) -> list[str]:
    from support.decks import line_of_bars

    cards = line_of_bars(n=8, length=2.0, e=7.0e10, nu=0.33, rho=2700.0, area=7e-4, i=4e-8, ps=ps)
    return cards + ([grdset] if grdset else []) + ["SPC1,7,123456,1"]


def test_grdset_gives_blank_grid_fields_its_values(tmp_path):
    explicit = _modes(tmp_path, _cantilever(), "explicit")
    defaulted = _modes(tmp_path, _cantilever(ps="", grdset="GRDSET,,,,,,,345"), "grdset")
    np.testing.assert_allclose(defaulted, explicit, rtol=1e-12)
    assert not np.allclose(_modes(tmp_path, _cantilever(ps=""), "free")[:4], explicit[:4])  # the PS matters


def test_celas1_pelas_cmass1_pmass_conm1_stand_for_celas2_cmass2_conm2(tmp_path):
    base = _cantilever()
    tip = 9  # the free end
    two = base + [f"CELAS2,900,3.0e4,{tip},2", f"CMASS2,901,0.7,{tip},1", f"CONM2,902,{tip},,1.5\n,0.01,,0.02,,,0.03"]
    one = base + [f"CELAS1,900,50,{tip},2", "PELAS,50,3.0e4,,,51,1.0", f"CMASS1,901,60,{tip},1,0,0", "PMASS,60,0.7",
                  f"CONM1,902,{tip},,1.5,,1.5\n,1.5,,,,0.01\n,,0.02,,,,,,0.03"]
    np.testing.assert_allclose(_modes(tmp_path, one, "one"), _modes(tmp_path, two, "two"), rtol=1e-12)
    assert not np.allclose(_modes(tmp_path, base, "base"), _modes(tmp_path, two, "two"))  # they matter


def test_spcadd_and_mpcadd_are_the_union_of_their_sets(tmp_path):
    base = [c for c in _cantilever() if not c.startswith("SPC1")]
    direct = base + ["SPC1,7,123,1", "SPC1,7,456,1", "MPC,8,9,2,1.0,8,2,-1.0"]
    added = base + ["SPC1,2,123,1", "SPC1,3,456,1", "SPCADD,7,2,3", "MPC,4,9,2,1.0,8,2,-1.0", "MPCADD,8,4"]
    case = "SPC = 7\nMPC = 8\n"
    np.testing.assert_allclose(_modes(tmp_path, added, "added", case), _modes(tmp_path, direct, "direct", case),
                               rtol=1e-12)
    with pytest.raises(DeckError, match=r"SPCADD 7, S2: set 5 is not defined \(expected an SPC or SPC1 set ID\)"):
        read_deck_text(BASE.format(card="SPC1,2,123,1\nSPCADD,7,2,5"), name="x.bdf")


def test_conrod_chain_gives_the_lumped_chain_closed_form(tmp_path):
    """A fixed-free chain of n CONRODs with NASTRAN's lumped rod mass (m/2 at each end of each rod): masses m
    at the inner grids and m/2 at the tip give omega_j = 2 sqrt(k/m) sin((2j - 1) pi / (4n)), k = E A / L_e."""
    n, length, e, area, rho = 10, 3.0, 2.0e11, 1e-4, 7800.0
    cards = [f"MAT1,1,{e:.6e},,0.3,{rho:.6e}"]
    cards += [f"GRID,{k + 1},,{k * length / n:.10e},0.,0.,,23456" for k in range(n + 1)]
    cards += [f"CONROD,{k + 1},{k + 1},{k + 2},1,{area:.6e}" for k in range(n)]
    cards += ["CROD,99,98,1,2", "PROD,98,1,0.0", "SPC1,7,1,1"]  # a CROD of no area changes nothing
    ours = _modes(tmp_path, cards, "rods", case="SPC = 7\n")
    k_e, m = e * area / (length / n), rho * area * length / n
    exact = [2 * np.sqrt(k_e / m) * np.sin((2 * j - 1) * np.pi / (4 * n)) / (2 * np.pi) for j in range(1, 7)]
    np.testing.assert_allclose(ours, exact, rtol=1e-10)


def test_offt_b_reads_the_orientation_vector_in_basic(tmp_path):
    """The grids' displacement system 1 is basic turned 90 degrees about X (y1 = Z, z1 = -Y): the vector
    (0, 1, 0) in basic (OFFT BGG) is (0, 0, -1) in system 1 (OFFT GGG, or blank). Plane 1 (I1, the smaller)
    then holds basic Y, so the tip of the first mode moves along Y; with (0, 1, 0) in system 1 it moves along Z."""
    def tip_of_first_mode(v: str, offt: str) -> np.ndarray:
        cards = ["MAT1,1,7.e10,,0.33,2700.", "PBAR,1,1,7.e-4,4.e-8,9.e-8,1.e-8",
                 "CORD2R,1,,0.,0.,0.,0.,-1.,0.\n,1.,0.,0.", "SPC1,7,123456,1", "EIGRL,1,,,6"]
        cards += [f"GRID,{k + 1},,{0.25 * k:.3f},0.,0.,1" for k in range(9)]
        cards += [f"CBAR,{k + 1},1,{k + 1},{k + 2},{v},{offt}" for k in range(8)]
        path = tmp_path / "offt.bdf"
        path.write_text("SOL 103\nCEND\nSPC = 7\nMETHOD = 1\nBEGIN BULK\n" + "\n".join(cards) + "\nENDDATA\n")
        modes = compute_modes(read_deck(path), configuration="0g").modes
        return np.abs([modes.shape(9, c)[0] for c in (1, 2, 3)])

    for v, offt in (("0.,1.,0.", "BGG"), ("0.,0.,-1.", "GGG"), ("0.,0.,-1.", "")):
        tip = tip_of_first_mode(v, offt)
        assert tip[1] > 1e3 * max(tip[0], tip[2]), (offt, tip)  # along basic Y
    tip = tip_of_first_mode("0.,1.,0.", "GGG")
    assert tip[2] > 1e3 * max(tip[0], tip[1])  # along basic Z


def test_cord1r_is_the_cord2r_through_its_grids(tmp_path):
    """CORD1R on grids at A, B, C (one given in a CORD2R system) is the CORD2R through A, B, C: a beam whose
    grids are in it, with displacement systems in it, has the same modes either way."""
    def bulk(system: str) -> list[str]:
        cards = ["MAT1,1,7.e10,,0.33,2700.", "PBAR,1,1,7.e-4,4.e-8,9.e-8,1.e-8", "SPC1,7,123456,1",
                 "CORD2R,5,,0.,0.,0.,0.,0.,1.\n,1.,0.,0.",  # basic, written out
                 "GRID,91,,1.,2.,3.", "GRID,92,5,1.,2.,4.", "GRID,93,,2.,2.,3.5", system]
        cards += [f"GRID,{k + 1},9,0.,0.,{0.25 * k:.3f},9" for k in range(9)]
        cards += [f"CBAR,{k + 1},1,{k + 1},{k + 2},1.,0.,0." for k in range(8)]
        return cards + ["CELAS2,50,1.e3,9,1", "CONM2,51,9,,0.5"]

    one = _modes(tmp_path, bulk("CORD1R,9,91,92,93"), "cord1r")
    two = _modes(tmp_path, bulk("CORD2R,9,,1.,2.,3.,1.,2.,4.\n,2.,2.,3.5"), "cord2r")
    np.testing.assert_allclose(one, two, rtol=1e-12)
    with pytest.raises(DeckError, match=r"x.bdf:9: CORD1R 9, field 4 \(G2\): grid 77 is not defined"):
        read_deck_text(BASE.format(card="CORD1R,9,1,77,2"), name="x.bdf")


def test_a_gravity_preload_with_beams_or_rods_is_refused_not_solved_without_them(tmp_path):
    """The 1-g preload's tangent stiffness is built from CBARs and springs only: a CBEAM would silently lose its
    stiffness there, so a 1-g analysis of a deck with one is an error naming it."""
    cards = _cantilever() + ["GRID,20,,2.25,0.,0.,,345", "CBEAM,300,30,9,20,0.,1.,0.", "PBEAML,30,1,,ROD\n,0.01",
                             "GRAV,5,,9.81,0.,0.,-1."]
    path = tmp_path / "g.bdf"
    path.write_text("SOL 103\nCEND\nSUBCASE 1\n  SPC = 7\n  LOAD = 5\nSUBCASE 2\n  SPC = 7\n  METHOD = 1\n"
                    "BEGIN BULK\nEIGRL,1,,,4\n" + "\n".join(cards) + "\nENDDATA\n")
    deck = read_deck(path)
    assert len(compute_modes(deck, configuration="0g").modes) == 4
    with pytest.raises(MaceError, match=r"1-g gravity preload models CBAR and CELAS2 elements only, and this deck "
                                        r"has 1 CBEAM \(first .*g.bdf:\d+\)"):
        compute_modes(deck, configuration="1g")


@pytest.mark.parametrize("rigid", ["RBE2,40,9,123456,30", "RBAR,40,9,30,123456", "RBAR,40,30,9,,123456"])
def test_a_mass_on_a_rigid_element_is_the_offset_mass(tmp_path, rigid):
    """A CONM2 on grid 30, held rigidly to the beam's tip 9 by an RBE2 or an RBAR (either end independent; grid
    30's displacement system turned), has the modes of the same CONM2 on grid 9 with grid 30's offset."""
    base = [c for c in _cantilever(ps="") if not c.startswith("SPC1")] + ["SPC1,7,123456,1"]
    mass = "1.5\n,0.01,0.002,0.02,0.001,0.003,0.03"
    offset = base + [f"CONM2,50,9,,{mass.replace('1.5', '1.5,0.0,0.3,0.1', 1)}"]
    rigid_model = base + ["CORD2R,3,,0.,0.,0.,0.3,0.2,1.\n,1.,0.5,0.2", "GRID,30,,2.,0.3,0.1,3", rigid,
                          f"CONM2,50,30,,{mass}"]
    ours = _modes(tmp_path, rigid_model, "rigid")
    np.testing.assert_allclose(ours, _modes(tmp_path, offset, "offset"), rtol=1e-9)
    assert not np.allclose(ours, _modes(tmp_path, base + [f"CONM2,50,9,,{mass}"], "no_offset"), rtol=1e-3)


if __name__ == "__main__":  # python tests/fe/test_nastran_decks.py: the worst relative error of each deck
    worst = {}
    for folder, (name, asked) in sorted(DECKS.items()):
        ours = compute_modes(read_deck(NASTRAN / folder / name), configuration="0g").modes.frequencies_hz
        worst[folder] = check_against_nastran(ours, reference(folder)[:asked])
    buckled = compute_modes(read_deck(BUCKLED), configuration="0g").modes.frequencies_hz
    worst["nlfltr_buckled"] = check_against_nastran(buckled[:15], reference("nlfltr_buckled"))
    every_root = compute_modes(read_deck(NASTRAN / "pt145" / "pt145.bdf"), configuration="0g", max_hz=1e6)
    worst["pt145, all 30 roots"] = check_against_nastran(every_root.frequencies_hz, reference("pt145"))
    for folder, error in worst.items():
        print(f"{folder:20s} worst relative error of the elastic modes {error:.2g}")
    print(f"{'all':20s} {max(worst.values()):.2g}")
