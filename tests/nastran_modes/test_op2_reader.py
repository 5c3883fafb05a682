"""NASTRAN's normal modes read from public SOL 103 OP2 files, against independent routes: NASTRAN's own .f06
printout of the same run, NASTRAN's own basic grid table (BGPDT) and coordinate system matrices (CSTM), pyNastran's
reading of the same files (run once in an environment of its own, tests/data/nastran/pynastran_modes.py) and,
for the beam model, the FE core solving the same deck."""

from __future__ import annotations

import numpy as np
import pytest
from support.f06_modes import read_f06_modes
from support.nastran_results import (
    MODELS,
    NASTRAN,
    op2_path,
    pynastran_eigenvalues,
    pynastran_vectors,
)

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.nastran_modes import read_nastran_modes
from mace_fmu.nastran_modes.fortran import Op2Records
from mace_fmu.nastran_modes.op2 import read_op2_modes

#: NASTRAN prints 7 significant digits (half a unit of the last: 5e-7 relative); an OP2 holds 32-bit reals (6e-8)
PRINTED = 5e-7 + 6e-8
COMPONENTS = ("t1", "t2", "t3", "r1", "r2", "r3")
WITH_F06 = [m for m, (_, f06) in MODELS.items() if f06]


def printed(model: str):
    return read_f06_modes(NASTRAN / model / MODELS[model][1])


@pytest.mark.parametrize("model", WITH_F06)
def test_frequencies_equal_nastrans_eigenvalue_table(model):
    ours = read_nastran_modes(op2_path(model))
    table = printed(model)
    assert len(ours.modes) == len(table.modes)
    np.testing.assert_allclose(ours.eigenvalues, table.eigenvalues, rtol=PRINTED)
    np.testing.assert_allclose(ours.modes.frequencies_hz, table.cycles, rtol=PRINTED)
    assert ours.modes.labels == tuple(f"mode {m}" for m in table.modes)


@pytest.mark.parametrize("model", ["gpsc1", "plate_py"])
def test_frequencies_equal_the_eigenvalues_in_the_op2(model):
    """The models without an .f06: the eigenvalues (LAMA, else each vector's header) as pyNastran reads them."""
    ours = read_nastran_modes(op2_path(model))
    _, eigenvalues, masses = pynastran_eigenvalues(model)
    np.testing.assert_array_equal(np.float32(ours.eigenvalues), np.float32(eigenvalues))
    lam = np.sign(ours.modes.frequencies_hz) * (2 * np.pi * ours.modes.frequencies_hz) ** 2
    np.testing.assert_allclose(lam, ours.eigenvalues, rtol=1e-12)
    if masses is not None:
        np.testing.assert_array_equal(np.float32(ours.generalized_masses), np.float32(masses))


def test_solid_shell_bar_eigenvectors_equal_the_f06_printout():
    """Every component of every grid (CHEXA, CPENTA, CTETRA, shells, bars), to the printed digits."""
    raw = read_op2_modes(op2_path("solid_shell_bar"), subcase=None)
    table = printed("solid_shell_bar")
    for column, mode in enumerate(raw.mode_numbers):
        expected = np.array([table.vectors[mode][g] for g in raw.grid_ids])
        np.testing.assert_allclose(raw.vectors[:, :, column], expected, rtol=PRINTED, atol=0)
    assert len(raw.grid_ids) == 25 and raw.vectors.shape[2] == 3


def test_beam_eigenvectors_equal_the_f06_printout_up_to_the_choice_within_repeated_roots():
    """beam_modes: the OP2 and the .f06 are two runs of one deck. The single roots (modes 5, 6) are the same
    vectors component by component; a repeated root's two vectors may be any pair spanning the same plane,
    so the OP2's pair must be the .f06's pair times an orthogonal 2 x 2 (in mass-normalised form). Components
    at round-off level (below 1e-12 of the largest) differ between two runs and are held to that only."""
    ours = read_nastran_modes(op2_path("beam_modes_op2"))
    raw = read_op2_modes(op2_path("beam_modes_op2"), subcase=None)
    table = printed("beam_modes_op2")
    f06 = np.stack([np.concatenate([table.vectors[m][g] for g in raw.grid_ids]) for m in table.modes], axis=1)
    f06 = f06 / np.sqrt(table.generalized_masses)
    for column in (4, 5):
        expected = f06[:, column] * np.sqrt(table.generalized_masses[column])
        np.testing.assert_allclose(raw.vectors[:, :, column].ravel(), expected, rtol=PRINTED,
                                   atol=1e-12 * np.abs(expected).max())
        assert raw.generalized_masses[column] == pytest.approx(table.generalized_masses[column], rel=PRINTED)
    for pair in ((0, 1), (2, 3), (6, 7), (8, 9)):
        cols = list(pair)
        q, *_ = np.linalg.lstsq(f06[:, cols], ours.modes.shapes[:, cols], rcond=None)
        np.testing.assert_allclose(q.T @ q, np.eye(2), atol=2e-6)
        residual = ours.modes.shapes[:, cols] - f06[:, cols] @ q
        assert np.abs(residual).max() <= 2e-6 * np.abs(f06[:, cols]).max()


