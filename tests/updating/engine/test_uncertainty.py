"""The uncertainty an update reports is calibrated: its 95 % intervals hold the truth about 95 % of the time.

Forty seeded noise realisations of the two-mass experiment (k1 = 0.75, k2 = 1.20 N/m; 5 % output noise),
each updated by the cost-sensitivity method from 2 % off; the reported intervals must cover the
truth in 88-99 % of the 80 cases (a binomial 95 % coverage over 80 draws lands there with
probability above 0.98). A second check: the reported standard deviations match the spread of the
forty answers within a factor 1.5.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.two_mass_records import true_damping, two_mass_record

from mace_fmu.updating.engine.costs import TimeResponseCost
from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateSettings, update
from mace_fmu.updating.engine.uncertainty import format_uncertainty, stage_uncertainty, uncertainty_toml
from mace_fmu.updating.sample.family import MODE_LABELS, TwoMassFamily
from mace_fmu.updating.sample.two_mass import TwoMassSystem

TRUTH = {"k_1": 0.75, "k_2": 1.20}
SETTINGS = UpdateSettings(method="cost-sensitivity", perturbation="full", penalty=False, relative_step=1e-4,
                          difference="central", max_outer=20)


def _update(seed: int):
    family = TwoMassFamily(masses=TwoMassSystem())
    cost = TimeResponseCost(two_mass_record(samples=512, noise=0.05, seed=seed))
    start = {"k_1": 0.98 * TRUTH["k_1"], "k_2": 1.02 * TRUTH["k_2"],
             **{f"damping:{label}": z for label, z in zip(MODE_LABELS, true_damping())}}
    bounds = {n: Bounds(0.2 * v, 5.0 * v) for n, v in start.items()}
    return update(family, cost, start=start, stages=[Stage("stiffness", ("k_1", "k_2"))], bounds=bounds,
                  settings=SETTINGS)


@pytest.fixture(scope="module")
def runs():
    out = []
    for seed in range(100, 140):
        result = _update(seed)
        assert result.converged, result.reasons
        (stage,) = stage_uncertainty(result)
        out.append((result, stage))
    return out


def test_95_percent_intervals_cover_the_truth_in_88_to_99_percent_of_runs(runs):
    hits = [st.interval_95[n][0] <= TRUTH[n] <= st.interval_95[n][1] for _, st in runs for n in TRUTH]
    assert 0.88 <= np.mean(hits) <= 0.99, np.mean(hits)


def test_reported_standard_deviations_match_the_spread_of_the_answers(runs):
    for n in TRUTH:
        spread = 100 * np.std([r.values[n] / TRUTH[n] - 1 for r, _ in runs], ddof=1)
        reported = np.median([st.standard_deviation_percent[n] for _, st in runs])
        assert 1 / 1.5 <= reported / spread <= 1.5, (n, reported, spread)


def test_report_files_and_table_name_every_parameter(runs):
    import tomllib

    result, stage = runs[0]
    text = uncertainty_toml((stage,))
    parsed = tomllib.loads(text)["stage"][0]
    assert parsed["parameters"] == ["k_1", "k_2"] and len(parsed["correlation"]) == 2
    assert parsed["interval_95_low"][0] < result.values["k_1"] < parsed["interval_95_high"][0]
    table = format_uncertainty((stage,))
    assert "k_1" in table and "95 % interval" in table


def test_a_combination_the_data_cannot_see_is_named():
    """k1 and k2 moved together from a record too short to separate them: the weak direction is flagged in names."""
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty as su

    family = TwoMassFamily(masses=TwoMassSystem())
    cost = TimeResponseCost(two_mass_record(samples=24, noise=0.3, seed=5))
    start = {"k_1": 0.98 * TRUTH["k_1"], "k_2": 1.02 * TRUTH["k_2"],
             **{f"damping:{label}": z for label, z in zip(MODE_LABELS, true_damping())}}
    bounds = {n: Bounds(0.2 * v, 5.0 * v) for n, v in start.items()}
    result = update(family, cost, start=start, stages=[Stage("stiffness", ("k_1", "k_2"))], bounds=bounds,
                    settings=SETTINGS)
    (stage,) = su(result, tolerance_percent=1.0)
    assert stage.weak_directions, format_uncertainty((stage,))
    text = stage.weak_directions[0].text()
    assert "k_1" in text and "k_2" in text
