"""The modal-test route on real data: the three-storey frame's measured FRFs (examples/three_storey_frame/data) to
its modes, their correlation with the frame's deck and the update of its storeys' moduli and floors' masses, as
docs/guide/modal_updating.md shows it and the gallery's example runs it.

Independent of the code under test: the bins where each driving-point FRF peaks (the identified frequencies within
0.3 % of them), and the FRF route (``update fmu --cost log-frf`` on the same three files through the FMU's
simulated response: another cost, another model of the same deck) whose values the modal route's 95 % intervals
must hold.
"""

from __future__ import annotations

import importlib.util
import json
import re

import numpy as np
import pytest
from support.paths import DOCS, EXAMPLES
from support.printed import printed_in

from mace_fmu.parameters.sets import ParameterSet
from mace_fmu.updating.files import read_frequency_response
from mace_fmu.updating.modal.identify import peak_frequencies_hz

pytestmark = pytest.mark.slow  # an identification of nine FRFs and an update of six parameters (about 20 s)

FRAME = EXAMPLES / "three_storey_frame"
FILES = ("Experimental.csv", "test_2.csv", "test_3.csv")
UPDATE = "E_storey_1,E_storey_2,E_storey_3,m_floor_1,m_floor_2,m_floor_3"


def _example():
    spec = importlib.util.spec_from_file_location("modal_frame_example", FRAME / "modal_test_three_storey_frame.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def route(tmp_path_factory):
    """The guide's three commands: (stdout of each, the update's folder)."""
    import contextlib
    import io

    from mace_fmu.cli import main

    out = tmp_path_factory.mktemp("frame_modal")
    printed = {}
    commands = {
        "ema": ["ema", *(str(FRAME / "data" / f) for f in FILES), "--band-hz", "4", "32", "--structure",
                str(FRAME / "frame.toml"), "-o", str(out / "ema")],
        "correlate": ["correlate", "--deck", str(FRAME / "frame.bdf"), "--structure", str(FRAME / "frame.toml"),
                      "--modes", str(out / "ema" / "modes.toml"), "-o", str(out / "ema")],
        "update": ["update", "modal", "--deck", str(FRAME / "frame.bdf"), "--structure", str(FRAME / "frame.toml"),
                   "--modes", str(out / "ema" / "modes.toml"), "--update", UPDATE, "-o", str(out / "modal_update")],
    }
    for name, argv in commands.items():
        buffer = io.StringIO()
        with contextlib.redirect_stdout(buffer):
            assert main(argv) == 0, name
        printed[name] = buffer.getvalue()
    return printed, out / "modal_update"


def test_the_guide_s_tables_are_what_the_commands_print(route):
    printed, _ = route
    guide = (DOCS / "guide" / "modal_updating.md").read_text()
    blocks = re.findall(r"```text\n(.*?)```", guide, flags=re.S)
    assert len(blocks) == 4
    everything = "\n".join(printed.values())
    for block in blocks:
        assert printed_in(block, everything), f"documented block no longer printed by the code:\n{block}"


def test_the_updated_frame_meets_the_measured_modes_and_keeps_their_shapes(route):
    _, folder = route
    summary = json.loads((folder / "summary.json").read_text())
    assert [p["model"] for p in summary["after"]] == [f"{k} bending about Y" for k in ("1st", "2nd", "3rd")]
    for pair in summary["after"]:
        assert abs(pair["difference_percent"]) < 0.1 and pair["mac"] > 0.995
    assert summary["rms_difference_percent"]["before"] > 9 > 0.1 > summary["rms_difference_percent"]["after"]
    assert summary["converged"] is True
    params = ParameterSet.read(folder / "parameters.toml")
    measured = [summary["damping"][f"damping:{k} bending about Y"] for k in ("1st", "2nd", "3rd")]
    assert [params[f"damping:{k} bending about Y"] for k in ("1st", "2nd", "3rd")] == measured


def test_the_modal_route_holds_the_frf_route_s_values_within_its_95_percent_intervals(route):
    """The FRF route on the same three files (the example's FRF_ROUTE, from update fmu --cost log-frf) lies inside
    every interval of the modal route, 1.4-3.1 % below its values; the measured damping ratios are within 5 % of the
    FRF route's fitted ones."""
    import tomllib

    _, folder = route
    example = _example()
    stage = tomllib.loads((folder / "uncertainty.toml").read_text())["stage"][0]
    for name, value, low, high in zip(stage["parameters"], stage["values"], stage["interval_95_low"],
                                      stage["interval_95_high"]):
        other = example.FRF_ROUTE[name]
        assert low < other < high, name
        assert 0.0 < value / other - 1 < 0.035, name
    damping = json.loads((folder / "summary.json").read_text())["damping"]
    for k, other in zip(("1st", "2nd", "3rd"), example.FRF_ROUTE_DAMPING):
        assert damping[f"damping:{k} bending about Y"] == pytest.approx(other, rel=0.05)


def test_the_gallery_example_runs_and_its_identified_frequencies_sit_at_the_measured_peaks(tmp_path):
    summary = _example().main(tmp_path)
    identified = np.array(summary["identified_hz"])
    for name in FILES:
        frd = read_frequency_response(FRAME / "data" / name)
        driven = frd.inputs[0].replace("force", "acc")
        peaks = peak_frequencies_hz(frd, output=driven, input=frd.inputs[0], near_hz=identified)
        assert np.all(np.abs(identified / peaks - 1) < 0.003)
    assert all(abs(p["model_hz"] / p["measured_hz"] - 1) < 1e-3 and p["mac"] > 0.995 for p in summary["after"])
    for path in summary["figures"]:
        assert (tmp_path / path.rsplit("/", 1)[-1]).stat().st_size > 10_000


def test_the_export_and_update_fmu_start_take_the_modal_route_s_set(route, tmp_path):
    """parameters.toml of update modal: export re-solves its moduli and masses and takes its damping ratios (by mode
    label) as the FMU's start values; update fmu --start reads the same set by the FMU's names."""
    import zipfile
    from xml.etree import ElementTree as ET

    from mace_fmu.cli import main
    from mace_fmu.cli.update import _read_start

    _, folder = route
    params = ParameterSet.read(folder / "parameters.toml")
    assert main(["export", "1g", "--deck", str(FRAME / "frame.bdf"), "--structure", str(FRAME / "frame.toml"),
                 "--parameters", str(folder / "parameters.toml"), "-o", str(tmp_path)]) == 0
    fmu = next(tmp_path.glob("*.fmu"))
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    start = {v.get("name"): float(v.find("Real").get("start")) for v in root.iter("ScalarVariable")
             if v.find("Real") is not None and v.find("Real").get("start") is not None}
    for name in UPDATE.split(","):
        assert start[name] == pytest.approx(params[name], rel=1e-12), name
    for k, label in enumerate(("1st", "2nd", "3rd"), start=1):
        assert start[f"damping_mode_{k}"] == pytest.approx(params[f"damping:{label} bending about Y"], rel=1e-12)
    by_fmu_name, _ = _read_start(str(folder / "parameters.toml"), str(fmu))
    assert by_fmu_name["damping_mode_2"] == params["damping:2nd bending about Y"]
    assert by_fmu_name["m_floor_3"] == params["m_floor_3"]
