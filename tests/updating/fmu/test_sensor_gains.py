"""Sensor gains known only to a stated accuracy, estimated with the moduli as nuisance parameters.

The lab: the 1-g native FMU of the bundled deck, an active-strut test (both piezo inputs, 8 s of
0.5-60 Hz noise at 2 ms) recording strut 2's strain gauges and a payload gyro, 2 % output noise,
and gauges whose gains are off by +0.8 % and -0.8 % (within a 1 % calibration). Treating those
gains as exact biases the strut moduli (the fit ends 8 standard deviations above the noise floor);
estimating them with a 1 % prior ends on the floor with the truth inside every reported interval.
The prior's arithmetic is checked against the closed form of a linear Gaussian problem.
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from support.cli import run_cli

from mace_fmu.cli import main
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.files import write_time_history

pytestmark = pytest.mark.slow  # the module runs updates with gains free and held first

STEP = 0.002
SECONDS = 8.0
STRUT = ("E_active_strut_end", "E_active_strut_piezo", "E_active_strut_center")
INPUTS = ("active_strut_y", "active_strut_z")
OUTPUTS = ("strain_strut2_y", "strain_strut2_z", "gyro_payload_x")
TRUE_GAINS = {"strain_strut2_y": 1.008, "strain_strut2_z": 0.992}
HELD = "rwa_x=0,rwa_y=0,rwa_z=0,gimbal_primary_x=0,gimbal_primary_z=0,gimbal_secondary_x=0,gimbal_secondary_z=0"


def _band_limited(rng, n: int) -> np.ndarray:
    f = np.fft.rfftfreq(n, STEP)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    spectrum[(f < 0.5) | (f > 60.0)] = 0.0
    return np.fft.irfft(spectrum, n)


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """(folder, the model's FMU: the strut moduli 3 % off built in, the data's family, truth moduli, the strut test's
    file). The data come from the deck's own FMU (another full re-solve), with the gauges' gains."""
    from support.reexported import fmu_with

    from mace_fmu.updating.fmu.model import fmu_family

    folder = tmp_path_factory.mktemp("gains")
    family = fmu_family(fmu_with(folder, factors={}, name="MACE_1g_truth"))
    fmu = fmu_with(folder, factors=dict(zip(STRUT, (1.03, 0.97, 1.03))), name="MACE_1g_native")
    rng = np.random.default_rng(3)
    t = np.arange(int(round(SECONDS / STEP)) + 1) * STEP
    u = {name: _band_limited(rng, t.size) for name in INPUTS}
    y = family.full({}).time_response(t, u, outputs=list(OUTPUTS)) * np.array([TRUE_GAINS.get(o, 1.0)
                                                                                for o in OUTPUTS])
    y = y + 0.02 * np.sqrt(np.mean(y**2, axis=0)) * rng.standard_normal(y.shape)
    path = write_time_history(TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(OUTPUTS)}, source="strut test"),
                              folder / "strut.csv")
    truth = {n: family.interface.parameters[n] for n in STRUT}
    return folder, fmu, family, truth, path


def _update(lab, out, *extra):
    folder, fmu, _, truth, data = lab
    code = main(["update", "fmu", str(fmu), "--update", ",".join(STRUT), "--data", str(data),
                 "--hold-input", HELD, "--workers", "1", "-o", str(out), *extra])
    values = tomllib.loads((out / "parameters.toml").read_text())
    stage = tomllib.loads((out / "uncertainty.toml").read_text())["stage"][0]
    sd = dict(zip(stage["parameters"], stage["standard_deviation_percent"]))
    report = tomllib.loads((out / "convergence.toml").read_text())
    report["uncertainty"] = stage  # the stage's table of uncertainty.toml, beside the verdict
    return code, values, sd, report


@pytest.fixture(scope="module")
def exact_and_estimated(lab, tmp_path_factory):
    """The update with the gauges' gains taken as exact, and with them known to 1 %."""
    out = tmp_path_factory.mktemp("runs")
    return (_update(lab, out / "exact"),
            _update(lab, out / "estimated", "--gain-uncertainty", "strain_strut2_y=1%,strain_strut2_z=1%"))


