"""Another structure's deck keeps NASTRAN's meaning: nothing of MACE's structure file reaches it.

The defect this guards against: a deck that was not MACE's lost MACE's suspension IDs (elements
22-24, 38-40, 80-82, 103-126, 138-140 and grids 32-34, 63-92) on the way to its 0-g modes, so a
beam whose tip mass was CONM2 22 silently lost it. The beam below uses exactly those IDs (bars
100-119 include 103-105; the tip mass is CONM2 22) and is checked against the closed-form
frequencies of a cantilever with a tip mass and against the same beam renumbered.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.cantilever import (
    INERTIA,
    RHO,
    TIP_MASS,
    E,
    L,
    N,
    beam_deck,
    tip_mass_cantilever_hz,
)
from support.decks import r
from support.paths import EXAMPLES

from mace_fmu.cli import main
from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes


@pytest.fixture()
def beam(tmp_path):
    path = tmp_path / "beam.bdf"
    path.write_text(beam_deck())
    return path


def test_a_beam_numbered_like_mace_suspension_keeps_its_tip_mass(beam, tmp_path):
    renumbered = tmp_path / "renumbered.bdf"
    renumbered.write_text(beam_deck(first_grid=1001, mass_id=9022))
    for kind in ("0g",):
        ours = compute_modes(read_deck(beam), configuration=kind)
        other = compute_modes(read_deck(renumbered), configuration=kind)
        assert ours.structure.file is None and len(ours.structure.deck.conm2s) == 1
        assert len(ours.structure.deck.bars) == N
        np.testing.assert_allclose(ours.frequencies_hz, other.frequencies_hz, rtol=1e-12)
    bending = [f for f, lab in zip(ours.frequencies_hz, ours.labels) if "bending" in lab]
    # NASTRAN's lumped bar mass converges from below as (n pi / N)^2: 0.3 % covers the 2nd mode at 20 bars
    np.testing.assert_allclose(bending[:2], tip_mass_cantilever_hz(2), rtol=3e-3)
    assert ours.labels[:2] == ("1st bending about Z", "2nd bending about Z")


def test_cli_modes_of_another_deck_say_there_is_no_structure_file(beam, capsys):
    assert main(["modes", "0g", "--deck", str(beam)]) == 0
    out = capsys.readouterr().out
    assert "structure file: none" in out and "1st bending about Z" in out and "X translation" not in out


def test_eigrl_count_decides_when_no_range_is_given(tmp_path):
    """EIGRL ND = 4 with V1, V2 blank: the four lowest modes, wherever they are (here all above 250 Hz,
    where the 250 Hz default gave none and exited 0)."""
    short = compute_modes(read_deck(_write(tmp_path / "short.bdf", beam_deck(length=L / 12))), configuration="0g")
    assert len(short.modes) == 4 and short.frequencies_hz[0] > 250.0
    # the same beam 12x longer (tip mass in proportion): bending frequencies 1/144 of these, exactly
    long = compute_modes(read_deck(_write(tmp_path / "long.bdf", beam_deck())), configuration="0g")

    def bending(result):
        return np.array([f for f, lab in zip(result.frequencies_hz, result.labels) if "bending" in lab])

    np.testing.assert_allclose(bending(short)[:2] / 144.0, bending(long)[:2], rtol=1e-9)


def _write(path, text):
    path.write_text(text)
    return path


def test_eigrl_range_without_modes_is_an_error_not_an_empty_table(tmp_path, capsys):
    path = tmp_path / "empty.bdf"
    path.write_text(beam_deck(eigrl="EIGRL,1,,0.5"))
    assert main(["modes", "0g", "--deck", str(path)]) == 2
    err = capsys.readouterr().err
    assert "no modes in the range asked for, EIGRL 1 (V1 = None, V2 = 0.5" in err and "lowest mode is at" in err


def test_a_volts_model_of_a_deck_without_instruments_is_refused_with_the_reason(beam, capsys):
    assert main(["model", "0g", "--deck", str(beam)]) == 2
    assert "needs actuators and sensors, and this deck has no structure file" in capsys.readouterr().err


def test_a_structure_file_that_names_ids_the_deck_lacks_is_refused(beam, tmp_path):
    spec = tmp_path / "beam.toml"
    spec.write_text('[components]\nbeam = ["1-21"]\ntip = [99]\n')
    with pytest.raises(MaceError, match=r"beam.toml: names IDs that .*beam.bdf lacks: \[components\] tip: grids 99"):
        compute_modes(read_deck(beam), configuration="0g", structure_file=spec)


def test_a_structure_file_with_an_unknown_table_names_file_and_line(beam, tmp_path):
    spec = tmp_path / "beam.toml"
    spec.write_text('# a comment\n[components]\nbeam = ["1-21"]\n\n[sensor]\nname = "tip"\n')
    with pytest.raises(MaceError, match=r"beam.toml:5: \[sensor\]: unknown table 'sensor'; a structure file has"):
        compute_modes(read_deck(beam), configuration="0g", structure_file=spec)


def test_the_bundled_structure_file_applies_to_a_copy_of_the_bundled_deck(tmp_path):
    from mace_fmu.structure.file import bundled_deck_path

    copy = tmp_path / "copy.bdf"
    copy.write_bytes(bundled_deck_path().read_bytes())
    assert compute_modes(read_deck(copy), configuration="0g").structure.file is not None
    edited = tmp_path / "edited.bdf"
    edited.write_text(bundled_deck_path().read_text() + "$ a comment\n")
    result = compute_modes(read_deck(edited), configuration="0g", max_hz=3.5)
    assert result.structure.file is None and 22 in result.structure.deck.conm2s  # nothing removed


def test_a_grid_attached_to_nothing_is_constrained_automatically_and_reported(tmp_path, capsys):
    """NASTRAN's AUTOSPC: grid 99 has neither stiffness nor mass; its 6 DOFs are constrained and listed, the
    beam's frequencies are those without it. With PARAM,AUTOSPC,NO the grid is named in the error."""
    text = beam_deck().replace("ENDDATA", "GRID,99,,5.0,5.0,5.0\nENDDATA")
    free = _write(tmp_path / "free.bdf", text)
    with_free = compute_modes(read_deck(free), configuration="0g")
    without = compute_modes(read_deck(_write(tmp_path / "beam.bdf", beam_deck())), configuration="0g")
    assert with_free.auto_constrained == tuple((99, c) for c in range(1, 7))
    np.testing.assert_allclose(with_free.frequencies_hz, without.frequencies_hz, rtol=1e-10)
    assert main(["modes", "0g", "--deck", str(free)]) == 0
    assert "AUTOSPC: constrained 6 DOFs with neither stiffness nor mass: grid 99 (1-6)" in capsys.readouterr().out
    strict = _write(tmp_path / "strict.bdf", text.replace("ENDDATA", "PARAM,AUTOSPC,NO\nENDDATA"))
    assert main(["modes", "0g", "--deck", str(strict)]) == 2
    err = capsys.readouterr().err
    assert "99-1" in err and "Warning" not in err, err


