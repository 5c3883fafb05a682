"""The record between a volts-volts model and the FMU writers: built once, the writers only serialise it."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from mace_fmu import SignalSelection, compute_modes, volts_model
from mace_fmu.errors import MaceError
from mace_fmu.fmu.export import export_fmu
from mace_fmu.fmu.native.model_description import fmu_variables
from mace_fmu.fmu.parametric import parametric_model
from mace_fmu.iomodel.parametric_data import parametric_arrays


@pytest.fixture(scope="module")
def model():
    modes = compute_modes(configuration="0g", max_hz=5.0)
    return volts_model(modes, signals=SignalSelection(inputs=["gimbal_secondary_z"], outputs=["gyro_payload_z"]))


def _entries(path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as z:
        return {n: z.read(n) for n in z.namelist() if n.startswith(("resources/", "modelDescription"))}


def test_the_record_holds_what_the_arrays_say(model):
    arrays = parametric_arrays(model)
    record = parametric_model(model, arrays=arrays, frequency_bounds={14: 0.05})
    assert [p.name for p in record.parameters] == [str(n) for n in arrays["param_names"]]
    assert [s.name for s in record.inputs] == ["gimbal_secondary_z"]
    assert record.signal_units == model.signal_units
    assert record.ranges["frequency_scale_mode_14"] == pytest.approx((0.95, 1.05))
    assert record.stiffness_sensitivities.shape == (len(record.physical_names), 15, 15)
    assert len(record.state_names) == model.system.nstates
    assert record.jacobian.a.shape == (model.system.nstates, model.system.nstates)
    assert record.jacobian is record.jacobian  # found once
    with pytest.raises(TypeError):
        record.arrays["param_names"] = np.array([])  # read-only
    causalities = {v.causality for v in fmu_variables(record)}
    assert causalities == {"input", "output", "parameter", "calculatedParameter", "local", "independent"}


def test_one_record_makes_the_same_fmus_as_the_model_alone(model, tmp_path):
    record = parametric_model(model)
    for runtime in ("native", "pythonfmu"):
        platforms = ["x86_64-linux"] if runtime == "native" else None
        alone = export_fmu(model, runtime=runtime, out_dir=tmp_path / "alone", name="m", platforms=platforms)
        given = export_fmu(model, runtime=runtime, out_dir=tmp_path / "given", name="m", platforms=platforms,
                           parametric=record)
        a, b = _entries(alone), _entries(given)
        if runtime == "pythonfmu":  # pythonfmu stamps its own GUID and time
            a.pop("modelDescription.xml"), b.pop("modelDescription.xml")
        assert a == b


def test_a_record_comes_without_arrays_or_bounds_beside_it(model, tmp_path):
    record = parametric_model(model)
    with pytest.raises(MaceError, match="parametric_model"):
        export_fmu(model, runtime="pythonfmu", out_dir=tmp_path, parametric=record, frequency_bounds={14: 0.05})