def test_gains_taken_as_exact_bias_the_fit_and_the_verdict_says_the_model_does_not_explain_the_data(
        exact_and_estimated):
    """The fit converges (exit 0), and the residual, far above the noise floor on the mis-calibrated gauges, is a
    model error: the gain errors are a misfit no modulus can explain."""
    code, _, _, report = exact_and_estimated[0]
    assert code == 0 and report["converged"] and report["verdict"] == "model error"
    assert report["noise_floor"]["sigmas_above"] > 3.0
    misfits = {c["name"] for c in report["channel"] if not c["explained"]}
    assert misfits & {"strain_strut2_y", "strain_strut2_z"}, misfits


def test_estimated_gains_end_on_the_noise_floor_with_every_truth_inside_its_interval(lab, exact_and_estimated):
    truth = lab[3]
    code, values, sd, report = exact_and_estimated[1]
    assert code == 0 and report["verdict"] == "explained" and abs(report["noise_floor"]["sigmas_above"]) < 3.0, report
    for n in STRUT:
        error = 100 * (values["values"][n] / truth[n] - 1)
        assert abs(error) <= 1.96 * sd[n], (n, error, sd[n])
    gains = values["sensor_gains"]
    assert set(gains) == set(TRUE_GAINS) and not any(k.startswith("gain:") for k in values["values"])
    for o, g in TRUE_GAINS.items():
        error = 100 * (gains[o] / g - 1)
        assert abs(error) <= 1.96 * sd[f"gain:{o}"] and sd[f"gain:{o}"] < 1.0, (o, error, sd[f"gain:{o}"])


def test_the_moduli_uncertainty_includes_the_gains(exact_and_estimated):
    """With the gains estimated, each modulus's reported standard deviation is its marginal one: larger than the
    same covariance conditioned on the gains (as if they were exact), rebuilt from uncertainty.toml's standard
    deviations and correlations. The fit with the gains taken as exact is a model error, so its intervals come
    from its residuals and say so."""
    exact, estimated = (run[3] for run in exact_and_estimated)
    assert exact["verdict"] == "model error" and exact["uncertainty"]["method"] == "residuals"
    st = estimated["uncertainty"]
    assert st["method"] == "noise"
    names = st["parameters"]
    sd = np.array(st["standard_deviation_percent"])
    cov = np.array(st["correlation"]) * np.outer(sd, sd)
    m = [k for k, n in enumerate(names) if n in STRUT]
    g = [k for k, n in enumerate(names) if n.startswith("gain:")]
    conditional = cov[np.ix_(m, m)] - cov[np.ix_(m, g)] @ np.linalg.solve(cov[np.ix_(g, g)], cov[np.ix_(g, m)])
    assert np.all(sd[m] > np.sqrt(np.diag(conditional)) * 1.01), (sd[m], np.sqrt(np.diag(conditional)))

def test_the_prior_is_the_closed_form_of_a_linear_gaussian_problem(lab):
    """Only a gain updated, at 60 % output noise so that data and prior weigh alike: the update's answer and
    standard deviation equal the posterior mean and standard deviation of y_meas = g y + e, g ~ N(1, 0.01^2)."""
    from mace_fmu.updating.engine.costs import TimeResponseCost, WithPriors
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty
    from mace_fmu.updating.fmu.model import FmuFamily
    from mace_fmu.updating.fmu.update import update_fmu

    family = FmuFamily(interface=lab[2].interface, gain_outputs=("gyro_payload_x",))
    rng = np.random.default_rng(5)
    t = np.arange(2001) * STEP
    u = {"active_strut_y": _band_limited(rng, t.size)}
    y = family.full({}).time_response(t, u, outputs=["gyro_payload_x"])[:, 0]
    measured = 1.004 * y + 0.6 * np.sqrt(np.mean(y**2)) * rng.standard_normal(y.size)
    history = TimeHistory(t, {**u, **{k: np.zeros_like(t) for k in lab[2].interface.inputs if k not in u}},
                          {"gyro_payload_x": measured})
    noise, prior = 0.6 * np.sqrt(np.mean(y**2)) / np.sqrt(np.mean(measured**2)), 0.01
    cost = WithPriors(TimeResponseCost(history), priors={"gain:gyro_payload_x": (1.0, prior)}, noise_sd=noise)
    result = update_fmu(family=family, cost=cost, start={"gain:gyro_payload_x": 1.0}, stages=[["gain:gyro_payload_x"]])
    (stage,) = stage_uncertainty(result, noise_variance=noise**2)
    scale = np.sqrt(np.mean(measured**2))
    information = np.sum((y / scale) ** 2) / noise**2 + 1 / prior**2
    mean = (np.sum(y * measured / scale**2) / noise**2 + 1 / prior**2) / information
    assert result.values["gain:gyro_payload_x"] == pytest.approx(mean, rel=1e-9)
    assert stage.standard_deviation_percent["gain:gyro_payload_x"] / 100 == pytest.approx(1 / math.sqrt(information),
                                                                                           rel=1e-6)


