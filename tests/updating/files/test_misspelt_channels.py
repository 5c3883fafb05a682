"""A misspelt data channel is named with the closest names there are.

A data file's channel the FMU does not have was refused with the FMU's whole signal list (fifty names and
more for MACE) and no hint; a channel the channel map lacks, with none at all.
"""

from __future__ import annotations

import pytest

from mace_fmu.errors import MaceError
from mace_fmu.updating.files import read_channel_map, read_time_history
from mace_fmu.updating.fmu.model import FmuInterface

OUTPUTS = ("gyro_bus_x", "gyro_bus_y", "gyro_bus_z", "gyro_payload_x", "strain_strut2_y")


def _interface() -> FmuInterface:
    return FmuInterface(path="MACE_1g_native.fmu", guid="", model_identifier="MACE_1g_native", generation_tool="",
                        inputs=("gimbal_primary_x", "gimbal_primary_z"), outputs=OUTPUTS, parameters={},
                        references={}, units={})


def test_a_channel_the_fmu_lacks_is_named_with_its_closest_signals():
    with pytest.raises(MaceError) as refused:
        _interface().check_signals(inputs=["gimbal_primary_x"], outputs=["gyro_bus_xx"], where="test.csv")
    message = str(refused.value)
    assert message.startswith("test.csv: channel(s) output 'gyro_bus_xx' (did you mean 'gyro_bus_x' or "), message
    with pytest.raises(MaceError, match=r"input 'gimbal_primry_z' \(did you mean 'gimbal_primary_z'"):
        _interface().check_signals(inputs=["gimbal_primry_z"], outputs=[], where="test.csv")
    with pytest.raises(MaceError, match=r"channel\(s\) output 'temperature' not in MACE_1g_native.fmu"):
        _interface().check_signals(inputs=[], outputs=["temperature"], where="test.csv")  # nothing close: no hint


def test_a_channel_the_map_lacks_is_named_with_the_maps_closest(tmp_path):
    (tmp_path / "map.csv").write_text("channel,signal,role,unit\nCH01,gimbal_primary_x,input,V\n"
                                      "CH02,gyro_bus_x,output,V\n")
    channel_map = read_channel_map(tmp_path / "map.csv")
    (tmp_path / "typo.csv").write_text("time [s],CH01 [V],CH2 [V]\n0,0,0\n0.002,0,0\n")
    with pytest.raises(MaceError, match=r"channel 'CH2' is not in the channel map .*map\.csv \(did you mean "
                                        r"'CH02'\? Else add it, with role 'ignore' to skip it\)"):
        read_time_history(tmp_path / "typo.csv", channel_map=channel_map)
