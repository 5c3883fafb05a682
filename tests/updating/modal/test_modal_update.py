"""``mace-fmu update modal``: a deck's structure-file parameters against measured modes (thesis 4.2).

The closed form (test_correlate.py's shear chain): the frame's storeys as springs k = 12 E I / L^3 with moduli 60, 66
and 55 GPa and floors of 5.0, 4.6 and 4.8 kg (plus half the legs' mass above and below), its modes written as a
modes file with mass-normalised shapes. From the stated frame (70 GPa, 5.201 kg) the update brings the deck's 0-g
model to those moduli and masses within the shear chain's own approximation of the deck (its frequencies are within
0.5 % of the deck's at equal parameters), and to its frequencies exactly.
"""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest
import scipy.linalg as sla
from support.cli import run_cli
from support.paths import EXAMPLES
from test_correlate import AREA, I, L, RHO, modes_text

from mace_fmu.cli import main
from mace_fmu.parameters.sets import ParameterSet

FRAME = EXAMPLES / "three_storey_frame"
DECK, STRUCTURE = str(FRAME / "frame.bdf"), str(FRAME / "frame.toml")
NAMES = "E_storey_1,E_storey_2,E_storey_3,m_floor_1,m_floor_2,m_floor_3"
TRUTH = {"E_storey_1": 60e9, "E_storey_2": 66e9, "E_storey_3": 55e9, "m_floor_1": 5.0, "m_floor_2": 4.6,
         "m_floor_3": 4.8}


def chain_modes() -> tuple[np.ndarray, np.ndarray]:
    e = np.array([TRUTH[f"E_storey_{k}"] for k in (1, 2, 3)])
    k = 12 * e * I / L**3
    leg = RHO * AREA * L
    stiffness = np.array([[k[0] + k[1], -k[1], 0.0], [-k[1], k[1] + k[2], -k[2]], [0.0, -k[2], k[2]]])
    mass = np.diag([TRUTH["m_floor_1"] + leg, TRUTH["m_floor_2"] + leg, TRUTH["m_floor_3"] + leg / 2])
    w2, phi = sla.eigh(stiffness, mass)
    return np.sqrt(w2) / (2 * np.pi), phi


def modal_update(tmp_path, capsys, modes_file, *extra: str) -> tuple[int, str, str]:
    return run_cli(capsys, ["update", "modal", "--deck", DECK, "--structure", STRUCTURE, "--modes", str(modes_file),
                            "--update", NAMES, *extra])


@pytest.fixture(scope="module")
def chain_update(tmp_path_factory):
    folder = tmp_path_factory.mktemp("chain")
    f, phi = chain_modes()
    (folder / "modes.toml").write_text(modes_text(f, phi))
    out = folder / "update"
    code = main(["update", "modal", "--deck", DECK, "--structure", STRUCTURE, "--modes", str(folder / "modes.toml"),
                 "--configuration", "0g", "--update", NAMES, "-o", str(out)])
    return code, out, f


@pytest.mark.slow  # two rounds of the cost-sensitivity method on full FE re-solves (about 4 s)
def test_the_shear_chain_s_moduli_and_masses_come_back_within_its_approximation_of_the_deck(chain_update):
    code, out, f = chain_update
    assert code == 0
    params = ParameterSet.read(out / "parameters.toml")
    for name, truth in TRUTH.items():
        assert params[name] == pytest.approx(truth, rel=0.015), name
    summary = json.loads((out / "summary.json").read_text())
    for pair, hz in zip(summary["after"], f):
        assert pair["model_hz"] == pytest.approx(hz, rel=1e-4) and pair["mac"] > 0.9999
        assert pair["shape_difference"] < 0.005
    assert summary["selection"]["kept"] == NAMES.split(",")
    assert summary["scaled_shapes"] is True


@pytest.mark.slow  # reads the module's update
def test_it_writes_what_the_fmu_updates_write_and_says_where_the_set_comes_from(chain_update):
    code, out, _ = chain_update
    for name in ("parameters.toml", "convergence.toml", "uncertainty.toml", "report.txt", "summary.json",
                 "mac_before.png", "mac_after.png", "orthogonality.png", "strength.png"):
        assert (out / name).stat().st_size > 100, name
    convergence = tomllib.loads((out / "convergence.toml").read_text())
    assert convergence["converged"] is True and convergence["verdict"] == "untested"
    uncertainty = tomllib.loads((out / "uncertainty.toml").read_text())["stage"][0]
    assert uncertainty["parameters"] == NAMES.split(",") and max(uncertainty["standard_deviation_percent"]) < 1
    prov = ParameterSet.read(out / "parameters.toml").provenance
    assert prov.configuration == "0g" and prov.deck == "frame.bdf" and "eq. 4.2" in prov.cost
    values = ParameterSet.read(out / "parameters.toml").values
    assert values["damping:1st bending about Y"] == 0.002  # the measured modes' damping ratios, by mode label


@pytest.mark.slow  # one more update (about 4 s)
def test_frequencies_alone_do_not_tell_masses_from_moduli_and_the_uncertainty_says_so(tmp_path, capsys):
    """Eq. 4.2 alone: the frequencies are those of a structure whose every stiffness and mass are scaled alike, so
    the six parameters have a direction the data do not fix; the mass-normalised shapes fix it (above)."""
    f, phi = chain_modes()
    (tmp_path / "modes.toml").write_text(modes_text(f, phi))
    code, out, err = modal_update(tmp_path, capsys, tmp_path / "modes.toml", "--configuration", "0g",
                                  "--shape-weight", "0", "--keep-all", "-o", str(tmp_path / "out"))
    assert code == 0, err
    stage = tomllib.loads((tmp_path / "out" / "uncertainty.toml").read_text())["stage"][0]
    assert stage["weak_directions"], stage
    assert max(stage["standard_deviation_percent"]) > 5


@pytest.mark.parametrize("extra, message", [
    (["--update", "E_storey_9"], "--update E_storey_9: not a parameter of frame.bdf with frame.toml; its moduli, "
                                 "springs and masses (the structure file's [parameters]) are E_storey_1"),
    (["--shape-weight", "-1"], "argument --shape-weight: expected a finite number >= 0, got '-1'"),
    (["--shapes", "mass-normalised"], "mass-normalised shapes asked for, but not every mode has one"),
])
def test_bad_requests_end_with_one_line_before_any_work(tmp_path, capsys, extra, message):
    f, phi = chain_modes()
    (tmp_path / "modes.toml").write_text(modes_text(f, phi, scaled="--shapes" not in extra))
    code, _, err = run_cli(capsys, ["update", "modal", "--deck", DECK, "--structure", STRUCTURE, "--modes",
                                    str(tmp_path / "modes.toml"), "--update", extra[1] if extra[0] == "--update"
                                    else NAMES, *(extra if extra[0] != "--update" else []), "-o",
                                    str(tmp_path / "out")])
    assert code == 2 and message in err, err
    assert not (tmp_path / "out").exists()


def test_a_measured_mode_the_model_cannot_pair_stops_the_update_and_is_named(tmp_path, capsys):
    f, phi = chain_modes()
    odd = np.column_stack([phi, [1.0, 1.0, -3.0]])
    (tmp_path / "modes.toml").write_text(modes_text(np.append(f, 24.0), odd, scaled=False))
    code, _, err = modal_update(tmp_path, capsys, tmp_path / "modes.toml", "--min-mac", "0.9", "-o",
                                str(tmp_path / "out"))
    assert code == 2 and "measured mode(s) mode 4 at 24 Hz pair with no model mode (MAC >= 0.9)" in err
    assert not (tmp_path / "out").exists()
