"""The updating engine (thesis 4.2): parameter sets, costs, inclusion methods, sensitivities, selection, solver.

Checked against closed forms on the two-mass system (eigenvalue derivatives, exact recovery from
noise-free data) and against a second route on the MACE model (reanalysis and modal
sensitivities against full re-solves).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.parameters.sets import ParameterSet, Provenance, deck_fingerprint, fe_overrides
from mace_fmu.structure.build import apply_overrides
from mace_fmu.structure.file import bundled_deck_path
from mace_fmu.updating.engine.costs import FrequencyResponseCost, ModalCost, TimeResponseCost, UnpairedModeError
from mace_fmu.updating.engine.inclusion import modal_sensitivity, track_modes
from mace_fmu.updating.engine.measured import MeasuredFrf, MeasuredMode, TimeHistory
from mace_fmu.updating.engine.selection import SelectionRule, select_parameters
from mace_fmu.updating.engine.sensitivity import CostSensitivities, cost_sensitivities
from mace_fmu.updating.engine.solve import Bounds, Stage, UpdateSettings, update
from mace_fmu.updating.sample.family import TwoMassFamily
from mace_fmu.updating.sample.two_mass import TwoMassSystem

START = {"k_1": 1.0, "k_2": 1.0, "damping:mode 1": 0.01, "damping:mode 2": 0.01}
TRUTH = {"k_1": 0.75, "k_2": 1.2, "damping:mode 1": 0.004, "damping:mode 2": 0.008}


# --- parameter sets ---------------------------------------------------------------------------
def test_parameter_set_round_trips_through_toml(tmp_path):
    prov = Provenance(created="2026-11-23T10:00:00+00:00", tool="mace-fmu test", deck="mace_em.bdf",
                      deck_sha256=deck_fingerprint(bundled_deck_path()), configuration="1g", data="Table 4.7",
                      cost="modal", initial_cost=0.0223, final_cost=0.0145, notes='quote " and\nnewline')
    values = {"E_lexan_center": 2.335e9, "k_suspension_device_1": 17.04, "delay_gimbal_primary_x": 4.56e-3,
              "K_a": -2.0, "damping:1st Z bending": 0.022}
    path = ParameterSet(values, prov).write(tmp_path / "p.toml")
    back = ParameterSet.read(path)
    assert dict(back.values) == values  # repr(float) round-trips exactly
    assert back.provenance == prov
    assert "# [Pa]" in path.read_text() and '"damping:1st Z bending"' in path.read_text()


@pytest.mark.parametrize(("values", "message"), [
    ({"E_lexan_center": math.nan}, "must be a finite number"),
    ({"G_lexan": 1e9}, "unknown kind of name"),
    ({"damping:": 0.1}, "unknown kind of name"),
    ({"K_a": True}, "must be a finite number"),
])
def test_bad_parameter_values_are_refused(values, message):
    with pytest.raises(MaceError, match=message):
        ParameterSet(values)


def test_parameter_files_that_are_not_parameter_sets_are_refused(tmp_path):
    with pytest.raises(MaceError, match="no such parameter file"):
        ParameterSet.read(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[values]\nE_lexan_center = 'stiff'\n")
    with pytest.raises(MaceError, match=r"bad.toml: parameter 'E_lexan_center': value must be a finite number"):
        ParameterSet.read(bad)
    bad.write_text("[valuez]\nK_a = 1.0\n")
    with pytest.raises(MaceError, match=r"unknown table\(s\) \['valuez'\]"):
        ParameterSet.read(bad)


def test_a_parameter_set_made_for_another_deck_is_refused(tmp_path):
    other = tmp_path / "other.bdf"
    other.write_text(bundled_deck_path().read_text() + "$ edited\n")
    made_for_other = ParameterSet({"E_lexan_center": 2.4e9}, Provenance(created="now", tool="t", deck="other.bdf",
                                                                         deck_sha256=deck_fingerprint(other)))
    with pytest.raises(MaceError, match="made for deck 'other.bdf'"):
        compute_modes(configuration="0g", parameters=made_for_other)


def test_moduli_in_a_parameter_set_are_deck_overrides():
    """E_ and k_ names resolve to MAT1 and CELAS2 cards through the data file's [parameters] table."""
    assert fe_overrides(ParameterSet({"E_lexan_center": 2.4e9, "k_suspension_device_2": 20.0})) == {
        ("MAT1", 2): {"e": 2.4e9}, ("CELAS2", 139): {"k": 20.0}}
    a = compute_modes(configuration="0g", parameters=ParameterSet({"E_lexan_center": 2.4e9}))
    b = compute_modes(apply_overrides(read_deck(bundled_deck_path()), {("MAT1", 2): {"e": 2.4e9}}), configuration="0g")
    np.testing.assert_array_equal(a.frequencies_hz, b.frequencies_hz)
    with pytest.raises(MaceError, match="no such material; known: E_lexan_end"):
        fe_overrides(ParameterSet({"E_unobtainium": 1e9}))