def test_a_grid_attached_to_nothing_is_named_by_the_preload(tmp_path, capsys):
    """MACE's deck (no AUTOSPC) with grid 999 attached to nothing: the 1-g preload's static solution names it
    and what to do (it said "check its SPC and MPC sets" without a grid)."""
    from mace_fmu.structure.file import bundled_deck_path, bundled_structure_path

    text = bundled_deck_path().read_text()
    first = text.index("\nGRID")
    deck = _write(tmp_path / "mace_plus.bdf", text[:first] + "\nGRID    999             0.1     0.2     0.3" + text[first:])
    assert main(["modes", "1g", "--deck", str(deck), "--structure", str(bundled_structure_path())]) == 2
    err = capsys.readouterr().err
    assert "the preload stiffness is singular: grid 999 component(s) 123456 have no stiffness at all" in err, err
    assert "constrain them with an SPC (or PARAM,AUTOSPC,YES)" in err


BEAM_STRUCTURE = """
[components]
beam = ["1-21"]

[[actuators]]
name = "tip_force_y"
description = "force along Y at the beam's tip"
dofs = [[21, 2, 1.0]]
gain = 2.0   # N per V

[[sensors]]
name = "tip_y"
description = "tip displacement along Y"
kind = "displacement"
dofs = [[21, 2, 1.0]]
gain = 100.0   # V per m

[[sensors]]
name = "tip_rate_z"
description = "tip rotation rate about Z"
kind = "rate"
dofs = [[21, 6, 1.0]]
gain = 10.0   # V per rad/s
"""