@pytest.mark.parametrize("model", sorted(MODELS))
def test_the_reader_gives_what_pynastran_reads(model):
    """Every 32-bit value of every vector, as it is in the file (each grid's CD system), and the grid IDs."""
    raw = read_op2_modes(op2_path(model), subcase=None)
    ref = pynastran_vectors(model)
    n_modes = raw.vectors.shape[2]
    expected = np.column_stack([ref[f"cd_{c}"] for c in COMPONENTS]).reshape(n_modes, -1, 6)
    np.testing.assert_array_equal(ref["grid"].reshape(n_modes, -1)[0], raw.grid_ids)
    np.testing.assert_array_equal(np.float32(np.moveaxis(raw.vectors, 2, 0)), np.float32(expected))
    np.testing.assert_array_equal(raw.mode_numbers, np.unique(ref["mode"]).astype(int))


def _nastran_table(path, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(ints, floats) of the data record of one of NASTRAN's own geometry tables (BGPDT, CSTM)."""
    records = Op2Records(path, path.read_bytes())
    (table,) = [t for t in records.tables(lambda n: n == name) if t.name == name]
    return np.frombuffer(table.records[0], "<i4"), np.frombuffer(table.records[0], "<f4")


def test_grid_positions_and_output_systems_are_nastrans_own():
    """gpsc1: 18 grids given in a CORD2C whose RID is a CORD2R, the others in that CORD2R; every CD that
    CORD2R. NASTRAN wrote its own basic positions (BGPDT: CD, x, y, z per grid, here in ID order) and the
    axes of every system (CSTM: ID, type, origin, 3 x 3 with the axes as columns): ours equal them to
    32-bit precision."""
    path = op2_path("gpsc1")
    ours = read_nastran_modes(path)
    raw = read_op2_modes(path, subcase=None)
    ints, floats = _nastran_table(path, "BGPDT")
    bgpdt_cd, bgpdt_xyz = ints.reshape(-1, 4)[:, 0], floats.reshape(-1, 4)[:, 1:]
    grids = sorted(ours.grid_positions)
    assert len(grids) == len(bgpdt_xyz) == 51
    assert sum(raw.geometry.grids[g][0] == 20 for g in grids) == 18
    np.testing.assert_allclose([ours.grid_positions[g] for g in grids], bgpdt_xyz, rtol=0, atol=2e-5)
    np.testing.assert_array_equal(bgpdt_cd, [raw.geometry.grids[g][2] for g in grids])
    ints, floats = _nastran_table(path, "CSTM")
    cstm = {int(i[0]): (f[2:5], f[5:].reshape(3, 3)) for i, f in zip(ints.reshape(-1, 14), floats.reshape(-1, 14))}
    assert set(cstm) == {10, 20}
    for row, gid in enumerate(ours.modes.dofs.grid_ids):
        cd = raw.geometry.grids[gid][2]
        np.testing.assert_allclose(ours.modes.cd_frames[row], cstm[cd][1] if cd else np.eye(3), atol=1e-7)


def test_the_cylindrical_system_is_nastrans_own():
    """The CORD2C of gpsc1 (A, B, C given in its RID) resolves to the origin and axes NASTRAN's CSTM holds."""
    from mace_fmu.nastran_modes.frames import resolve_geometry

    path = op2_path("gpsc1")
    raw = read_op2_modes(path, subcase=None)
    ints, floats = _nastran_table(path, "CSTM")
    origin, axes = next((f[2:5], f[5:].reshape(3, 3)) for i, f in zip(ints.reshape(-1, 14), floats.reshape(-1, 14))
                        if i[0] == 20)
    positions, _ = resolve_geometry(path, raw.geometry, where="table GEOM1")
    for gid, (cp, (r, theta, z), _) in raw.geometry.grids.items():
        if cp == 20:
            local = np.array([r * np.cos(np.radians(theta)), r * np.sin(np.radians(theta)), z])
            np.testing.assert_allclose(positions[gid], origin + axes @ local, atol=2e-5)


def test_mass_normalisation_is_checked_and_nastrans_max_normalisation_rescaled():
    """beam_modes' run asked for NORM=MAX: generalized masses 3.7e-3 to 2.2e-2. Rescaled, the shapes are
    mass-normalised in the FE core's mass matrix of the same deck (an independent M): phi^T M phi = I."""
    ours = read_nastran_modes(op2_path("beam_modes_op2"))
    assert ours.normalisation.startswith("rescaled to MASS")
    assert ours.generalized_masses.min() == pytest.approx(3.668128e-03, rel=PRINTED)
    fe = compute_modes(read_deck(NASTRAN / "beam_modes" / "beam_modes.dat"), configuration="0g")
    rows = np.concatenate([fe.model.dofs.indices(g) for g in ours.modes.dofs.grid_ids])
    mass = fe.model.mass.toarray()[np.ix_(rows, rows)]
    generalized = ours.modes.shapes.T @ mass @ ours.modes.shapes
    np.testing.assert_allclose(generalized, np.eye(len(ours.modes)), atol=2e-7)
    assert read_nastran_modes(op2_path("gpsc1")).normalisation == "MASS"


def test_without_generalized_masses_the_normalisation_says_so():
    """solid_shell_bar's OP2 has no LAMA, but its DYNAMICS table holds the run's EIGRL (NORM=MASS); plate_py's OP2
    has neither: its vectors are taken as NASTRAN's default normalisation, and the text says so."""
    ours = read_nastran_modes(op2_path("solid_shell_bar"))
    assert ours.generalized_masses is None
    assert ours.normalisation == ("MASS, as the run asked (EIGRL 1 in table DYNAMICS: NORM=MASS); the file has no "
                                  "generalized masses to check it")
    assert read_nastran_modes(op2_path("plate_py")).normalisation.startswith("not stated")


def test_beam_modes_agree_with_the_fe_core_solving_the_deck():
    """The NASTRAN-modes route and the deck route (mace_fmu.fe on beam_modes.dat): frequencies to 1e-6 and
    shapes at every grid to 1e-6 of the largest component (a repeated root's pair up to an orthogonal 2 x 2,
    a single root up to its sign)."""
    ours = read_nastran_modes(op2_path("beam_modes_op2"), geometry=NASTRAN / "beam_modes" / "beam_modes.dat")
    fe = compute_modes(read_deck(NASTRAN / "beam_modes" / "beam_modes.dat"), configuration="0g").modes
    np.testing.assert_allclose(ours.modes.frequencies_hz, fe.frequencies_hz, rtol=1e-6)
    rows = np.concatenate([fe.dofs.indices(g) for g in ours.modes.dofs.grid_ids])
    theirs = fe.shapes[rows]
    for cols in ([0, 1], [2, 3], [4], [5], [6, 7], [8, 9]):
        q, *_ = np.linalg.lstsq(theirs[:, cols], ours.modes.shapes[:, cols], rcond=None)
        np.testing.assert_allclose(q.T @ q, np.eye(len(cols)), atol=1e-6)
        residual = ours.modes.shapes[:, cols] - theirs[:, cols] @ q
        assert np.abs(residual).max() <= 1e-6 * np.abs(ours.modes.shapes[:, cols]).max(), cols


def test_two_writers_of_one_run_give_the_same_modes():
    """beam_modes_m1.op2 and beam_modes_m2.op2 hold the same run in different table sets (OUGV1 with OEF1X or
    with OEF1, GEOM1 before or after the elements)."""
    one = read_nastran_modes(op2_path("beam_modes_op2"))
    two = read_nastran_modes(NASTRAN / "beam_modes_op2" / "beam_modes_m2.op2")
    np.testing.assert_array_equal(one.modes.shapes, two.modes.shapes)
    np.testing.assert_array_equal(one.eigenvalues, two.eigenvalues)


def test_the_deck_gives_the_geometry_of_a_shell_deck_the_fe_core_cannot_model():
    """plate_py's OP2 has no geometry: its deck (CQUAD4, CORD2C, CORD2S, MAT4 ...) gives the grids' positions."""
    bare = read_nastran_modes(op2_path("plate_py"))
    assert bare.grid_positions is None and any("not known" in note for note in bare.notes)
    ours = read_nastran_modes(op2_path("plate_py"), geometry=NASTRAN / "plate_py" / "plate_py.dat")
    assert len(ours.grid_positions) == 231 and ours.notes == ()
    np.testing.assert_array_equal(ours.modes.shapes, bare.modes.shapes)  # every CD is basic in this deck
