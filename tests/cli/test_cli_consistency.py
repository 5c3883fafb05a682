"""The command line says the same things the same way: each finding, as it was seen.

Removed spellings refused by name, ``--version``, an FMI 3 controller beside the FMI 2 one, FMUs of two
updates' parameter sets beside each other, the user's own paths in errors, help text without ``%%``, the
workers counted, a structure without electronics described as it is, and a modulus far outside the deck's
blamed on the set that gave it.
"""

from __future__ import annotations

import argparse
import os
import re
import tomllib

import numpy as np
import pytest
from support.paths import DOCS, EXAMPLES, ROOT

from mace_fmu.cli import build_parser, main


def _error_line(capsys) -> str:
    return capsys.readouterr().err.strip().splitlines()[-1]


# ---- removed spellings, --version -----------------------------------------------------------------------------

@pytest.mark.parametrize("argv, named, now", [
    (["export", "1g", "--kind", "native"], "--kind", "--runtime"),
    (["predict-0g", "--kind=pythonfmu"], "--kind", "--runtime"),
    (["update", "--fmu", "x.fmu", "--data", "d.csv"], "--fmu", "mace-fmu update fmu FILE"),
    (["update", "--sample-problem"], "--sample-problem", "mace-fmu update sample-problem"),
    (["update", "-o", "out"], "-o", "mace-fmu update mace -o DIR"),
    (["--verbose", "update", "--out=out"], "--out", "mace-fmu update mace -o DIR"),
])
def test_a_removed_spelling_is_refused_by_name(capsys, argv, named, now):
    """They were refused as any unknown argument ("unrecognized arguments: --kind native", "invalid choice:
    'x.fmu'"), never named as the spellings docs/reference/renamed.md lists."""
    with pytest.raises(SystemExit) as stopped:
        main(argv)
    line = _error_line(capsys)
    command = next(a for a in argv if not a.startswith("-"))
    assert stopped.value.code == 2
    assert line.startswith(f"mace-fmu {command}: error: {named} was removed before the first release; write {now}"), \
        line


def test_todays_spellings_are_not_taken_for_removed_ones():
    from mace_fmu.cli.renamed import removed_spelling

    for argv in (["update", "mace", "-o", "out"], ["update", "fmu", "x.fmu", "-o", "out"], ["export", "1g", "--runtime",
                                                                                             "native"]):
        assert removed_spelling(argv) is None, argv


def test_every_removed_command_line_spelling_is_on_the_renamed_page():
    from mace_fmu.cli.renamed import REMOVED

    page = (DOCS / "reference" / "renamed.md").read_text()
    for removed in REMOVED:
        assert removed.spelling in page and removed.command in page, removed


def test_version_prints_the_packages_version(capsys):
    with pytest.raises(SystemExit) as stopped:
        main(["--version"])
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert stopped.value.code == 0 and capsys.readouterr().out.strip() == f"mace-fmu {version}"


# ---- names of what is written ---------------------------------------------------------------------------------

@pytest.mark.slow  # two controller FMUs compiled
def test_an_fmi3_controller_does_not_replace_the_fmi2_one(tmp_path, capsys):
    """``export-controller --fmi-version 3`` wrote controller.fmu, the FMI 2 export's name."""
    import fmpy

    np.savez(tmp_path / "k.npz", A=np.array([[0.5]]), B=np.array([[1.0]]), C=np.array([[1.0]]), D=np.array([[0.0]]),
             sample_time_s=0.002, inputs=np.array(["y"]), outputs=np.array(["u"]))
    for version in ("2", "3"):
        assert main(["export-controller", "--npz", str(tmp_path / "k.npz"), "--fmi-version", version, "-o",
                     str(tmp_path), "--platforms", "x86_64-linux"]) == 0
    written = [line.split()[1] for line in capsys.readouterr().out.splitlines() if line.startswith("wrote ")]
    assert [os.path.basename(p) for p in written] == ["controller.fmu", "controller_fmi3.fmu"]
    assert [fmpy.read_model_description(p).fmiVersion for p in written] == ["2.0", "3.0"]


def _set(folder, values: dict[str, float], name: str = "parameters.toml"):
    from mace_fmu.parameters.sets import ParameterSet

    folder.mkdir(parents=True, exist_ok=True)
    return ParameterSet(values).write(folder / name)