# --- costs ------------------------------------------------------------------------------------
def test_costs_vanish_on_the_model_that_made_the_data_and_see_a_known_error():
    family = TwoMassFamily()
    model = family.full(TRUTH)
    poles = model.poles()
    measured = tuple(MeasuredMode(label=p.label, pattern=p.label, frequency_hz=p.frequency_hz, damping=p.damping)
                     for p in poles)
    assert np.abs(ModalCost(measured=measured).residual(model)).max() < 1e-12
    f = np.linspace(0.02, 0.4, 50)
    h = model.frequency_response(f)
    data = MeasuredFrf(f, ("force_1",), ("displacement_1",), h)
    assert np.abs(FrequencyResponseCost(data).residual(model)).max() < 1e-12
    # data twice the model: log|G_d/G_m| = ln 2 at every line, no phase error (eq. 4.5)
    doubled = FrequencyResponseCost(MeasuredFrf(f, data.inputs, data.outputs, 2 * h))
    j = doubled.residual(model)
    np.testing.assert_allclose(j[:50], math.log(2.0), atol=1e-12)
    np.testing.assert_allclose(j[50:], 0.0, atol=1e-12)
    magnitude = FrequencyResponseCost(MeasuredFrf(f, data.inputs, data.outputs, 2 * h), kind="magnitude")
    np.testing.assert_allclose(magnitude.residual(model)[:50], h[:, 0, 0].real, atol=1e-15)
    t = 0.5 * np.arange(400)
    u = np.random.default_rng(3).standard_normal(400)
    y = model.time_response(t, {"force_1": u})[:, 0]
    record = TimeHistory(t, {"force_1": u}, {"displacement_1": y})
    assert np.abs(TimeResponseCost(record).residual(model)).max() < 1e-10


def test_time_response_is_the_zero_order_hold_of_the_physical_system():
    """Second route: the modal LinearModel (eigen-coordinates, lfilter) against python-control's
    own discretisation of the physical state-space model with the same modal damping."""
    import control as ct

    family = TwoMassFamily()
    values = {**TRUTH, "damping:mode 1": 0.0, "damping:mode 2": 0.0}  # undamped: modal = physical model
    t = 0.25 * np.arange(2000)
    u = np.sin(0.3 * t) + np.random.default_rng(0).standard_normal(t.size)
    ours = family.full(values).time_response(t, {"force_1": u})[:, 0]
    plant = TwoMassSystem(c1=0.0, c2=0.0).state_space()
    ref = ct.forced_response(ct.c2d(plant, 0.25, method="zoh"), T=t, U=u).outputs
    assert np.max(np.abs(ours - ref)) < 1e-9 * np.max(np.abs(ref))