def test_your_own_deck_with_a_structure_file_gives_a_volts_model_and_an_fmu(tmp_path):
    """A structure file with only instruments (no electronics, loops or damping table): the model has
    the declared gains and 1 % damping, its static gain is the beam's tip compliance, and its native
    FMU (FMI 2 and 3) steps as the exact ZOH of its state space."""
    import control as ct
    import fmpy
    from support.fmu_checks import make_inputs, zoh_reference

    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model

    deck = _write(tmp_path / "beam.bdf", beam_deck())
    spec = _write(tmp_path / "beam.toml", BEAM_STRUCTURE)
    model = volts_model(compute_modes(read_deck(deck), configuration="0g", structure_file=spec, max_hz=200.0))
    assert list(model.system.input_labels) == ["tip_force_y"]
    assert list(model.system.output_labels) == ["tip_y", "tip_rate_z"]
    assert model.structure_modes.structure.file.path.name == "beam.toml"
    # static gain: V -> N (2) -> tip deflection of the retained modes -> V (100); within 2 % of the beam's
    # exact tip compliance L^3 / (3 E I) (the truncated modes carry the rest)
    dc = ct.dcgain(model.system)[0, 0] / (2.0 * 100.0)
    np.testing.assert_allclose(dc, L**3 / (3 * E * INERTIA), rtol=0.02)
    for version in (2, 3):
        fmu = export_fmu(model, out_dir=tmp_path, name=f"beam_fmi{version}", fmi_version=version)
        md = fmpy.read_model_description(str(fmu))
        outputs = {v.name: v.description for v in md.modelVariables if v.causality == "output"}
        assert set(outputs) == {"tip_y", "tip_rate_z"}
        assert md.description.startswith("beam 0g volts-volts model")  # not MACE's
        assert "100.0 V per m" in outputs["tip_y"] and "10.0 V per rad/s" in outputs["tip_rate_z"]
    t = np.arange(0, 1.0 + 1e-12, 2e-3)
    u = make_inputs("multisine", t, 1)
    ref = zoh_reference(model, t, u)
    inputs = np.zeros(len(t), dtype=[("time", float), ("tip_force_y", float)])
    inputs["time"], inputs["tip_force_y"] = t, u[0]
    run = fmpy.simulate_fmu(str(tmp_path / "beam_fmi2.fmu"), input=inputs, output=["tip_y", "tip_rate_z"],
                            step_size=2e-3, output_interval=2e-3, stop_time=t[-1])
    y = np.stack([run["tip_y"], run["tip_rate_z"]])[:, :len(t)]
    span = np.ptp(ref, axis=1, keepdims=True)
    assert np.all(span > 0) and np.max(np.abs(y - ref[:, :y.shape[1]]) / span) <= 1e-10


def test_export_of_another_deck_names_the_fmu_after_it(tmp_path, capsys):
    deck = _write(tmp_path / "beam.bdf", beam_deck())
    spec = _write(tmp_path / "beam.toml", BEAM_STRUCTURE)
    assert main(["export", "0g", "--deck", str(deck), "--structure", str(spec), "--max-hz", "200",
                 "-o", str(tmp_path / "fmus")]) == 0
    assert [p.name for p in (tmp_path / "fmus").iterdir()] == ["beam_0g_native.fmu"]
    assert "wrote" in capsys.readouterr().out


