"""The MACE update of thesis 4.5 through the command line: from the pre-update moduli to updated FMUs.

One run of ``mace-fmu update mace -o DIR`` (module fixture) is checked against the update's goals and
the thesis: the start model against Table 4.1, the selection against the thesis's choice, the
updated closed-loop modes against Table 4.7's measurement model (RMS no worse than the thesis's
own, every lightly damped bending mode within 2 %), and the parameter set it writes, read back
by ``mace-fmu model`` (python-control route) and ``mace-fmu export`` (the FMU's start values).
"""

from __future__ import annotations

import json
import zipfile
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from support.cli import run_cli

from mace_fmu.cli import main
from mace_fmu.parameters.sets import ParameterSet
from mace_fmu.thesis import thesis_data
from mace_fmu.updating.mace.family import MaceFamily
from mace_fmu.updating.mace.update import CANDIDATES, pre_update_parameters, table_4_1_rows, table_4_4_moduli

pytestmark = pytest.mark.slow  # the module runs the MACE modal update first (about 35 s)

FILES = ("parameters.toml", "report.txt", "summary.json", "orthogonality.png", "strength.png", "cost_history.png",
         "bode_gimbal_secondary_z_to_gyro_payload_z.png", "bode_gimbal_secondary_x_to_gyro_payload_x.png",
         "bode_gimbal_primary_x_to_gyro_bus_x.png")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("update")
    # the README's own command: converged, exit 0, with a damping ratio at its bound named (see below)
    assert main(["update", "mace", "-o", str(out)]) == 0
    return out, json.loads((out / "summary.json").read_text())


def test_every_stage_stops_on_a_stated_test_and_a_parameter_at_a_bound_is_named_not_failed(run):
    """No stage of the MACE update runs into its iteration cap; the damping stage leaves the 2nd Y bending
    mode's damping ratio at its lower bound (x0.2 of the start). That is a converged fit whose data ask for a
    value outside the range: convergence.toml says so and why it matters, and the run exits 0."""
    import tomllib

    out, _ = run
    report = tomllib.loads((out / "convergence.toml").read_text())
    assert not any("iteration cap" in r for r in report["reasons"])
    assert all(any(t in r for t in ("largest step", "cost fell", "first-order", "no lower cost")) for r in report["reasons"])
    assert report["converged"] is True
    assert report["at_bounds"] == {"damping:2nd Y bending": "lower"}
    assert "outside the allowed range" in report["at_bounds_note"]["text"]
    assert "one-sided" in report["at_bounds_note"]["text"]


def test_pre_update_moduli_are_table_4_4_back_computed():
    pre = pre_update_parameters()
    assert pre["E_lexan_center"] == pytest.approx(2.335e9 / (1 - 0.049), rel=1e-12)
    assert pre["E_cable_1"] == pytest.approx(1.982e11 / 1.089, rel=1e-12)
    assert set(pre.values) == set(table_4_4_moduli())


def test_the_pre_update_model_sits_near_table_4_1_for_the_bending_modes():
    """Table 4.1's FE column is the thesis's model after engineering insight: our pre-update
    closed-loop bending modes within 2 % of it (measured: within 0.6 %, but for the servo-dominated
    3rd Z bending at 1.9 %)."""
    family = MaceFamily(base=pre_update_parameters())
    rows = table_4_1_rows(family, family.base.values)
    bending = [r for r in rows if "bending" in r.label]
    assert len(bending) == 11
    for r in bending:
        assert r.ours_hz == pytest.approx(r.thesis_hz, rel=0.02), r.label


def test_every_file_is_written(run):
    out, _ = run
    for name in FILES:
        assert (out / name).stat().st_size > 1000 or name.endswith((".toml", ".txt")), name
    assert not list(out.glob(".*.part"))  # no temporary files left


def test_the_selection_drops_what_the_thesis_dropped(run):
    """Thesis 4.5: aluminium, stainless steel and the three suspension springs have virtually no
    effect on the initial error; the active-strut moduli stay or go together."""
    _, summary = run
    sel = summary["selection"]
    assert sel["candidates"] == list(CANDIDATES)
    kept = set(sel["kept"])
    dropped = {"E_aluminium", "E_stainless_steel", "k_suspension_device_1", "k_suspension_device_2",
               "k_suspension_device_3"}
    assert not kept & dropped
    assert {"E_lexan_center", "E_active_strut_end", "E_active_strut_piezo", "E_active_strut_center"} <= kept
    strength = dict(zip(sel["candidates"], sel["strength"]))
    assert max(strength[n] for n in dropped) < 0.02 * max(strength.values())


def test_the_update_meets_the_goals(run):
    _, summary = run
    rms = summary["rms_light_percent"]
    assert rms["after"] <= rms["thesis"]  # no larger than Table 4.7's own error column
    assert rms["after"] < rms["before"]
    modes = summary["modes"]
    for m in modes:
        if m["measured_zeta"] < 0.1 and "bending" in m["label"]:
            assert abs(m["after_hz"] / m["measured_hz"] - 1) <= 0.02, m["label"]
    assert summary["reduction"] > 0.25  # the thesis's automated update: 27.8 %
    physical = [h for h in summary["history"] if "physical" in h["step"]]
    assert len(physical) >= 3  # at least two recomputations of the sensitivities


