"""Thesis Appendix A (modelling for control): LQG cost against an independent H2 computation and
against the thesis's stated findings, with the tolerances named in each test."""

from __future__ import annotations

import sys

import control as ct
import numpy as np
import pytest
import scipy.linalg as sla
from support.paths import EXAMPLES

from mace_fmu.cli import main
from mace_fmu.control_studies.cantilever import CantileverSpec, cantilever_model
from mace_fmu.control_studies.loop_shapes import dereverberated_crossover_hz, loop_shapes, siso_response
from mace_fmu.control_studies.lqg import LqgWeights, closed_loop_cost, design_lqg
from mace_fmu.control_studies.reduced_order import (THESIS_COSTS, balanced_model, modal_form, reduced_order_study,
                                                    weights_for_full_cost)
from mace_fmu.control_studies.stiffness_sensitivity import AUTHORITIES, study_authority
from mace_fmu.errors import MaceError
from mace_fmu.updating.sample.two_mass import TwoMassSystem

# Coarse grid (the CLI's default is 0.05 N/m); 600 designs per authority
K1_GRID = np.round(np.arange(0.1, 3.0 + 1e-9, 0.1), 10)
K2_GRID = np.round(np.arange(0.1, 2.0 + 1e-9, 0.1), 10)


@pytest.fixture(scope="module")
def studies():
    """The three maps; low authority only up to k1 = 2 N/m (its tests look no further)."""
    return {name: study_authority(name=name, actual=TwoMassSystem(), weights=w,
                                  k1_values=K1_GRID[K1_GRID <= 2.0 + 1e-9] if name == "low" else K1_GRID,
                                  k2_values=K2_GRID)
            for name, w in AUTHORITIES.items()}


def test_closed_loop_cost_is_the_h2_norm_of_the_interconnected_loop():
    """J from our Lyapunov solve equals python-control's H2 norm of the loop built by interconnect (1e-8)."""
    weights = LqgWeights(rho=1e-2, theta=0.5)
    plant = TwoMassSystem().state_space(force_on=1, measured=2)
    design = design_lqg(TwoMassSystem(k1=0.9, k2=1.1).state_space(force_on=1, measured=2), weights)
    # noises scaled to unit intensity; cost outputs y and sqrt(rho) u
    g = ct.ss(plant.A, np.hstack([plant.B, plant.B]), plant.C, np.zeros((1, 2)), inputs=["u", "w"], outputs=["y"])
    k = ct.ss(design.compensator.A, design.compensator.B, design.compensator.C, 0, inputs=["ym"], outputs=["u"])
    sensor = ct.ss([], [], [], [[1.0, np.sqrt(weights.theta)]], inputs=["y", "v"], outputs=["ym"])
    weight = ct.ss([], [], [], [[np.sqrt(weights.rho)]], inputs=["u"], outputs=["zu"])
    loop = ct.interconnect([g, k, sensor, weight], inputs=["w", "v"], outputs=["y", "zu"])
    assert closed_loop_cost(plant, design) == pytest.approx(ct.norm(loop, p=2) ** 2, rel=1e-8)


def test_unstable_loop_costs_infinity_and_bad_weights_are_refused():
    plant = TwoMassSystem().state_space(force_on=1, measured=2)
    soft = design_lqg(TwoMassSystem(k1=0.1, k2=0.1).state_space(force_on=1, measured=2), AUTHORITIES["low"])
    assert closed_loop_cost(plant, soft) == float("inf")
    with pytest.raises(MaceError, match="positive"):
        LqgWeights(rho=0.0, theta=1.0)


def test_the_actual_model_is_the_global_minimum(studies):
    """LQG is optimal for its own model: no design model does better on the actual system (to 1e-9)."""
    for s in studies.values():
        c = s.cost_map.normalised_cost
        assert np.nanmin(np.where(np.isfinite(c), c, np.nan)) >= 1.0 - 1e-9
        assert (s.minima[0].k1, s.minima[0].k2) == pytest.approx((0.75, 1.2), abs=2e-3)


def test_authorities_sit_below_inside_and_above_the_dynamics():
    """Our rule for rho (the thesis gives none): regulator poles vs. the modes at 0.56 and 1.68 rad/s."""
    plant = TwoMassSystem().state_space(force_on=1, measured=2)
    modes = np.sort(TwoMassSystem().modes()[0])
    poles = {n: np.sort(np.abs(np.linalg.eigvals(plant.A - plant.B @ design_lqg(plant, w).regulator_gain)))
             for n, w in AUTHORITIES.items()}
    assert np.allclose(poles["low"][::2], modes, rtol=5e-3)
    assert modes[0] < poles["moderate"][0] < modes[1] < poles["moderate"][-1]
    assert poles["high"].min() > modes[1]


