"""A structure file's values checked when it is read: a damping ratio outside [0, 1), a delay
or a cut-off outside what the physics allows, a parameter name that cannot be one, and a [parameters] entry
naming a card the deck lacks, each refused in one line naming the file, its line, the table and key and what was
expected; the files that ship with the package and its examples still read."""

from __future__ import annotations

import re

import pytest
from support.paths import EXAMPLES

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.structure.file import bundled_structure_path, load_structure_file

FRAME = EXAMPLES / "three_storey_frame"


def _with(tmp_path, table: str, body: str, *, base=FRAME / "frame.toml"):
    """The frame's structure file with ``[table]`` replaced by ``body`` (added where the file has none)."""
    text = base.read_text()
    pattern = re.compile(r"^\[" + re.escape(table) + r"\]\n(?:(?!\[).*\n?)*", re.MULTILINE)
    text = pattern.sub("", text) if pattern.search(text) else text
    path = tmp_path / "frame.toml"
    path.write_text(text.rstrip() + f"\n\n[{table}]\n{body}\n")
    return path


def _line_of(path, text: str) -> int:
    return next(n for n, line in enumerate(path.read_text().splitlines(), start=1) if line.startswith(text))


@pytest.mark.parametrize("value", ["1.5", "1.0", "-0.01", "nan", "\"2 %\""])
def test_a_damping_ratio_outside_0_to_1_is_refused_at_reading(tmp_path, value):
    """1.5 reached an FMU whose start value lay outside the [0, 1] it declares; -0.01 an unstable model."""
    path = _with(tmp_path, "damping", f"default = {value}")
    with pytest.raises(MaceError) as caught:
        load_structure_file(path)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:{_line_of(path, 'default')}: [damping] default: ")
    assert "expected a damping ratio in [0, 1)" in message


@pytest.mark.parametrize("body, key, expected", [
    ('by_label = { "mode 2" = 1.2 }', "by_label.'mode 2'", "a damping ratio in [0, 1)"),
    ("zero_frequency = -0.5", "zero_frequency", "a damping ratio in [0, 1)"),
    ("violin_families = [{ order = 1, cables = [1], zeta = [0.02, 3.0] }]", "violin_families[1].zeta",
     "a damping ratio in [0, 1)"),
    ("violin_families = [{ order = 0, cables = [1], zeta = [0.02] }]", "violin_families[1].order",
     "the violin order, an integer >= 1"),
    ("defualt = 0.02", "defualt", "unknown key 'defualt'; expected default, zero_frequency, by_label, violin_families"),
])
def test_every_damping_value_is_checked(tmp_path, body, key, expected):
    path = _with(tmp_path, "damping", body)
    with pytest.raises(MaceError, match=re.escape(f"[damping] {key}: ") + ".*" + re.escape(expected)):
        load_structure_file(path)


@pytest.mark.parametrize("body, key, expected", [
    ("actuator_delays_s = { force_floor_1 = -0.001 }", "actuator_delays_s.force_floor_1", "a delay in [0, 1] s"),
    ("gyro_delays_s = { acc_floor_1 = 2.5 }", "gyro_delays_s.acc_floor_1", "a delay in [0, 1] s"),
    ("filter_order = 2.5", "filter_order", "the filter's order, an integer >= 0"),
    ("filter_order = 4\nfilter_cutoff_hz = 0.0", "filter_cutoff_hz", "the filter's -3.01 dB frequency, > 0 Hz"),
])
def test_electronics_values_are_checked(tmp_path, body, key, expected):
    path = _with(tmp_path, "electronics", body)
    with pytest.raises(MaceError, match=re.escape(f"[electronics] {key}: ") + ".*" + re.escape(expected)):
        load_structure_file(path)


@pytest.mark.parametrize("body, expected", [
    ('materials = { "1" = "storey-1" }', "MAT1 1: name 'storey-1' (expected letters, digits and '_'"),
    ('materials = { "one" = "storey_1" }', "key 'one' is no MAT1 ID"),
    ('materials = { "1" = "storey", "2" = "storey" }', "name 'storey' is given to MAT1 1 and MAT1 2"),
    ('moduli = { "1" = "storey_1" }', "moduli: unknown key 'moduli'; expected materials, springs, masses"),
])
def test_parameter_names_are_checked(tmp_path, body, expected):
    path = _with(tmp_path, "parameters", body)
    with pytest.raises(MaceError, match=re.escape(f"{path}:{_line_of(path, '[parameters]') + 1}: [parameters] ")
                       + ".*" + re.escape(expected)):
        load_structure_file(path)


def test_a_parameters_entry_naming_a_mat1_the_deck_lacks_is_refused_with_the_ids_it_has(tmp_path):
    """The entry was silently no parameter at all: the card it was meant for kept its default name."""
    path = _with(tmp_path, "parameters", 'materials = { "1" = "storey_1", "7" = "storey_7" }')
    deck = read_deck(FRAME / "frame.bdf")
    with pytest.raises(MaceError) as caught:
        compute_modes(deck, configuration="0g", structure_file=path)
    assert str(caught.value) == (f"{path}:{_line_of(path, 'materials')}: [parameters] materials: \"7\" = 'storey_7' "
                                 f"names MAT1 7, which {deck.path} lacks (its MAT1 IDs: 1-3)")


@pytest.mark.parametrize("body, card", [('springs = { "5" = "spring" }', "CELAS2 5, which"),
                                        ('masses = { "101" = "floor" }', "CONM2 101, which")])
def test_springs_and_masses_the_deck_lacks_are_refused(tmp_path, body, card):
    path = _with(tmp_path, "parameters", body)
    with pytest.raises(MaceError, match=re.escape(card)):
        compute_modes(read_deck(FRAME / "frame.bdf"), configuration="1g", structure_file=path)


@pytest.mark.parametrize("path", [bundled_structure_path(), *sorted(EXAMPLES.rglob("*.toml"))],
                         ids=lambda p: p.name)
def test_the_shipped_structure_files_read(path):
    assert load_structure_file(path).path == path.resolve()
