"""The 0-g / 1-g structures of the bundled deck, the structure data file and card overrides."""

from __future__ import annotations

import re
from importlib import resources

import numpy as np
import pytest

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.structure.build import apply_overrides, build_structure
from mace_fmu.structure.file import bundled_deck_path, load_spec

TOML_TEXT = (resources.files("mace_fmu") / "data" / "mace_em.toml").read_text()
SUSPENSION_GRIDS = {32, 33, 34, *range(63, 93)}


@pytest.fixture(scope="module")
def deck():
    return read_deck(bundled_deck_path())


@pytest.fixture(scope="module")
def zero_g(deck):
    return build_structure(deck, configuration="0g")


@pytest.fixture(scope="module")
def m0(deck):
    return compute_modes(deck, configuration="0g")


def _first_z_bending(result) -> float:
    labels = list(result.labels)
    assert labels.count("1st Z bending") == 1, labels
    return float(result.frequencies_hz[labels.index("1st Z bending")])


# ---------------------------------------------------------------------------------------------
# The 0-g structure


def test_0g_deck_has_the_78_nodal_points_of_the_free_free_model(deck, zero_g):
    d = zero_g.deck
    assert zero_g.configuration == "0g" and zero_g.preload is None
    connected = {g for b in d.bars.values() for g in (b.ga, b.gb)} | {m.grid for m in d.conm2s.values()}
    assert len(connected) == 78  # thesis 3.2: 78 nodal points
    # The deck keeps one unconnected grid: the fixed reference node 62 (SPC 53, all components).
    assert set(d.grids) - connected == {62}
    assert len(d.grids) == 79
    assert set(d.grids) == set(deck.grids) - SUSPENSION_GRIDS
    # every remaining element only references remaining grids
    assert connected <= set(d.grids)


def test_0g_deck_has_no_suspension_elements(deck, zero_g):
    d = zero_g.deck
    assert len(deck.celas2s) == 3 and len(d.celas2s) == 0
    assert not set(d.bars) & {*range(103, 127), 80, 81, 82}
    assert not set(d.conm2s) & {22, 23, 24, 38, 39, 40}
    # only those were removed
    assert set(deck.bars) - set(d.bars) == {*range(103, 127), 80, 81, 82}
    assert set(deck.conm2s) - set(d.conm2s) == {22, 23, 24, 38, 39, 40}
    # the input deck is not modified
    assert {80, 103} <= set(deck.bars) and 63 in deck.grids


def test_0g_constraint_sets_lose_the_suspension_grids(deck, zero_g):
    d = zero_g.deck
    assert zero_g.modal.mpc == 6 and zero_g.modal.spc == 53
    gone = {90, 91, 92, 32, 33, 34}
    assert any(t.grid in gone for e in deck.mpcs[6] for t in e.terms)  # the test would prove nothing otherwise
    assert not any(t.grid in gone for e in d.mpcs[6] for t in e.terms)
    # the 7 mechanisms keep their 5 equations each
    assert len(d.mpcs[6]) == 7 * 5
    assert len(deck.mpcs[6]) - len(d.mpcs[6]) == 3 * 4
    spc_grids = {g for card in d.spc1s[53] for g in card.grids}
    assert not spc_grids & {63, 71, 79, 87, 88, 89}
    assert spc_grids == {62}
    assert [card.components for card in d.spc1s[53]] == ["123456"]


def test_1g_structure_is_the_deck_as_is(deck):
    s = build_structure(deck, configuration="1g")
    assert s.deck.grids == deck.grids and s.deck.bars == deck.bars
    assert (s.preload.spc, s.preload.mpc, s.preload.load, s.preload.nlparm) == (51, 5, 100, 10)
    assert (s.modal.spc, s.modal.mpc) == (53, 6)


# ---------------------------------------------------------------------------------------------
# The structure data file


def _write_toml(tmp_path, text: str):
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


def test_forgotten_suspension_element_is_named(deck, tmp_path):
    old = 'elements = ["22-24", "38-40", "80-82", "103-126", "138-140"]'
    assert old in TOML_TEXT
    path = _write_toml(tmp_path, TOML_TEXT.replace(old, 'elements = ["22-24", "38-40", "80-82", "138-140"]'))
    spec = load_spec(path)
    assert not spec.suspension_elements & set(range(103, 127))
    with pytest.raises(MaceError) as exc:
        build_structure(deck, configuration="0g", spec=spec)
    msg = str(exc.value)
    m = re.search(r"CBAR (\d+)", msg)
    assert m is not None and 103 <= int(m.group(1)) <= 126, msg
    assert str(path) in msg
    assert str(bundled_deck_path()) in msg  # and where the card is in the deck