def _fraction_below(study, level: float) -> float:
    """Fraction of the grid points with k1, k2 <= 2 N/m whose J/J_opt is below ``level``."""
    return float(np.mean(study.cost_map.normalised_cost[study.cost_map.k1 <= 2.0 + 1e-9] < level))


def test_low_authority_is_flat_with_an_unstable_lower_left_corner(studies):
    """Fig. A.2: flat, a large region within 10 %: on k1, k2 <= 2 N/m ours is within 20 % on over
    half (57 %) and within 10 % on 39 %, over five times the moderate and high regions (6-7 %).
    The unstable region is the corner of soft springs only (ours: k1 <= 0.5 and k2 <= 0.3)."""
    s = studies["low"]
    assert _fraction_below(s, 1.2) > 0.5
    assert _fraction_below(s, 1.1) > 5 * max(_fraction_below(studies[n], 1.1) for n in ("moderate", "high"))
    k2, k1 = np.meshgrid(s.cost_map.k2, s.cost_map.k1)
    unstable = ~np.isfinite(s.cost_map.normalised_cost)
    assert unstable[0, 0] and unstable.any()
    assert k1[unstable].max() <= 0.5 + 1e-9 and k2[unstable].max() <= 0.3 + 1e-9


def test_moderate_authority_tolerates_k2_from_1_0_to_1_4_and_is_more_sensitive_to_k2(studies):
    """Fig. A.3: J/J_opt < 1.1 only for k2 from 1.0 to 1.4 (ends within one grid step, 0.1 N/m); the
    cost curves twice as fast in k2 as in k1 at the actual system (ours: 3.6 vs 1.8), and the
    tolerable span in k2 is narrower than in k1."""
    s = studies["moderate"]
    (a1, b1), (a2, b2) = s.tolerable
    assert a2 == pytest.approx(1.0, abs=0.1) and b2 == pytest.approx(1.4, abs=0.1)
    assert s.curvatures[1] > 1.5 * s.curvatures[0]
    assert b2 - a2 < b1 - a1


def test_high_authority_is_a_valley_along_k1(studies):
    """Fig. A.4: the low-cost region stretches along k1 (span in k1 > 1.5x span in k2) and the cost
    curves at least 2.5x faster in k2 than in k1 at the actual system (ours: 4.5 vs 1.4)."""
    s = studies["high"]
    (a1, b1), (a2, b2) = s.tolerable
    assert b1 - a1 > 1.5 * (b2 - a2)
    assert s.curvatures[1] > 2.5 * s.curvatures[0]


def test_second_minimum_has_the_same_frequencies_and_another_mode_shape():
    """k1 + 2 k2 and k1 k2 fix both frequencies (m1 = m2 = 1): (2.4, 0.375) N/m has the actual
    system's frequencies to 1e-12 and different shapes (the thesis's reading of the second minimum)."""
    w_actual, phi_actual = TwoMassSystem().modes()
    w_other, phi_other = TwoMassSystem(k1=2.4, k2=0.375).modes()
    np.testing.assert_allclose(w_other, w_actual, rtol=1e-12)
    assert np.abs(phi_other - phi_actual).max() > 0.3


@pytest.mark.parametrize("authority", ["moderate", "high"])
def test_second_minimum_for_k1_between_2_and_3(studies, authority):
    """Thesis: a second local minimum for k1 in 2-3 at a cost about 60 % above the global one
    (high authority), in the same place for the other authorities. Ours: J/J_opt 1.41 (high) and
    1.47 (moderate), within 15 % of 1.6, at k1 = 2.15 N/m, within 0.3 N/m of the same-frequency
    point (2.4, 0.375). At low authority ours lies at (1.34, 0.47) N/m instead (docs/guide/appendix_a.md)."""
    second = studies[authority].minima[1]
    assert 2.0 <= second.k1 <= 3.0
    assert second.normalised_cost == pytest.approx(1.6, rel=0.15)
    assert second.k1 == pytest.approx(2.4, abs=0.3) and second.k2 == pytest.approx(0.375, abs=0.1)


