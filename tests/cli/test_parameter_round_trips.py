"""Every flow takes every parameter name every other flow writes: a set as ``update fmu``
writes it (the FMU's names: ``damping_mode_<k>``, ``frequency_scale_mode_<k>``, moduli and masses off their
nominal values) and the same set by mode label (``damping:<label>``, as ``update mace`` and ``predict-0g``
write) go into ``export --parameters`` (native and pythonfmu), ``export --ssp`` and ``update fmu --start``;
``params to-ssv`` is in tests/parameters/test_per_mode_names.py, with the models' poles against the set.

The proof is the set's own numbers: each FMU declares them as its parameters' start values (or the SSV binds
them), and both spellings give the same FMU. The structure is the three-storey frame (four modes), whose
how-to (docs/howto/update_from_measured_frfs.md) exports its update's set with the command run here.
"""

from __future__ import annotations

import platform
import re
import shlex
import zipfile

import pytest
from support.cli import run_cli
from support.paths import DOCS, EXAMPLES, ROOT
from support.update_sets import write_as_fmu_update

from mace_fmu.cli import main
from mace_fmu.parameters.sets import ParameterSet

FRAME = EXAMPLES / "three_storey_frame"
DECK = ["--deck", str(FRAME / "frame.bdf"), "--structure", str(FRAME / "frame.toml")]
#: the native FMUs carry this machine's binary alone: the other platforms' cross compilers take tens of seconds
HOST = ["--platforms", f"{'aarch64' if platform.machine() in ('aarch64', 'arm64') else 'x86_64'}-linux"]
ZETA, SCALE = 0.0137, 1.05  #: mode 2's damping ratio (the frame's table: 0.002) and mode 3's frequency scale
PHYSICAL = {"E_storey_1": 7.5e10, "m_floor_2": 4.8}  #: off the deck's 7.0e10 Pa and 5.201 kg
LABELS = {2: "2nd bending about Y", 3: "3rd bending about Y"}  #: the frame's modes 2 and 3 (FMU descriptions)
BY_NUMBER = {**PHYSICAL, "damping_mode_2": ZETA, "frequency_scale_mode_3": SCALE}
BY_LABEL = {**PHYSICAL, f"damping:{LABELS[2]}": ZETA, f"frequency_scale:{LABELS[3]}": SCALE}


def _howto_export() -> str:
    """The how-to's command that exports the updated frame from its update's parameters.toml."""
    text = (DOCS / "howto" / "update_from_measured_frfs.md").read_text()
    (command,) = re.findall(r"^mace-fmu export 1g .*--parameters frame_update/parameters\.toml.*$", text, re.MULTILINE)
    return command


def _start_values(fmu) -> dict[str, float]:
    """Every parameter's start value in an FMU's modelDescription.xml."""
    import fmpy

    return {v.name: float(v.start) for v in fmpy.read_model_description(str(fmu)).modelVariables
            if v.causality == "parameter" and v.start is not None}


def _model_data(fmu) -> bytes:
    """The data a native FMU rebuilds its model from (resources/mace_model.bin: every block, mode and parameter)."""
    with zipfile.ZipFile(fmu) as z:
        return z.read("resources/mace_model.bin")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A working folder laid out as the how-to's: examples/ and frame_update/parameters.toml (written by
    ``update fmu``'s own writer), and by_label/parameters.toml, the same set by mode label."""
    root = tmp_path_factory.mktemp("round_trips")
    (root / "examples").symlink_to(ROOT / "examples")
    (root / "frame_update").mkdir()
    write_as_fmu_update(root / "frame_update" / "parameters.toml", BY_NUMBER)
    (root / "by_label").mkdir()
    ParameterSet(BY_LABEL).write(root / "by_label" / "parameters.toml")
    return root


@pytest.fixture(scope="module")
def exported(folder):
    """The how-to's export of its update's set, and the same command on the set by label: the two FMUs."""
    out = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(folder)
        for spelling, where in (("number", "frame_update"), ("label", "by_label")):
            argv = shlex.split(_howto_export())[1:]
            argv[argv.index("frame_update/parameters.toml")] = f"{where}/parameters.toml"
            argv[argv.index("-o") + 1] = f"fmus_{spelling}"
            assert main(argv + HOST) == 0
            (out[spelling],) = (folder / f"fmus_{spelling}").glob("*.fmu")
    return out


def test_the_howto_exports_its_updates_set_with_the_sets_values(exported, folder):
    start = _start_values(exported["number"])
    digest = ParameterSet.read(folder / "frame_update" / "parameters.toml").digest()[:6]
    assert exported["number"].name == f"frame_1g_native_frame_update_parameters_{digest}.fmu"
    assert start["damping_mode_2"] == ZETA and start["E_storey_1"] == PHYSICAL["E_storey_1"]
    assert start["m_floor_2"] == PHYSICAL["m_floor_2"]
    assert start["damping_mode_1"] == start["damping_mode_3"] == 0.002  # the frame's table, untouched
    # the scale is built into the modes (the FMU's own scales are relative to the model it was built from)
    assert start["frequency_scale_mode_3"] == 1.0


def test_both_spellings_export_the_same_fmu(exported):
    assert _start_values(exported["number"]) == _start_values(exported["label"])
    assert _model_data(exported["number"]) == _model_data(exported["label"])


