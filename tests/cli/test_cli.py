"""The ``mace-fmu`` command line, called in-process through mace_fmu.cli.main."""

from __future__ import annotations

import json
import re

import pytest

from mace_fmu.cli import main


def _run(capsys, argv: list[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_modes_0g_json(capsys):
    code, out, err = _run(capsys, ["modes", "0g", "--json"])
    assert code == 0
    data = json.loads(out)
    assert {"configuration", "modes", "mass_properties"} <= set(data)
    assert data["configuration"] == "0g" and data["preload"] is None
    modes = data["modes"]
    assert len(modes) == 35  # thesis: 35 modes cover 0-250 Hz in 0-g
    assert [m["index"] for m in modes] == list(range(1, 36))
    freqs = [m["frequency_hz"] for m in modes]
    assert freqs == sorted(freqs) and max(freqs) <= 250.0
    assert all(isinstance(m["label"], str) and m["label"] for m in modes)
    props = data["mass_properties"]
    assert props["mass_kg"] == pytest.approx(36.64, rel=5e-3)
    inertia = props["inertia_about_center_node_kgm2"]
    assert len(inertia) == 3 and all(len(row) == 3 for row in inertia)
    for got, want in zip((inertia[i][i] for i in range(3)), (0.664, 9.104, 9.557)):
        assert got == pytest.approx(want, rel=5e-3)
    assert inertia[0][1] == pytest.approx(inertia[1][0], abs=1e-12)  # symmetric
    com = props["center_of_mass_m"]
    assert len(com) == 3 and all(isinstance(x, float) for x in com)
    assert props["reference_grid"] == 16
    assert err == ""  # --json: no progress chatter


def test_modes_1g_linear_json(capsys):
    code, out, _ = _run(capsys, ["modes", "1g", "--json", "--preload", "linear", "--max-hz", "5"])
    assert code == 0
    data = json.loads(out)
    assert data["configuration"] == "1g" and data["preload"] == "linear"
    modes = data["modes"]
    assert all(m["frequency_hz"] <= 5.0 for m in modes)
    zero = [m for m in modes if abs(m["frequency_hz"]) < 0.01]
    assert len(zero) == 3
    assert all(m["label"].startswith("mechanism: reaction wheel ") for m in zero)
    assert sorted(m["label"] for m in zero) == [f"mechanism: reaction wheel {i}" for i in (1, 2, 3)]
    bending = next(m for m in modes if "bending" in m["label"])
    assert bending["label"] == "1st Z bending"
    assert bending["frequency_hz"] == pytest.approx(2.06, rel=1.5e-2)


def _write_broken_deck(tmp_path):
    path = tmp_path / "broken.bdf"
    path.write_text("BEGIN BULK\n"
                    "MAT1,1,2.0e11,,0.3,7800.0\n"
                    "PBAR,1,1,1.0e-4,1.0e-8,1.0e-8,2.0e-8\n"
                    "GRID,1,,0.0,0.0,0.0\n"
                    "CBAR,10,1,1,99,0.0,0.0,1.0\n"  # line 5: grid 99 does not exist
                    "ENDDATA\n")
    return path


def test_broken_deck_gives_one_line_error(capsys, tmp_path):
    path = _write_broken_deck(tmp_path)
    code, out, err = _run(capsys, ["modes", "0g", "--deck", str(path)])
    assert code == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith("mace-fmu: error:")
    assert str(path) in line and f"{path}:5:" in line
    assert "CBAR" in line and "99" in line
    assert "Traceback" not in err


def test_nonexistent_deck_gives_one_line_error(capsys, tmp_path):
    path = tmp_path / "missing.bdf"
    code, out, err = _run(capsys, ["modes", "1g", "--deck", str(path)])
    assert code == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0] == f"mace-fmu: error: {path}: no such file"


def test_modes_0g_text_output(capsys):
    code, out, _ = _run(capsys, ["modes", "0g", "--max-hz", "15"])
    assert code == 0
    rows = [m for m in re.finditer(r"^\s*(\d+)\s+(-?\d+\.\d+)\s+(.+?)\s*$", out, re.M)]
    assert len(rows) == 21  # 13 zero modes + 8 flexible modes below 15 Hz
    assert [m.group(2) for m in rows[:13]] == ["0.0000"] * 13  # round-off such as -4e-4 Hz is not shown
    assert [int(m.group(1)) for m in rows] == list(range(1, 22))
    assert all(float(m.group(2)) <= 15.0 for m in rows)
    bending = [m for m in rows if m.group(3) == "1st Z bending"]
    assert len(bending) == 1
    assert float(bending[0].group(2)) == pytest.approx(2.10, rel=5e-3)
    mass = re.search(r"^mass (\d+\.\d+) kg, centre of mass .* Jxx (\d+\.\d+), Jyy (\d+\.\d+), Jzz (\d+\.\d+)", out, re.M)
    assert mass is not None, out
    assert float(mass.group(1)) == pytest.approx(36.64, rel=5e-3)
    assert float(mass.group(2)) == pytest.approx(0.664, rel=5e-3)


@pytest.mark.parametrize("argv", [["modes", "2g"], ["modes"], ["modes", "0g", "--preload", "huge"],
                                  ["modes", "0g", "--max-hz", "abc"], ["frobnicate"]])
def test_argparse_errors_exit_with_status_2(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "usage: mace-fmu" in err


@pytest.mark.slow
def test_export_with_motion_grids_names_their_outputs(capsys, tmp_path):
    import fmpy

    code, out, _ = _run(capsys, ["export", "0g", "-o", str(tmp_path), "--motion-grids", "1,7"])
    assert code == 0 and out.strip() == f"wrote {tmp_path / 'MACE_0g_native_motion_1_7.fmu'}"
    assert not (tmp_path / "MACE_0g_native.fmu").exists()  # the plain FMU's name stays the plain FMU's
    md = fmpy.read_model_description(str(tmp_path / "MACE_0g_native_motion_1_7.fmu"))
    outs = [v for v in md.modelVariables if v.causality == "output"]
    assert len(outs) == 20 + 12
    assert [(v.name, v.unit) for v in outs[20:23]] == [("grid_1_tx", "m"), ("grid_1_ty", "m"), ("grid_1_tz", "m")]
    assert outs[-1].name == "grid_7_rz" and outs[-1].unit == "rad" and "rotation about basic Z" in outs[-1].description


@pytest.mark.parametrize("value, message", [("1,x", "takes 'all' or comma-separated grid IDs, got '1,x'"),
                                            ("1,99999", "are not in the 0g model")])
def test_bad_motion_grids_give_one_line_errors(capsys, tmp_path, value, message):
    code, _, err = _run(capsys, ["export", "0g", "-o", str(tmp_path), "--motion-grids", value])
    last = err.strip().splitlines()[-1]  # after the progress lines: one error line
    assert code == 2 and last.startswith("mace-fmu: error: ") and message in last


@pytest.mark.slow
@pytest.mark.parametrize("options, stem, fmi_version", [([], "MACE_0g_native", "2.0"),
                                                        (["--fmi-version", "3"], "MACE_0g_native_fmi3", "3.0"),
                                                        (["--runtime", "pythonfmu"], "MACE_0g_pythonfmu", "2.0")])
def test_export_writes_the_kind_it_is_asked_for_under_a_name_that_says_so(capsys, tmp_path, options, stem,
                                                                          fmi_version):
    import fmpy

    code, out, _ = _run(capsys, ["export", "0g", "-o", str(tmp_path), "--max-hz", "20", *options])
    path = out.strip().splitlines()[-1].removeprefix("wrote ")
    assert code == 0 and path.endswith(f"{stem}.fmu")
    md = fmpy.read_model_description(path)
    assert md.fmiVersion == fmi_version and md.coSimulation.modelIdentifier == stem
    assert (md.modelExchange is not None) == (stem == "MACE_0g_native")  # native FMI 2.0: also model exchange


def test_an_fmu_of_a_parameter_set_is_named_after_it_and_says_where_it_comes_from(capsys, tmp_path):
    """``export --parameters fitted.toml`` writes MACE_0g_native_fitted_<digest>.fmu (never the plain model's name,
    nor another set's) and its description names the set, what it was fitted to and when; ``build`` names its
    FMUs the same way."""
    import fmpy

    from mace_fmu.cli import build_parser

    (tmp_path / "fitted.toml").write_text(
        '[provenance]\ncreated = "2026-11-27T21:00:00Z"\ntool = "mace-fmu 0.1.0"\nfitted_to = "MACE_0g_native.fmu"\n'
        'data = "gimbal.csv"\ncost = "time"\n\n[values]\nE_lexan_center = 2.4e9\n')
    code, out, _ = _run(capsys, ["export", "0g", "-o", str(tmp_path), "--max-hz", "20", "--parameters",
                                 str(tmp_path / "fitted.toml")])
    from mace_fmu.parameters.sets import ParameterSet

    digest = ParameterSet.read(tmp_path / "fitted.toml").digest()[:6]
    path = out.strip().splitlines()[-1].removeprefix("wrote ")
    assert code == 0 and path.endswith(f"MACE_0g_native_fitted_{digest}.fmu"), path
    description = fmpy.read_model_description(path).description
    assert description.endswith("; parameter set fitted.toml, fitted to MACE_0g_native.fmu, data gimbal.csv, time "
                                "cost, created 2026-11-27T21:00:00Z by mace-fmu 0.1.0"), description
    from mace_fmu.cli.common import model_variant

    args = build_parser().parse_args(["build", "--parameters", str(tmp_path / "fitted.toml")])
    assert model_variant(args) == f"fitted_{digest}"


def test_export_refuses_fmi3_for_pythonfmu(capsys, tmp_path):
    code, _, err = _run(capsys, ["export", "0g", "-o", str(tmp_path), "--runtime", "pythonfmu", "--fmi-version", "3"])
    assert code == 2 and "--fmi-version 3 needs --runtime native" in err.strip().splitlines()[-1]
    assert not list(tmp_path.iterdir())


def test_fmu_names_say_which_outputs_an_fmu_has():
    from mace_fmu.fmu.naming import fmu_model_name

    grids = list(range(1, 80))
    assert fmu_model_name("1g") == "MACE_1g"
    assert fmu_model_name("0g", motion_grids=grids, all_grids=grids) == "MACE_0g_motion"
    assert fmu_model_name("0g", motion_grids=[7, 1, 7], all_grids=grids) == "MACE_0g_motion_1_7"
    assert fmu_model_name("0g", motion_grids=grids[:10], all_grids=grids) == "MACE_0g_motion_10_grids"
    assert fmu_model_name("1g", runtime="native", fmi_version=3) == "MACE_1g_native_fmi3"
    assert fmu_model_name("0g", runtime="pythonfmu", motion_grids=[1], all_grids=grids) == "MACE_0g_pythonfmu_motion_1"


def test_hz_text_shows_the_zero_frequency_cluster_as_zero():
    from mace_fmu.util.frequency import hz_text

    assert [hz_text(f, decimals=3) for f in (-4e-4, -1e-7, 0.0, 0.0099)] == ["0.000"] * 4
    assert hz_text(-0.02, decimals=3) == "-0.020" and hz_text(2.0996, decimals=3) == "2.100"


def test_view_response_checks_its_signals_before_any_work(capsys, tmp_path):
    """Misspelled --input, bad --output, bad duration: status 2 at once, nothing exported or written."""
    from mace_fmu.iomodel.instruments import load_instruments

    page = str(tmp_path / "r.html")
    for argv, message in (
            (["--input", "rwa_zz"], "--input 'rwa_zz' is not an actuator of "),  # the structure file's actuators
            (["--input", "rwa_zz"], "use one of gimbal_primary_x, "),
            (["--input", "rwa_z", "--output", "gyro_payload_q"], "--output 'gyro_payload_q' is not an output of the "
                                                                 "0g model: use a sensor (encoder_primary_x, "),
            (["--input", "rwa_z", "--output", "grid_64_tx"], "grid_<id>_<tx|ty|tz|rx|ry|rz> for one of its 79 grids"),
            (["--input", "rwa_z", "--duration", "0.1", "--step", "0.003"], "not a whole number of 0.003 s steps")):
        code, out, err = _run(capsys, ["view", "response", "0g", *argv, "--html", page])
        assert code == 2 and message in err, err
        assert out == "" and list(tmp_path.iterdir()) == []  # no FMU, page or plot
    with pytest.raises(SystemExit) as exc:
        main(["view", "response", "--help"])
    assert exc.value.code == 0
    help_text = " ".join(capsys.readouterr().out.split())
    instruments = load_instruments()
    assert all(a.name in help_text for a in instruments.actuators)
    assert all(s.name in help_text for s in instruments.sensors)


def test_each_input_is_collocated_with_its_own_sensor():
    """Servo partners for gimbals and wheels; the active strut's patches with strut 2's strain gauges."""
    from mace_fmu.deck.geometry import grid_positions
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.iomodel.collocation import collocated_sensor
    from mace_fmu.iomodel.instruments import load_instruments
    from mace_fmu.structure.file import bundled_deck_path

    instruments = load_instruments()
    positions = grid_positions(read_deck(bundled_deck_path()))
    found = {a.name: collocated_sensor(instruments, a.name, positions) for a in instruments.actuators}
    assert found == {**instruments.servos.gimbals, **instruments.servos.wheels,
                     "active_strut_y": "strain_strut2_y", "active_strut_z": "strain_strut2_z"}
    for axis in "yz":  # the data file's own words: strut 2 is the active strut
        assert "active strut" in instruments.sensor(found[f"active_strut_{axis}"]).description


def test_the_parser_loads_no_numerics(tmp_path):
    """``mace-fmu --help`` and a refused argument answer before numpy's companions load: building the parser
    imports neither scipy, python-control, fmpy nor the deck reader (they took 2-3 s at every start)."""
    import subprocess
    import sys

    code = ("import sys\nfrom mace_fmu.cli import build_parser\nbuild_parser()\n"
            "print(sorted(m for m in ('scipy', 'control', 'fmpy', 'pythonfmu', 'mace_fmu.deck.reader', "
            "'mace_fmu.fe.modes', 'modelica_like') if m in sys.modules))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "[]"
    from mace_fmu.cli.common import BUNDLED_DECK
    from mace_fmu.structure.file import bundled_deck_path

    assert BUNDLED_DECK == str(bundled_deck_path())


def test_an_output_folder_that_is_a_file_is_refused_before_any_work(capsys, tmp_path):
    taken = tmp_path / "taken"
    taken.write_text("a file\n")
    for argv, why in ((["export", "0g", "-o", str(taken)], "is a file, not a folder (outputs go into a folder)"),
                      (["export", "0g", "-o", str(taken / "x")], f"cannot create the folder ({taken} is a file)"),
                      (["build", "-o", str(taken)], "is a file, not a folder (outputs go into a folder)")):
        code, out, err = _run(capsys, argv)
        assert code == 2 and out == "" and err == f"mace-fmu: error: -o {argv[-1]}: {why}\n", err


def test_a_pade_order_beyond_the_runtimes_is_one_line(capsys):
    code, _, err = _run(capsys, ["model", "0g", "--pade-order", "99"])
    assert code == 2 and err.strip() == "mace-fmu: error: pade_order must be an integer from 1 to 10, got 99"


@pytest.mark.parametrize("command", [["modes", "1g"], ["model", "0g"], ["modes", "0g"]])
def test_an_instrument_on_a_missing_grid_names_the_file_and_the_instrument(capsys, tmp_path, command):
    from mace_fmu.structure.file import bundled_structure_path

    text = bundled_structure_path().read_text()
    assert "dofs = [[37, 4, -1.0], [38, 4, 1.0]]" in text
    spec = tmp_path / "mace.toml"
    spec.write_text(text.replace("dofs = [[37, 4, -1.0], [38, 4, 1.0]]", "dofs = [[9937, 4, -1.0], [38, 4, 1.0]]"))
    code, _, err = _run(capsys, [*command, "--structure", str(spec)])
    assert code == 2
    assert f"{spec}: actuator 'gimbal_primary_x' names grid 9937, which" in err and "does not have" in err, err


@pytest.mark.parametrize("argv, message", [
    (["view", "modes", "0g", "--scale", "-1"], "argument --scale: expected a finite number > 0, got '-1'"),
    (["view", "modes", "0g", "--png", "still.jpg"], "argument --png: the still is a PNG image"),
])
def test_view_options_that_cannot_work_are_refused_at_once(capsys, argv, message):
    with pytest.raises(SystemExit) as stopped:
        main(argv)
    assert stopped.value.code == 2 and message in capsys.readouterr().err


def test_report_takes_o_like_every_other_command():
    from mace_fmu.cli import build_parser

    assert build_parser().parse_args(["report", "-o", "somewhere"]).out == "somewhere"


def test_a_parameter_set_with_a_name_the_deck_lacks_names_its_file(capsys, tmp_path):
    (tmp_path / "bad.toml").write_text("[values]\nE_foo = 2e9\n")
    code, _, err = _run(capsys, ["model", "0g", "--parameters", str(tmp_path / "bad.toml")])
    assert code == 2 and err.startswith(f"mace-fmu: error: {tmp_path / 'bad.toml'}: parameter 'E_foo': no such material")


def test_mass_properties_of_a_deck_without_grdpnt_are_about_the_basic_origin(capsys, tmp_path):
    """No PARAM,GRDPNT: the inertia is about the basic origin, and the line says so (it said "grid None")."""
    from support.decks import deck_text, line_of_bars

    deck = tmp_path / "beam.bdf"
    deck.write_text(deck_text(line_of_bars(n=4, length=1.0, e=7e10, nu=0.3, rho=2700.0, area=1e-4, i=1e-8)
                              + ["SPC1,1,123456,1", "EIGRL,1,,,3"], case="SPC = 1\nMETHOD = 1\n"))
    code, out, _ = _run(capsys, ["modes", "0g", "--deck", str(deck)])
    assert code == 0 and "inertia about the basic origin: Jxx" in out and "grid None" not in out
    # a deck states no units: its own words, not kg, unless its structure file says which
    assert "mass 0.2700 (the deck's mass unit), centre of mass [0.5, 0.0, 0.0] (the deck's length unit)" in out
    spec = tmp_path / "beam.toml"
    spec.write_text('[units]\nmass = "lbf s^2/in"\nlength = "in"\n')
    code, out, _ = _run(capsys, ["modes", "0g", "--deck", str(deck), "--structure", str(spec)])
    assert code == 0 and "mass 0.2700 lbf s^2/in, centre of mass [0.5, 0.0, 0.0] in," in out and "lbf s^2/in in^2" in out
    code, out, _ = _run(capsys, ["modes", "0g"])
    assert "kg, centre of mass" in out and "kg m^2" in out  # the bundled MACE deck is SI


def test_a_refusal_of_many_cards_is_short_and_verbose_gives_the_whole_list(capsys, tmp_path):
    deck = tmp_path / "foreign.bdf"
    names = ("CQUAD4", "CTRIA3", "CHEXA", "CPENTA", "CTETRA", "CSHEAR", "CBUSH", "CGAP")
    deck.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\n" + "".join(f"{n},1,1,1,2\n" for n in names)
                    + "ENDDATA\n")
    code, _, err = _run(capsys, ["modes", "0g", "--deck", str(deck)])
    assert code == 2 and "and 2 more" in err and "(8 lines more with mace-fmu --verbose ...)" in err
    assert len(err) < 800 + len(str(deck)) and "CGAP" not in err
    code, _, err = _run(capsys, ["--verbose", "modes", "0g", "--deck", str(deck)])
    assert code == 2 and all(f"  {n}: 1 card(s), first at " in err for n in names)


def test_build_of_another_deck_lists_its_modes_and_names_its_fmus_as_export_does(capsys, tmp_path, monkeypatch):
    """``build`` of another deck lists that deck's modes in place of the thesis's tables (which pair MACE's own
    modes: on the frame they stopped the job with StopIteration) and names its FMUs by the deck (frame_1g_native,
    ...), with the one naming function ``export`` uses (the FMUs themselves are not written here)."""
    from support.paths import EXAMPLES

    import mace_fmu.fmu.export
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes

    names = []
    monkeypatch.setattr(mace_fmu.fmu.export, "export_fmu",
                        lambda model, *, name, out_dir, fmi_version=2, **_: names.append(name) or tmp_path / name)
    frame = EXAMPLES / "three_storey_frame"
    code, out, err = _run(capsys, ["build", "--deck", str(frame / "frame.bdf"), "--structure",
                                   str(frame / "frame.toml"), "-o", str(tmp_path)])
    assert code == 0, err
    assert names == [f"frame_{c}_{r}" for c in ("1g", "0g") for r in ("native", "native_fmi3", "pythonfmu")]
    assert "Table 5.1" not in out and "0-g modes up to 250 Hz" in out
    first = compute_modes(read_deck(frame / "frame.bdf"), configuration="0g",
                          structure_file=frame / "frame.toml").modes.frequencies_hz
    table = out.split("0-g modes up to 250 Hz")[1].split("\n\n")[0]
    printed = [float(line.split()[1]) for line in table.splitlines()[1:]]
    assert printed[:3] == pytest.approx(first[:3], abs=5e-4)  # printed to 3 decimals


def test_no_command_names_an_fmu_by_hand():
    """Every command names its FMUs and SSP systems by the model (model_fmu_name: the deck, the configuration,
    the motion outputs), never with a fixed "MACE" or from the configuration alone."""
    from support.paths import ROOT

    for path in sorted((ROOT / "mace_fmu" / "cli").glob("*.py")):
        text = path.read_text(encoding="utf-8")
        assert "fmu_model_name(" not in text and 'name=f"MACE' not in text, path.name


@pytest.mark.slow  # a model of the frame and its FMU: about 4 s
def test_an_ssp_package_names_its_system_after_the_model(capsys, tmp_path):
    import xml.etree.ElementTree as ET
    import zipfile

    from support.paths import EXAMPLES

    frame = EXAMPLES / "three_storey_frame"
    code, _, err = _run(capsys, ["export", "1g", "--deck", str(frame / "frame.bdf"), "--structure",
                                 str(frame / "frame.toml"), "--runtime", "pythonfmu", "--ssp", str(tmp_path / "f.ssp")])
    assert code == 0, err
    with zipfile.ZipFile(tmp_path / "f.ssp") as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    assert root.get("name") == "frame_1g" and root[0].get("name") == "frame_1g"
