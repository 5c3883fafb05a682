"""Instruments, damping and the physical modal model (thesis 3.4, Appendix C)."""

from __future__ import annotations

import numpy as np
import pytest
from support.paths import DATA

from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.damping import modal_damping
from mace_fmu.iomodel.instruments import influence_vector, load_instruments
from mace_fmu.iomodel.modal_ss import modal_plant
from mace_fmu.util.frequency import ZERO_HZ


@pytest.fixture(scope="module")
def inst():
    return load_instruments()


@pytest.fixture(scope="module")
def m0():
    return compute_modes(configuration="0g")


@pytest.fixture(scope="module")
def m1():
    return compute_modes(configuration="1g", preload="linear")


def test_nine_actuators_and_twenty_sensors_in_thesis_order(inst):
    assert [a.name for a in inst.actuators] == [
        "gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z",
        "rwa_x", "rwa_y", "rwa_z", "active_strut_y", "active_strut_z"]
    assert len(inst.sensors) == 20
    assert len(inst.analog_sensor_names) == 13  # 8 strain gages + 5 rate gyros carry Bessel filters
    kinds = [s.kind for s in inst.sensors]
    assert kinds.count("displacement") == 8 and kinds.count("rate") == 12


def test_gains_follow_tables_3_11_to_3_13(inst):
    assert inst.actuator("gimbal_primary_x").gain == pytest.approx(0.2625)
    assert inst.actuator("rwa_y").gain == pytest.approx(0.1031, rel=1e-3)
    assert inst.actuator("active_strut_z").gain == pytest.approx(0.1223, rel=1e-3)
    assert inst.sensor("strain_strut3_y").gain == pytest.approx(500.0)  # 0.5 mV / microstrain
    notch = {"gyro_payload_x": 2.30, "gyro_payload_z": 2.70, "gyro_bus_x": 2.59, "gyro_bus_y": 2.32, "gyro_bus_z": 2.39}
    for name, dc in notch.items():
        assert inst.sensor(name).gain == pytest.approx(8.213 * dc, rel=1e-4)


def test_wheel_axes_are_the_deck_skew_systems_and_orthonormal(inst, m0):
    """The wheel input rows are the z axes of CORD2R 1-3 (they happen to be orthonormal)."""
    rows = np.array([[w for _, _, w in inst.actuator(n).dofs[::2]] for n in ("rwa_x", "rwa_y", "rwa_z")])
    # Appendix C prints 6 digits: 2 * 0.707146^2 = 1.00011
    np.testing.assert_allclose(rows @ rows.T, np.eye(3), atol=3e-4)
    frames = m0.model.cd_frames
    for k, grid in enumerate((54, 57, 60)):
        spin = frames[m0.model.dofs.grid_index(grid)][:, 2]
        np.testing.assert_allclose(rows[:, k], spin, atol=2e-5)


def test_actuators_are_internal_no_net_force_or_moment(inst, m0):
    """Relative torques on coincident grids and piezo moment pairs exert no net load (eq. 3.8)."""
    from mace_fmu.fe.labels import rigid_body_vectors

    rigid = rigid_body_vectors(m0.model, m0.mass_properties.reference_point_m)
    for a in inst.actuators:
        b = influence_vector(a.dofs, m0.model.dofs, m0.model.cd_frames)
        assert np.abs(rigid.T @ b).max() < 1e-12, a.name


def test_damping_by_label_and_violin_family(inst, m1):
    z = modal_damping(m1.labels, m1.frequencies_hz, inst.damping)
    by = dict(zip(m1.labels, z))
    assert by["1st Z bending"] == 0.022 and by["Z tilt (Z rotation)"] == 0.038 and by["4th Y bending"] == 0.070
    first = sorted((f, zz) for f, lab, zz in zip(m1.frequencies_hz, m1.labels, z)
                   if lab.startswith("1st") and "violin" in lab and "cable 2" not in lab)
    assert [zz for _, zz in first] == [0.033, 0.024, 0.022, 0.024]
    assert by["torsion, primary end"] == inst.damping.default
    assert all(zz == 0.0 for f, zz in zip(m1.frequencies_hz, z) if abs(f) < 0.01)


