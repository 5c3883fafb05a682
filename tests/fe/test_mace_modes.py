"""The bundled MACE deck against the thesis: Tables 3.1, 3.15, 4.4, 4.7 and 5.1."""

from __future__ import annotations

import numpy as np
import pytest

from mace_fmu.deck.geometry import grid_positions
from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.structure.file import bundled_deck_path
from mace_fmu.thesis import table_3_15_comparison, table_5_1_0g, table_5_1_1g, thesis_data


@pytest.fixture(scope="module")
def deck():
    return read_deck(bundled_deck_path())


@pytest.fixture(scope="module")
def m0(deck):
    return compute_modes(deck, configuration="0g")


@pytest.fixture(scope="module", params=["large", "linear"])
def m1(request, deck):
    return compute_modes(deck, configuration="1g", preload=request.param, max_hz=60.0)


def test_deck_counts_match_the_thesis_text(deck):
    """Thesis 3.3: 108 connected grids, 97 bars (32 struts), 3 springs; 112 grids in all."""
    connected = {g for b in deck.bars.values() for g in (b.ga, b.gb)} | {m.grid for m in deck.conm2s.values()} \
        | {s.g1 for s in deck.celas2s.values()}
    assert (len(deck.grids), len(connected), len(deck.bars), len(deck.celas2s), len(deck.conm2s)) == (112, 108, 97, 3, 40)
    lexan_mids = {1, 2, 8, 9, 10}  # Lexan and active-strut materials
    assert sum(deck.pbars[b.pid].mid in lexan_mids for b in deck.bars.values()) == 32


def test_materials_are_the_updated_values_of_table_4_4(deck):
    for name, row in thesis_data()["table_4_4"].items():
        assert deck.mat1s[row["mid"]].e == pytest.approx(row["e"], rel=1e-4), name


@pytest.mark.parametrize(("grid", "node_grid", "offset_cm"), [
    (36, 2, (-0.281, -7.257, -0.116)),  # gimbal base
    (39, 2, (6.661, -7.824, -0.437)),  # inner (X-axis) stage
    (42, 2, (10.593, -11.401, -0.005)),  # outer (Z-axis) stage
    (43, 2, (10.508, -26.307, 0.0)),  # payload rate gyro
    (37, 2, (10.508, -7.988, 0.0)),  # gimbal axes
    (51, 30, (-10.508, -24.498, 0.0)),  # dummy payload, secondary gimbal (rotated 180 deg about Y)
    (52, 16, (0.0, 6.279, 0.0)),  # RWA base (above the node: +y offsets from the top face)
    (53, 16, (0.0, 8.067, 10.629)),  # wheel 1
    (56, 16, (9.205, 8.067, -5.314)),  # wheel 2
    (35, 16, (0.0, -4.350, 0.0)),  # bus rate gyro
])
def test_component_centres_of_mass_match_table_3_1(deck, grid, node_grid, offset_cm):
    """Table 3.1 offsets are from the node interface: the node cube face 3.175 cm from its centre."""
    pos = grid_positions(deck)
    face = np.array([0.0, 3.175 if offset_cm[1] > 0 else -3.175, 0.0])
    expected = pos[node_grid] + (face + np.array(offset_cm)) / 100.0
    np.testing.assert_allclose(pos[grid], expected, atol=2e-5)


def test_0g_mass_properties_match_table_3_15(m0):
    ref = thesis_data()["table_3_15"]
    p = m0.mass_properties
    assert p.reference_grid == 16
    assert p.mass_kg == pytest.approx(ref["mass_kg"], rel=5e-3)
    np.testing.assert_allclose(np.diag(p.inertia_about_reference_kgm2), [ref["jxx"], ref["jyy"], ref["jzz"]], rtol=5e-3)
    rows = table_3_15_comparison(m0)  # what `mace-fmu build` prints
    assert [r.thesis for r in rows] == [ref["mass_kg"], ref["jxx"], ref["jyy"], ref["jzz"]]
    assert rows[0].ours == p.mass_kg and max(abs(r.error_percent) for r in rows) < 0.5


def test_0g_has_13_zero_modes_rigid_gimbal_wheel(m0):
    f, labels = m0.frequencies_hz, m0.labels
    zero = [lab for fr, lab in zip(f, labels) if abs(fr) < 0.01]
    assert len(zero) == 13
    assert sum(lab.startswith("rigid body") for lab in zero) == 6
    assert sum("gimbal" in lab for lab in zero) == 4
    assert sum("reaction wheel" in lab for lab in zero) == 3
    assert abs(f[13]) > 1.0  # nothing hides just above the threshold


def test_0g_flexible_modes_match_table_5_1_with_labels(m0):
    rows = table_5_1_0g(m0)
    assert len(rows) == 14
    for row in rows:
        assert row.ours_label == row.thesis_label
        assert abs(row.error_percent) < 0.5, row
    # they are the first 14 flexible modes, in frequency order
    assert [r.index for r in rows] == sorted(r.index for r in rows) == list(range(13, 27))


def test_1g_has_only_the_three_wheel_mechanisms_at_zero(m1):
    f, labels = m1.frequencies_hz, m1.labels
    zero = [lab for fr, lab in zip(f, labels) if abs(fr) < 0.01]
    assert sorted(zero) == [f"mechanism: reaction wheel {i}" for i in (1, 2, 3)]


