"""A mode's damping ratio or frequency scale in either spelling, wherever a parameter set meets a model.

``mace-fmu update fmu`` writes the FMU's names (``damping_mode_<k>``, 1-based in the model's retained-mode
order); the engine's update and the 0-g prediction write labels (``damping:<mode label>``). A set takes
both (mace_fmu.parameters.per_mode resolves them against the model's modes) and both give the same model:
checked here on the three-storey frame (examples/three_storey_frame, four modes) by its poles, whose damping
ratio and frequency are the set's values; the CLI's writers and readers in tests/cli/test_parameter_round_trips.py.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest
from support.paths import EXAMPLES
from support.update_sets import write_as_fmu_update

from mace_fmu.cli import main
from mace_fmu.errors import MaceError
from mace_fmu.parameters.per_mode import label_mode_names, resolve_mode_names
from mace_fmu.parameters.sets import ParameterSet, parameter_kind

FRAME = EXAMPLES / "three_storey_frame"
ZETA, SCALE = 0.0137, 1.05  #: mode 2's damping ratio (the frame's table: 0.002) and mode 3's frequency scale
PHYSICAL = {"E_storey_1": 7.5e10, "m_floor_2": 4.8}  #: off the deck's 7.0e10 Pa and 5.201 kg


def _frame_model(parameters: ParameterSet | None = None):
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.volts import volts_model

    return volts_model(compute_modes(read_deck(FRAME / "frame.bdf"), configuration="1g",
                                     structure_file=FRAME / "frame.toml", parameters=parameters))


@pytest.fixture(scope="module")
def frame():
    """The frame's model with the moduli and masses alone (mode labels and the unscaled frequencies), and the
    models of the set by mode number and by mode label."""
    physical = _frame_model(ParameterSet(PHYSICAL))
    labels = physical.plant.labels
    by_number = {**PHYSICAL, "damping_mode_2": ZETA, "frequency_scale_mode_3": SCALE}
    by_label = {**PHYSICAL, f"damping:{labels[1]}": ZETA, f"frequency_scale:{labels[2]}": SCALE}
    return physical, _frame_model(ParameterSet(by_number)), _frame_model(ParameterSet(by_label))


def test_a_set_reads_the_names_an_fmu_update_writes(tmp_path):
    values = {**PHYSICAL, "damping_mode_2": ZETA, "frequency_scale_mode_3": SCALE, "delay_gimbal_primary_x": 0.002}
    read = ParameterSet.read(write_as_fmu_update(tmp_path / "parameters.toml", values))
    assert dict(read.values) == values
    assert read.of_kind("damping") == {"damping_mode_2": ZETA}
    assert read.of_kind("frequency_scale") == {"frequency_scale_mode_3": SCALE}
    assert parameter_kind("damping_mode_2") == "damping"


def test_both_spellings_build_one_model_with_the_sets_damping_and_frequency(frame):
    physical, by_number, by_label = frame
    for m in "ABCD":
        assert np.array_equal(getattr(by_number.system, m), getattr(by_label.system, m)), m
    # the frame's model is its modes alone (no servos, delays or filters): each pole pair is one mode's
    poles = np.linalg.eigvals(by_number.system.A)
    poles = poles[poles.imag > 0]
    hz, zeta = np.abs(poles) / (2 * np.pi), -poles.real / np.abs(poles)
    nominal_hz = physical.plant.frequencies_hz
    second = np.argmin(np.abs(hz - nominal_hz[1]))
    assert zeta[second] == pytest.approx(ZETA, rel=1e-9)
    third = np.argmin(np.abs(hz - SCALE * nominal_hz[2]))
    assert hz[third] == pytest.approx(SCALE * nominal_hz[2], rel=1e-9)
    others = [k for k in range(len(hz)) if k not in (second, third)]
    assert np.allclose(zeta[others], physical.plant.damping[0])  # the table's 0.002, untouched


@pytest.mark.parametrize("values, message", [
    ({"damping_mode_7": ZETA}, (r"p.toml: parameter 'damping_mode_7': no mode 7: the 1g structure has modes 1 to 4; "
                                r"expected damping_mode_<k> with k from 1 to 4, or damping:<mode label>$")),
    ({"frequency_scale_mode_0": SCALE}, r"p.toml: parameter 'frequency_scale_mode_0': no mode 0: .* k from 1 to 4"),
    ({"damping:2nd bending about X": ZETA}, (r"p.toml: parameter 'damping:2nd bending about X': no mode labelled "
                                             r"'2nd bending about X' in the 1g structure; closest: "
                                             r"damping:2nd bending about Y")),
    ({"damping_mode_2": ZETA, "damping:2nd bending about Y": 0.02},
     r"p.toml: parameter 'damping:2nd bending about Y' = 0.02 and 'damping_mode_2' = 0.0137 both set damping_mode_2"),
])
def test_a_mode_the_model_lacks_is_one_line_naming_the_file_and_what_it_has(tmp_path, values, message):
    ParameterSet(values).write(tmp_path / "p.toml")
    with pytest.raises(MaceError, match=message) as caught:
        _frame_model(ParameterSet.read(tmp_path / "p.toml"))
    assert "\n" not in str(caught.value)


def test_the_resolver_by_label_by_number_and_for_an_fmus_variables():
    labels = ("rigid X", "1st bending", "1st bending", "torsion")  # a label may name two modes
    assert resolve_mode_names({"damping:1st bending": 0.02, "damping_mode_4": 0.03, "K_a": 2.0}, mode_labels=labels,
                              model="m") == {"damping_mode_2": 0.02, "damping_mode_3": 0.02, "damping_mode_4": 0.03,
                                             "K_a": 2.0}
    # an FMU without a frequency scale of its rigid-body mode: a label names the modes that have one
    fmu = {"frequency_scale_mode_2", "frequency_scale_mode_3", "frequency_scale_mode_4"}
    assert resolve_mode_names({"frequency_scale:1st bending": 1.1}, mode_labels=labels, model="m", available=fmu) == \
        {"frequency_scale_mode_2": 1.1, "frequency_scale_mode_3": 1.1}
    with pytest.raises(MaceError, match=r"^p.toml: parameter 'frequency_scale_mode_1': mode 1 \(rigid X\) of the m has "
                                        r"no frequency scale parameter"):
        resolve_mode_names({"frequency_scale_mode_1": 1.1}, mode_labels=labels, model="m", available=fmu,
                           source="p.toml")
    with pytest.raises(MaceError, match=r"'frequency_scale:rigid X': the modes labelled 'rigid X' in the m have no "
                                        r"frequency scale parameter"):
        resolve_mode_names({"frequency_scale:rigid X": 1.1}, mode_labels=labels, model="m", available=fmu)
    # a set made for another structure: its labels this one lacks are passed over, its numbers refused
    assert resolve_mode_names({"damping:suspension": 0.2}, mode_labels=labels, model="0g structure",
                              other_structure="1g") == {}
    with pytest.raises(MaceError, match="'damping_mode_2' names a mode of the 1g structure .* by its number"):
        resolve_mode_names({"damping_mode_2": 0.2}, mode_labels=labels, model="0g structure", other_structure="1g")
    # numbers to labels, for a set that goes on to a structure numbered otherwise
    assert label_mode_names({"damping_mode_4": 0.03, "E_x": 1.0}, mode_labels=labels, model="1g structure") == \
        {"damping:torsion": 0.03, "E_x": 1.0}
    assert label_mode_names({"damping:nowhere": 0.1}, mode_labels=labels, model="1g structure") == \
        {"damping:nowhere": 0.1}  # a label is left to the model that takes the set
    with pytest.raises(MaceError, match=r"^p.toml: parameter 'damping_mode_3' = 0.05 and 'damping_mode_2' = 0.02 both "
                                        r"set 'damping:1st bending' of the 1g structure"):
        label_mode_names({"damping_mode_2": 0.02, "damping_mode_3": 0.05}, mode_labels=labels, model="1g structure",
                         source="p.toml")
    with pytest.raises(MaceError, match=r"^p.toml: parameter 'damping_mode_5': no mode 5: the 1g structure has modes "
                                        r"1 to 4"):
        label_mode_names({"damping_mode_5": 0.02}, mode_labels=labels, model="1g structure", source="p.toml")


@pytest.mark.parametrize("spelling", ["number", "label"])
def test_params_to_ssv_and_back_keep_an_updates_set(tmp_path, capsys, spelling):
    """``params to-ssv`` of a set as ``update fmu`` writes it (or by label): every value in the SSV with its unit
    (kg for a floor's mass), and ``from-ssv`` gives the same set back."""
    mode = {"number": {"damping_mode_2": ZETA}, "label": {"damping:2nd bending about Y": ZETA}}[spelling]
    values = {**PHYSICAL, **mode}
    source = write_as_fmu_update(tmp_path / "parameters.toml", values)
    assert main(["params", "to-ssv", str(source), "-o", str(tmp_path / "p.ssv")]) == 0, capsys.readouterr().err
    ns = {"ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
    reals = {p.get("name"): p.find("ssv:Real", ns) for p in ET.parse(tmp_path / "p.ssv").iterfind(".//ssv:Parameter", ns)}
    assert {n: float(r.get("value")) for n, r in reals.items()} == values
    assert reals["m_floor_2"].get("unit") == "kg" and reals["E_storey_1"].get("unit") == "Pa"
    assert reals[next(iter(mode))].get("unit") == "1"
    assert main(["params", "from-ssv", str(tmp_path / "p.ssv"), "-o", str(tmp_path / "back.toml")]) == 0
    assert ParameterSet.read(tmp_path / "back.toml") == ParameterSet.read(source)