def test_example_own_structure_spacecraft(tmp_path):
    """examples/own_structure: a spacecraft the project wrote, on its test stand (1-g, gravity preload) and in
    orbit (0-g, free): modes labelled by motion, its FMUs (FMI 2 and 3) equal to the exact ZOH, an animation."""
    import importlib.util

    path = EXAMPLES / "own_structure" / "own_structure.py"
    spec = importlib.util.spec_from_file_location("own_structure_example", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    summary = example.main(tmp_path)
    assert all(e <= 1e-10 for e in summary["zoh_error"].values()) and set(summary["zoh_error"]) == {2, 3}
    labels_0g = [label for _, label in summary["modes_0g"]]
    assert sum(label.startswith("rigid body") for label in labels_0g) == 6  # free in orbit
    assert not any(label.startswith("rigid body") for _, label in summary["modes_1g"])  # held by the stand
    assert "1st bending about Y" in labels_0g and not any("violin" in x or "gimbal" in x for x in labels_0g)
    assert (tmp_path / "spacecraft_0g_modes.html").stat().st_size > 10_000


def test_include_files_nested_and_relative_read_as_one_deck(tmp_path):
    """INCLUDE 'path' (relative to the including file, nested): the same modes as the deck in one file;
    an error inside an included file names that file and its line."""
    whole = beam_deck()
    head, bulk = whole.split("BEGIN BULK\n")
    body = bulk.replace("ENDDATA\n", "").splitlines()
    grids = [c for c in body if c.startswith("GRID")]
    rest = [c for c in body if not c.startswith("GRID")]
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "grids.blk").write_text("\n".join(grids[:5]) + "\nINCLUDE 'more_grids.blk'\n")
    (tmp_path / "parts" / "more_grids.blk").write_text("\n".join(grids[5:]) + "\n")
    main_deck = _write(tmp_path / "main.bdf", head + "BEGIN BULK\n" + "\n".join(rest)
                       + "\nINCLUDE 'parts/grids.blk'\nUSET,U2,1,123\nENDDATA\n")
    one = compute_modes(read_deck(_write(tmp_path / "one.bdf", whole)), configuration="0g")
    split = compute_modes(read_deck(main_deck), configuration="0g")
    np.testing.assert_allclose(split.frequencies_hz, one.frequencies_hz, rtol=1e-14)
    assert split.structure.deck.skipped == (("USET", 1, f"{main_deck}:{len((head + 'BEGIN BULK').splitlines()) + len(rest) + 2}"),)
    (tmp_path / "parts" / "more_grids.blk").write_text("\n".join(grids[5:]) + "\nGRID,abc\n")
    with pytest.raises(Exception, match=r"more_grids.blk:\d+: GRID"):
        read_deck(main_deck)


@pytest.mark.parametrize("include, message", [
    ("INCLUDE 'nowhere.blk'", r"main.bdf:\d+: INCLUDE: INCLUDE 'nowhere.blk': no such file"),
    ("INCLUDE 'self.blk'", r"INCLUDE 'self.blk' is circular"),
    ("INCLUDE nowhere.blk", r"expected INCLUDE 'path'"),
])
def test_bad_includes_name_file_and_line(tmp_path, include, message):
    (tmp_path / "self.blk").write_text("INCLUDE 'self.blk'\n")
    deck = _write(tmp_path / "main.bdf", beam_deck().replace("ENDDATA", include + "\nENDDATA"))
    with pytest.raises(Exception, match=message):
        read_deck(deck)