@pytest.mark.parametrize("key", ["0g_large", "1g_large", "1g_linear"])
def test_unique_labels_leave_every_damping_ratio_as_it_was(inst, key):
    """Same modes, same damping table: the ratios of every mode up to 250 Hz equal those computed with
    the labels before they were made unique (tests/data/modal_damping_before_unique_labels.json)."""
    import json

    before = json.loads((DATA / "modal_damping_before_unique_labels.json").read_text())
    ref = before["models"][key]
    configuration, preload = key.split("_")
    sm = compute_modes(configuration=configuration, preload=preload, max_hz=250.0)
    # zero-frequency modes (rigid bodies, mechanisms) are rounding noise below 0.01 Hz, which moves
    # with the BLAS thread count: they must stay below it; the others within 2e-6 Hz
    f, f_ref = sm.frequencies_hz, np.array(ref["frequencies_hz"])
    zero = np.abs(f_ref) < ZERO_HZ
    assert np.all(np.abs(f[zero]) < ZERO_HZ)
    np.testing.assert_allclose(f[~zero], f_ref[~zero], rtol=0, atol=2e-6)
    z = modal_damping(sm.labels, sm.frequencies_hz, inst.damping)
    np.testing.assert_array_equal(z, ref["damping"])
    assert len(set(sm.labels)) == len(sm.labels)
    # only labels that used to repeat changed
    changed = [(old, new) for old, new in zip(ref["labels"], sm.labels) if old != new]
    assert changed and all(ref["labels"].count(old) > 1 for old, _ in changed)


def test_1g_plant_keeps_80_modes_and_drops_the_wheel_angles(inst, m1):
    z = modal_damping(m1.labels, m1.frequencies_hz, inst.damping)
    plant = modal_plant(m1.modes, inst, z, max_hz=250.0)
    assert len(plant.frequencies_hz) == 80  # thesis 3.3: 80 modes up to 250 Hz
    assert plant.system.nstates == 157  # 160 - 3 wheel angles (unobservable)
    assert "3 displacement directions" in plant.removed_states[0][1]
    assert plant.system.ninputs == 9 and plant.system.noutputs == 24  # 20 sensors + 4 encoder angles


def test_0g_plant_drops_rigid_body_states_and_wheel_angles(inst, m0):
    z = modal_damping(m0.labels, m0.frequencies_hz, inst.damping)
    plant = modal_plant(m0.modes, inst, z, max_hz=250.0)
    assert len(plant.frequencies_hz) == 35  # thesis 3.2
    # 22 flexible modes x 2 + 4 gimbal angles + 7 mechanism rates
    assert plant.system.nstates == 2 * 22 + 4 + 7
    reasons = " ".join(r for _, r in plant.removed_states)
    assert "6 directions no actuator moves" in reasons and "3 displacement directions" in reasons


def test_modal_plant_dc_strain_matches_a_static_solution(inst, m0):
    """Independent check of B and C: the active strut's static strain response from the modal
    model (flexible modes, sum of phi phi^T / w^2) equals K^-1 b computed on the constrained
    0-g structure with the zero-frequency motions removed."""
    modes = m0.modes
    flex = np.abs(modes.frequencies_hz) >= 0.01
    phi = modes.shapes[:, flex]
    w2 = (2 * np.pi * modes.frequencies_hz[flex]) ** 2
    b = influence_vector(inst.actuator("active_strut_y").dofs, modes.dofs, modes.cd_frames)
    c = influence_vector(inst.sensor("strain_strut2_y").dofs, modes.dofs, modes.cd_frames)
    z = modal_damping(modes.labels, modes.frequencies_hz, inst.damping)
    plant = modal_plant(modes, inst, z, max_hz=1e9)
    i, o = plant.system.input_labels.index("active_strut_y"), plant.system.output_labels.index("strain_strut2_y")
    a, bb, cc = plant.system.A, plant.system.B, plant.system.C
    keep = np.abs(np.linalg.eigvals(a)) > 1e-6  # the flexible part has a regular A
    modal_dc = c @ phi @ np.diag(1 / w2) @ phi.T @ b
    # the state-space DC gain restricted to flexible states equals the sum over flexible modes
    n_flex = int(np.sum(flex))
    states = [k for k, s in enumerate(plant.system.state_labels)
              if int(s.split("mode")[1].split("_")[0]) - 1 in set(np.flatnonzero(flex))]
    sub_a, sub_b, sub_c = a[np.ix_(states, states)], bb[states, i], cc[o, states]
    assert len(states) == 2 * n_flex and keep.sum() >= 2 * n_flex
    assert -sub_c @ np.linalg.solve(sub_a, sub_b) == pytest.approx(modal_dc, rel=1e-9)


def test_a_negative_frequency_is_an_unstable_mode_not_an_oscillator():
    """A negative eigenvalue (frequency reported as -f, e.g. a softened spring) gives the poles
    +-2 pi f of eta'' = (2 pi f)^2 eta, the divergent solution, as an FMU reanalysis must show."""
    from mace_fmu.iomodel.modal_core import modal_matrices

    freq = np.array([-1.5, 4.0])
    a, *_ = modal_matrices(freq, np.zeros(2), ("soft", "stiff"), np.zeros((0, 2)), np.ones((2, 1)),
                           {"x": np.ones(2)}, {}, ["x"])
    poles = np.sort_complex(np.linalg.eigvals(a))
    np.testing.assert_allclose(poles, np.sort_complex([-3.0 * np.pi, 3.0 * np.pi, -8j * np.pi, 8j * np.pi]),
                               atol=1e-12)
