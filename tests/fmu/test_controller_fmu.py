"""The controller FMU: a discrete state space on the native runtime, checked against control.forced_response.

The FMU is driven through FMI itself (fmpy's FMU2Slave / FMU3Slave): inputs u_k set at t_k, the
outputs y_k = C x_k + D u_k read at t_k, then a step to t_{k+1}; that is the discrete system's own
recursion, so the outputs must equal ``control.forced_response`` of it to rounding.
"""

from __future__ import annotations

import zipfile

import control as ct
import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from mace_fmu.cli import main
from mace_fmu.errors import MaceError
from mace_fmu.fmu.controller import DiscreteController, export_controller_fmu
from mace_fmu.fmu.validation import validate_fmu

STEP = 0.002


def _random_controller(seed: int = 3) -> ct.StateSpace:
    """A stable MIMO discrete system with a feedthrough, named signals."""
    rng = np.random.default_rng(seed)
    n, m, p = 7, 2, 3
    a = rng.normal(size=(n, n))
    a *= 0.97 / np.max(np.abs(np.linalg.eigvals(a)))
    return ct.ss(a, rng.normal(size=(n, m)), rng.normal(size=(p, n)), rng.normal(size=(p, m)), STEP,
                 inputs=["gyro_a", "gyro_b"], outputs=["cmd_x", "cmd_y", "cmd_z"])


@pytest.fixture(scope="module", params=[2, 3])
def exported(request, tmp_path_factory):
    system = _random_controller()
    fmu = export_controller_fmu(DiscreteController.from_statespace(system), out_dir=tmp_path_factory.mktemp("ctl"),
                                name=f"ctl_fmi{request.param}", fmi_version=request.param)
    return system, fmu, request.param


def _slave(fmu, version, tmp_path):
    md = fmpy.read_model_description(str(fmu))
    unzipped = fmpy.extract(str(fmu), unzipdir=str(tmp_path / "x"))
    if version == 2:
        slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
    else:
        slave = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier)
        slave.instantiate()
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return slave, vr


def _run(slave, vr, system, u, version, steps_per_call=1):
    set_, get = (slave.setReal, slave.getReal) if version == 2 else (slave.setFloat64, slave.getFloat64)
    ins = [vr[n] for n in system.input_labels]
    outs = [vr[n] for n in system.output_labels]
    y = np.zeros((system.noutputs, u.shape[1]))
    for k in range(u.shape[1]):
        set_(ins, list(u[:, k]))
        y[:, k] = get(outs)
        if k % steps_per_call == steps_per_call - 1 or steps_per_call == 1:
            slave.doStep(currentCommunicationPoint=(k + 1 - steps_per_call) * STEP,
                         communicationStepSize=steps_per_call * STEP)
    return y


def test_outputs_equal_forced_response_of_the_discrete_system(exported, tmp_path):
    system, fmu, version = exported
    t = np.arange(800) * STEP
    u = np.stack([np.sin(2 * np.pi * 3.0 * t), np.sign(np.sin(2 * np.pi * 11.0 * t))])
    ref = ct.forced_response(system, T=t, U=u).outputs
    slave, vr = _slave(fmu, version, tmp_path)
    y = _run(slave, vr, system, u, version)
    slave.terminate()
    slave.freeInstance()
    span = np.ptp(ref, axis=1)
    assert np.all(span > 0.1)
    assert np.max(np.abs(y - ref) / span[:, None]) <= 1e-12


def test_a_step_of_several_samples_runs_them_with_the_inputs_held(exported, tmp_path):
    system, fmu, version = exported
    u = np.repeat(np.random.default_rng(5).normal(size=(2, 40)), 4, axis=1)  # held over 4 samples
    ref = ct.forced_response(system, T=np.arange(u.shape[1]) * STEP, U=u).outputs
    slave, vr = _slave(fmu, version, tmp_path)
    set_, get = (slave.setReal, slave.getReal) if version == 2 else (slave.setFloat64, slave.getFloat64)
    ins, outs = [vr[n] for n in system.input_labels], [vr[n] for n in system.output_labels]
    for k in range(0, u.shape[1], 4):
        set_(ins, list(u[:, k]))
        assert np.allclose(get(outs), ref[:, k], rtol=0, atol=1e-12 * np.max(np.abs(ref)))
        slave.doStep(currentCommunicationPoint=k * STEP, communicationStepSize=4 * STEP)
    slave.freeInstance()