def test_one_forgotten_cable_bar_is_named_exactly(deck, tmp_path):
    old = '"103-126"'
    path = _write_toml(tmp_path, TOML_TEXT.replace(old, '"103-116", "118-126"'))
    with pytest.raises(MaceError, match=r"CBAR 117: connects suspension grid") as exc:
        build_structure(deck, configuration="0g", spec=load_spec(path))
    assert str(path) in str(exc.value)


def test_load_spec_bad_range_names_file_and_value(tmp_path):
    path = _write_toml(tmp_path, TOML_TEXT.replace('"63-92"', '"63-92", "5-x"'))
    with pytest.raises(MaceError) as exc:
        load_spec(path)
    msg = str(exc.value)
    assert str(path) in msg and "'5-x'" in msg and "[suspension] grids" in msg


def test_load_spec_bundled_values():
    spec = load_spec()
    assert spec.suspension_grids == frozenset(SUSPENSION_GRIDS)
    assert len(spec.mechanisms) == 7
    wheel = next(m for m in spec.mechanisms if m.name == "reaction wheel 1")
    assert (wheel.dependent, wheel.independent, wheel.component) == (54, 53, 6)
    assert spec.component_of(54) == "reaction_wheels" and spec.component_of(62) is None


def test_load_spec_missing_key_and_unreadable_file(tmp_path):
    path = _write_toml(tmp_path, TOML_TEXT.replace("[mechanisms]", "[mechanism]"))
    with pytest.raises(MaceError, match=re.escape(str(path)) + r":\d+: \[mechanism\]: unknown table 'mechanism'.*"
                                        r"\[mechanisms\]"):
        load_spec(path)
    with pytest.raises(MaceError, match="absent.toml: no such structure file"):
        load_spec(tmp_path / "absent.toml")


def test_load_spec_rejects_reversed_range(tmp_path):
    path = _write_toml(tmp_path, TOML_TEXT.replace('bus_rate_gyro = [35]', 'bus_rate_gyro = ["40-35"]'))
    with pytest.raises(MaceError, match="40-35"):
        load_spec(path)


# ---------------------------------------------------------------------------------------------
# Overrides


def test_override_changes_only_that_field(deck):
    new = apply_overrides(deck, {("MAT1", 2): {"e": 2.4e9}})
    old_mat, new_mat = deck.mat1s[2], new.mat1s[2]
    assert new_mat.e == 2.4e9 and old_mat.e == pytest.approx(2.335e9)
    assert (new_mat.id, new_mat.g, new_mat.nu, new_mat.rho, new_mat.source) == \
           (old_mat.id, old_mat.g, old_mat.nu, old_mat.rho, old_mat.source)
    assert all(new.mat1s[k] == deck.mat1s[k] for k in deck.mat1s if k != 2)
    assert new.pbars == deck.pbars and new.bars == deck.bars and new.grids == deck.grids
    assert deck.mat1s[2].e == pytest.approx(2.335e9)  # the input deck is unchanged


def test_lexan_modulus_moves_first_bending_frequency(deck, m0):
    base = _first_z_bending(m0)
    assert base == pytest.approx(2.10, rel=5e-3)
    stiffer = _first_z_bending(compute_modes(apply_overrides(deck, {("MAT1", 2): {"e": 2.4e9}}), configuration="0g"))
    softer = _first_z_bending(compute_modes(apply_overrides(deck, {("MAT1", 2): {"e": 0.9 * 2.335e9}}),
                                                configuration="0g"))
    assert stiffer > base
    assert 0.94 * base < softer < 0.99 * base
    # no more than the square root of the stiffness ratio (sqrt(0.9) = 0.9487)
    assert softer > np.sqrt(0.9) * base * 0.999


def test_override_unknown_card_type(deck):
    with pytest.raises(ValueError, match="unknown card type 'MAT8'") as exc:
        apply_overrides(deck, {("MAT8", 2): {"e": 1.0}})
    for allowed in ("MAT1", "PBAR", "CBAR", "GRID", "CONM2", "CELAS2"):
        assert allowed in str(exc.value)


def test_override_unknown_id_raises(deck):
    with pytest.raises(ValueError, match="MAT1 99"):
        apply_overrides(deck, {("MAT1", 99): {"e": 1.0}})


