"""``mace-fmu modes --parameters FILE`` (and ``model``) for any deck with a structure file: an
update's frequencies are one command.

The deck is the tip-mass cantilever of the own-deck tests, its material named ``beam`` by a structure file; a set
doubles its modulus and scales its second mode by 1.1. The closed form (tests/support/cantilever.py) gives the
frequencies: a bending frequency goes as sqrt(E).
"""

from __future__ import annotations

import json

import numpy as np
from support.cantilever import beam_deck, tip_mass_cantilever_hz
from support.cli import run_cli

SET = """[provenance]
created = "2026-01-15T10:00:00Z"
tool = "mace-fmu 0.1.0"
configuration = "0g"
fitted_to = "beam_0g_native.fmu"

[values]
E_beam = {modulus!r}
frequency_scale_mode_2 = 1.1
damping_mode_1 = 0.01
"""


def _beam(tmp_path):
    from support.cantilever import E

    deck = tmp_path / "beam.bdf"
    deck.write_text(beam_deck())
    structure = tmp_path / "beam.toml"
    structure.write_text('[components]\nbeam = ["1-21"]\n\n[parameters]\nmaterials = { "1" = "beam" }\n')
    parameters = tmp_path / "updated.toml"
    parameters.write_text(SET.format(modulus=2.0 * E))
    return deck, structure, parameters


def test_modes_of_a_deck_with_an_update_s_parameter_set(tmp_path, capsys):
    deck, structure, parameters = _beam(tmp_path)
    common = ["modes", "0g", "--deck", str(deck), "--structure", str(structure), "--json"]
    code, out, err = run_cli(capsys, [*common, "--parameters", str(parameters)])
    assert code == 0, err
    result = json.loads(out)
    bending = np.array([m["frequency_hz"] for m in result["modes"] if "bending" in m["label"]][:2])
    # NASTRAN's lumped bar mass converges from below: 0.3 % covers the second mode at 20 bars
    np.testing.assert_allclose(bending, tip_mass_cantilever_hz(2) * np.sqrt(2.0) * [1.0, 1.1], rtol=3e-3)
    assert result["parameters"] == {"file": str(parameters), "re_solved": ["E_beam"],
                                    "scaled": ["frequency_scale_mode_2"], "not_in_the_modes": ["damping_mode_1"]}
    code, out, err = run_cli(capsys, [*common[:-1], "--parameters", str(parameters)])
    assert code == 0 and (f"parameter set: {parameters} (1 moduli, springs and masses re-solved; 1 frequency scales "
                          "applied; 1 others (damping ratios, delays, gains) are the input-output model's: mace-fmu "
                          "model --poles)") in out, out


def test_a_set_fitted_to_the_other_structure_is_refused_by_modes_too(tmp_path, capsys):
    deck, structure, parameters = _beam(tmp_path)
    code, _, err = run_cli(capsys, ["modes", "1g", "--deck", str(deck), "--structure", str(structure),
                                    "--parameters", str(parameters)])
    assert code == 2 and "fitted to the 0g FMU beam_0g_native.fmu, not to the 1g model" in err, err


def test_model_poles_of_another_deck_are_its_own_without_the_thesis_s_tables(tmp_path, capsys):
    """The three-storey frame's updated poles: the frame's own list, not 30 rows of MACE's Table 4.7 that match
    nothing; the set's damping ratio on its mode."""
    from support.paths import EXAMPLES

    frame = EXAMPLES / "three_storey_frame"
    parameters = tmp_path / "frame.toml"
    parameters.write_text(SET.replace("E_beam = {modulus!r}\n", "E_storey_1 = 6.0e10\n").replace(
        '"0g"', '"1g"').replace("frequency_scale_mode_2 = 1.1\n", ""))
    code, out, err = run_cli(capsys, ["model", "1g", "--deck", str(frame / "frame.bdf"), "--structure",
                                      str(frame / "frame.toml"), "--parameters", str(parameters), "--poles"])
    assert code == 0, err
    assert "Table 4.7" not in out and f"parameter set: {parameters}" in out
    first = next(line for line in out.splitlines() if line.strip().endswith("1st bending about Y"))
    assert "zeta  0.010" in first, out
