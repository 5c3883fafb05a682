"""What a NASTRAN results file says, taken at its word or refused in one line.

The files are the public OP2s of tests/data/nastran with one thing changed (tests/support/op2_files.py), each
as a public OP2 that the tests do not hold has it: pyNastran's models/msc/sol103_test_pcompg_2021.op2 (a
negative eigenvalue, -37.4 Hz; vectors normalised to max = 1 by its EIGRL, NORM=MAX, without a LAMA table),
models/aero/fmondsp.op2 (20 vectors of an EIGRL asking up to 60 Hz: the two above, 102 and 161 Hz, are residual
vectors), models/other/sbuckl2a.op2 (a buckling run), models/elements/modes_complex_elements.op2 (a complex
eigenvalue run), models/plate/plate_formatted.op2 (a formatted OUTPUT2). The expected values are pyNastran's
reading of the unchanged files (tests/data/nastran/*/pynastran_*.csv).
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from support.cli import run_cli
from support.nastran_results import (
    NASTRAN,
    op2_path,
    pynastran_eigenvalues,
    pynastran_vectors,
)
from support.op2_files import read_tables, table, words, write_op2

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.modal_source import modal_structure
from mace_fmu.nastran_modes import read_nastran_modes


def _rewritten(tmp_path, model: str, edit, name: str = "edited.op2"):
    endian, tables = read_tables(op2_path(model))
    edit(tables, endian)
    return write_op2(tmp_path / name, tables, endian)


def _idents(t, endian):
    """(index, words) of each IDENT record of a vector table (records alternate IDENT, data)."""
    return [(k, words(t.records[k], endian)) for k in range(0, len(t.records) - 1, 2)]


def _eigrl(tables, endian):
    """(DYNAMICS record index, its words) of the EIGRL record."""
    dynamics = table(tables, "DYNAMICS")
    k = next(k for k, r in enumerate(dynamics.records) if tuple(words(r[:12], endian)) == (308, 8, 348))
    return dynamics, k, words(dynamics.records[k], endian)


def test_a_file_written_back_unchanged_gives_the_same_modes(tmp_path):
    ours = read_nastran_modes(_rewritten(tmp_path, "gpsc1", lambda tables, endian: None))
    theirs = read_nastran_modes(op2_path("gpsc1"))
    np.testing.assert_array_equal(ours.modes.shapes, theirs.modes.shapes)
    np.testing.assert_array_equal(ours.eigenvalues, theirs.eigenvalues)
    assert ours.modes.labels == theirs.modes.labels and ours.normalisation == theirs.normalisation == "MASS"


def _structure_text(path) -> str:
    """A structure file naming the OP2 at ``path`` (gpsc1's grids), with a force and a displacement sensor."""
    return (f'[modes]\nfile = "{path.as_posix()}"\n\n[[actuators]]\nname = "shaker"\ndescription = "force"\n'
            'dofs = [[1, 3, 1.0]]\n\n[[sensors]]\nname = "disp"\ndescription = "displacement"\n'
            'kind = "displacement"\ndofs = [[2, 3, 1.0]]\n')


def _negative(mode: int):
    def edit(tables, endian):
        lama = table(tables, "LAMA")
        rows = words(lama.records[1], endian, "f4").reshape(-1, 7)
        rows[mode - 1, 2] *= -1  # the eigenvalue; radians and cycles as NASTRAN prints them, positive
        lama.records[1] = rows.tobytes()
        vectors = table(tables, "OUGV1")
        for k, ident in _idents(vectors, endian):
            if ident[4] == mode:
                values = words(vectors.records[k], endian, "f4")
                values[5] *= -1
                vectors.records[k] = values.tobytes()
    return edit


def test_a_negative_eigenvalue_is_refused_naming_the_mode_and_its_value(tmp_path):
    """A negative eigenvalue is an unstable pole at +sqrt(-lambda) 1/s: it became an FMU that grows without bound,
    with exit status 0 and no word. Refused in one line, through the reader, the [modes] route and the CLI."""
    path = _rewritten(tmp_path, "gpsc1", _negative(3))
    lam = float(np.float32(pynastran_eigenvalues("gpsc1")[1][2]))
    hz = np.sqrt(lam) / (2 * np.pi)
    expected = (f"{path}: table LAMA: mode 3 has the eigenvalue {-lam:.7g} rad^2/s^2 (-{hz:.4g} Hz): an unstable mode, "
                f"a pole at +{np.sqrt(lam):.4g} 1/s, which no model of vibrations holds "
                "(expected eigenvalues >= 0")
    assert expected.startswith(f"{path}: table LAMA: mode 3 has the eigenvalue -12304.76 rad^2/s^2 (-17.65 Hz)")
    with pytest.raises(MaceError) as caught:
        read_nastran_modes(path)
    assert str(caught.value).startswith(expected) and "\n" not in str(caught.value)
    structure = tmp_path / "gpsc1.toml"
    structure.write_text(_structure_text(path))
    with pytest.raises(MaceError, match=re.escape(expected)):
        modal_structure(structure)


def test_the_cli_refuses_an_unstable_modes_file_without_writing_an_fmu(tmp_path, capsys):
    path = _rewritten(tmp_path, "gpsc1", _negative(1))
    structure = tmp_path / "gpsc1.toml"
    structure.write_text(_structure_text(path))
    code, _, err = run_cli(capsys, ["export", "modes", "--structure", str(structure), "-o", str(tmp_path / "out")])
    assert code == 2 and "mode 1 has the eigenvalue -7291.963 rad^2/s^2 (-13.59 Hz): an unstable mode" in err, err
    assert not list(tmp_path.rglob("*.fmu"))


def test_vectors_the_run_normalised_to_max_without_generalized_masses_are_refused(tmp_path):
    """solid_shell_bar's OP2 has no LAMA; its DYNAMICS table holds the run's EIGRL. With NORM=MAX there, its vectors
    cannot be made mass-normalised: refused, naming the request, whatever is stated."""
    def edit(tables, endian):
        dynamics, k, _ = _eigrl(tables, endian)
        record = bytearray(dynamics.records[k])
        record[12 + 36:12 + 44] = b"MAX     "
        dynamics.records[k] = bytes(record)

    path = _rewritten(tmp_path, "solid_shell_bar", edit)
    message = (f"{path}: table OUGV1: the eigenvectors are normalised to NORM=MAX (EIGRL 1 in table DYNAMICS) and the "
               "file holds no generalized masses (no LAMA table) to make them mass-normalised: every modal gain would "
               "be off by an unknown factor (expected the LAMA table in the OP2, PARAM,POST,-1, or a run with "
               "NORM=MASS, the default)")
    for stated in (None, "mass"):
        with pytest.raises(MaceError) as caught:
            read_nastran_modes(path, normalisation=stated)
        assert str(caught.value) == message


def _max_normalised(tables, endian):
    """Each of plate_py's vectors divided by its largest component, as NORM=MAX writes them."""
    vectors = table(tables, "OUGV1")
    for k, _ in _idents(vectors, endian):
        data = words(vectors.records[k + 1], endian, "f4").reshape(-1, 8)
        data[:, 2:] /= np.abs(data[:, 2:]).max()
        vectors.records[k + 1] = data.tobytes()


def test_vectors_normalised_to_max_without_generalized_masses_are_refused_unless_stated(tmp_path):
    """plate_py's OP2 holds neither LAMA nor DYNAMICS: vectors whose largest component is 1 are NORM=MAX's, each
    off its mass-normalised self by an unknown factor. Refused; taken as they are when the user states that they
    are mass-normalised (the reader's keyword, or the structure file's [modes] normalisation = "mass")."""
    path = _rewritten(tmp_path, "plate_py", _max_normalised)
    with pytest.raises(MaceError) as caught:
        read_nastran_modes(path)
    assert str(caught.value) == (
        f"{path}: table OUGV1: the eigenvectors look normalised to NORM=MAX (the largest component of every vector is "
        "1) and the file holds no generalized masses (no LAMA table) to make them mass-normalised: every modal gain "
        "would be off by an unknown factor (expected the OP2 with its LAMA table, PARAM,POST,-1; or, if they are "
        "mass-normalised after all, say so: [modes] normalisation = \"mass\", read_nastran_modes(normalisation="
        "\"mass\"))")
    stated = read_nastran_modes(path, normalisation="mass")
    assert stated.normalisation.startswith("MASS, as stated (normalisation = \"mass\")")
    theirs = pynastran_vectors("plate_py")  # pyNastran's reading of the unchanged file, in each grid's CD system
    for column, mode in enumerate(stated.modes.labels):
        rows = theirs["mode"] == int(mode.split()[1])
        file_values = np.column_stack([theirs[f"cd_{c}"][rows] for c in ("t1", "t2", "t3", "r1", "r2", "r3")])
        ours = np.array([stated.modes.grid_motion(int(g))[:, column] for g in theirs["grid"][rows]])
        np.testing.assert_allclose(ours, file_values / np.abs(file_values).max(), rtol=2e-7, atol=1e-7)
    structure = tmp_path / "plate.toml"
    geometry = (NASTRAN / "plate_py" / "plate_py.dat").as_posix()
    text = (f'[modes]\nfile = "{path.as_posix()}"\ngeometry = "{geometry}"\n{{}}\n\n[[actuators]]\nname = "shaker"\n'
            'description = "force"\ndofs = [[231, 3, 1.0]]\n\n[[sensors]]\nname = "disp"\n'
            'description = "displacement"\nkind = "displacement"\ndofs = [[116, 3, 1.0]]\n')
    structure.write_text(text.format(""))
    with pytest.raises(MaceError, match="the eigenvectors look normalised to NORM=MAX"):
        modal_structure(structure)
    structure.write_text(text.format('normalisation = "mass"'))
    assert len(modal_structure(structure).modes) == 10
    structure.write_text(text.format('normalisation = "max"'))
    with pytest.raises(MaceError, match=r"\[modes\]: normalisation must be \"mass\""):
        modal_structure(structure)


@pytest.mark.parametrize("word, value, residual", [(6, 15, (16, 17)), (5, 50.0, (13, 14, 15, 16, 17))],
                         ids=["ND=15", "V2=50Hz"])
def test_vectors_beyond_what_the_run_asked_for_are_labelled_residual_vectors(tmp_path, word, value, residual):
    """NASTRAN returns at most ND eigenvectors, none above V2 (gpsc1's EIGRL: V1 = 1 Hz, V2 = 70 Hz, 17 modes): the
    vectors beyond are the residual vectors PARAM,RESVEC appends, not modes of the structure."""
    def edit(tables, endian):
        dynamics, k, entry = _eigrl(tables, endian)
        entry[word] = value if word == 6 else np.float32(value).view(np.int32)
        dynamics.records[k] = entry.tobytes()

    ours = read_nastran_modes(_rewritten(tmp_path, "gpsc1", edit))
    modes, eigenvalues, _ = pynastran_eigenvalues("gpsc1")
    hz = np.sqrt(eigenvalues) / (2 * np.pi)
    assert residual == tuple(int(m) for m, f in zip(modes, hz) if (m > 15 if word == 6 else f > 50.0))
    assert ours.modes.labels == tuple(f"mode {m}" for m in modes if m not in residual) + tuple(
        f"residual vector {k}" for k in range(1, len(residual) + 1))
    assert any(f"{len(residual)} residual vector(s) (NASTRAN's vectors {', '.join(map(str, residual))}" in note
               for note in ours.notes)
    np.testing.assert_array_equal(ours.modes.shapes, read_nastran_modes(op2_path("gpsc1")).modes.shapes)


@pytest.mark.parametrize("approach, table_code, summary, says", [
    (8, 7, "BLAMA", "it holds buckling modes (SOL 105) in OUGV1, and buckling eigenvalues (BLAMA)"),
    (9, 1007, "CLAMA", "it holds complex modes (SOL 107, 110) in OUGV1, and complex eigenvalues (CLAMA)"),
    (1, 1, "LAMA", "it holds static displacements (SOL 101) in OUGV1, and real eigenvalues (LAMA)"),
], ids=["buckling", "complex", "static"])
def test_a_run_of_another_solution_is_said_to_hold_what_it_holds(tmp_path, approach, table_code, summary, says):
    """A buckling, complex eigenvalue or static run was told to 'add DISPLACEMENT(PLOT)=ALL', which it has."""
    def edit(tables, endian):
        vectors = table(tables, "OUGV1")
        for k, ident in _idents(vectors, endian):
            ident[0], ident[1] = approach * 10 + ident[0] % 10, table_code
            vectors.records[k] = ident.tobytes()
        table(tables, "LAMA").name = summary

    path = _rewritten(tmp_path, "gpsc1", edit)
    with pytest.raises(MaceError) as caught:
        read_nastran_modes(path)
    assert str(caught.value) == (f"{path}: table OUGV1, its IDENT records: no real eigenvectors of a normal-modes run "
                                 f"in the file: {says} (expected the OP2 of a SOL 103 run: its normal modes)")


def test_complex_normal_modes_are_refused_as_complex_not_sort2(tmp_path):
    """A table code of 1007 is SORT1 complex (sort code bit 1), 2007 SORT2 real: each named as what it is."""
    for code, says in ((1007, "the eigenvectors are complex (expected real ones"),
                       (2007, "the eigenvectors are in SORT2 (expected SORT1")):
        def edit(tables, endian, code=code):
            vectors = table(tables, "OUGV1")
            for k, ident in _idents(vectors, endian):
                ident[1] = code
                vectors.records[k] = ident.tobytes()

        with pytest.raises(MaceError, match=r"table OUGV1, record 3 \(the IDENT of a vector\): " + re.escape(says)):
            read_nastran_modes(_rewritten(tmp_path, "gpsc1", edit, name=f"{code}.op2"))


def test_files_are_told_apart_by_their_content_not_their_name(tmp_path):
    """A formatted (ASCII) OUTPUT2 was read as a punch file (and refused as one without eigenvectors); a punch
    file named .op2 is a punch file; text that is neither, or binary that is no OP2, is said to be so."""
    formatted = tmp_path / "plate.op2"
    formatted.write_text("X 0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ$/+-()'=.*\"#%&,;:<>?@![]^_\\        020080\n"
                         " 62^626N6C^66^GNASTGRAN GFORTG TAPGE IDG CODGE - ^61^GXXXXGXXXX^4^3^HHHHHHHHHHHH\n")
    with pytest.raises(MaceError) as caught:
        read_nastran_modes(formatted)
    assert str(caught.value) == (f"{formatted}: a formatted (ASCII) OUTPUT2 file: it opens with NASTRAN's "
                                 "character-set line (expected a binary OP2, OUTPUT2's default unformatted form, e.g. "
                                 "PARAM,POST,-1; or a punch file)")
    punch = tmp_path / "modes.op2"
    lines = ["$TITLE   = run", "$EIGENVECTOR", "$REAL OUTPUT", "$SUBCASE ID =           1",
             "$EIGENVALUE =  3.9478418E+03  MODE =     1",
             f"{1:10d}{'G':>8}" + "".join(f"{x:18.6E}" for x in (0.5, 0.0, 0.0)),
             f"{'-CONT-':18}" + "".join(f"{x:18.6E}" for x in (0.0, 0.0, 0.25))]
    punch.write_text("\n".join(f"{line:72}{k:8d}" for k, line in enumerate(lines, start=1)) + "\n")
    read = read_nastran_modes(punch)
    assert read.modes.frequencies_hz[0] == pytest.approx(10.0, rel=1e-7) and read.modes.labels == ("mode 1",)
    text = tmp_path / "notes.op2"
    text.write_text("results of the plate run\n")
    with pytest.raises(MaceError, match=re.escape(f"{text}: a text file without a punch file's $ lines ($TITLE, "
                                                  "$EIGENVECTOR, ...): neither a punch file nor an OP2")):
        read_nastran_modes(text)
    binary = tmp_path / "modes.pch"
    binary.write_bytes(bytes(64))
    with pytest.raises(MaceError, match=re.escape(f"{binary}: the file header's first record: the file does not start "
                                                  "with a Fortran record of one word (found a length of 0 bytes): not "
                                                  "an OP2 file")):
        read_nastran_modes(binary)