def test_override_unknown_id_names_allowed_ids(deck):
    with pytest.raises(ValueError) as exc:
        apply_overrides(deck, {("MAT1", 99): {"e": 1.0}})
    numbers = set(re.findall(r"\b\d+\b", str(exc.value).replace(deck.path, "")))
    assert {str(k) for k in deck.mat1s} <= numbers or "1-10" in str(exc.value)


def test_override_with_undefined_coordinate_system_is_a_mace_error(deck):
    with pytest.raises(MaceError, match="99"):
        compute_modes(apply_overrides(deck, {("GRID", 54): {"cd": 99}}), configuration="0g")


def test_override_unknown_field(deck):
    with pytest.raises(ValueError, match=r"unknown field\(s\) \['youngs'\]") as exc:
        apply_overrides(deck, {("MAT1", 2): {"youngs": 1.0}})
    for allowed in ("'e'", "'g'", "'nu'", "'rho'"):
        assert allowed in str(exc.value)
    assert "'id'" not in str(exc.value) and "'source'" not in str(exc.value)


@pytest.mark.parametrize(("kwargs", "allowed"), [
    ({"preload": "huge"}, ("'large'", "'linear'")),
    ({"mass": "diagonal"}, ("'lumped'", "'consistent'")),
    ({"configuration": "2g"}, ("'1g'", "'0g'")),
])
def test_compute_modes_bad_options(deck, kwargs, allowed):
    with pytest.raises(ValueError) as exc:
        compute_modes(deck, **kwargs)
    for value in allowed:
        assert value in str(exc.value)


# ---------------------------------------------------------------------------------------------
# Mode shapes


def test_mode_shape_in_skew_cd_system_is_projection_on_spin_axis(m0):
    modes = m0.modes
    axis = np.array([0.0, 0.57729, 0.81654])
    axis /= np.linalg.norm(axis)
    basic = np.array([modes.shape(54, c) for c in (4, 5, 6)])  # (3, n_modes)
    np.testing.assert_allclose(modes.shape(54, 6, system="cd"), axis @ basic, rtol=0, atol=1e-10)
    np.testing.assert_allclose(basic, modes.shapes[modes.dofs.indices(54)[3:]], rtol=0, atol=0)
    # the skew system really matters for this grid
    assert np.abs(modes.shape(54, 6, system="cd") - modes.shape(54, 6)).max() > 1e-2


def test_wheel_mpc_holds_in_cd_components(m0):
    """MPC 6 ties 54 to 53 in components 1-5 of their (common, skew) CD system; 6 is the wheel spin."""
    modes = m0.modes
    for c in range(1, 6):
        np.testing.assert_allclose(modes.shape(54, c, system="cd"), modes.shape(53, c, system="cd"), atol=1e-10)
    spin = modes.shape(54, 6, system="cd") - modes.shape(53, 6, system="cd")
    wheel = list(modes.labels).index("mechanism: reaction wheel 1")
    assert abs(spin[wheel]) > 1.0  # a free spin, mass-normalised on the small wheel inertia


def test_mode_shape_cd_equals_basic_for_basic_grid(m0):
    modes = m0.modes
    for c in range(1, 7):
        np.testing.assert_array_equal(modes.shape(16, c, system="cd"), modes.shape(16, c))
    assert np.abs(modes.shape(16, 2)).max() > 0.0


@pytest.mark.parametrize("grid", [9999, 63])
def test_mode_shape_unknown_grid(m0, grid):
    with pytest.raises(KeyError, match=f"grid {grid}"):
        m0.modes.shape(grid, 1)
    with pytest.raises(KeyError, match=f"grid {grid}"):
        m0.modes.shape(grid, 1, system="cd")


def test_mode_shape_bad_system_or_component(m0):
    with pytest.raises(MaceError, match="'basic' or 'cd'"):
        m0.modes.shape(16, 1, system="local")
    with pytest.raises(MaceError, match="1-6"):
        m0.modes.shape(16, 7)


@pytest.mark.parametrize("component", [0, 7])
def test_mode_shape_bad_component_in_cd_system(m0, component):
    with pytest.raises(MaceError, match="1-6"):
        m0.modes.shape(16, component, system="cd")


def test_modes_are_mass_normalised(m0):
    phi, mass = m0.modes.shapes, m0.model.mass
    assert phi.shape[1] == 35
    np.testing.assert_allclose(phi.T @ mass @ phi, np.eye(35), rtol=0, atol=1e-8)
