"""The one registry of parameter kinds: both spellings of every kind decode to it, and the ranges
FMUs declare follow from it (mace_fmu.parameters.kinds)."""

from __future__ import annotations

import pytest

from mace_fmu.parameters.kinds import (DAMPING, DELAY, FREQUENCY_SCALE, GAIN, KINDS, MASS, MODULUS, SPRING, ZERO_HZ,
                                       declared_range, kind_of_fmu_name, kind_of_set_name, mode_label, mode_number,
                                       unit_of)
from mace_fmu.parameters.sets import parameter_kind, parameter_unit


@pytest.mark.parametrize("set_name, fmu_name, kind, unit", [
    ("E_lexan_center", "E_lexan_center", MODULUS, "Pa"),
    ("k_suspension_device_1", "k_suspension_device_1", SPRING, "N/m"),
    ("m_floor_1", "m_floor_1", MASS, "kg"),
    ("delay_gyro_bus_y", "delay_gyro_bus_y", DELAY, "s"),
    ("K_a", "K_a", GAIN, "V/deg"),
    ("K_r", "K_r", GAIN, "V/(deg/s)"),
    ("damping:1st Z bending", "damping_mode_14", DAMPING, "1"),
    ("frequency_scale:1st Z bending", "frequency_scale_mode_14", FREQUENCY_SCALE, "1"),
])
def test_both_spellings_decode_to_one_kind(set_name, fmu_name, kind, unit):
    assert kind_of_set_name(set_name) is kind and kind_of_fmu_name(fmu_name) is kind
    assert parameter_kind(set_name) == kind.name
    assert unit_of(kind, fmu_name) == unit and parameter_unit(set_name) == unit
    if kind.per_mode:
        assert mode_number(fmu_name) == 14 and mode_label(set_name) == "1st Z bending"
        assert kind.fmu_name(14) == fmu_name and kind.set_name("1st Z bending") == set_name


@pytest.mark.parametrize("name", ["damping_mode_", "damping_mode_x", "frequency_scale_mode_1a", "E_", "K_z", "zeta"])
def test_names_of_no_kind_are_not_guessed(name):
    assert kind_of_fmu_name(name) is None


def test_declared_ranges_follow_the_kinds():
    assert declared_range("E_lexan_center", 2.335e9) == pytest.approx((1.6345e9, 3.5025e9), rel=1e-15)
    assert declared_range("k_suspension_device_1", 16.9878) == pytest.approx((11.89146, 25.4817), rel=1e-15)
    assert declared_range("m_floor_1", 5.2) == pytest.approx((3.64, 7.8), rel=1e-15)
    assert declared_range("delay_rwa_x", 0.00674) == (0.0, 1.0)
    assert declared_range("damping_mode_3", 0.02) == (0.0, 1.0)
    assert declared_range("K_f", 4.3) == (-4300.0, 4300.0) and declared_range("K_a", -2.0) == (-2000.0, 2000.0)
    assert declared_range("K_r_gimbal_z", 0.0) == (-1000.0, 1000.0)
    assert declared_range("frequency_scale_mode_9", 1.0, frequency_hz=2.0) == (0.1, 10.0)
    # a slow mode: the lowest scale keeps it just above the zero-frequency cluster
    low, high = declared_range("frequency_scale_mode_9", 1.0, frequency_hz=0.05)
    assert high == 10.0 and low * 0.05 > ZERO_HZ and low * 0.05 == pytest.approx(ZERO_HZ, rel=1e-8)
    assert len({k.name for k in KINDS}) == len(KINDS) == 7


def test_the_registry_builds_the_names_it_decodes():
    from mace_fmu.parameters.kinds import (DELAY, MODULUS, SPRING, frequency_output_name, is_frequency_output,
                                           kind_of_set_name)

    assert MODULUS.named("lexan_end") == "E_lexan_end" and kind_of_set_name("E_lexan_end") is MODULUS
    assert SPRING.named("suspension_device_1") == "k_suspension_device_1"
    assert DELAY.named("gyro_bus_y") == "delay_gyro_bus_y" and kind_of_set_name("delay_gyro_bus_y") is DELAY
    with pytest.raises(ValueError):
        DAMPING.named("1st Z bending")  # per mode: DAMPING.set_name(label) and DAMPING.fmu_name(mode)
    assert frequency_output_name(14) == "frequency_mode_14" and is_frequency_output("frequency_mode_14")
    assert not is_frequency_output("frequency_mode_") and not is_frequency_output("frequency_scale_mode_14")
    # a modulus must be > 0 everywhere: the FMUs declare a positive minimum
    assert MODULUS.range_for(2.0e9)[0] > 0 and SPRING.range_for(17.0)[0] > 0