def test_the_parameter_set_says_where_it_comes_from(run):
    out, summary = run
    params = ParameterSet.read(out / "parameters.toml")
    prov = params.provenance
    assert prov.configuration == "1g" and "Table 4.7" in prov.data and prov.cost.startswith("modal")
    assert prov.final_cost == pytest.approx(summary["final_cost"], rel=1e-12)
    for name, value in summary["parameters"]["updated"].items():
        if not name.startswith("damping:"):  # a damping ratio may be keyed by its mode's fresh label
            assert params[name] == value
    for name in set(pre_update_parameters().values) - set(summary["parameters"]["updated"]):
        assert params[name] == pre_update_parameters()[name]  # not updated: the start value stands


def test_model_and_export_take_the_updated_parameters(run, capsys, tmp_path):
    """Second route: the python-control volts model built from parameters.toml has the poles the
    update reported (its own numpy rebuild), and the FMU's start values are the updated ones. Both continue the
    deck's own modes, so each mode keeps one label and one damping ratio whichever route builds it (when the
    family labelled a fresh solve from its start, two violins of cables 1 and 3 swapped damping ratios and
    moved the bending poles by up to 2e-7 of their frequency)."""
    out, summary = run
    assert main(["model", "1g", "--parameters", str(out / "parameters.toml"), "--json"]) == 0
    poles = json.loads(capsys.readouterr().out)["poles"]
    for m in summary["modes"]:
        if "bending" in m["label"] and m["measured_zeta"] < 0.1:
            nearest = min(poles, key=lambda p: abs(p["frequency_hz"] - m["after_hz"]))
            assert nearest["frequency_hz"] == pytest.approx(m["after_hz"], rel=1e-9), m["label"]
    assert main(["export", "1g", "--parameters", str(out / "parameters.toml"), "-o", str(tmp_path)]) == 0
    fmu = next(tmp_path.glob("*.fmu"))
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    start = {v.get("name"): float(v.find("Real").get("start")) for v in root.iter("ScalarVariable")
             if v.find("Real") is not None and v.find("Real").get("start") is not None}
    for name, value in summary["parameters"]["updated"].items():
        if name.startswith("E_"):
            assert start[name] == pytest.approx(value, rel=1e-12), name


def test_the_family_takes_a_start_set_by_mode_number_as_the_same_set_by_label():
    """``update mace --start`` with an FMU update's set (``damping_mode_<k>``): the family keys its base by mode
    label, as the update's own values are, so an updated value replaces the start's, and both spellings give one
    model."""
    nominal = MaceFamily(configuration="0g", max_hz=20.0)
    k = nominal.solution(nominal.base.values).system.mode_labels.index("1st Z bending") + 1
    families = [MaceFamily(configuration="0g", max_hz=20.0, base=ParameterSet({"E_lexan_center": 2.4e9, name: 0.03}))
                for name in (f"damping_mode_{k}", "damping:1st Z bending")]
    assert [dict(f.base.values) for f in families] == [{"E_lexan_center": 2.4e9, "damping:1st Z bending": 0.03}] * 2
    number, label = (f.full({"damping:1st Z bending": 0.05}) for f in families)
    assert np.array_equal(number.a, label.a) and np.array_equal(number.b, label.b)
    system = families[0].solution(families[0].base.values).system
    assert families[0].vector(system, {"damping:1st Z bending": 0.05})[system.index(f"damping_mode_{k}")] == 0.05


def test_bad_start_files_stop_before_any_work(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[values]\nE_unobtainium = 1e9\n")
    out = tmp_path / "out"
    assert main(["update", "mace", "-o", str(out), "--start", str(bad)]) == 2
    assert "E_unobtainium" in capsys.readouterr().err
    assert not out.exists()  # nothing written half-way
    code, _, err = run_cli(capsys, ["update", "mace", "-o", str(out), "--rounds", "0"])
    assert code == 2 and "argument --rounds: expected an integer >= 1, got '0'" in err
    assert not out.exists()


def test_measured_tables_that_cannot_be_used_stop_before_any_work(tmp_path, capsys):
    """A measured mode no model pole can be paired with, a bad number: one line naming it, status 2, nothing written."""
    out = tmp_path / "out"
    table = tmp_path / "modes.csv"
    table.write_text("label,pattern,frequency_hz,damping\n1st Z bending,* Z bending,1.96,0.022\n"
                     "2nd W bending,* W bending,9.0,0.01\n")
    assert main(["update", "mace", "-o", str(out), "--measured", str(table)]) == 2
    err = capsys.readouterr().err
    assert "measured mode '2nd W bending' at 9.0 Hz: no model pole matches its pattern '* W bending'" in err
    assert not out.exists()
    table.write_text("label,pattern,frequency_hz,damping\n1st Z bending,* Z bending,nan,0.022\n")
    assert main(["update", "mace", "-o", str(out), "--measured", str(table)]) == 2
    assert "modes.csv:2: measured mode '1st Z bending': frequency must be a positive number" in capsys.readouterr().err
    table.write_text("label,frequency_hz\nx,1.0\n")
    assert main(["update", "mace", "-o", str(out), "--measured", str(table)]) == 2
    assert "missing column(s) pattern, damping" in capsys.readouterr().err
    assert not out.exists()


def test_table_4_4_is_what_the_thesis_prints():
    assert thesis_data()["table_4_4"]["lexan_center"]["change_percent"] == -4.9
    assert np.isclose(table_4_4_moduli()["E_active_strut_piezo"], 3.783e9)
