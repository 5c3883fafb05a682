"""An update converges or says it did not: stopping tests, bounds, and the time cost's noise floor.

The problem is the thesis's two-mass system (k1 = 0.75, k2 = 1.20 N/m), started at k = 1.0, on the
time-domain cost of a record with known white measurement noise: the noise floor is known exactly,
so the verdicts can be checked against it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.two_mass_records import true_damping, two_mass_record

from mace_fmu.cli import main
from mace_fmu.updating.engine.convergence import convergence_report, time_noise_floor
from mace_fmu.updating.engine.costs import TimeResponseCost
from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateSettings, update
from mace_fmu.updating.sample.family import MODE_LABELS, TwoMassFamily
from mace_fmu.updating.sample.two_mass import TwoMassSystem

NOISE = 0.05  # noise RMS / noise-free output RMS
SAMPLES = 2048


def _record(*, band_limited: bool, seed: int = 3):
    return two_mass_record(samples=SAMPLES, noise=NOISE, seed=seed, band_limited=band_limited)


def _update(cost, *, off: float = 0.02, **settings):
    """k1 and k2 from ``off`` below and above the truth (a time cost over many cycles has a local minimum
    at every cycle of phase drift: the start must be within about a quarter cycle)."""
    family = TwoMassFamily(masses=TwoMassSystem())
    actual = TwoMassSystem()
    start = {"k_1": (1 - off) * actual.k1, "k_2": (1 + off) * actual.k2,
             **{f"damping:{label}": z for label, z in zip(MODE_LABELS, true_damping())}}
    bounds = {n: Bounds(0.2 * start[n], 5.0 * start[n]) for n in start}
    bounds.update(settings.pop("bounds", {}))
    run = UpdateSettings(**{"method": "reanalysis", "penalty": False, "relative_step": 1e-4, **settings})
    return update(family, cost, start=start, stages=[Stage("stiffness", ("k_1", "k_2"))], bounds=bounds,
                  settings=run)


def test_a_converged_update_names_its_stopping_test_and_ends_on_the_noise_floor():
    cost = TimeResponseCost(_record(band_limited=False))
    result = _update(cost)
    floor = time_noise_floor(cost, noise_rms_fraction=NOISE / math.sqrt(1 + NOISE**2))
    report = convergence_report(result, noise_floor=floor, cost=cost)
    assert result.converged and report.verdict == "explained", report.summary()
    (channel,) = report.residuals.channels
    assert channel.white and not channel.correlated_inputs and abs(channel.rms_over_noise - 1) < 0.05
    assert any(test in result.reasons[0] for test in ("largest step", "cost fell", "first-order", "no lower cost"))
    assert abs(floor.sigmas_above(result.final_cost)) < 3.0
    np.testing.assert_allclose([result.values["k_1"], result.values["k_2"]], [0.75, 1.20], rtol=0.01)


def test_a_local_minimum_is_a_converged_fit_the_model_does_not_explain_and_never_called_unconverged():
    """From 10 % off, the time cost's phase-drift minima hold the update: its steps stop (a stated test). That is
    converged; the residual, far above the noise and correlated with the force, says the model at these values
    does not explain the data, and the verdict names both causes it cannot tell apart (a model error or a local
    minimum), never "stopped short of the optimum"."""
    cost = TimeResponseCost(_record(band_limited=False))
    result = _update(cost, off=0.10)
    report = convergence_report(result, noise_floor=time_noise_floor(cost, noise_rms_fraction=NOISE), cost=cost)
    assert result.converged and report.converged and report.verdict == "model error" and not report.failed
    assert "standard deviations from the noise floor" in report.reasons[-1]
    assert "stopped short" not in report.summary() and "local minimum" in report.headline()
    (channel,) = report.residuals.channels
    assert channel.rms_over_noise > 3 and channel.above_noise and not channel.white
    assert convergence_report(result, noise_floor=report.noise_floor, cost=cost, strict=True).failed


def test_an_update_stopped_by_its_cap_says_so_in_the_result_and_the_written_report():
    cost = TimeResponseCost(_record(band_limited=False))
    result = _update(cost, max_outer=1)
    floor = time_noise_floor(cost, noise_rms_fraction=NOISE / math.sqrt(1 + NOISE**2))
    report = convergence_report(result, noise_floor=floor)
    assert not result.converged and "iteration cap reached (max_outer = 1)" in result.reasons[0]
    assert not report.converged and report.verdict == "not converged" and "NOT CONVERGED" in report.summary()
    import tomllib

    parsed = tomllib.loads(report.to_toml())
    assert parsed["converged"] is False and parsed["verdict"] == "not converged" and "iteration cap" in parsed["reasons"][0]
    assert parsed["noise_floor"]["sigmas_above"] == pytest.approx(floor.sigmas_above(result.final_cost))


def test_an_update_that_ends_at_a_bound_has_converged_and_names_it_and_strict_fails_it():
    """The fit meets its test with k_2 at its upper bound (the truth, 1.20, is outside [0.5, 1.19]): converged,
    the bound named with what it means; --strict (``strict=True``) counts it as not converged."""
    from mace_fmu.updating.engine.convergence import convergence_report

    cost = TimeResponseCost(_record(band_limited=False))
    result = _update(cost, off=-0.02, bounds={"k_2": Bounds(0.5, 1.19)})  # from 1.176
    assert result.converged and "k_2 at its upper bound" in result.reasons[0]
    assert result.at_bounds == (("k_2", "upper"),)
    report = convergence_report(result)
    assert report.converged and report.summary().startswith("converged (with k_2 at its upper bound: the data ask")
    assert "[at_bounds]\n\"k_2\" = \"upper\"" in report.to_toml()
    strict = convergence_report(result, strict=True)
    assert not strict.converged and strict.summary().startswith("NOT CONVERGED")


def test_the_noise_is_estimated_from_the_spectrum_above_a_band_limited_input():
    cost = TimeResponseCost(_record(band_limited=True))
    floor = time_noise_floor(cost)
    assert floor is not None and "above the inputs' band" in floor.source
    # the output's RMS holds the noise too: its noise is NOISE / sqrt(1 + NOISE^2) of it
    expected = 100 * NOISE / math.sqrt(1 + NOISE**2)
    assert floor.noise_rms_percent["displacement_1"] == pytest.approx(expected, rel=0.1)


def test_white_inputs_leave_no_quiet_band_to_measure_the_noise_in():
    assert time_noise_floor(TimeResponseCost(_record(band_limited=False))) is None


def test_help_documents_the_exit_status(capsys):
    with pytest.raises(SystemExit):
        main(["update", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "exit status: 0 converged, whether the model explains the data to their noise or not (a model error" in text
    assert "2 bad input (nothing written); 3 the update stopped without converging (at its iteration cap)" in text


def test_the_trust_radius_grows_while_the_linearisation_holds_and_shrinks_when_it_does_not():
    from mace_fmu.updating.engine.solve import _next_radius

    # a step that reached the radius and fell as predicted (fall 90 of a predicted 100): doubled
    assert _next_radius(0.1, step=0.1, before=200.0, predicted=100.0, after=110.0) == 0.2
    # the same fall from a step inside the radius: the radius was not what limited it, kept
    assert _next_radius(0.1, step=0.05, before=200.0, predicted=100.0, after=110.0) == 0.1
    # a fall of 10 of a predicted 100: half the step
    assert _next_radius(0.1, step=0.08, before=200.0, predicted=100.0, after=190.0) == pytest.approx(0.04)
    # unbounded stays unbounded (the engine's default: the thesis's MACE update is unchanged)
    assert _next_radius(math.inf, step=0.3, before=200.0, predicted=100.0, after=190.0) == math.inf



def test_without_a_noise_floor_the_residual_is_still_held_to_the_input_correlation_test():
    """White inputs fill the band to Nyquist: no quiet band to measure the noise in. The reasons say the level
    test was not made and how to supply the noise; the fit has converged, and the residual's correlation with the
    force still tells a right model (explained) from one the data show wrong (a sensor lag the model lacks)."""
    from mace_fmu.updating.engine.convergence import convergence_report, missing_noise_floor, noise_floor

    cost = TimeResponseCost(_record(band_limited=False))
    result = _update(cost, off=0.02)
    why = missing_noise_floor(cost)
    assert "noise-floor test not made: the inputs fill the band up to" in why and "--noise-rms-percent" in why
    report = convergence_report(result, noise_floor=noise_floor(cost), missing_floor=why, cost=cost)
    assert report.converged and report.verdict == "explained" and report.reasons[-1] == why
    assert report.residuals.channels[0].noise_rms is None
    lagged = TimeResponseCost(_lagged_record(samples=SAMPLES, seed=3, lag_s=0.4))
    wrong = convergence_report(_update(lagged), noise_floor=None, missing_floor=missing_noise_floor(lagged),
                               cost=lagged)
    assert wrong.converged and wrong.verdict == "model error" and wrong.residuals.channels[0].noise_rms is None
    assert missing_noise_floor(cost, noise_rms_fraction=NOISE) == ""
    given = convergence_report(result, noise_floor=noise_floor(cost, noise_rms_fraction=NOISE))
    assert given.noise_floor is not None and "standard deviations from the noise floor" in given.reasons[-1]
    assert missing_noise_floor(TimeResponseCost(_record(band_limited=True))) == ""


def _lagged_record(*, samples: int, seed: int, lag_s: float) -> object:
    """The two-mass record as a sensor with a first-order lag of ``lag_s`` [s] reads it (a sensor dynamics the
    two-mass model lacks), with the same 5 % white noise."""
    import scipy.signal

    clean = two_mass_record(samples=samples, noise=0.0, seed=seed)
    y = clean.outputs["displacement_1"]
    a = np.exp(-clean.sample_time_s / lag_s)
    lagged = scipy.signal.lfilter([1 - a], [1, -a], y)
    rng = np.random.default_rng(seed + 1)
    noisy = lagged + NOISE * np.sqrt(np.mean(lagged**2)) * rng.standard_normal(lagged.size)
    from mace_fmu.updating.engine.measured import TimeHistory

    return TimeHistory(clean.times_s, clean.inputs, {"displacement_1": noisy}, source="lagged sensor")


def test_a_sensor_the_model_lacks_is_a_model_error_with_its_size_and_band_and_intervals_from_the_residuals():
    """The data's sensor lags by 0.4 s (a dynamics the two-mass model has not): the fit converges (step test),
    exit status 0, and the verdict says the model does not explain the data: residual RMS several times the
    noise, correlated with the force. The intervals then come from the residuals (the sandwich), wider than the
    noise's, and say so."""
    from mace_fmu.updating.engine.convergence import noise_floor
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty

    cost = TimeResponseCost(_lagged_record(samples=SAMPLES, seed=11, lag_s=0.4))
    result = _update(cost, off=0.02, method="cost-sensitivity", perturbation="reanalysis", max_outer=20)
    floor = noise_floor(cost, noise_rms_fraction=NOISE)
    report = convergence_report(result, noise_floor=floor, cost=cost)
    assert result.converged and report.verdict == "model error" and not report.failed
    (channel,) = report.residuals.channels
    assert channel.rms_over_noise > 2 and channel.correlated_inputs == ("force_1",)
    assert "model does not explain the data to their noise" in report.headline()
    noise_based = stage_uncertainty(result, noise_variance=floor.expected_cost / result.final_residual.size)[0]
    from_residuals = stage_uncertainty(result, noise_variance=floor.expected_cost / result.final_residual.size,
                                       residual_blocks=report.residuals and cost.residual_blocks())[0]
    assert from_residuals.method == "residuals" and "sandwich" in from_residuals.method_text
    for name in ("k_1", "k_2"):
        assert from_residuals.standard_deviation_percent[name] > 1.5 * noise_based.standard_deviation_percent[name]
