"""plan-test: the uncertainty an update would report, predicted from the model before any test is run.

The reference is independent of the FMU that plan-test linearises: the Fisher information of full re-solves
(tests/support/resolves.py: each modulus built into the deck and solved again, central differences of their
responses, the same excitations, noise and gain priors). plan-test's standard deviations equal it within 2 %
(measured: within 1 %, 20 s records, e.g. the gimbal test recording the strut-2 gauges: strut end / piezo /
center 0.021 / 0.028 / 0.015 % with exact gauge gains, 0.065 / 0.24 / 0.71 % with the gains known to 1 %).
Before the static corrections of the FMU's parameter route the same plans predicted 2.25 / 8.71 / 26.0 %
and 4.0 / 15.6 / 46.5 %: ``test_plan_test_predicts_the_fisher_information_of_full_resolves`` would have
failed by factors of 100 to 1700.

Besides (the update's own mechanics, on data the FMU makes): the predicted standard deviations equal the
spread of 16 updates (16 noise and excitation realisations, none the plan's own) within a factor 1.5, and
the updates' reported uncertainties rank the candidates as the plan does.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.paths import EXAMPLES

from mace_fmu.cli import main
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.fmu.planning import Candidate, TestDesign, plan_tests, predict_uncertainty, read_test_plan
from mace_fmu.updating.fmu.truth import band_limited_noise

pytestmark = pytest.mark.slow  # plans and updates simulate the FMU for seconds each

GIMBAL = TestDesign(name="gimbal", seconds=4.0,
                    inputs=("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z"),
                    outputs=("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z"))
STRUT = ("E_active_strut_end", "E_active_strut_piezo", "E_active_strut_center")
PLAN = """
[[test]]
name = "strut"
inputs = ["active_strut_y", "active_strut_z"]
outputs = ["strain_strut2_y", "strain_strut2_z", "gyro_payload_x"]

[[test]]
name = "strut, gauges to 1 %"
inputs = ["active_strut_y", "active_strut_z"]
outputs = ["strain_strut2_y", "strain_strut2_z", "gyro_payload_x"]
gain_uncertainty_percent = { strain_strut2_y = 1, strain_strut2_z = 1 }
"""


@pytest.fixture(scope="module")
def family(native_fmu_1g):
    from mace_fmu.updating.fmu.model import fmu_family

    return fmu_family(native_fmu_1g)


def _measure(family, test: TestDesign, *, seed: int) -> TimeHistory:
    """A synthetic record of ``test``: its own excitation and noise realisation (seeds unlike the plan's)."""
    n = int(round(test.seconds / test.sample_time_s)) + 1
    t = np.arange(n) * test.sample_time_s
    u = {k: np.zeros(n) for k in family.interface.inputs}
    for j, name in enumerate(test.inputs):
        u[name] = band_limited_noise(samples=n, step_s=test.sample_time_s, band_hz=test.band_hz,
                                     seed=100 + 10 * seed + j)
    y = family.full({}).time_response(t, u, outputs=list(test.outputs))
    rng = np.random.default_rng(500 + seed)
    y = y + test.noise_rms_percent / 100 * np.sqrt(np.mean(y**2, axis=0)) * rng.standard_normal(y.shape)
    return TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(test.outputs)}, source=f"{test.name} {seed}")


