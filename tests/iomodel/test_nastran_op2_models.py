"""Models of public NASTRAN runs with shells and solids, built from their OP2 through a [modes] structure file.

pyNastran's ``plate_py`` (200 CQUAD4, free-free: six rigid-body modes) and ``mode_solid_shell_bar``
(CHEXA, CPENTA, CTETRA, CQUAD4, CTRIA3, CBAR, CBEAM, CROD). The independent route is pyNastran 1.4.1's
reading of the same OP2 files (tests/data/nastran/*/pynastran_*.csv, written in a separate environment):
the model's frequencies are its eigenvalues' (to 1e-7: both are the OP2's float32 numbers), and the
model's FRF between two grids is the modal superposition written out from pyNastran's eigenvectors at the
model's frequencies, to 2e-8 of the FRF's peak (pyNastran printed 9 significant digits), and from the
eigenvectors as read to 1e-10. The viewer draws the deck's
element edges, read for drawing only (tests/viewer/test_outline.py).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from support.modes_file import DATA, RUNS, op2_structure_file
from support.paths import ROOT

from mace_fmu.iomodel.modal_source import modal_structure
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.util.frequency import ZERO_HZ

ZETA = 0.015


def _structure_file(tmp_path: Path, run: str) -> Path:
    return op2_structure_file(tmp_path, run, zeta=ZETA)


def _pynastran(run: str) -> tuple[np.ndarray, dict[tuple[int, int], np.ndarray]]:
    """(eigenvalues [rad^2/s^2], (grid, component) -> that component in every mode) as pyNastran read them."""
    folder = DATA / Path(RUNS[run][0]).parent
    rows = lambda name: [r for r in csv.DictReader(t for t in (folder / name).read_text().splitlines()  # noqa: E731
                                                  if not t.startswith("#"))]
    eigenvalues = np.array([float(r["eigenvalue"]) for r in rows("pynastran_eigenvalues.csv")])
    shapes: dict[tuple[int, int], np.ndarray] = {}
    for r in rows("pynastran_modes.csv"):
        for c, key in enumerate(("cd_t1", "cd_t2", "cd_t3", "cd_r1", "cd_r2", "cd_r3"), start=1):
            shapes.setdefault((int(r["grid"]), c), np.zeros(len(eigenvalues)))[int(r["mode"]) - 1] = float(r[key])
    return eigenvalues, shapes


@pytest.mark.parametrize("run", sorted(RUNS))
def test_frequencies_and_frf_equal_pynastrans_reading_of_the_op2(tmp_path, run):
    structure = modal_structure(_structure_file(tmp_path, run))
    eigenvalues, shapes = _pynastran(run)
    hz = np.sign(eigenvalues) * np.sqrt(np.abs(eigenvalues)) / (2 * np.pi)
    np.testing.assert_allclose(structure.frequencies_hz, hz, rtol=1e-7, atol=1e-9)
    model = volts_model(structure)
    _, _, force, sensor = RUNS[run]
    flexible = hz[np.abs(hz) >= ZERO_HZ]
    f = np.sort(np.concatenate([np.geomspace(0.05, 2.0, 20) * flexible.min(), flexible]))
    w = 2 * np.pi * f
    # the model's frequencies (equal to pyNastran's eigenvalues' to 1e-7 above: the OP2's float32 and the 9 digits
    # printed); rigid-body modes (below ZERO_HZ) have no stiffness and no damping in the model
    omega = np.where(np.abs(hz) < ZERO_HZ, 0.0, 2 * np.pi * structure.frequencies_hz)
    omega2 = omega**2
    read = structure.modes  # the eigenvectors as read, which the model is built from

    def superposition(terms: np.ndarray) -> np.ndarray:
        return np.array([np.sum(terms / (omega2 - x**2 + 2j * ZETA * omega * x)) for x in w])

    # pyNastran printed 9 significant digits: each factor within 5e-9 of the OP2's float32, a product within 1e-8
    for terms, tolerance in ((shapes[sensor] * shapes[force], 2e-8),
                             (read.shape(*sensor, system="cd") * read.shape(*force, system="cd"), 1e-10)):
        h = model.frequency_response(f)
        outs = list(model.system.output_labels)
        expected = superposition(terms)
        for name, reference in (("displacement", expected), ("accelerometer", -w**2 * expected)):
            got = h[:, outs.index(name), 0]
            assert np.max(np.abs(got - reference)) < tolerance * np.max(np.abs(reference)), name


@pytest.mark.slow  # builds a native FMU and runs it
def test_the_command_line_takes_configuration_modes(tmp_path, capsys):
    from support.cli import run_cli

    toml = str(_structure_file(tmp_path, "solid_shell_bar"))
    code, out, err = run_cli(capsys, ["model", "modes", "--structure", toml])
    assert code == 0 and "modes volts-volts model" in out
    code, out, err = run_cli(capsys, ["view", "modes", "modes", "--structure", toml, "--html",
                                      str(tmp_path / "modes.html")])
    assert code == 0 and (tmp_path / "modes.html").stat().st_size > 10_000
    code, out, err = run_cli(capsys, ["export", "modes", "--structure", toml, "--motion-grids", "all", "-o",
                                      str(tmp_path)])
    fmu = tmp_path / "mode_solid_shell_bar_modes_native_motion.fmu"
    assert code == 0 and fmu.is_file()
    code, out, err = run_cli(capsys, ["view", "response", "modes", "--structure", toml, "--input", "shaker", "--fmu",
                                      str(fmu), "--duration", "0.02", "--step", "0.001", "--speed", "0.1", "--html",
                                      str(tmp_path / "response.html")])
    assert code == 0 and "wrote" in out and (tmp_path / "response.html").stat().st_size > 10_000
    code, out, err = run_cli(capsys, ["model", "modes"])
    assert code == 2 and "configuration 'modes' needs --structure FILE" in err
    (tmp_path / "e.toml").write_text('[values]\nE_steel = 2.0e11\n')
    code, out, err = run_cli(capsys, ["model", "modes", "--structure", toml, "--parameters", str(tmp_path / "e.toml")])
    assert code == 2 and "not an FE model" in err and len(err.strip().splitlines()[-1]) > 0


def test_a_deck_route_refuses_a_structure_file_that_points_at_modes(tmp_path):
    from mace_fmu.errors import MaceError
    from mace_fmu.fe.modes import compute_modes

    toml = _structure_file(tmp_path, "solid_shell_bar")
    deck = DATA / "beam_modes" / "beam_modes.dat"
    with pytest.raises(MaceError, match=r"\[modes\] table points at NASTRAN's modes, not at the deck"):
        compute_modes(str(deck), configuration="0g", structure_file=toml)


@pytest.mark.slow  # builds a native FMU
def test_example_nastran_plate(tmp_path):
    """examples/nastran_plate: plate_py's OP2 to a model (its FRF equal to the modal superposition), a native FMU
    (equal to the exact ZOH, nominal and with a frequency scale set through FMI) and an animation on its edges."""
    import importlib.util

    path = ROOT / "examples" / "nastran_plate" / "nastran_plate.py"
    spec = importlib.util.spec_from_file_location("nastran_plate_example", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    summary = example.main(tmp_path)
    assert summary["superposition_error"] < 1e-10
    assert summary["fmu_error"] < 1e-8 and summary["fmu_error_scaled"] < 1e-8
    assert summary["edges"] == 430 and (tmp_path / "plate_modes.html").stat().st_size > 100_000


BEAM_INSTRUMENTS = """
[[actuators]]
name = "force"
description = "force at grid 6 along Y"
dofs = [[6, 2, 1.0]]