def test_unpaired_measured_modes_and_bad_data_are_clear_errors():
    model = TwoMassFamily().full(TRUTH)
    cost = ModalCost(measured=(MeasuredMode(label="3rd violin", pattern="*violin*", frequency_hz=0.3, damping=0.01),))
    with pytest.raises(UnpairedModeError, match="'3rd violin' at 0.3 Hz: no model pole matches its pattern"):
        cost.residual(model)
    with pytest.raises(MaceError, match=r"data.csv: channel 'y' is not finite \(NaN or inf\) at row 2"):
        TimeHistory(np.arange(4.0), {"u": np.zeros(4)}, {"y": np.array([0.0, 1.0, np.nan, 2.0])}, source="data.csv")
    with pytest.raises(MaceError, match="time is not increasing at row 2"):
        TimeHistory(np.array([0.0, 1.0, 1.0, 2.0]), {}, {"y": np.zeros(4)}, source="data.csv")
    with pytest.raises(MaceError, match="damping ratio must be in"):
        MeasuredMode(label="m", pattern="*", frequency_hz=1.0, damping=math.nan)


# --- inclusion methods and sensitivities ---------------------------------------------------------
def test_reanalysis_of_the_two_mass_system_is_exact():
    """Two retained modes span the whole space: Ritz reanalysis equals a new eigen-solution."""
    family = TwoMassFamily()
    at = family.basis(START).model(TRUTH)
    exact = family.full(TRUTH)
    np.testing.assert_allclose(sorted(abs(p.eigenvalue) for p in at.poles()),
                               sorted(abs(p.eigenvalue) for p in exact.poles()), rtol=1e-12)


def test_modal_sensitivities_extrapolate_linearly_and_match_eigenvalue_derivatives():
    """df/dk_i from finite differences against the closed form phi^T dK/dk_i phi / (2 omega) / (2 pi)."""
    family = TwoMassFamily()
    sens = modal_sensitivity(family.basis(START), START, ["k_1", "k_2"], relative_step=1e-6)
    omega2, phi = family.modes(START)
    dk = {"k_1": np.array([[1.0, 0.0], [0.0, 0.0]]), "k_2": np.array([[1.0, -1.0], [-1.0, 1.0]])}
    for i, name in enumerate(sens.names):
        exact = np.array([phi[:, m] @ dk[name] @ phi[:, m] for m in range(2)]) / (2 * np.sqrt(omega2)) / (2 * np.pi)
        np.testing.assert_allclose(sens.df[i], START[name] * exact, rtol=1e-5)
    near = {**START, "k_1": 1.001}
    np.testing.assert_allclose(sorted(abs(p.eigenvalue) for p in sens(near).poles()),
                               sorted(abs(p.eigenvalue) for p in family.full(near).poles()), rtol=1e-6)


def test_mode_tracking_undoes_a_swap_and_a_sign_flip():
    t = np.array([[0.0, -0.99, 0.1], [1.0, 0.0, 0.0], [0.0, 0.1, 0.99]])
    f, tt = track_modes(np.array([2.0, 1.0, 3.0]), t)
    np.testing.assert_array_equal(f, [1.0, 2.0, 3.0])
    assert np.all(np.diag(tt) > 0)


def test_cost_sensitivities_match_analytic_frequency_derivatives():
    """Eq. 4.12 for a modal cost j = (f_meas - f) / f_meas: dj/dx_i = -x_i df/dk_i / f_meas."""
    family = TwoMassFamily()
    model = family.full(TRUTH)
    measured = tuple(MeasuredMode(label=p.label, pattern=p.label, frequency_hz=p.frequency_hz, damping=p.damping)
                     for p in model.poles())
    cost = ModalCost(measured=measured, damping_weight=0.0)
    sens = cost_sensitivities(cost, base_model=family.full(START), perturbed=family.full, base=START,
                              names=["k_1", "k_2"], relative_step=1e-7)
    omega2, phi = family.modes(START)
    for i, (name, dk) in enumerate((("k_1", [[1, 0], [0, 0]]), ("k_2", [[1, -1], [-1, 1]]))):
        dk = np.array(dk, dtype=float)
        df = np.array([phi[:, m] @ dk @ phi[:, m] for m in range(2)]) / (2 * np.sqrt(omega2)) / (2 * np.pi)
        expected = -START[name] * df / np.array([m.frequency_hz for m in measured])
        np.testing.assert_allclose(sens.matrix[:2, i], expected, rtol=1e-5)


