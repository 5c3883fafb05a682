"""SSP 1.0 packages and SSV parameter files: schema-valid, lossless, and run by another host (ecos).

The proof of a package is that another tool runs it and gets our model: the 0-g plant with a
parameter set, as `mace-fmu export --ssp` writes it, run by ecos (its parameter set named at
initialisation) equals the exact ZOH response of `volts_model(parameters=set)`.
"""

from __future__ import annotations

import math
import zipfile

import numpy as np
import pytest
from support.paths import EXAMPLES

from mace_fmu.cli import main
from mace_fmu.errors import MaceError
from mace_fmu.parameters.sets import ParameterSet, Provenance
from mace_fmu.ssp import (FrequencyBound, SspComponent, SsvContent, parameter_set_from_ssv, parameter_set_to_ssv,
                          schema_problems, write_ssp)

pytestmark = pytest.mark.slow  # runs packages in ecos and fmpy


def _ecospy():
    """ecospy, or a skip that says what is missing (its library links against the libtbb12 system library,
    which .ci/run installs)."""
    try:
        import ecospy
    except (ImportError, OSError) as exc:
        pytest.skip(f"ecospy cannot load ({exc}); install it and the libtbb12 system library")
    return ecospy


SET = {"E_lexan_end": 2.9e9, "damping:1st Z bending": 0.031, "frequency_scale:1st Y bending": 1.02,
       "delay_gimbal_primary_x": 0.0021, "K_a": 0.9}


def test_ssv_round_trip_is_lossless_and_schema_valid():
    values = {**SET, "k_suspension_device_1": 1234.5678901234567, "damping:2nd Y bending": 1 / 3}
    prov = Provenance(created="2026-11-24T10:00:00+00:00", tool="mace-fmu test", configuration="0g",
                      final_cost=0.1 + 0.2, initial_cost=math.pi, notes="a \"quoted\" <note> & more")
    bounds = (FrequencyBound(mode=7, mode_label="1st Z bending", bound_percent=1.1),
              FrequencyBound(mode=9, mode_label="2nd Y bending", bound_percent=100 / 7))
    text = parameter_set_to_ssv(SsvContent(parameters=ParameterSet(values, prov), frequency_bounds=bounds))
    assert schema_problems(text, kind="ssv") == []
    back = parameter_set_from_ssv(text)
    assert dict(back.parameters.values) == values  # bit for bit: float repr round-trips
    assert back.parameters.provenance == prov
    assert back.frequency_bounds == bounds


def test_ssv_cli_round_trip_through_toml(tmp_path):
    provenance = Provenance(created="2026-11-24T10:00:00+00:00", tool="t", configuration="0g")
    ParameterSet(SET, provenance).write(tmp_path / "p.toml")
    (tmp_path / "b.toml").write_text('[[mode]]\nmode = 7\nmode_label = "1st Z bending"\nbound_percent = 1.1\n\n'
                                     '[[mode]]\nlabel = "servo"\n')
    assert main(["params", "to-ssv", str(tmp_path / "p.toml"), "--frequency-bounds", str(tmp_path / "b.toml"),
                 "-o", str(tmp_path / "p.ssv")]) == 0
    assert main(["params", "from-ssv", str(tmp_path / "p.ssv"), "-o", str(tmp_path / "q.toml"),
                 "--frequency-bounds-out", str(tmp_path / "c.toml")]) == 0
    assert ParameterSet.read(tmp_path / "q.toml") == ParameterSet.read(tmp_path / "p.toml")
    from mace_fmu.zero_g.table import read_frequency_bounds

    labels = ["x"] * 6 + ["1st Z bending"]
    assert read_frequency_bounds(tmp_path / "c.toml", mode_labels=labels) == {7: 1.1 / 100.0}


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace('unit="Pa"', 'unit="psi"'), "unit 'psi' is not declared"),
    (lambda t: t.replace('name="K_a"', 'name="K_zz"'), "K_zz"),
    (lambda t: t.replace('value="0.9"', 'value="nan"'), "not finite"),
    (lambda t: t.replace("SystemStructureParameterValues", "SomethingElse"), "expected an SSP 1.0"),
    (lambda t: t[:40], "not an XML file"),
])
def test_bad_ssv_is_one_message_naming_the_element(edit, message):
    text = edit(parameter_set_to_ssv(ParameterSet(SET)))
    with pytest.raises(MaceError, match=message):
        parameter_set_from_ssv(text, source="bad.ssv")