[[sensors]]
name = "tip_y"
description = "grid 11 displacement along Y"
kind = "displacement"
dofs = [[11, 2, 1.0]]

[[sensors]]
name = "acc_9_y"
description = "grid 9 acceleration along Y"
kind = "acceleration"
dofs = [[9, 2, 1.0]]

[damping]
default = 0.02
"""


def test_a_beams_nastran_modes_and_its_deck_give_the_same_model(tmp_path):
    """pyNastran's beam_modes run (CBAR, CBEAM, CONM2): the model from NASTRAN's OP2 and the model from the FE
    core's solution of the same deck, through the same pipeline, agree (NASTRAN's and the FE core's eigenvalues
    agree to 5e-8, which the resonance peaks carry divided by 2 zeta)."""
    from mace_fmu.fe.modes import compute_modes

    deck = DATA / "beam_modes" / "beam_modes.dat"
    (tmp_path / "deck.toml").write_text(BEAM_INSTRUMENTS)
    op2 = DATA / "beam_modes_op2" / "beam_modes_m1.op2"
    (tmp_path / "modes.toml").write_text(f'[modes]\nfile = "{op2.as_posix()}"\ngeometry = "{deck.as_posix()}"\n'
                                         + BEAM_INSTRUMENTS)
    from_deck = volts_model(compute_modes(str(deck), configuration="0g", structure_file=tmp_path / "deck.toml"))
    from_modes = volts_model(modal_structure(tmp_path / "modes.toml"))
    np.testing.assert_allclose(from_modes.plant.frequencies_hz, from_deck.plant.frequencies_hz, rtol=5e-8)
    f = np.geomspace(50.0, 15000.0, 300)
    a, b = from_deck.frequency_response(f), from_modes.frequency_response(f)
    for o in range(a.shape[1]):
        assert np.max(np.abs(b[:, o] - a[:, o])) < 1e-6 * np.max(np.abs(a[:, o]))