def test_1g_suspension_modes(m1):
    """Table 3.10: X/Z pendulum, Y twist and bounce near 0.23 Hz, Z tilt near 0.44 Hz (10 %)."""
    sus = thesis_data()["suspension_1g"]
    by_label = dict(zip(m1.labels, m1.frequencies_hz))
    for name in ("X suspension pendulum (X translation)", "Z suspension pendulum (Z translation)",
                 "Y suspension twist (Y rotation)", "bounce (Y translation)"):
        assert by_label[name] == pytest.approx(sus["pendulum_twist_bounce_hz"], rel=0.10), name
    assert by_label["Z tilt (Z rotation)"] == pytest.approx(sus["z_tilt_hz"], rel=0.10)


def test_1g_violin_families(m1):
    """Table 4.7 FE column (servoed final model): 7.11-7.18, 12.93, 14.34, 21.58 Hz; within 2 %
    since the servos and the preload option move these unservoed modes by up to ~1.5 %."""
    sus = thesis_data()["suspension_1g"]
    f, labels = m1.frequencies_hz, m1.labels

    def family(order, cable_filter):
        return sorted(fr for fr, lab in zip(f, labels)
                      if lab.startswith(f"{order} ") and "violin" in lab and cable_filter(lab))

    first_13 = family("1st", lambda lab: "2" not in lab.split("cable")[1])
    first_2 = family("1st", lambda lab: lab.endswith("cable 2"))
    np.testing.assert_allclose(first_13, sus["violin_1_cables_1_3_hz"], rtol=0.02)
    assert len(first_2) == 2
    np.testing.assert_allclose(first_2, sus["violin_1_cable_2_hz"], rtol=0.02)
    second = family("2nd", lambda lab: "2" not in lab.split("cable")[1])
    third = family("3rd", lambda lab: "2" not in lab.split("cable")[1])
    assert len(second) == len(third) == 4
    np.testing.assert_allclose(second, sus["violin_2_hz"][0], rtol=0.02)
    np.testing.assert_allclose(third, sus["violin_3_hz"][0], rtol=0.02)


def test_1g_structural_modes_match_table_5_1_paired_by_mac(m1, m0):
    for row in table_5_1_1g(m1, m0):
        assert row.mac > 0.8, row
        assert row.ours_label == row.thesis_label, row
        assert abs(row.error_percent) < 1.5, row


@pytest.mark.parametrize("configuration", ["0g", "1g"])
def test_every_label_is_unique_and_table_5_1_names_stay(deck, configuration):
    """Up to 250 Hz: no label repeats; each Table 5.1 name labels the lowest mode of its kind, and a repeat
    of it is the '2nd' (thesis: torsion modes at 10.3/12.4 Hz; ours also at 92.9/108.6 Hz in 0-g)."""
    from mace_fmu.viewer import mode_index

    sm = compute_modes(deck, configuration=configuration, max_hz=250.0)
    labels, hz = list(sm.labels), sm.frequencies_hz
    assert len(set(labels)) == len(labels)
    for row in thesis_data()["table_5_1"]:
        assert row["label"] in labels
        second = f"2nd {row['label']}"
        if second in labels:
            assert hz[labels.index(second)] > hz[labels.index(row["label"])]
    for end in ("primary", "secondary"):
        first, second = labels.index(f"torsion, {end} end"), labels.index(f"2nd torsion, {end} end")
        assert hz[first] < 13.0 and hz[second] > 90.0
        assert mode_index(sm, f"torsion, {end} end") == first + 1  # viewer --mode by label
        assert mode_index(sm, f"2nd torsion, {end} end") == second + 1


def test_violin_pairs_say_whether_the_two_cables_swing_together(m1):
    """Cables 1 and 3 hang in the X-Y plane: the in-plane (X) deflections of their mid-span grids have
    the same sign in an 'in-phase' mode and opposite signs in an 'antiphase' one."""
    spec, model = m1.structure.spec, m1.model
    pairs = [i for i, lab in enumerate(m1.labels) if "cables 1 and 3" in lab and "violin" in lab]
    assert {m1.labels[i].split(" violin")[0].split()[-1] for i in pairs} >= {"in-phase", "antiphase"}
    for i in pairs:
        mids = []
        for cable in ("cable_1", "cable_3"):
            grids = sorted((g for g in spec.components[cable] if g in model.dofs.grid_ids),
                           key=lambda g: model.positions[model.dofs.grid_index(g)][1])
            component = 0 if "in-plane" in m1.labels[i] else 2  # X in the cables' plane, Z normal to it
            mids.append(m1.modes.shapes[model.dofs.indices(grids[len(grids) // 2])[component], i])
        together = mids[0] * mids[1] > 0
        assert ("in-phase" in m1.labels[i]) == together, (m1.labels[i], mids)


def test_unique_labels_number_repeats_in_frequency_order():
    from mace_fmu.fe.labels import unique_labels

    got = unique_labels(["b", "a", "a", "c", "a"], np.array([1.0, 3.0, 2.0, 0.5, 4.0]))
    assert got == ("b", "2nd a", "a", "c", "3rd a")
    # a numbered repeat that collides with an existing label falls back to the mode number
    assert unique_labels(["x", "x", "2nd x"], np.array([1.0, 2.0, 3.0])) == ("x", "2nd x (mode 2)", "2nd x (mode 3)")