def test_example_lqg_model_error():
    """examples/lqg_model_error.py: k2 off by 10 % costs a few percent, by 20 % more (moderate)."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        from lqg_model_error import model_error_costs
    finally:
        sys.path.remove(str(EXAMPLES))
    costs = model_error_costs()
    assert costs[1.0] == pytest.approx(1.0, abs=1e-12)
    assert 1.0 < costs[0.9] < costs[0.8] and 1.0 < costs[1.1] < costs[1.2]


def test_cli_study_lqg_sensitivity_writes_figures_and_table(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["study", "lqg-sensitivity", "--out", str(out), "--k1", "0.5:1.0:0.25", "--k2", "1.0:1.4:0.2",
                 "--quiet"]) == 0
    for name in ("figure_A2_low_authority.png", "figure_A3_moderate_authority.png", "figure_A4_high_authority.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    table = (out / "lqg_sensitivity.txt").read_text()
    assert "moderate authority: rho = 0.01, theta = 1" in table
    assert "global minimum: k1 = 0.750, k2 = 1.200" in table
    assert not list(out.glob("*.part"))
    capsys.readouterr()
    assert main(["study", "lqg-sensitivity", "--out", str(out), "--k1", "1:0.5:0.1"]) == 2
    assert "START < STOP" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# A.2: the cantilever and Table A.1

EULER_BERNOULLI_BETA_L = np.array([1.875104069, 4.694091133, 7.854757438, 10.99554073, 14.13716839])


@pytest.fixture(scope="module")
def beam():
    return cantilever_model()


def test_cantilever_from_beam_elements_matches_euler_bernoulli(beam):
    """20 CBARs (consistent mass): the five frequencies within 3e-4 of (beta_n L)^2 sqrt(EI / rho A L^4)
    / 2 pi (mode 5 is 1.7e-4 high); the fundamental is the thesis's 27.8 Hz; the length is the
    closed-form one (1e-6); the tip's modal mass is m / 4 (phi_tip^2 m = 4, 0.3 %)."""
    spec = beam.spec
    ei, mu = spec.youngs_modulus * spec.bending_inertia, spec.density * spec.area
    exact = EULER_BERNOULLI_BETA_L**2 * np.sqrt(ei / (mu * beam.length**4)) / (2 * np.pi)
    np.testing.assert_allclose(beam.frequencies_hz, exact, rtol=3e-4)
    assert beam.frequencies_hz[0] == pytest.approx(27.8, rel=1e-6)
    length = np.sqrt(EULER_BERNOULLI_BETA_L[0] ** 2 * np.sqrt(ei / mu) / (2 * np.pi * 27.8))
    assert beam.length == pytest.approx(length, rel=1e-6)
    np.testing.assert_allclose(beam.tip_shapes**2 * mu * beam.length, 4.0, rtol=3e-3)
    assert beam.system.nstates == 10 and beam.system.input_labels == ["tip_force"]


def test_cantilever_refuses_too_few_elements():
    with pytest.raises(MaceError, match="fewer than"):
        cantilever_model(CantileverSpec(elements=2))


def test_modal_form_keeps_the_transfer_function(beam):
    """Second-order blocks with B = [0, 1], C = [n0, n1] reproduce the model to 1e-9 (relative)."""
    f = np.logspace(0, 4, 301)
    for system in (beam.system, balanced_model(beam.system, states=8)[0]):
        form = modal_form(system).system(inputs=["u"], outputs=["y"], name="modal")
        np.testing.assert_allclose(siso_response(form, f), siso_response(system, f), rtol=1e-9)


def _gramians(system: ct.StateSpace) -> tuple[np.ndarray, np.ndarray]:
    a, b, c = system.A, system.B, system.C
    return (sla.solve_continuous_lyapunov(a, -b @ b.T), sla.solve_continuous_lyapunov(a.T, -c.T @ c))


def test_balanced_truncation_is_balanced_and_within_its_error_bound(beam):
    """Square-root balanced truncation to 8 states: the reduced model's two gramians both equal
    diag of the first 8 Hankel singular values (1e-6 of the largest); these are the square roots of
    the eigenvalues of Wc Wo of the full model (1e-6); poles at the first four modes (0.1 %); and
    |G - G_r| below twice the sum of the discarded singular values at every frequency."""
    reduced, hsv = balanced_model(beam.system, states=8)
    assert reduced.nstates == 8
    wc, wo = _gramians(reduced)
    for w in (wc, wo):
        np.testing.assert_allclose(w, np.diag(hsv[:8]), atol=1e-6 * hsv[0])
    full_wc, full_wo = _gramians(beam.system)
    np.testing.assert_allclose(np.sort(np.sqrt(np.linalg.eigvals(full_wc @ full_wo).real))[::-1], hsv, rtol=1e-6)
    poles = np.sort(np.abs(np.linalg.eigvals(reduced.A)))[::2] / (2 * np.pi)
    np.testing.assert_allclose(poles, beam.frequencies_hz[:4], rtol=1e-3)
    f = np.logspace(0, 4.5, 3001)
    assert np.abs(siso_response(beam.system, f) - siso_response(reduced, f)).max() <= 2 * hsv[8:].sum()