def test_fmus_of_different_parameter_sets_never_share_a_name(tmp_path):
    """Every update writes DIR/parameters.toml: its FMU was MACE_1g_native_parameters.fmu, whichever the update.
    Now the set's folder names it too, and a digest of its values keeps apart two folders of one name."""
    from mace_fmu.cli.common import model_variant
    from mace_fmu.parameters.sets import ParameterSet

    def variant(path) -> str:
        return model_variant(build_parser().parse_args(["export", "1g", "--parameters", str(path)]))

    a = _set(tmp_path / "run_a", {"E_lexan_center": 2.3e9})
    b = _set(tmp_path / "run_b", {"E_lexan_center": 2.4e9})
    same_folder_name = _set(tmp_path / "elsewhere" / "run_a", {"E_lexan_center": 2.5e9})
    copy = _set(tmp_path / "copy", {"E_lexan_center": 2.3e9}, name="lexan.toml")
    digest = ParameterSet.read(a).digest()[:6]
    assert re.fullmatch(r"[0-9a-f]{6}", digest)
    assert variant(a) == f"run_a_parameters_{digest}"
    assert variant(copy) == f"lexan_{digest}"  # the same values: the same digest, the file's own stem
    assert len({variant(a), variant(b), variant(same_folder_name)}) == 3
    bounded = build_parser().parse_args(["export", "0g", "--parameters", str(b), "--frequency-bounds", "t.toml"])
    assert model_variant(bounded) == f"{variant(b)}_bounded"


@pytest.mark.slow  # two 0-g models and their FMUs
def test_two_updates_sets_export_to_two_fmus_and_the_command_says_which(tmp_path, capsys):
    sets = [_set(tmp_path / name / "out", {"E_lexan_center": value})
            for name, value in (("monday", 2.30e9), ("tuesday", 2.31e9))]
    written = []
    for path in sets:
        assert main(["export", "0g", "--max-hz", "5", "--parameters", str(path), "-o", str(tmp_path / "fmus")]) == 0
        written.append(capsys.readouterr().out.strip().splitlines()[-1].removeprefix("wrote "))
    names = [os.path.basename(p) for p in written]
    assert all(re.fullmatch(r"MACE_0g_native_out_parameters_[0-9a-f]{6}\.fmu", n) for n in names), names
    assert len(set(names)) == 2 and all(os.path.isfile(p) for p in written)


def test_structure_file_errors_name_the_file_as_given(tmp_path, capsys, monkeypatch):
    """A structure file given as s.toml was named /the/absolute/path/s.toml in its errors."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text('[suspension]\ngrids = "x"\n')
    assert main(["modes", "0g", "--structure", "s.toml"]) == 2
    line = _error_line(capsys)
    assert line.startswith("mace-fmu: error: s.toml:1: [suspension] grids: expected a list of IDs") \
        and str(tmp_path) not in line, line


# ---- what the commands print ----------------------------------------------------------------------------------

def _parsers(parser: argparse.ArgumentParser, path=("mace-fmu",)):
    yield " ".join(path), parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, (*path, name))


def test_no_help_shows_a_doubled_percent_sign():
    """argparse expands %-formats in the options' help, not in a description or epilog: plan-test's epilog
    showed "%%"."""
    checked = 0
    for command, parser in _parsers(build_parser()):
        text = parser.format_help()
        assert "%%" not in text, (command, [line for line in text.splitlines() if "%%" in line])
        checked += 1
    assert checked > 20


def test_local_workers_are_counted_in_words():
    """"FMU runs on one per core local worker processes": the count, then what it is."""
    from mace_fmu.cli.update import local_workers

    cores = os.cpu_count() or 1
    assert local_workers(None) == f"{cores} local worker process{'es' if cores != 1 else ''} (one per core)"
    assert local_workers(3) == "3 local worker processes" and local_workers(1) == "1 local worker process"


def test_a_structure_without_electronics_is_described_as_it_is():
    """The frame's structure file declares sensors and actuators only: its model said "servos closed, Bessel
    filters full, delays on"."""
    from mace_fmu.iomodel.instruments import load_instruments
    from mace_fmu.iomodel.model_options import ModelledElectronics

    frame = load_instruments(EXAMPLES / "three_storey_frame" / "frame.toml")
    mace = load_instruments()
    assert ModelledElectronics().describe(instruments=frame) == "no servos, no anti-aliasing filters, no delays"
    assert ModelledElectronics().describe(instruments=mace) == "servos closed, Bessel filters full, delays on"
    assert ModelledElectronics(servos=False, bessel="delay", delays=False).describe(instruments=mace) == \
        "servos open, Bessel filters delay, delays off"