def test_a_pythonfmu_export_takes_the_fmu_updates_set(folder, capsys):
    code, _, err = run_cli(capsys, ["export", "1g", *DECK, "--parameters", str(folder / "frame_update" / "parameters.toml"),
                                    "--runtime", "pythonfmu", "-o", str(folder / "pythonfmu")])
    assert code == 0, err
    digest = ParameterSet.read(folder / "frame_update" / "parameters.toml").digest()[:6]
    start = _start_values(folder / "pythonfmu" / f"frame_1g_pythonfmu_frame_update_parameters_{digest}.fmu")
    assert start["damping_mode_2"] == ZETA and start["E_storey_1"] == PHYSICAL["E_storey_1"]
    assert start["m_floor_2"] == PHYSICAL["m_floor_2"]


def _package(ssp) -> tuple[dict[str, float], dict[str, float]]:
    """(the SSV's bound values, the plant FMU's start values) of an SSP package."""
    import xml.etree.ElementTree as ET

    ns = {"ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
    with zipfile.ZipFile(ssp) as z:
        root = ET.fromstring(z.read("resources/plant.ssv"))
        (ssp.parent / "plant.fmu").write_bytes(z.read("resources/plant.fmu"))
    bound = {p.get("name"): float(p.find("ssv:Real", ns).get("value")) for p in root.iterfind(".//ssv:Parameter", ns)}
    return bound, _start_values(ssp.parent / "plant.fmu")


def test_an_ssp_package_binds_either_spelling_to_the_same_values(folder, capsys):
    packages = {}
    for spelling, where in (("number", "frame_update"), ("label", "by_label")):
        (folder / f"ssp_{spelling}").mkdir()
        ssp = folder / f"ssp_{spelling}" / "frame.ssp"
        code, _, err = run_cli(capsys, ["export", "1g", *DECK, "--parameters", str(folder / where / "parameters.toml"),
                                        "--ssp", str(ssp), *HOST])
        assert code == 0, err
        packages[spelling] = _package(ssp)
    bound, start = packages["number"]
    assert bound == {"damping_mode_2": ZETA}  # the damping ratio is a start value; the rest is built in
    assert start["E_storey_1"] == PHYSICAL["E_storey_1"] and start["m_floor_2"] == PHYSICAL["m_floor_2"]
    assert packages["label"] == packages["number"]


@pytest.fixture(scope="module")
def nominal_fmu(folder):
    """The frame's nominal FMU, as the how-to exports it before its update."""
    assert main(["export", "1g", *DECK, "-o", str(folder / "nominal"), *HOST]) == 0
    return folder / "nominal" / "frame_1g_native.fmu"


class _Stop(Exception):
    """Raised once the update's problem is set up: what it starts from is known, no FMU need run."""


def test_update_fmu_starts_from_either_spelling_and_from_no_mode_given_twice(folder, nominal_fmu, monkeypatch, capsys):
    """Both spellings start the update from the same FMU values; a start file that gives one mode two values
    (``damping_mode_2`` and its label) is refused, naming both, rather than one taken silently."""
    import mace_fmu.updating.fmu.problem as problem_module

    real, made = problem_module.fmu_problem, []

    def set_up(**kwargs):
        made.append(real(**kwargs))
        raise _Stop

    monkeypatch.setattr(problem_module, "fmu_problem", set_up)
    update = ["update", "fmu", str(nominal_fmu), "--data", str(FRAME / "data" / "Experimental.csv"), "--cost",
              "log-frf", "--band-hz", "5.9", "7.1", "--update", "E_storey_1,damping_mode_2", "-o", str(folder / "unused")]
    for where in ("frame_update", "by_label"):
        with pytest.raises(_Stop):
            run_cli(capsys, [*update, "--start", str(folder / where / "parameters.toml")])
    number, label = made
    # every FMU run of the update sets the start file's values, by the FMU's names
    assert dict(number.family.fixed) == dict(label.family.fixed) == BY_NUMBER
    assert dict(number.start) == dict(label.start) == {"E_storey_1": PHYSICAL["E_storey_1"], "damping_mode_2": ZETA}
    twice = folder / "twice.toml"
    ParameterSet({"damping_mode_2": ZETA, f"damping:{LABELS[2]}": 0.02}).write(twice)
    code, _, err = run_cli(capsys, [*update, "--start", str(twice)])
    assert code == 2 and f"{twice}: parameter 'damping:{LABELS[2]}' = 0.02 and 'damping_mode_2' = {ZETA} both set " \
                          "damping_mode_2" in err


def test_a_mode_number_the_model_lacks_is_one_line_naming_the_file_in_every_reader(folder, nominal_fmu, capsys):
    bad = folder / "bad.toml"
    ParameterSet({**PHYSICAL, "damping_mode_7": ZETA}).write(bad)
    expected = rf"^mace-fmu: error: {re.escape(str(bad))}: parameter 'damping_mode_7': no mode 7: the .* has modes 1 " \
               r"to 4; expected damping_mode_<k> with k from 1 to 4, or damping:<mode label>"
    for argv in (["export", "1g", *DECK, "--parameters", str(bad), "-o", str(folder / "bad"), *HOST],
                 ["export", "1g", *DECK, "--parameters", str(bad), "--ssp", str(folder / "bad.ssp"), *HOST],
                 ["update", "fmu", str(nominal_fmu), "--data", str(FRAME / "data" / "Experimental.csv"), "--cost",
                  "log-frf", "--update", "E_storey_1", "--start", str(bad), "-o", str(folder / "bad")]):
        code, _, err = run_cli(capsys, argv)
        lines = [line for line in err.splitlines() if not line.startswith("  ")]  # progress lines are indented
        assert code == 2 and len(lines) == 1 and re.match(expected, lines[0]), (argv[:2], err)
    assert not (folder / "bad").exists() and not (folder / "bad.ssp").exists()
