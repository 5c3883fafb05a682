"""The three-storey frame's measured FRFs (examples/three_storey_frame/data, real data of a laboratory rig), read
as the update reads them, and what they say about themselves, independently of any model:

* the unit is (m/s^2)/N: above the last resonance a driving-point accelerance tends to one over the driven
  floor's mass (5.201 kg stated), in phase with the force; in g/N it would be 9.81 times smaller;
* the force acts on floor 1, 2 and 3 in Experimental.csv, test_2.csv and test_3.csv (the source's README says
  floor 1 for all three): the mass line is in that column;
* reciprocity: H_21 of the first file is H_12 of the second, and H_31 is H_13 of the third, at the resonances.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.paths import EXAMPLES

from mace_fmu.updating.files import read_frequency_response

DATA = EXAMPLES / "three_storey_frame" / "data"
FILES = {"Experimental.csv": "force_floor_1", "test_2.csv": "force_floor_2", "test_3.csv": "force_floor_3"}
FLOOR_KG = 5.201


@pytest.fixture(scope="module")
def frfs():
    return {name: read_frequency_response(DATA / name) for name in FILES}


def test_the_files_read_as_one_force_and_three_accelerations_in_si_units(frfs):
    for name, frd in frfs.items():
        assert frd.inputs == (FILES[name],) and frd.outputs == ("acc_floor_1", "acc_floor_2", "acc_floor_3")
        assert frd.units == {FILES[name]: "N", "acc_floor_1": "m/s^2", "acc_floor_2": "m/s^2", "acc_floor_3": "m/s^2"}
        assert frd.frequencies_hz.size == 4096 and np.allclose(np.diff(frd.frequencies_hz), 0.03125)


@pytest.mark.parametrize("name", list(FILES))
def test_the_mass_line_is_in_the_driven_floor_s_column_in_m_per_s2_per_newton(frfs, name):
    frd = frfs[name]
    high = (frd.frequencies_hz >= 100) & (frd.frequencies_hz <= 128)
    driven = int(FILES[name][-1]) - 1
    line = frd.response[high, :, 0]
    assert abs(np.median(np.abs(line[:, driven])) * FLOOR_KG - 1) < 0.1  # (m/s^2)/N, not g/N
    assert abs(np.median(np.angle(line[:, driven], deg=True))) < 5  # acceleration in phase with the force
    others = [k for k in range(3) if k != driven]
    assert np.median(np.abs(line[:, others])) < 0.05 * np.median(np.abs(line[:, driven]))


@pytest.mark.parametrize("other, floor", [("test_2.csv", 2), ("test_3.csv", 3)])
def test_reciprocity_between_the_files_at_the_second_and_third_resonances(frfs, other, floor):
    first, second = frfs["Experimental.csv"], frfs[other]
    for hz in (17.46875, 26.5):
        k = int(np.argmin(np.abs(first.frequencies_hz - hz)))
        h_floor_from_1 = first.response[k, floor - 1, 0]
        h_1_from_floor = second.response[k, 0, 0]
        assert abs(abs(h_1_from_floor) / abs(h_floor_from_1) - 1) < 0.05
        assert abs(np.angle(h_1_from_floor / h_floor_from_1, deg=True)) < 5
