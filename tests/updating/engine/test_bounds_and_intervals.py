"""Bounds: the defaults by kind whatever the spelling of the name, and a parameter that ends at
a bound reported one-sided in the uncertainty table and uncertainty.toml, as the verdict says it is."""

from __future__ import annotations

import tomllib

import pytest
from support.two_mass_records import true_damping, two_mass_record

from mace_fmu.updating.engine.bounds import default_bounds
from mace_fmu.updating.engine.convergence import convergence_report
from mace_fmu.updating.engine.costs import TimeResponseCost
from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateSettings, update
from mace_fmu.updating.engine.uncertainty import (Z95_ONE_SIDED, format_uncertainty, one_sided_at_bounds,
                                                  stage_uncertainty, uncertainty_toml)
from mace_fmu.updating.sample.family import MODE_LABELS, TwoMassFamily
from mace_fmu.updating.sample.two_mass import TwoMassSystem


@pytest.mark.parametrize("name", ["damping_mode_3", "damping:1st Z bending"])
def test_a_damping_ratio_is_bounded_at_0_1_to_4_times_its_start_in_either_spelling(name):
    """A damping ratio that stopped at 5x its start: an FMU's name, damping_mode_3, was read as a parameter
    set's, had no kind, and took the others' x0.2-5."""
    bound = default_bounds([name], {name: 0.01})[name]
    assert (bound.lower, bound.upper) == pytest.approx((0.001, 0.04))
    assert default_bounds([name], {name: 0.5})[name].upper == 0.95


@pytest.mark.parametrize("name, low, high", [("E_lexan_end", 0.5, 1.5), ("m_floor_1", 0.5, 1.5), ("k_12", 0.2, 5.0),
                                             ("delay_gyro_bus_x", 0.2, 3.0), ("frequency_scale_mode_2", 0.2, 5.0),
                                             ("K_a", 0.2, 5.0), ("gain:strain_strut2_y", 0.2, 5.0)])
def test_the_defaults_by_kind_are_the_ones_the_guide_states(name, low, high):
    bound = default_bounds([name], {name: 2.0})[name]
    assert (bound.lower, bound.upper) == pytest.approx((2.0 * low, 2.0 * high))


def test_a_parameter_at_a_bound_has_a_one_sided_interval_in_the_table_and_the_file():
    """The two-mass fit with k_2 held below its truth (1.20) by the bound 1.19: the verdict names the upper bound,
    and so do the table and uncertainty.toml, the interval from value x (1 - 1.645 sd) to the bound, never past
    it (the two-sided interval went 1.96 sd beyond it)."""
    family = TwoMassFamily(masses=TwoMassSystem())
    actual = TwoMassSystem()
    start = {"k_1": 1.02 * actual.k1, "k_2": 0.98 * actual.k2,
             **{f"damping:{label}": z for label, z in zip(MODE_LABELS, true_damping())}}
    bounds = {"k_1": Bounds(0.2, 5.0), "k_2": Bounds(0.5, 1.19)}
    cost = TimeResponseCost(two_mass_record(samples=2048, noise=0.05, seed=3))
    result = update(family, cost, start=start, stages=[Stage("stiffness", ("k_1", "k_2"))], bounds=bounds,
                    settings=UpdateSettings(method="cost-sensitivity", perturbation="full", penalty=False,
                                            relative_step=1e-4, difference="central"))
    assert result.at_bounds == (("k_2", "upper"),)
    assert "interval is one-sided" in convergence_report(result).summary()
    two_sided = stage_uncertainty(result)
    (stage,) = one_sided_at_bounds(two_sided, result.at_bounds)
    value, sd = stage.values["k_2"], stage.standard_deviation_percent["k_2"] / 100
    assert two_sided[0].interval_95["k_2"][1] > 1.19  # the old table's: past the bound
    assert stage.interval_95["k_2"] == pytest.approx((value * (1 - Z95_ONE_SIDED * sd), value))
    assert value == pytest.approx(1.19, rel=1e-3) and stage.interval_95["k_2"][1] <= 1.19
    assert stage.interval_95["k_1"] == two_sided[0].interval_95["k_1"]  # the other parameter: two-sided, unchanged
    line = next(text for text in format_uncertainty((stage,)).splitlines() if text.strip().startswith("k_2"))
    assert line.endswith("one-sided: at its upper bound")
    written = tomllib.loads(uncertainty_toml((stage,)))["stage"][0]
    assert written["interval_95_at_bound"] == ["", "upper"]
    assert written["interval_95_high"][1] == value


def test_a_one_sided_interval_stays_within_the_declared_range():
    """The shaker beam's tip mass ended at its upper bound 0.15 kg with a standard deviation of 162 %: its one-sided
    interval ran to -0.25 kg. Held within the FMU's declared range (here 0.07-0.15 kg), it is [0.07, 0.15]; a
    reach that stays inside the range is unchanged, and so is the other side's."""
    from mace_fmu.updating.engine.uncertainty import StageUncertainty

    stage = StageUncertainty(stage="s", names=("m_shaker", "E_beam"), values={"m_shaker": 0.15, "E_beam": 1.4e11},
                             residuals=100, noise_variance=1.0,
                             standard_deviation_percent={"m_shaker": 162.0, "E_beam": 10.0},
                             correlation=None, interval_95={"m_shaker": (-0.33, 0.63), "E_beam": (1.1e11, 1.7e11)},
                             singular_values=None, weak_directions=(), tolerance_percent=5.0)
    ranges = {"m_shaker": (0.07, 0.15), "E_beam": (1.4e11, 3.0e11)}
    (clipped,) = one_sided_at_bounds((stage,), (("m_shaker", "upper"), ("E_beam", "lower")), ranges=ranges)
    assert clipped.interval_95["m_shaker"] == (0.07, 0.15)
    assert clipped.interval_95["E_beam"] == pytest.approx((1.4e11, 1.4e11 * (1 + Z95_ONE_SIDED * 0.10)))
    (free,) = one_sided_at_bounds((stage,), (("m_shaker", "upper"),))
    assert free.interval_95["m_shaker"][0] == pytest.approx(0.15 * (1 - Z95_ONE_SIDED * 1.62))
