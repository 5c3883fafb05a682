"""Frequency bounds (thesis 5.3, Table 5.3) spelled once (mace_fmu.parameters.frequency_bounds): the [[mode]] rows
predict-0g writes into table_5_3.toml and params from-ssv writes are read by one reader, and a bound is checked
and turned into a frequency scale's range in one place."""

from __future__ import annotations

import numpy as np
import pytest

from mace_fmu.errors import MaceError
from mace_fmu.parameters.frequency_bounds import (FrequencyBound, bounds_toml, read_bounds, relative_bound,
                                                  relative_bounds, scale_range)

BOUNDS = (FrequencyBound(mode=7, mode_label="1st Z bending", bound_percent=1.1),
          FrequencyBound(mode=9, mode_label="2nd Y bending", bound_percent=100 / 7))
TABLE_ROWS = """source = "Table 4.7 measurement model"

[[mode]]
label = "gimbal pendulum"
nominal_hz = 0.5
bound_percent = 10.0

[[mode]]
label = "1st Z bending"
nominal_hz = 1.91
bound_percent = 1.1
mode = 7
mode_label = "1st Z bending"
"""


def test_what_one_writes_the_reader_reads_to_the_last_digit(tmp_path):
    path = tmp_path / "bounds.toml"
    path.write_text(bounds_toml(BOUNDS, comment="two modes"))
    assert read_bounds(path) == BOUNDS
    assert relative_bounds(read_bounds(path)) == {7: 1.1 / 100, 9: (100 / 7) / 100}


def test_a_table_5_3_toml_gives_its_modes_bounds_and_checks_their_labels(tmp_path):
    from mace_fmu.zero_g.table import read_frequency_bounds

    path = tmp_path / "table_5_3.toml"
    path.write_text(TABLE_ROWS)  # a servo row without a mode carries no bound
    labels = ["x"] * 6 + ["1st Z bending"]
    assert read_frequency_bounds(path, mode_labels=labels) == {7: 1.1 / 100}
    with pytest.raises(MaceError, match=r"table_5_3\.toml: mode 7 is '1st Z bending' there but 'y' in this model"):
        read_frequency_bounds(path, mode_labels=["x"] * 6 + ["y"])
    path.write_text(TABLE_ROWS.replace("bound_percent = 1.1", "bound_percent = 100.0"))
    with pytest.raises(MaceError, match=r"\[\[mode\]\] 2: expected mode >= 1, mode_label and bound_percent in"):
        read_bounds(path)


@pytest.mark.parametrize("value", [1.0, -0.1, "0.1", True, float("nan")])
def test_a_relative_bound_outside_0_to_1_is_refused_by_name(value):
    with pytest.raises(MaceError, match=r"^--bound 9=x: .* is not a relative bound in \[0, 1\)"):
        relative_bound(value, what="--bound 9=x")


def test_a_bound_is_a_frequency_scales_range_either_side_of_one():
    assert relative_bound(np.float64(0.25), what="b") == 0.25
    assert scale_range(0.25) == (0.75, 1.25)
