"""Punch files (.pch): the eigenvectors of the solid/shell/bar run as NASTRAN would punch them equal its .f06
printout; output systems (CD) resolved to basic as the closed-form rotation of a cylindrical and a spherical
system says; public punch files of other kinds refused in one line."""

from __future__ import annotations

import numpy as np
import pytest
from support.f06_modes import read_f06_modes
from support.nastran_results import NASTRAN

from mace_fmu.errors import DeckError, MaceError
from mace_fmu.nastran_modes import read_nastran_modes


def punch_text(modes: dict[int, tuple[float, dict[int, np.ndarray]]], *, subcase: int = 1,
               scalar_points: dict[int, float] | None = None) -> str:
    """NASTRAN's punch layout (as in pyNastran's public models/fsi/fsi.pch, real instead of complex): 72 columns
    of data, a line counter in 73-80; a grid's T1 T2 T3 on its line, R1 R2 R3 on the -CONT- line."""
    lines = ["$TITLE   = MSC.Nastran job", "$SUBTITLE=Default", "$LABEL   ="]
    for mode, (eigenvalue, vectors) in modes.items():
        lines += ["$EIGENVECTOR", "$REAL OUTPUT", f"$SUBCASE ID = {subcase:11d}",
                  f"$EIGENVALUE = {eigenvalue:14.7E}  MODE = {mode:5d}"]
        for gid, v in vectors.items():
            lines.append(f"{gid:10d}{'G':>8}" + "".join(f"{x:18.6E}" for x in v[:3]))
            lines.append(f"{'-CONT-':18}" + "".join(f"{x:18.6E}" for x in v[3:]))
        for sid, value in (scalar_points or {}).items():
            lines.append(f"{sid:10d}{'S':>8}{value:18.6E}")
    return "\n".join(f"{line:72}{k:8d}" for k, line in enumerate(lines, start=1)) + "\n"


def test_punched_modes_equal_the_f06_printout(tmp_path):
    printed = read_f06_modes(NASTRAN / "solid_shell_bar" / "mode_solid_shell_bar.f06")
    modes = {int(m): (float(lam), printed.vectors[m]) for m, lam in zip(printed.modes, printed.eigenvalues)}
    path = tmp_path / "solid_shell_bar.pch"
    path.write_text(punch_text(modes, scalar_points={900: 1.5}))
    ours = read_nastran_modes(path, geometry=NASTRAN / "solid_shell_bar" / "mode_solid_shell_bar.bdf")
    np.testing.assert_allclose(ours.eigenvalues, printed.eigenvalues, rtol=1e-15)
    np.testing.assert_allclose(ours.modes.frequencies_hz, printed.cycles, rtol=5e-7)
    for column, mode in enumerate(printed.modes):
        for gid, values in printed.vectors[mode].items():
            np.testing.assert_allclose(ours.modes.grid_motion(gid)[:, column], values, rtol=1e-15, atol=0)
    assert ours.generalized_masses is None and ours.normalisation.startswith("not stated")
    assert any("900" in note for note in ours.notes)  # the scalar point: left out and named


def test_punch_equals_the_op2_to_the_printed_digits(tmp_path):
    printed = read_f06_modes(NASTRAN / "solid_shell_bar" / "mode_solid_shell_bar.f06")
    path = tmp_path / "modes.pch"
    path.write_text(punch_text({int(m): (float(lam), printed.vectors[m])
                                for m, lam in zip(printed.modes, printed.eigenvalues)}))
    punch = read_nastran_modes(path)
    op2 = read_nastran_modes(NASTRAN / "solid_shell_bar" / "mode_solid_shell_bar.op2")
    np.testing.assert_allclose(punch.modes.shapes, op2.modes.shapes, rtol=6e-7, atol=0)
    assert punch.modes.dofs == op2.modes.dofs