# --- selection ----------------------------------------------------------------------------------
def test_selection_drops_weak_and_aligned_parameters_and_keeps_groups():
    j0 = np.array([1.0, 1.0, 0.0])
    dj = np.column_stack([[1.0, 0.0, 0.0], [2.0, 0.02, 0.0], [0.0, 1e-3, 1.0], [0.0, 0.3, 0.0], [0.0, 0.01, 0.0]])
    sens = CostSensitivities(names=("a", "a_twin", "weak", "b", "b_partner"), base={}, j0=j0, matrix=dj,
                             relative_step=0.01, perturbation="full")
    sel = select_parameters(sens, rule=SelectionRule(min_relative_strength=0.1, max_alignment=0.99,
                                                     groups=(("b", "b_partner"),)))
    assert sel.keep == ("a_twin", "b", "b_partner")
    assert "aligned with the stronger a_twin" in sel.reasons["a"]
    assert sel.reasons["weak"].startswith("weak")
    assert "kept with its group" in sel.reasons["b_partner"]
    np.testing.assert_allclose(np.diag(sel.orthogonality), 1.0)
    # scaled by allowed perturbations (thesis 4.2.2): a parameter that may move 100x further counts 100x more
    scaled = select_parameters(sens, allowed_perturbation={"weak": 1000.0})
    assert "weak" in scaled.keep


# --- the solver -----------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["cost-sensitivity", "full", "reanalysis", "modal-sensitivity"])
def test_every_method_recovers_the_springs_from_exact_modal_data(method):
    family = TwoMassFamily()
    truth = family.full(TRUTH)
    measured = tuple(MeasuredMode(label=p.label, pattern=p.label, frequency_hz=p.frequency_hz, damping=p.damping)
                     for p in truth.poles())
    cost = ModalCost(measured=measured, damping_weight=0.0)
    bounds = {n: Bounds(0.2, 5.0) for n in ("k_1", "k_2")}
    settings = UpdateSettings(method=method, penalty=False, tolerance=1e-9, max_outer=30, relative_step=1e-4,
                              perturbation="full")
    result = update(family, cost, start=START, stages=[Stage("springs", ("k_1", "k_2"))], bounds=bounds,
                    settings=settings)
    assert result.values["k_1"] == pytest.approx(0.75, rel=1e-6)
    assert result.values["k_2"] == pytest.approx(1.2, rel=1e-6)
    assert result.final_cost < 1e-12 * result.initial_cost


def test_the_penalty_holds_parameters_back_by_the_stated_weighting():
    """Eq. 4.18 with gamma = 10 %: the penalised optimum moves less than the unpenalised one."""
    family = TwoMassFamily()
    measured = tuple(MeasuredMode(label=p.label, pattern=p.label, frequency_hz=p.frequency_hz, damping=p.damping)
                     for p in family.full(TRUTH).poles())
    cost = ModalCost(measured=measured, damping_weight=0.0)
    bounds = {n: Bounds(0.2, 5.0, gamma_percent=10.0) for n in ("k_1", "k_2")}
    kwargs = dict(start=START, stages=[Stage("springs", ("k_1", "k_2"))], bounds=bounds)
    free = update(family, cost, settings=UpdateSettings(method="full", penalty=False), **kwargs)
    held = update(family, cost, settings=UpdateSettings(method="full", penalty=True), **kwargs)
    assert abs(held.values["k_1"] - 1.0) < abs(free.values["k_1"] - 1.0)
    assert held.final_cost > free.final_cost


@pytest.mark.parametrize(("stages", "bounds", "message"), [
    ([Stage("s", ("k_3",))], {"k_3": Bounds(0.1, 2.0)}, "'k_3' has no start value"),
    ([Stage("s", ("k_1",))], {}, "'k_1' has no bounds"),
    ([Stage("s", ("k_1",))], {"k_1": Bounds(1.5, 2.0)}, r"bounds \[1.5, 2\] exclude its start value 1"),
])
def test_bad_update_requests_are_refused_before_any_work(stages, bounds, message):
    with pytest.raises(MaceError, match=message):
        update(TwoMassFamily(), ModalCost(measured=()), start=START, stages=stages, bounds=bounds)