def test_ssv_with_a_foreign_unit_is_refused(tmp_path):
    text = parameter_set_to_ssv(ParameterSet(SET)).replace('<ssv:Real value="0.0021" unit="s"',
                                                           '<ssv:Real value="0.0021" unit="Pa"')
    with pytest.raises(MaceError, match=r"bad.ssv: <Parameter name='delay_gimbal_primary_x'>: unit 'Pa', expected 's'"):
        parameter_set_from_ssv(text, source="bad.ssv")


@pytest.fixture(scope="module")
def plant_ssp(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ssp")
    ParameterSet(SET).write(folder / "set.toml")
    ssp = folder / "plant.ssp"
    assert main(["export", "0g", "--parameters", str(folder / "set.toml"), "--ssp", str(ssp)]) == 0
    return ssp


def test_exported_package_is_schema_valid_and_binds_the_set(plant_ssp):
    with zipfile.ZipFile(plant_ssp) as z:
        assert sorted(z.namelist()) == ["SystemStructure.ssd", "resources/plant.fmu", "resources/plant.ssv"]
        assert schema_problems(z.read("SystemStructure.ssd"), kind="ssd") == []
        assert schema_problems(z.read("resources/plant.ssv"), kind="ssv") == []
        ssv = z.read("resources/plant.ssv").decode()
    # a label-named damping ratio became the FMU's per-mode parameter; the modulus and the frequency
    # scale are built in (the FMU's own scales are relative to the model it was built from)
    assert 'name="delay_gimbal_primary_x"' in ssv and 'name="K_a"' in ssv and "damping_mode_" in ssv
    assert "frequency_scale_mode_" not in ssv and "E_lexan_end" not in ssv


def test_ecos_runs_the_package_as_our_state_space_model(plant_ssp):
    ecospy = _ecospy()
    from support.fmu_checks import make_inputs, zoh_reference

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.volts import volts_model

    model = volts_model(compute_modes(configuration="0g", parameters=ParameterSet(SET)))
    h, n = 2e-3, 300
    t = np.arange(n + 1) * h
    inputs = list(model.system.input_labels)
    outputs = list(model.system.output_labels)
    u = make_inputs("multisine", t, len(inputs))
    ref = zoh_reference(model, t, u)
    def run(parameter_set):
        y = np.zeros_like(ref)
        with ecospy.EcosSimulation(ssp_path=str(plant_ssp), step_size=h) as sim:
            assert sim.init(parameter_set=parameter_set)
            for k in range(n + 1):
                if k:
                    sim.step()  # holds the inputs set at t_{k-1} over [t_{k-1}, t_k), as the ZOH does
                y[:, k] = [sim.get_real(f"plant::{name}") for name in outputs]
                for i, name in enumerate(inputs):
                    sim.set_real(f"plant::{name}", float(u[i, k]))
        return np.max(np.abs(y - ref) / np.ptp(ref, axis=1)[:, None])

    assert np.all(np.ptp(ref, axis=1) > 0)
    assert run("plant parameters") <= 1e-9
    # without the SSV (ecos applies a set only when named) the bound values are missing: far off
    assert run(None) > 1e-3


def test_package_with_an_unknown_parameter_or_signal_writes_nothing(plant_ssp, tmp_path):
    with zipfile.ZipFile(plant_ssp) as z:
        z.extract("resources/plant.fmu", tmp_path)
    fmu = tmp_path / "resources" / "plant.fmu"
    out = tmp_path / "x.ssp"
    with pytest.raises(MaceError, match=r"component 'plant' \(plant.fmu\): no tunable parameter 'E_nothing'"):
        write_ssp(out, components=[SspComponent("plant", fmu, {"E_nothing": 1.0})])
    with pytest.raises(MaceError, match=r"damping_mode_7 = 1.5 is outside the declared range \[0.0, 1.0\]"):
        write_ssp(out, components=[SspComponent("plant", fmu, {"damping_mode_7": 1.5})])
    from mace_fmu.ssp import SspConnection

    with pytest.raises(MaceError, match="component 'plant' has no input 'no_such_input'"):
        write_ssp(out, components=[SspComponent("plant", fmu), SspComponent("other", fmu)],
                  connections=[SspConnection("other", "gyro_bus_x", "plant", "no_such_input")])
    assert not out.exists()


@pytest.fixture(scope="module")
def closed_loop_ssp(tmp_path_factory):
    folder = tmp_path_factory.mktemp("loop")
    assert main(["export-controller", "--lqg", "-o", str(folder)]) == 0
    ssp = folder / "loop.ssp"
    assert main(["export", "0g", "--ssp", str(ssp), "--controller", str(folder / "controller.fmu")]) == 0
    return ssp


def _example():
    import importlib.util

    path = EXAMPLES / "closed_loop_ssp.py"
    spec = importlib.util.spec_from_file_location("closed_loop_ssp_example", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_closed_loop_package_runs_in_ecos_and_fmpy_as_the_state_space_loop(closed_loop_ssp, tmp_path, monkeypatch):
    """The 0-g plant with the Appendix A LQG controller, a 0.5 V step on the secondary gimbal's servo command."""
    _ecospy()
    example = _example()
    monkeypatch.setenv("TMPDIR", str(tmp_path))  # ecos extracts the package there
    h, n, w = 0.002, 1000, 0.5
    ref = example.state_space_loop(parameters=None, steps=n, step_s=h, disturbance_v=w)
    open_loop = example.state_space_loop(parameters=None, steps=n, step_s=h, disturbance_v=w, closed=False)
    span = np.ptp(ref)
    assert np.max(np.abs(open_loop - ref)) > 0.05 * span  # the controller acts: the check can tell the loops apart
    with zipfile.ZipFile(closed_loop_ssp) as z:
        assert schema_problems(z.read("SystemStructure.ssd"), kind="ssd") == []
    ecos = example.run_in_ecos(closed_loop_ssp, steps=n, step_s=h, disturbance_v=w, parameter_set=None)
    assert np.max(np.abs(ecos - ref)) <= 1e-9 * span
    fmpy_y = example.run_in_fmpy(closed_loop_ssp, steps=n, step_s=h, disturbance_v=w)  # holds t_1..t_n
    assert len(fmpy_y) == n and np.max(np.abs(fmpy_y - ref[1:])) <= 1e-9 * span


def test_example_from_the_updated_model_to_a_package_other_tools_run(tmp_path, monkeypatch):
    """examples/closed_loop_ssp.py: predict-0g's updated nominal model with its bounds, the LQG controller,
    one package; ecos and fmpy run it as the state-space loop."""
    _ecospy()
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    errors = _example().main(tmp_path / "out", quick=False)
    assert set(errors) == {"ecos", "fmpy"} and max(errors.values()) <= 1e-9
    with zipfile.ZipFile(tmp_path / "out" / "closed_loop.ssp") as z:
        ssv = z.read("resources/plant.ssv").decode()
    assert ssv.count("damping_mode_") >= 5  # Table 5.3's damping ratios travel in the SSV


def test_controller_with_another_sample_time_or_signal_is_refused(closed_loop_ssp, tmp_path, capsys):
    from mace_fmu.fmu.controller import DiscreteController, export_controller_fmu

    with zipfile.ZipFile(closed_loop_ssp) as z:
        z.extract("resources/plant.fmu", tmp_path)
    base = dict(a=[[0.5]], b=[[1.0]], c=[[1.0]], d=[[0.0]])
    slow = export_controller_fmu(DiscreteController(**base, sample_time_s=0.004, inputs=("gyro_payload_z",),
                                                    outputs=("gimbal_primary_z",)), out_dir=tmp_path, name="slow")
    alien = export_controller_fmu(DiscreteController(**base, sample_time_s=0.002, inputs=("gyro_nowhere",),
                                                     outputs=("gimbal_primary_z",)), out_dir=tmp_path, name="alien")
    for fmu, message in ((slow, "slow.fmu: <DefaultExperiment stepSize> .* 0.004 s is not the plant's communication "
                                "step 0.002 s"),
                         (alien, "alien.fmu: controller input 'gyro_nowhere' is not an output of the plant")):
        out = tmp_path / f"{fmu.stem}.ssp"
        assert main(["export", "0g", "--ssp", str(out), "--controller", str(fmu)]) == 2
        import re

        assert re.search(message, capsys.readouterr().err)
        assert not out.exists()