def test_the_channel_maps_column_states_the_same_prior_as_the_option(lab, tmp_path):
    from mace_fmu.updating.fmu.problem import fmu_problem

    folder, fmu, _, _, data = lab
    text = data.read_text()
    names = [c.strip() for c in next(line for line in text.splitlines() if not line.startswith("#")).split(",")]
    rows = ["channel,signal,role,unit,gain_uncertainty_percent"]
    for label in names[1:]:
        signal = label.split(":", 1)[1].split("[")[0].strip()
        role = "input" if label.startswith("in:") else "output"
        rows.append(f"{signal},{signal},{role},V,{'1' if signal in TRUE_GAINS else ''}")
    channel_map = tmp_path / "map.csv"
    channel_map.write_text("\n".join(rows) + "\n")
    common = dict(fmu=fmu, data=[data], names=STRUT, cost="time", held_inputs=HELD.replace("=0", "").split(","))
    by_map = fmu_problem(channel_map=channel_map, **common)
    by_option = fmu_problem(gain_uncertainty={o: 0.01 for o in TRUE_GAINS}, **common)
    assert by_map.names == by_option.names == STRUT + tuple(f"gain:{o}" for o in TRUE_GAINS)
    assert by_map.cost.priors == by_option.cost.priors == {f"gain:{o}": (1.0, 0.01) for o in TRUE_GAINS}
    assert by_map.cost.noise_sd == pytest.approx(0.02, rel=0.05)  # the noise estimated above the inputs' band


@pytest.mark.parametrize("extra, expected", [
    (["--gain-uncertainty", "gyro_bus_x=1%"], "no test records the output(s) gyro_bus_x"),
    (["--gain-uncertainty", "strain_strut2_y=0%"], "expected OUTPUT=P% with P > 0"),
    (["--gain-uncertainty", "strain_strut2_y=-1"], "expected OUTPUT=P% with P > 0"),
    (["--gain-uncertainty", "strain_strut2_y=1%", "--gain-uncertainty", "strain_strut2_y=2%"], "given twice"),
    (["--update", "E_active_strut_end"], "'E_active_strut_end' named twice in --update"),
])
def test_bad_gain_priors_and_repeated_parameters_are_refused_and_nothing_written(lab, tmp_path, capsys, extra,
                                                                                expected):
    folder, fmu, _, _, data = lab
    code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--update", "E_active_strut_end", "--data", str(data),
                                    "--hold-input", HELD, "-o", str(tmp_path / "out"), *extra])
    assert code == 2 and expected in err, err
    assert not (tmp_path / "out").exists()


def test_a_gain_column_on_an_input_row_names_the_map_line(tmp_path):
    from mace_fmu.errors import MaceError
    from mace_fmu.updating.files import read_channel_map

    path = tmp_path / "map.csv"
    path.write_text("channel,signal,role,unit,gain_uncertainty_percent\nai0,active_strut_y,input,V,1\n")
    with pytest.raises(MaceError, match=r"map.csv:2: gain_uncertainty_percent on channel 'ai0' \(role input\)"):
        read_channel_map(path)
    path.write_text("channel,signal,role,unit,gain_uncertainty_percent\nai0,gyro_bus_x,output,V,abc\n")
    with pytest.raises(MaceError, match=r"map.csv:2: gain_uncertainty_percent 'abc'"):
        read_channel_map(path)