def test_every_card_we_cannot_model_is_listed_at_once(tmp_path, capsys):
    text = beam_deck().replace("ENDDATA", "CQUAD4,1,1,1,2,3,4\nCQUAD4,2,1,2,3,4,5\nCBUSH,900,1,1,2,0.,0.,1.\n"
                                          "FORCE,5,21,,1.0,0.,1.,0.\nENDDATA")
    deck = _write(tmp_path / "many.bdf", text)
    assert main(["modes", "0g", "--deck", str(deck)]) == 2
    err = capsys.readouterr().err
    assert "cards this reader cannot model: CQUAD4 (2x, first at" in err and "CBUSH (1x, first at" in err
    assert "FORCE" not in err.split("(supported")[0]  # a load changes neither mass nor stiffness: read past


def test_spc_cards_fix_dofs_like_spc1(tmp_path):
    """SPC (grid, components, 0.0 pairs) fixes the same DOFs as SPC1; an enforced displacement is refused."""
    one = compute_modes(read_deck(_write(tmp_path / "spc1.bdf", beam_deck())), configuration="0g")
    spc = beam_deck().replace("SPC1,7,123456,1", "SPC,7,1,123,0.0,1,456")
    two = compute_modes(read_deck(_write(tmp_path / "spc.bdf", spc)), configuration="0g")
    np.testing.assert_allclose(two.frequencies_hz, one.frequencies_hz, rtol=1e-14)
    with pytest.raises(Exception, match="enforced displacement is not supported"):
        read_deck(_write(tmp_path / "bad.bdf", beam_deck().replace("SPC1,7,123456,1", "SPC,7,1,123456,0.01")))


def test_param_wtmass_scales_every_mass(tmp_path):
    """A deck in weight units: densities and the tip mass 386.1 times larger, PARAM,WTMASS,1/386.1 (NASTRAN's
    convention for lbf-in decks): the same modes as the deck in mass units."""
    w = 1.0 / 386.1
    text = beam_deck().replace(f"{r(RHO)}", f"{r(RHO / w)}").replace(f"{r(TIP_MASS)}", f"{r(TIP_MASS / w)}")
    text = text.replace("ENDDATA", f"PARAM,WTMASS,{r(w)}\nENDDATA")
    weighted = compute_modes(read_deck(_write(tmp_path / "weight.bdf", text)), configuration="0g")
    plain = compute_modes(read_deck(_write(tmp_path / "mass.bdf", beam_deck())), configuration="0g")
    # the decks print 11 significant digits: 1e-9 is their rounding, not the method's
    assert weighted.mass_properties.mass_kg == pytest.approx(plain.mass_properties.mass_kg, rel=1e-9)
    np.testing.assert_allclose(weighted.frequencies_hz, plain.frequencies_hz, rtol=1e-9)


def test_a_butterworth_filter_from_the_structure_file_filters_exactly_its_sensors(tmp_path):
    """[electronics] filter_kind = "butterworth": the gyro channels of the spacecraft equal the unfiltered
    model's times scipy's own Butterworth response (1e-9), the encoder channel is untouched, and the
    filter's four poles are in the model, labelled, at the cutoff."""
    import scipy.signal

    from mace_fmu.iomodel.poles import closed_loop_poles
    from mace_fmu.iomodel.volts import volts_model

    here = EXAMPLES / "own_structure"
    deck, plain = here / "spacecraft.bdf", here / "spacecraft.toml"
    filtered = tmp_path / "spacecraft_filtered.toml"
    filtered.write_text(plain.read_text() + '\n[electronics]\nfilter_kind = "butterworth"\nfilter_order = 4\n'
                        'filter_cutoff_hz = 30.0\nanalog_sensors = ["gyro_*"]\n')
    f = np.geomspace(0.5, 80.0, 60)
    g0 = volts_model(compute_modes(str(deck), configuration="0g", structure_file=plain)).frequency_response(f)
    model = volts_model(compute_modes(str(deck), configuration="0g", structure_file=filtered))
    g1 = model.frequency_response(f)
    b, a = scipy.signal.butter(4, 2 * np.pi * 30.0, analog=True)
    h = scipy.signal.freqs(b, a, worN=2 * np.pi * f)[1]
    outputs = list(model.system.output_labels)
    for o, name in enumerate(outputs):
        expected = g0[:, o, :] * (h[:, None] if name.startswith("gyro_") else 1.0)
        np.testing.assert_allclose(g1[:, o, :], expected, rtol=1e-9, atol=1e-12 * np.abs(g0).max())
    filter_poles = [p for p in closed_loop_poles(model) if p.label == "Butterworth filter"]
    assert len(filter_poles) == 2 * 2  # two gyros, two complex pairs each (Im >= 0)
    assert all(abs(abs(p.eigenvalue) / (2 * np.pi * 30.0) - 1.0) < 1e-9 for p in filter_poles)