def test_predicted_standard_deviations_are_the_spread_of_updates_within_a_factor_1_5(family, tmp_path):
    from mace_fmu.updating.engine.costs import TimeResponseCost
    from mace_fmu.updating.fmu.update import update_fmu

    from support.reexported import fmu_with

    from mace_fmu.updating.fmu.model import fmu_family

    names = ["E_lexan_end", "E_cable_1"]
    # the data: the deck's FMU; the model updated: an FMU with the two moduli 2 % off built in, from its nominal
    model = fmu_family(fmu_with(tmp_path, factors={"E_lexan_end": 1.02, "E_cable_1": 0.98}, name="model"))
    predicted = predict_uncertainty(family=model, parameters=names, candidate=Candidate("gimbal", (GIMBAL,)))
    truth = {n: family.interface.parameters[n] for n in names}
    errors = []
    for seed in range(16):
        result = update_fmu(family=model, cost=TimeResponseCost(_measure(family, GIMBAL, seed=seed)),
                            start={n: model.interface.parameters[n] for n in names}, stages=[names])
        assert result.converged, result.reasons
        errors.append([100 * (result.values[n] / truth[n] - 1) for n in names])
    spread = np.std(errors, axis=0, ddof=1)
    ratio = spread / np.array([predicted.standard_deviation_percent[n] for n in names])
    assert np.all((ratio > 1 / 1.5) & (ratio < 1.5)), (spread, predicted.standard_deviation_percent)


def test_plan_test_predicts_the_fisher_information_of_full_resolves(family):
    """The strut test (exact gauge gains, and gains known to 1 %) and the gimbal test recording the strut-2
    gauges (the 8 kept moduli): every standard deviation within 2 % of the full re-solves' Fisher prediction,
    and every parameter identifiable (no weak combination: the gauges sit on the strut's sections)."""
    from support.resolves import fisher_standard_deviations

    from mace_fmu.updating.mace.update import THESIS_KEPT

    strut = read_test_plan_text(PLAN)
    gauges = TestDesign(name="gimbal + gauges", seconds=4.0, inputs=GIMBAL.inputs,
                        outputs=GIMBAL.outputs + ("strain_strut2_y", "strain_strut2_z"))
    cases = [(STRUT, strut[0]), (STRUT, strut[1]), (THESIS_KEPT, Candidate("gimbal + gauges", (gauges,)))]
    for names, candidate in cases:
        predicted = predict_uncertainty(family=family, parameters=names, candidate=candidate)
        fisher = fisher_standard_deviations("1g", list(names), list(candidate.tests))
        assert set(fisher) == set(predicted.standard_deviation_percent)
        for name, sd in fisher.items():
            ratio = predicted.standard_deviation_percent[name] / sd
            assert abs(ratio - 1) < 0.02, (candidate.name, name, predicted.standard_deviation_percent[name], sd)
        assert not predicted.weak_directions, candidate.name
    # what a planner decides from it: the exact gains fix the strut sections better than gains known to 1 %
    assert max(fisher_standard_deviations("1g", list(STRUT), list(strut[0].tests)).values()) < \
        min(fisher_standard_deviations("1g", list(STRUT), list(strut[1].tests))[n] for n in STRUT[::2])


def read_test_plan_text(text: str):
    """The candidates of a plan given as text."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "plan.toml"
        path.write_text(text)
        return read_test_plan(path)


def test_the_plan_ranks_the_strut_tests_as_their_updates_turn_out(family, tmp_path, capsys):
    """The updates' reported uncertainties on data of the strut test: within 1.5x of the plan's, the exact
    gains' candidate ahead of the gains known to 1 %."""
    import tomllib

    from mace_fmu.updating.files import write_time_history

    (tmp_path / "plan.toml").write_text(PLAN)
    candidates = read_test_plan(tmp_path / "plan.toml")
    planned = plan_tests(fmu=family.interface.path, parameters=STRUT, candidates=candidates)
    assert [p.candidate.name for p in planned] == ["strut", "strut, gauges to 1 %"]
    data = write_time_history(_measure(family, candidates[0].tests[0], seed=3), tmp_path / "strut.csv")
    held = ",".join(f"{i}=0" for i in family.interface.inputs if i not in candidates[0].tests[0].inputs)
    reported = []
    for k, extra in enumerate(([], ["--gain-uncertainty", "strain_strut2_y=1%,strain_strut2_z=1%"])):
        out = tmp_path / f"out{k}"
        code = main(["update", "fmu", family.interface.path, "--update", ",".join(STRUT), "--data", str(data),
                     "--hold-input", held, "--workers", "1", "-o", str(out), *extra])
        assert code == 0, capsys.readouterr().err
        stage = tomllib.loads((out / "uncertainty.toml").read_text())["stage"][0]
        reported.append(dict(zip(stage["parameters"], stage["standard_deviation_percent"])))
    for p, sd in zip(planned, reported):
        predicted = p.uncertainty.standard_deviation_percent
        for n in STRUT:
            assert 1 / 1.5 < sd[n] / predicted[n] < 1.5, (p.candidate.name, n, sd[n], predicted[n])
    assert max(reported[0][n] for n in STRUT) < max(reported[1][n] for n in STRUT)