@pytest.mark.slow  # the frame's model through the command line
def test_model_of_a_structure_without_electronics_says_so(capsys):
    frame = EXAMPLES / "three_storey_frame"
    assert main(["model", "1g", "--deck", str(frame / "frame.bdf"), "--structure", str(frame / "frame.toml")]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.endswith("(no servos, no anti-aliasing filters, no delays)"), first


@pytest.mark.slow  # the 0-g modes, failing
def test_a_modulus_far_outside_the_decks_is_blamed_on_the_set(tmp_path, capsys, monkeypatch):
    """E_lexan_center 1e-6 x nominal left massless DOFs without stiffness: the error spoke of the model's DOFs
    and an SPC, as if the deck were broken."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.toml").write_text("[values]\nE_lexan_center = 2.4e3\n")
    assert main(["model", "0g", "--max-hz", "5", "--parameters", "tiny.toml"]) == 2
    line = _error_line(capsys)
    assert line.startswith("mace-fmu: error: tiny.toml: E_lexan_center = 2400 Pa is 1.03e-06 x the deck's "
                           "2.335e+09 Pa, outside the range the FMUs take (0.7-1.5 x); with it the model cannot be "
                           "solved ("), line


# ---- one way to write a progress line -------------------------------------------------------------------------

def test_every_progress_line_goes_through_progress():
    """A progress line (two spaces, on stderr) is written by mace_fmu.cli.common.progress alone, so that every
    command's lines look alike and change together; no command has a printer of its own beside it."""
    import ast

    found = []
    for path in sorted((ROOT / "mace_fmu" / "cli").glob("*.py")):
        if path.name in ("common.py", "__init__.py"):  # progress itself; an error's indented details
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "print" and node.args \
                    and any(k.arg == "file" and ast.unparse(k.value) == "sys.stderr" for k in node.keywords):
                first = node.args[0]
                text = first.value if isinstance(first, ast.Constant) else \
                    getattr(first.values[0], "value", "") if isinstance(first, ast.JoinedStr) and first.values else ""
                if isinstance(text, str) and text.startswith("  "):
                    found.append(f"{path.name}:{node.lineno}")
    assert found == []


# ---- every number an option takes is checked as it is parsed --------------------------------------------------

def test_no_option_takes_a_plain_float_or_int():
    """``type=float`` lets nan, inf and -5 through to fail later, or not at all; each option has a type that says
    what it expects (mace_fmu.cli.common: positive_number, positive_hz, fraction, percent, ...), in one line."""
    import ast

    plain = []
    for path in sorted((ROOT / "mace_fmu" / "cli").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "add_argument":
                keywords = {k.arg: k.value for k in node.keywords}
                kind = getattr(keywords.get("type"), "id", "")
                if kind == "float" or (kind == "int" and "choices" not in keywords):
                    plain.append(f"{path.name}:{node.lineno}")
    assert plain == []


@pytest.mark.parametrize("argv, message", [
    (["view", "response", "0g", "--chirp-hz", "-1", "5"], "argument --chirp-hz: expected a finite frequency >= 0 Hz, "
                                                          "got '-1'"),
    (["view", "response", "0g", "--duration", "nan"], "argument --duration: expected a finite number > 0, got 'nan'"),
    (["data", "h1", "x.csv", "--segment", "0"], "argument --segment: expected an integer >= 1, got '0'"),
    (["data", "h1", "x.csv", "--segment", "8", "--overlap", "1"], "argument --overlap: expected a fraction in [0, 1), "
                                                                  "got '1'"),
    (["model", "0g", "--list-max-hz", "-5"], "argument --list-max-hz: expected a finite frequency > 0 Hz, got '-5'"),
    (["study", "robust-0g", "--seed", "-1"], "argument --seed: expected an integer >= 0, got '-1'"),
])
def test_a_bad_number_is_one_line_naming_the_option_and_what_it_expects(capsys, argv, message):
    with pytest.raises(SystemExit) as stopped:
        main(argv)
    assert stopped.value.code == 2
    assert _error_line(capsys).endswith(f"error: {message}")