def test_any_step_size_runs_the_samples_whose_instants_it_passes(exported, tmp_path):
    """The model description says it handles variable steps: a step runs the samples at t0 + k T that lie in
    (t, t + h] with the inputs held, so steps of 1.5 T, 1.5 T, 0.25 T, 0.75 T end where 4 samples end (it
    refused them before, and left the instance in its error state)."""
    system, fmu, version = exported
    u = np.repeat(np.random.default_rng(6).normal(size=(2, 1)), 4, axis=1)
    ref = ct.forced_response(system, T=np.arange(5) * STEP, U=np.hstack([u, u[:, :1]])).outputs
    slave, vr = _slave(fmu, version, tmp_path)
    set_, get = (slave.setReal, slave.getReal) if version == 2 else (slave.setFloat64, slave.getFloat64)
    ins, outs = [vr[n] for n in system.input_labels], [vr[n] for n in system.output_labels]
    set_(ins, list(u[:, 0]))
    t, seen = 0.0, []
    for h, samples_done in ((1.5 * STEP, 1), (1.5 * STEP, 3), (0.25 * STEP, 3), (0.75 * STEP, 4)):
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        seen.append((samples_done, np.array(get(outs))))
    for samples_done, y in seen:
        assert np.allclose(y, ref[:, samples_done], rtol=0, atol=1e-12 * np.max(np.abs(ref))), samples_done
    slave.freeInstance()


@pytest.mark.parametrize("step_s", [1e20, 1e6, 2.1e3, 0.0])
def test_a_refused_step_leaves_the_instance_usable(exported, tmp_path, step_s):
    """One call runs at most a million samples (2000 s at 2 ms): doStep(h = 1e20) returned OK without stepping
    (the sample count overflowed) and h = 1e6 ran 250 s; both are refused before any work. A refused step is
    an invalid argument, as h = 0 is: an error that leaves the instance as it was, so the next step runs and
    gives the discrete system's next sample (the over-long step left it in its error state, every later step
    refused)."""
    system, fmu, version = exported
    slave, vr = _slave(fmu, version, tmp_path)
    set_, get = (slave.setReal, slave.getReal) if version == 2 else (slave.setFloat64, slave.getFloat64)
    ins, outs = [vr[n] for n in system.input_labels], [vr[n] for n in system.output_labels]
    u = np.array([[0.3], [-0.7]])
    set_(ins, list(u[:, 0]))
    with pytest.raises(FMICallException) as refused:
        slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=step_s)
    assert refused.value.status == 3  # an error, not fatal
    slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=STEP)
    ref = ct.forced_response(system, T=np.arange(2) * STEP, U=np.hstack([u, u])).outputs
    assert np.allclose(get(outs), ref[:, 1], rtol=0, atol=1e-12 * np.max(np.abs(ref)))
    slave.freeInstance()


def test_model_description_validates_and_carries_only_the_controller_runtime(exported):
    _, fmu, version = exported
    md = fmpy.read_model_description(str(fmu))
    assert md.modelExchange is None and md.coSimulation is not None
    assert float(md.defaultExperiment.stepSize) == STEP
    if version == 2:
        assert validate_fmu(str(fmu)) == []
    with zipfile.ZipFile(fmu) as z:
        sources = {n.split("/")[-1] for n in z.namelist() if n.startswith("sources/") and n.endswith(".c")}
    # a host that builds from sources compiles every C file there: no plant model beside the controller's
    assert "mace_discrete.c" in sources and "mace_model.c" not in sources and "mace_zoh.c" not in sources


def test_npz_round_trip_and_cli(tmp_path):
    controller = DiscreteController.from_statespace(_random_controller(seed=9))
    controller.write_npz(tmp_path / "k.npz")
    back = DiscreteController.read_npz(tmp_path / "k.npz")
    for name in "abcd":
        assert np.array_equal(getattr(back, name), getattr(controller, name))
    assert (back.inputs, back.outputs, back.sample_time_s) == (controller.inputs, controller.outputs, STEP)
    assert main(["export-controller", "--npz", str(tmp_path / "k.npz"), "--name", "k", "-o", str(tmp_path)]) == 0
    assert (tmp_path / "k.fmu").is_file()


@pytest.mark.parametrize("change, message", [
    (dict(a=np.ones((2, 3))), "A has shape"),
    (dict(sample_time_s=0.0), "sample time must be a positive"),
    (dict(inputs=("u", "u")), "distinct identifier names"),
    (dict(d=np.array([[np.nan, 0.0]])), "D has non-finite"),
])
def test_bad_controllers_are_refused(change, message):
    good = dict(a=np.eye(2) * 0.5, b=np.ones((2, 2)), c=np.ones((1, 2)), d=np.zeros((1, 2)), sample_time_s=STEP,
                inputs=("u", "v"), outputs=("y",))
    with pytest.raises(MaceError, match=message):
        DiscreteController(**{**good, **change})


def test_continuous_system_is_refused_with_a_hint():
    with pytest.raises(MaceError, match="discrete-time system"):
        DiscreteController.from_statespace(ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]]))


def test_fmu_manipulation_toolbox_checker_finds_no_error(exported):
    """fmutool -check, an independent checker, as on every FMU we write."""
    import subprocess
    import sys
    from pathlib import Path

    _, fmu, version = exported
    fmutool = Path(sys.executable).with_name("fmutool")
    done = subprocess.run([str(fmutool), "-input", str(fmu), "-check"], capture_output=True, text=True, timeout=300)
    text = done.stdout + done.stderr
    assert f"compliant with FMI-{version}.0" in text and "No semantic error" in text, text
    assert "ERROR" not in text, text