def test_cli_prints_the_ranking_and_writes_the_predictions(family, tmp_path, capsys):
    import tomllib

    (tmp_path / "plan.toml").write_text(PLAN)
    code = main(["plan-test", family.interface.path, "--tests", str(tmp_path / "plan.toml"), "--update",
                 "E_active_strut_end,E_active_strut_piezo", "--workers", "1", "-o", str(tmp_path / "p.toml")])
    out = capsys.readouterr().out
    assert code == 0
    assert out.index("1    strut ") < out.index("2    strut, gauges to 1 %")
    written = tomllib.loads((tmp_path / "p.toml").read_text())["stage"]
    assert [s["name"] for s in written] == ["strut", "strut, gauges to 1 %"]
    assert written[1]["parameters"][-2:] == ["gain:strain_strut2_y", "gain:strain_strut2_z"]


@pytest.mark.parametrize("text, expected", [
    ("[[test]]\nname = 'a'\ninputs = []\noutputs = ['x']\n", "inputs must be a list of signal names"),
    ("[[test]]\nname = 'a'\ninputs = ['x']\noutputs = ['y']\nnoise_rms_percent = 0\n",
     "noise_rms_percent must be a positive number"),
    ("[[test]]\nname = 'a'\ninputs = ['x']\noutputs = ['y']\nband_hz = [0.5, 300]\n", "at or above the Nyquist"),
    ("[[test]]\nname = 'a'\ninputs = ['x']\noutputs = ['y']\nduration = 3\n", "unknown key(s) ['duration']"),
    ("[[test]]\nname = 'a'\ninputs = ['x']\noutputs = ['y']\n[[candidate]]\nname = 'c'\ntests = ['b']\n",
     "no [[test]] named 'b'"),
    ("[[candidate]]\nname = 'c'\ntests = ['b']\n", "no [[test]] tables"),
])
def test_a_bad_test_plan_is_one_line_naming_the_file_and_entry(tmp_path, capsys, family, text, expected):
    (tmp_path / "plan.toml").write_text(text)
    code = main(["plan-test", family.interface.path, "--tests", str(tmp_path / "plan.toml"), "--update", STRUT[0]])
    err = capsys.readouterr().err
    assert code == 2 and expected in err and "plan.toml" in err, err


def test_signals_the_fmu_lacks_are_refused_before_any_simulation(tmp_path, capsys, family):
    (tmp_path / "plan.toml").write_text("[[test]]\nname = 'a'\ninputs = ['active_strut_y']\noutputs = ['strain_x']\n")
    code = main(["plan-test", family.interface.path, "--tests", str(tmp_path / "plan.toml"), "--update", STRUT[0]])
    err = capsys.readouterr().err
    assert code == 2 and "test 'a'" in err and "output 'strain_x'" in err, err


