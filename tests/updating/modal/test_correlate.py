"""``mace-fmu correlate``: measured modes paired with a deck's by MAC at the measured DOFs.

The closed form: the three-storey frame (examples/three_storey_frame) is a shear chain. Each storey's four legs,
clamped into rigid floors, are a spring k = 12 E I / L^3 (I = 4 x 25 x 3^3 / 12 mm^4, L = 153.3 mm, E = 70 GPa); each
floor carries 5.201 kg and half the legs' mass above and below it. The chain's modes, written as a modes file by
hand (the format a modes file from another tool needs), pair with the deck's 0-g modes one to one.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from support.cli import run_cli
from support.paths import EXAMPLES

FRAME = EXAMPLES / "three_storey_frame"
E, I, L, RHO, AREA, FLOOR_KG = 7.0e10, 4 * 25e-3 * 3e-3**3 / 12, 0.1533, 2700.0, 3.0e-4, 5.201  # noqa: E741  (E I / L^3)


def shear_chain() -> tuple[np.ndarray, np.ndarray]:
    """(frequencies [Hz], mass-normalised shapes (floor, mode)) of the frame as a shear chain."""
    k = 12 * E * I / L**3
    leg = RHO * AREA * L
    m = np.diag([FLOOR_KG + leg, FLOOR_KG + leg, FLOOR_KG + leg / 2])
    w2, phi = sla.eigh(k * np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1]]), m)
    return np.sqrt(w2) / (2 * np.pi), phi


def modes_text(frequencies_hz, shapes, *, names=("acc_floor_1", "acc_floor_2", "acc_floor_3"), scaled=True) -> str:
    lines = ['[identification]', 'method = "closed form: shear chain"', ""]
    for name in names:
        lines += ["[[dofs]]", f'name = "{name}"', ""]
    for k, (f, phi) in enumerate(zip(frequencies_hz, shapes.T), start=1):
        real = phi / phi[np.argmax(np.abs(phi))]
        lines += ["[[modes]]", f'label = "mode {k}"', f"frequency_hz = {float(f)!r}", "damping = 0.002",
                  f"shape_real = [{', '.join(repr(float(x)) for x in real)}]"]
        if scaled:
            lines.append(f"shape_mass_normalised = [{', '.join(repr(float(x)) for x in phi)}]")
        lines.append("")
    return "\n".join(lines)


@pytest.fixture()
def chain_modes(tmp_path):
    f, phi = shear_chain()
    path = tmp_path / "modes.toml"
    path.write_text(modes_text(f, phi))
    return path, f


def test_the_shear_chain_s_modes_pair_with_the_deck_s_at_mac_1_and_within_half_a_percent(chain_modes, tmp_path,
                                                                                          capsys):
    path, f = chain_modes
    code, out, err = run_cli(capsys, ["correlate", "--deck", str(FRAME / "frame.bdf"), "--structure",
                                      str(FRAME / "frame.toml"), "--modes", str(path), "--configuration", "0g",
                                      "-o", str(tmp_path)])
    assert code == 0, err
    rows = [line.split() for line in out.splitlines() if line.startswith("mode ")]
    assert [r[4:7] for r in rows] == [["1st", "bending", "about"], ["2nd", "bending", "about"],
                                      ["3rd", "bending", "about"]]
    for row, hz in zip(rows, f):
        assert float(row[2]) == pytest.approx(hz, rel=1e-4)  # the measured column
        assert abs(float(row[-3])) < 0.5  # frequency difference [%]
        assert float(row[-2]) > 0.999  # MAC
        assert float(row[-1]) < 2.0  # mass-normalised shapes' difference [%]
    assert "unpaired" not in out
    assert (tmp_path / "mac.png").stat().st_size > 10_000


def test_a_mode_no_model_mode_looks_like_is_named_unpaired(tmp_path, capsys):
    f, phi = shear_chain()
    odd = np.column_stack([phi, [1.0, 1.0, -3.0]])  # no sway mode has floors 1 and 2 in phase against floor 3 so
    path = tmp_path / "modes.toml"
    path.write_text(modes_text(np.append(f, 24.0), odd, scaled=False))
    code, out, _ = run_cli(capsys, ["correlate", "--deck", str(FRAME / "frame.bdf"), "--structure",
                                    str(FRAME / "frame.toml"), "--modes", str(path), "--configuration", "0g",
                                    "--min-mac", "0.9", "-o", str(tmp_path)])
    assert code == 0
    assert "unpaired measured mode: mode 4 at 24.0000 Hz, no model mode with MAC >= 0.9" in out


@pytest.mark.parametrize("text, message", [
    ('[[dofs]]\nname = "floor_9"\n[[modes]]\nfrequency_hz = 7.0\ndamping = 0.01\nshape_real = [1.0]\n',
     "measured DOF 'floor_9': where is it on the model?"),
    ('[[dofs]]\nname = "acc_floor_1"\n[[modes]]\nfrequency_hz = 7.0\ndamping = 0.01\nshape_real = [1.0, 2.0]\n',
     "[[modes]] entry 1: shape_real must be a list of 1 finite numbers"),
    ('[[modes]]\nfrequency_hz = 7.0\n', "no [[dofs]] entries"),
])
def test_bad_modes_files_end_with_one_line_naming_the_entry(tmp_path, capsys, text, message):
    path = tmp_path / "modes.toml"
    path.write_text(text)
    code, _, err = run_cli(capsys, ["correlate", "--deck", str(FRAME / "frame.bdf"), "--structure",
                                    str(FRAME / "frame.toml"), "--modes", str(path), "-o", str(tmp_path / "out")])
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_a_dof_map_places_channels_by_node_and_a_uff_name_places_itself(tmp_path, capsys):
    f, phi = shear_chain()
    path = tmp_path / "modes.toml"
    path.write_text(modes_text(f, phi, names=("floor_one", "200+X", "300+X")))
    dof_map = tmp_path / "dofs.toml"
    dof_map.write_text('floor_one = [[100, 1, 1.0]]\n')
    code, out, err = run_cli(capsys, ["correlate", "--deck", str(FRAME / "frame.bdf"), "--modes", str(path),
                                      "--structure", str(FRAME / "frame.toml"), "--dof-map", str(dof_map),
                                      "--configuration", "0g", "-o", str(tmp_path)])
    assert code == 0, err
    assert "MAC 1.000 to 1.000" in out