#: every command that takes --structure, with the arguments it needs besides it
STRUCTURE_COMMANDS = {
    "modes": ["modes", "0g"], "model": ["model", "0g"], "export": ["export", "0g", "--out", "{tmp}"],
    "report": ["report", "--out", "{tmp}"], "build": ["build", "--out", "{tmp}"],
    "update mace": ["update", "mace", "-o", "{tmp}"],
    "predict-0g": ["predict-0g"],
    "view modes": ["view", "modes", "0g", "--html", "{tmp}/v.html"],
    "view pairs": ["view", "pairs", "--html", "{tmp}/v.html"],
    "view response": ["view", "response", "0g", "--input", "gimbal_secondary_z", "--html", "{tmp}/v.html"],
    "correlate": ["correlate", "--deck", "{deck}", "--modes", "{tmp}/modes.toml", "-o", "{tmp}"],
    "update modal": ["update", "modal", "--deck", "{deck}", "--modes", "{tmp}/modes.toml", "--update",
                     "E_lexan_end", "-o", "{tmp}/out"],
}
#: commands that take --structure without a deck (a measured data file's channel names), so nothing to mismatch
NO_DECK = {"ema"}
#: a measured mode of one DOF: enough for the commands that read measured modes to reach the structure file
MODES_FILE = """[identification]
method = "by hand"

[[dofs]]
name = "gyro_payload_x"

[[modes]]
label = "mode 1"
frequency_hz = 2.0
damping = 0.01
shape_real = [1.0]
"""


def _commands_with_option(parser, option: str, prefix: str = "") -> list[str]:
    import argparse

    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += _commands_with_option(sub, option, f"{prefix} {name}".strip())
        elif option in action.option_strings:
            found.append(prefix)
    return found


@pytest.mark.parametrize("command", sorted(STRUCTURE_COMMANDS))
def test_no_command_ignores_the_structure_file_it_is_given(command, tmp_path, capsys):
    """The bundled deck with another structure's file (its suspension IDs are not MACE's): every command
    that takes --structure reads it and stops on the mismatch, or says why it does not take one."""
    from mace_fmu.cli import build_parser

    from mace_fmu.structure.file import bundled_deck_path

    assert sorted(_commands_with_option(build_parser(), "--structure")) == sorted(set(STRUCTURE_COMMANDS) | NO_DECK)
    spacecraft = EXAMPLES / "own_structure" / "spacecraft.toml"
    (tmp_path / "modes.toml").write_text(MODES_FILE)
    argv = [a.replace("{tmp}", str(tmp_path)).replace("{deck}", str(bundled_deck_path()))
            for a in STRUCTURE_COMMANDS[command]]
    assert main([*argv, "--structure", str(spacecraft)]) == 2
    err = capsys.readouterr().err
    assert "spacecraft.toml" in err, err
    assert ("names IDs that" in err and "mace_em.bdf lacks: [suspension] elements 201-206" in err
            or command in ("update", "update mace", "view response")), err