def test_at_predicts_about_given_values_as_the_api_does(family, tmp_path, capsys):
    """--at FILE linearises about those values: the printed standard deviation is predict_uncertainty's there,
    not at the FMU's start values (the cable moduli's move with the point)."""
    (tmp_path / "plan.toml").write_text(PLAN)
    at = {"E_cable_1": 0.97 * family.interface.parameters["E_cable_1"]}
    (tmp_path / "at.toml").write_text(f"[values]\nE_cable_1 = {at['E_cable_1']!r}\n")
    code = main(["plan-test", family.interface.path, "--tests", str(tmp_path / "plan.toml"), "--update", "E_cable_1",
                 "--at", str(tmp_path / "at.toml"), "--workers", "1", "-o", str(tmp_path / "p.toml")])
    assert code == 0, capsys.readouterr().err
    import tomllib

    written = {s["name"]: s["standard_deviation_percent"][0]
               for s in tomllib.loads((tmp_path / "p.toml").read_text())["stage"]}
    strut = read_test_plan(tmp_path / "plan.toml")[0]
    there = predict_uncertainty(family=family, parameters=["E_cable_1"], candidate=strut, values=at)
    nominal = predict_uncertainty(family=family, parameters=["E_cable_1"], candidate=strut)
    assert written["strut"] == pytest.approx(there.standard_deviation_percent["E_cable_1"], rel=1e-12)
    assert there.standard_deviation_percent["E_cable_1"] != nominal.standard_deviation_percent["E_cable_1"]


def test_example_plan_then_update_quick(tmp_path):
    """examples/plan_then_update.py with 2 s tests: the plan picks a candidate, the update on its data converges
    with the gauges' gains estimated, and every modulus's truth lies inside its reported 95 % interval."""
    import importlib.util

    path = EXAMPLES / "plan_then_update.py"
    spec = importlib.util.spec_from_file_location("plan_then_update", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    summary = example.main(["--seconds", "2", "--workers", "1", "--out", str(tmp_path)])
    assert summary["best"] == "gimbal + strut" and summary["converged"]
    for name, (error, sd, _) in summary["rows"].items():
        assert abs(error) <= 1.96 * sd, (name, error, sd)


def test_a_parameter_set_of_the_engine_passes_to_the_fmu_flows_and_params_list_shows_them(family, tmp_path, capsys):
    """``update mace`` writes damping ratios by mode label (``damping:1st Z bending``); ``plan-test --at`` and
    ``update fmu --start`` take them as the FMU's ``damping_mode_<k>`` (the FMU's parameter descriptions say
    each mode's label); a label no mode has is one line naming the file, the closest labels and the command
    that lists the FMU's parameters."""
    from mace_fmu.errors import MaceError

    interface = family.interface
    k = next(n for n, d in interface.descriptions.items() if d.endswith("mode 14: 1st Z bending"))
    assert k == "damping_mode_14"
    values = interface.values_by_fmu_name({"damping:1st Z bending": 0.03, "E_lexan_center": 2.4e9}, source="p.toml")
    assert values == {"damping_mode_14": 0.03, "E_lexan_center": 2.4e9}
    assert interface.values_by_fmu_name({"frequency_scale:1st Z bending": 1.01}, source="p.toml") == \
        {"frequency_scale_mode_14": 1.01}
    with pytest.raises(MaceError, match=r"p.toml: parameter 'damping:1st Q bending': no mode labelled '1st Q bending' "
                                        r"in the FMU .*; closest: damping:1st Z bending.*mace-fmu params list"):
        interface.values_by_fmu_name({"damping:1st Q bending": 0.03}, source="p.toml")
    (tmp_path / "at.toml").write_text("[values]\nE_cable_1 = 1.9e11\n\"damping:1st Z bending\" = 0.03\n")
    (tmp_path / "plan.toml").write_text(PLAN)
    code = main(["plan-test", interface.path, "--tests", str(tmp_path / "plan.toml"), "--update", "E_cable_1",
                 "--at", str(tmp_path / "at.toml"), "--workers", "1"])
    assert code == 0, capsys.readouterr().err
    capsys.readouterr()
    assert main(["params", "list", interface.path]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("E_lexan_center "))
    assert row.split()[1:4] == ["2.335e+09", "1.6345e+09", "3.5025e+09"] and "MAT1 2" in row