def test_balanced_truncation_equals_control_balred_where_slycot_is_installed(beam):
    """Where slycot is present (not a dependency: see balanced_truncation.py), control.balred gives
    the same transfer function to 1e-6 of its peak."""
    pytest.importorskip("slycot")
    f = np.logspace(0, 4, 801)
    ours = siso_response(balanced_model(beam.system, states=8)[0], f)
    theirs = siso_response(ct.balred(beam.system, 8, method="truncate"), f)
    assert np.abs(ours - theirs).max() <= 1e-6 * np.abs(theirs).max()


def test_balanced_truncation_refuses_unstable_models_and_orders_beyond_the_minimal_one():
    with pytest.raises(MaceError, match="not asymptotically stable"):
        balanced_model(ct.ss([[0.0, 1.0], [-1.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]], 0), states=1)
    uncontrollable = ct.ss(np.diag([-1.0, -2.0]), [[1.0], [0.0]], [[1.0, 1.0]], 0)
    with pytest.raises(MaceError, match="states must be 1-1 .*1 of its 2 states are uncontrollable"):
        balanced_model(uncontrollable, states=2)
    # within the numerical order it reduces: the controllable part is 1 / (s + 1) exactly
    reduced = balanced_model(uncontrollable, states=1)[0]
    np.testing.assert_allclose(np.linalg.eigvals(reduced.A), [-1.0], rtol=1e-12)
    np.testing.assert_allclose((reduced.C @ reduced.B)[0, 0], 1.0, rtol=1e-12)


@pytest.fixture(scope="module")
def table_a1(beam):
    """Table A.1 with a short update (12 BFGS iterations; the CLI's default 200 reach J/J_full 1.053)."""
    weights = weights_for_full_cost(beam.system, target_cost=THESIS_COSTS["full"])
    return reduced_order_study(full=beam.system, weights=weights, max_iterations=12)


def test_full_order_loop_crosses_over_near_the_third_mode(beam, table_a1):
    """rho = theta is set by the thesis's J_full alone; the dereverberated loop then crosses over
    within a factor 1.5 of the third mode (ours: 334 Hz, third mode 488 Hz), as the thesis says."""
    assert table_a1.costs["full"] == pytest.approx(THESIS_COSTS["full"], rel=1e-6)
    f = np.logspace(0, 4, 4001)
    crossover = dereverberated_crossover_hz(loop_shapes(table_a1, frequencies_hz=f).loops["full"], f)
    assert beam.frequencies_hz[2] / 1.5 < crossover < 1.5 * beam.frequencies_hz[2]


def test_table_a1_ordering_and_ratios(table_a1):
    """J_full < J_updated < J_balanced; the ratios to J_full within 5 % of the thesis's 1.125 and
    1.091 (ours: 1.078, -4.2 %; 1.066 after 12 iterations, 1.053 after the CLI's 200)."""
    c = table_a1.costs
    assert c["full"] < c["updated"] < c["balanced"]
    thesis = {k: v / THESIS_COSTS["full"] for k, v in THESIS_COSTS.items()}
    assert c["balanced"] / c["full"] == pytest.approx(thesis["balanced"], rel=0.05)
    assert c["updated"] / c["full"] == pytest.approx(thesis["updated"], rel=0.05)


def test_unreachable_full_cost_is_refused(beam):
    with pytest.raises(MaceError, match="no rho"):
        weights_for_full_cost(beam.system, target_cost=1.0)


@pytest.mark.slow
def test_cli_study_reduced_order_writes_figures_and_table(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["study", "reduced-order", "--out", str(out), "--max-iterations", "1", "--quiet"]) == 0
    for name in ("figure_A6_open_loop.png", "figure_A7_loop.png", "figure_A8_compensators.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    table = (out / "table_A1.txt").read_text()
    assert "rho = theta = 3.864e-10" in table and "balanced" in table
    capsys.readouterr()
    with pytest.raises(SystemExit) as refused:  # refused as it is parsed, in one line naming the option
        main(["study", "reduced-order", "--out", str(out), "--max-iterations", "-1"])
    assert refused.value.code == 2
    assert "argument --max-iterations: expected an integer >= 1, got '-1'" in capsys.readouterr().err


def test_failed_riccati_solution_is_one_clear_error():
    """An unstable mode the force cannot move: no stabilising regulator, one message naming the model."""
    model = ct.ss(np.diag([1.0, -1.0]), [[0.0], [1.0]], [[1.0, 1.0]], 0, name="unstabilisable")
    with pytest.raises(MaceError, match="LQG design of 'unstabilisable' failed for rho = 1, theta = 1"):
        design_lqg(model, LqgWeights(rho=1.0, theta=1.0))