@pytest.mark.parametrize("kind", ["C", "S"])
def test_cylindrical_and_spherical_output_systems_rotate_to_basic(tmp_path, kind):
    """A grid at 30 degrees (and, spherical, 60 degrees from the pole) of a system whose z axis is basic x:
    a unit radial motion in the grid's CD system is, in basic, the closed-form radial direction there."""
    theta, phi = 30.0, 60.0
    position = (2.0, theta, 0.5) if kind == "C" else (2.0, phi, theta)  # (r, theta, z) / (r, polar, azimuth)
    deck = tmp_path / "deck.bdf"
    # system 7: origin (1, 2, 3), z along basic x, x along basic y (so y along basic z)
    deck.write_text("BEGIN BULK\n"
                    f"CORD2{kind},7,0,1.,2.,3.,2.,2.,3.\n,1.,3.,3.\n"
                    f"GRID,1,7,{position[0]},{position[1]},{position[2]},7\n"
                    "GRID,2,0,0.,0.,0.\n"
                    "ENDDATA\n")
    pch = tmp_path / "modes.pch"
    motion = {1: np.array([1.0, 0.0, 0.0, 0.0, 0.0, 1.0]), 2: np.array([0.0, 1.0, 0.0, 0.0, 0.0, 0.0])}
    pch.write_text(punch_text({1: (4.0e4, motion)}))
    # unit motions: the largest component of the vector is 1, as NORM=MAX's would be; stated mass-normalised
    ours = read_nastran_modes(pch, geometry=deck, normalisation="mass")
    ex, ey, ez = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    t, p = np.radians(theta), np.radians(phi)
    if kind == "C":
        radial, third = np.cos(t) * ex + np.sin(t) * ey, ez  # e_r and e_z
        where = np.array([1.0, 2.0, 3.0]) + 2.0 * radial + 0.5 * ez
    else:
        radial = np.sin(p) * (np.cos(t) * ex + np.sin(t) * ey) + np.cos(p) * ez  # e_r; e_phi is the 3rd axis
        third = -np.sin(t) * ex + np.cos(t) * ey
        where = np.array([1.0, 2.0, 3.0]) + 2.0 * radial
    np.testing.assert_allclose(ours.modes.grid_motion(1)[:3, 0], radial, atol=1e-12)
    np.testing.assert_allclose(ours.modes.grid_motion(1)[3:, 0], third, atol=1e-12)
    np.testing.assert_allclose(ours.grid_positions[1], where, atol=1e-12)
    np.testing.assert_allclose(ours.modes.shape(1, 1, system="cd"), [1.0], atol=1e-12)
    np.testing.assert_allclose(ours.modes.grid_motion(2)[:, 0], motion[2], atol=0)
    assert ours.modes.frequencies_hz[0] == pytest.approx(200.0 / (2 * np.pi), rel=1e-15)


def test_subcases_are_told_apart(tmp_path):
    one = {1: (1.0e4, {5: np.arange(1.0, 7.0)})}
    two = {1: (4.0e4, {5: -np.arange(1.0, 7.0)})}
    path = tmp_path / "two.pch"
    path.write_text(punch_text(one, subcase=1) + punch_text(two, subcase=2))
    with pytest.raises(MaceError, match=r"two\.pch: eigenvectors of subcases \[1, 2\] \(expected one: choose it"):
        read_nastran_modes(path)
    assert read_nastran_modes(path, subcase=2).eigenvalues[0] == 4.0e4
    with pytest.raises(MaceError, match="no eigenvectors of subcase 3"):
        read_nastran_modes(path, subcase=3)


def test_complex_eigenvectors_are_refused_in_one_line():
    """pyNastran's public fsi.pch: the complex eigenvectors of a fluid-structure run."""
    with pytest.raises(MaceError, match=r"fsi\.pch:5: \$EIGENVECTOR block: complex eigenvectors") as caught:
        read_nastran_modes(NASTRAN / "fsi" / "fsi.pch")
    assert "\n" not in str(caught.value)


def test_a_missing_rotation_line_and_a_bad_number_name_the_line(tmp_path):
    good = punch_text({1: (1.0e4, {5: np.arange(1.0, 7.0), 6: np.arange(1.0, 7.0)})}).splitlines()
    path = tmp_path / "cut.pch"
    path.write_text("\n".join(good[:-3] + good[-2:]) + "\n")  # grid 5's -CONT- line gone
    with pytest.raises(MaceError, match=r"cut\.pch:9: \$EIGENVECTOR block, grid 5: expected the -CONT- line"):
        read_nastran_modes(path)
    path.write_text("\n".join(good).replace("2.000000E+00", "2.0000x0E+00", 1) + "\n")
    with pytest.raises(MaceError, match=r"cut\.pch:8: grid 5: '2.0000x0E\+00' is not a number"):
        read_nastran_modes(path)


def test_a_punch_without_eigenvectors_says_what_to_request(tmp_path):
    path = tmp_path / "static.pch"
    path.write_text(punch_text({1: (1.0, {1: np.ones(6)})}).replace("$EIGENVECTOR", "$DISPLACEMENTS"))
    with pytest.raises(MaceError, match=r"static\.pch: no \$EIGENVECTOR block .*DISPLACEMENT\(PUNCH\)=ALL"):
        read_nastran_modes(path)


def test_a_grid_missing_from_the_geometry_is_named(tmp_path):
    deck = tmp_path / "deck.bdf"
    deck.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nENDDATA\n")
    pch = tmp_path / "modes.pch"
    pch.write_text(punch_text({1: (1.0, {1: np.ones(6), 2: np.ones(6)})}))
    with pytest.raises(MaceError, match=r"modes\.pch: \$EIGENVECTOR blocks: grids \[2\] have eigenvectors but no GRID"):
        read_nastran_modes(pch, geometry=deck)
    deck.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.,5\nGRID,2,,1.,0.,0.\nENDDATA\n")
    with pytest.raises(MaceError, match=r"deck\.bdf: bulk data: GRID 1: CD system 5 is not defined"):
        read_nastran_modes(pch, geometry=deck)
    deck.write_text("BEGIN BULK\nGRID,1,,0.,0.,x.\nENDDATA\n")
    with pytest.raises(DeckError, match=r"deck\.bdf:2: GRID"):
        read_nastran_modes(pch, geometry=deck)