def test_predict_0g_takes_your_own_structure_with_its_measurement_model(tmp_path, capsys):
    """The spacecraft example through predict-0g: each 0-g mode moves by its 1-g mode's measured/model ratio
    (the nominal 0-g frequency = 0-g pole x measured 1-g / model 1-g), and its FMU is named after the deck."""
    import fmpy

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.poles import closed_loop_poles
    from mace_fmu.iomodel.volts import volts_model

    here = EXAMPLES / "own_structure"
    deck, spec = here / "spacecraft.bdf", here / "spacecraft.toml"
    measured = _write(tmp_path / "measured.csv", "label,pattern,frequency_hz,damping,pattern_0g\n"
                      "suspension bounce,1st spring mode,1.10,0.02,\n"
                      "boom bending Y,1st bending about Y,3.50,0.006,1st bending about Y\n"
                      "boom bending Z,1st bending about Z,29.0,0.004,1st bending about Z\n")
    assert main(["predict-0g", "--deck", str(deck), "--structure", str(spec), "--measured", str(measured),
                 "-o", str(tmp_path / "out"), "--fmu", "--json"]) == 0
    import json

    result = json.loads(capsys.readouterr().out)
    rows = {row["label"]: row for row in result["rows"]}
    assert set(rows) == {"boom bending Y", "boom bending Z"}
    models = {kind: volts_model(compute_modes(read_deck(deck), configuration=kind, structure_file=spec))
              for kind in ("1g", "0g")}
    poles = {kind: {p.label: p.frequency_hz for p in closed_loop_poles(model)} for kind, model in models.items()}
    for label, pattern, hz in (("boom bending Y", "1st bending about Y", 3.50),
                               ("boom bending Z", "1st bending about Z", 29.0)):
        expected = poles["0g"][pattern] * hz / poles["1g"][pattern]
        np.testing.assert_allclose(rows[label]["nominal_hz"], expected, rtol=1e-6)
    fmu = Path(result["files"]["fmu"])
    assert fmu.name == "spacecraft_0g_native_nominal.fmu"
    md = fmpy.read_model_description(str(fmu))
    scales = {v.name: (float(v.min), float(v.max)) for v in md.modelVariables
              if v.name.startswith("frequency_scale_mode_") and v.name[len("frequency_scale_mode_"):].isdigit()
              and int(v.name[len("frequency_scale_mode_"):]) in {r["mode"] for r in rows.values()}}
    assert sorted(scales.values()) == [(0.99, 1.01)] * 2  # the 1 % bounds of lightly damped modes


def test_the_0g_structure_drops_suspension_elements_of_every_kind(tmp_path):
    """A suspension made of a CROD and a CMASS2 to a grid of its own (not CBAR/CONM2/CELAS2, MACE's kinds):
    its 0-g structure is the beam without them (the same modes to 1e-12), and a structure file that leaves
    one of them out is refused, naming the card and its line."""
    plain = compute_modes(read_deck(_write(tmp_path / "plain.bdf", beam_deck())), configuration="0g")
    extra = ("GRID,99,,2.0,1.0,0.0,,123456\nCROD,201,7,99,21\nPROD,7,1,1.0e-6\nCMASS2,202,0.5,99,1\n")
    hung = _write(tmp_path / "hung.bdf", beam_deck().replace("ENDDATA", extra + "ENDDATA"))
    spec = _write(tmp_path / "hung.toml", '[suspension]\ngrids = [99]\nelements = [201, 202]\n')
    free = compute_modes(read_deck(hung), configuration="0g", structure_file=spec)
    np.testing.assert_allclose(free.frequencies_hz, plain.frequencies_hz, rtol=1e-12)
    missing = _write(tmp_path / "missing.toml", '[suspension]\ngrids = [99]\nelements = [202]\n')
    with pytest.raises(MaceError, match=r"CROD 201.*connects suspension grid\(s\) \[99\] but is not listed"):
        compute_modes(read_deck(hung), configuration="0g", structure_file=missing)
