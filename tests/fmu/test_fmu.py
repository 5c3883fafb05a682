"""The 1-g and 0-g FMUs against the same models' state-space responses (exact ZOH).

pythonfmu pitfall: deleting an extracted FMU folder while the process runs and then loading
more pythonfmu FMUs has been seen to abort Python at exit. Each FMU is therefore extracted once
into a pytest temporary directory that lives until the session ends, and every simulation uses
that folder (fmpy then extracts and deletes nothing).
"""

from __future__ import annotations

from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from support.fmu_checks import (DURATION, check_close, initialised_slave, make_inputs, nominal_slave, rss_bytes,
                                run_in_libcosim, run_steps, value_references, zoh_reference)
from support.paths import EXAMPLES

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.fmu.validation import validate_fmu
from mace_fmu.iomodel.model_options import ModelledElectronics, SignalSelection
from mace_fmu.iomodel.motion import MOTION_COMPONENTS
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.structure.build import apply_overrides
from mace_fmu.structure.file import bundled_deck_path


@pytest.fixture(scope="module", params=["1g", "0g"])
def built(request, tmp_path_factory):
    model = volts_model(compute_modes(configuration=request.param))
    fmu = export_fmu(model, out_dir=tmp_path_factory.mktemp("fmu"), runtime="pythonfmu")
    unzipped = fmpy.extract(str(fmu), unzipdir=str(tmp_path_factory.mktemp("unzipped")))
    return model, fmu, unzipped


def test_model_description_validates_and_names_signals(built):
    model, fmu, _ = built
    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    assert md.modelName == f"MACE_{model.structure_modes.structure.configuration}"
    assert md.defaultExperiment.startTime == "0.0" and md.defaultExperiment.stopTime == "10.0"
    assert md.defaultExperiment.stepSize == "0.002"
    ins = [v for v in md.modelVariables if v.causality == "input"]
    outs = [v for v in md.modelVariables if v.causality == "output"]
    assert [v.name for v in ins] == list(model.system.input_labels)
    assert [v.name for v in outs] == list(model.system.output_labels)
    assert all(v.unit == "V" and v.description for v in ins + outs)
    assert "1 V = 1 deg" in ins[0].description and md.description and md.author == "mace-fmu"


@pytest.mark.parametrize("signal", ["step", "chirp", "multisine"])
@pytest.mark.parametrize("step", [1e-3, 2e-3])
def test_fmpy_simulation_equals_state_space(built, signal, step):
    model, _, unzipped = built
    t = np.arange(0.0, DURATION + step / 2, step)
    names = list(model.system.input_labels)
    u = make_inputs(signal, t, len(names))
    table = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = t
    for i, n in enumerate(names):
        table[n] = u[i]
    res = fmpy.simulate_fmu(unzipped, start_time=0.0, stop_time=t[-1], step_size=step, output_interval=step,
                            input=table, output=list(model.system.output_labels))
    assert np.allclose(res["time"], t)
    y = np.array([res[n] for n in model.system.output_labels])
    check_close(model, y, zoh_reference(model, t, u))


def test_varying_step_sizes_are_exact(built):
    model, _, unzipped = built
    rng = np.random.default_rng(3)
    t = np.concatenate([[0.0], np.cumsum(rng.choice([0.5e-3, 1e-3, 2e-3, 3.7e-3], size=300))])
    u = make_inputs("multisine", t, model.system.ninputs)
    fmu = nominal_slave(model, unzipped)
    y = run_steps(model, fmu, unzipped, t, u)
    fmu.terminate()
    fmu.freeInstance()
    check_close(model, y, zoh_reference(model, t, u))


def test_instances_are_independent_and_state_can_be_saved(built):
    model, _, unzipped = built
    t = np.arange(0.0, 0.3, 2e-3)
    u1, u2 = make_inputs("multisine", t, model.system.ninputs), make_inputs("step", t, model.system.ninputs)
    a, b = nominal_slave(model, unzipped, "a"), nominal_slave(model, unzipped, "b")
    ya, yb = run_steps(model, a, unzipped, t, u1), run_steps(model, b, unzipped, t, u2)
    check_close(model, ya, zoh_reference(model, t, u1))
    check_close(model, yb, zoh_reference(model, t, u2))
    # save the state of a, disturb it, restore it: the continuation is the same
    ins, outs = value_references(unzipped)
    out_vr = [outs[n] for n in model.system.output_labels]
    state = a.getFMUstate()
    a.doStep(currentCommunicationPoint=t[-1], communicationStepSize=2e-3)
    first = a.getReal(out_vr)
    a.setFMUstate(state)
    a.doStep(currentCommunicationPoint=t[-1], communicationStepSize=2e-3)
    assert a.getReal(out_vr) == first
    for fmu in (a, b):
        fmu.terminate()
        fmu.freeInstance()


def test_non_finite_input_is_an_error_not_garbage(built):
    model, _, unzipped = built
    ins, _ = value_references(unzipped)
    fmu = nominal_slave(model, unzipped)
    fmu.setReal([ins[model.system.input_labels[0]]], [float("nan")])
    with pytest.raises(FMICallException):
        fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1e-3)
    fmu.freeInstance()


@pytest.mark.slow
def test_libcosim_gives_the_same_outputs_as_fmpy(built):
    """The Open Simulation Platform's libcosim (libcosimpy) as a second, independent FMI host."""
    from pathlib import Path

    model, fmu, unzipped = built
    step, n = 2e-3, 200
    t = np.arange(n + 1) * step
    u = make_inputs("multisine", t, model.system.ninputs)
    y_cosim = run_in_libcosim(fmu, model=model, u=u[:, :n], step_s=step,
                              exchange=Path(unzipped).parent / "libcosim_io.npz")
    fmu_fmpy = nominal_slave(model, unzipped, "fmpy")
    y_fmpy = run_steps(model, fmu_fmpy, unzipped, t, u)[:, 1:]
    fmu_fmpy.terminate()
    fmu_fmpy.freeInstance()
    span = np.ptp(y_fmpy, axis=1, keepdims=True)
    assert np.max(np.abs(y_cosim - y_fmpy) / span) <= 1e-10


@pytest.fixture(scope="module")
def fmu_1g(tmp_path_factory):
    return export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=tmp_path_factory.mktemp("fmu_1g"),
                      runtime="pythonfmu")


@pytest.mark.slow
def test_cosimulation_example_closes_a_loop_around_the_1g_fmu(fmu_1g, tmp_path_factory):
    """examples/cosimulate.py: a Python controller stepping the FMU through fmpy damps the payload."""
    import sys

    import fmpy

    # unpacked into a folder that outlives the test process's FMU instances (docs/guide/fmus.md, "Teardown")
    unzipped = fmpy.extract(str(fmu_1g), unzipdir=str(tmp_path_factory.mktemp("cosim_unzipped")))
    sys.path.insert(0, str(EXAMPLES))
    from cosimulate import simulate

    rms = lambda y: float(np.sqrt(np.mean(y**2)))  # noqa: E731
    open_loop, closed = simulate(unzipped, gain=0.0), simulate(unzipped, gain=0.2)
    assert 0.05 < rms(open_loop) < 1.0
    assert 20 * np.log10(rms(closed) / rms(open_loop)) < -2.0


@pytest.mark.slow
def test_fmu_runs_in_a_fresh_venv_without_mace_fmu(fmu_1g, tmp_path):
    """Self-contained: a new virtual environment with only numpy, scipy and a host (fmpy) runs
    the FMU (pythonfmu itself is embedded in it) and reproduces this process's outputs.

    The three distributions and what they require are linked from this environment
    (tests/support/curated_site.py) rather than downloaded: the same packages, without the index."""
    import json
    import subprocess
    import sys

    from support.curated_site import curated_site

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    linked = curated_site(tmp_path / "site", ("numpy", "scipy", "fmpy"))
    assert "pythonfmu" not in linked and "mace-fmu" not in linked
    purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                             check=True, capture_output=True, text=True).stdout.strip()
    Path(purelib, "curated.pth").write_text(f"{tmp_path / 'site'}\n")
    script = tmp_path / "host.py"
    script.write_text(
        "import importlib.util, json, sys, fmpy, numpy as np\n"
        "assert importlib.util.find_spec('mace_fmu') is None and importlib.util.find_spec('pythonfmu') is None\n"
        "assert importlib.util.find_spec('control') is None\n"
        "t = np.arange(0, 0.2001, 0.002)\n"
        "sig = np.zeros(len(t), dtype=[('time', float), ('gimbal_secondary_z', float)])\n"
        "sig['time'] = t; sig['gimbal_secondary_z'] = 1.0\n"
        "res = fmpy.simulate_fmu(sys.argv[1], stop_time=0.2, step_size=0.002, output_interval=0.002, input=sig,\n"
        "                        output=['gyro_payload_z', 'encoder_secondary_z'])\n"
        "print(json.dumps([list(res['gyro_payload_z']), list(res['encoder_secondary_z'])]), flush=True)\n"
        # pythonfmu's native wrapper can corrupt the heap while the interpreter finalises, after the
        # results are out (seen 1 run in 3); the host skips finalisation, as conftest.py does
        "import os; os._exit(0)\n")
    out = subprocess.run([str(python), str(script), str(fmu_1g)], check=True, capture_output=True, text=True,
                         cwd=tmp_path)
    fresh = np.array(json.loads(out.stdout.strip().splitlines()[-1]))
    model = volts_model(compute_modes(configuration="1g"))
    t = np.arange(0, 0.2001, 0.002)
    u = np.zeros((model.system.ninputs, len(t)))
    u[list(model.system.input_labels).index("gimbal_secondary_z")] = 1.0
    ref = zoh_reference(model, t, u)
    outs = list(model.system.output_labels)
    expected = np.array([ref[outs.index("gyro_payload_z")], ref[outs.index("encoder_secondary_z")]])
    assert np.max(np.abs(fresh - expected) / np.ptp(expected, axis=1, keepdims=True)) <= 1e-8


@pytest.mark.slow
def test_instantiate_simulate_free_cycles_do_not_grow_memory(tmp_path):
    """pythonfmu 0.7 leaks what each instantiation's re-execution of the entry script creates and
    takes a reference to the module dict it does not own; the entry script (fmu/export.py)
    creates its class once and pays that reference back, so instances cost no memory.

    The leak was about 52 kB per instance, whatever the model (the entry script is the same), so a
    small model (15 states: 10 ms a cycle against 87 ms for the 1-g model) stands in. After 300
    warm-up cycles (the allocator's pools settle: about 5 MB) 500 cycles grew the resident set by
    2.2-2.5 MB in four runs; at most 8 MB is allowed (16 kB per cycle): the leak would give 26 MB."""
    model = volts_model(compute_modes(configuration="0g", max_hz=5.0),
                        electronics=ModelledElectronics(servos=False, bessel="none", delays=False),
                        signals=SignalSelection(inputs=["gimbal_secondary_z"], outputs=["gyro_payload_z"]))
    fmu_small = export_fmu(model, out_dir=tmp_path, runtime="pythonfmu", name="small")
    unzipped = fmpy.extract(str(fmu_small), unzipdir=str(tmp_path / "unzipped"))
    ins, outs = value_references(unzipped)
    in_vr, out_vr = [ins["gimbal_secondary_z"]], [outs["gyro_payload_z"]]

    def cycle(k: int) -> float:
        fmu = nominal_slave(model, unzipped, f"cycle{k}")
        fmu.setReal(in_vr, [1.0])
        for j in range(10):
            fmu.doStep(currentCommunicationPoint=j * 2e-3, communicationStepSize=2e-3)
        value = fmu.getReal(out_vr)[0]
        fmu.terminate()
        fmu.freeInstance()
        return value

    first = [cycle(k) for k in range(300)]  # warm-up: caches, allocator pools
    before = rss_bytes()
    values = [cycle(k) for k in range(300, 800)]
    growth = rss_bytes() - before
    assert len(set(first + values)) == 1  # every instance starts from rest and computes the same
    print(f"resident memory growth over 500 cycles: {growth / 2**20:.2f} MB")
    assert growth < 8 * 2**20, f"resident memory grew by {growth / 2**20:.1f} MB over 500 cycles"


def test_reset_returns_to_rest_and_reruns_identically(built):
    model, _, unzipped = built
    t = np.arange(0.0, 0.1, 2e-3)
    u = make_inputs("multisine", t, model.system.ninputs)
    fmu = nominal_slave(model, unzipped)
    first = run_steps(model, fmu, unzipped, t, u)
    fmu.reset()
    _, outs = value_references(unzipped)
    assert fmu.getReal([outs[n] for n in model.system.output_labels]) == [0.0] * model.system.noutputs
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    again = run_steps(model, fmu, unzipped, t, u)
    fmu.terminate()
    fmu.freeInstance()
    np.testing.assert_array_equal(first, again)


def _frequencies(fmu, unzipped) -> np.ndarray:
    md = fmpy.read_model_description(unzipped)
    freq = sorted((int(v.name.rsplit("_", 1)[1]), v.valueReference) for v in md.modelVariables
                  if v.name.startswith("frequency_mode_"))
    return np.array(fmu.getReal([vr for _, vr in freq]))


def test_physical_parameter_reanalysis_matches_the_fe_rebuild(built):
    """E of Lexan center +5 % set in the FMU (Ritz reanalysis on the retained modes, eq. 4.6-4.9)
    against the FE core rebuilt with that modulus: every flexible mode within 1e-3 (measured 2.8e-4
    in 0-g, 7.8e-4 in 1-g, where the stiffness change is taken about the sagged configuration)."""

    model, _, unzipped = built
    kind = model.structure_modes.structure.configuration
    e = model.structure_modes.structure.deck.mat1s[2].youngs_modulus
    fmu = initialised_slave(model, unzipped, {"E_lexan_center": 1.05 * e})
    ours = _frequencies(fmu, unzipped)
    fmu.freeInstance()
    rebuilt = compute_modes(apply_overrides(read_deck(bundled_deck_path()), {("MAT1", 2): {"e": 1.05 * e}}),
                            configuration=kind).modes
    ref, labels = rebuilt.frequencies_hz[:len(ours)], rebuilt.labels[:len(ours)]
    nominal = model.plant.frequencies_hz
    flexible = np.abs(ref) > 0.01
    assert np.max(np.abs(ref[flexible] / nominal[flexible] - 1)) > 0.015  # the change moves modes by 2 %
    error = np.abs(np.sort(ours)[flexible] / ref[flexible] - 1)
    assert np.max(error) < 1e-3, f"worst: {np.array(labels)[flexible][np.argmax(error)]} ({np.max(error):.1e})"


def test_reanalysed_modes_keep_their_index_through_a_frequency_crossing(motion_fmu_0g):
    """The piezo stack modulus x 1.5 (the top of its declared range) lifts 2nd Y bending (8.638 Hz) above
    2nd Z bending (8.667 Hz). frequency_mode_k (and damping_mode_k) must follow the physical mode: checked
    against the FE rebuild, whose modes are labelled from their energy distributions."""

    model, _, unzipped = motion_fmu_0g
    md = fmpy.read_model_description(unzipped)
    param = next(v for v in md.modelVariables if v.name == "E_active_strut_piezo")
    mid = int(param.description.split("MAT1 ")[1].split(")")[0])
    fmu = initialised_slave(model, unzipped, {param.name: 1.5 * float(param.start)})
    ours = _frequencies(fmu, unzipped)
    fmu.freeInstance()
    deck = read_deck(bundled_deck_path())
    rebuilt = compute_modes(apply_overrides(deck, {("MAT1", mid): {"e": 1.5 * float(param.start)}}),
                            configuration="0g").modes
    labels = list(model.plant.labels)
    y, z = labels.index("2nd Y bending"), labels.index("2nd Z bending")
    want = {k: rebuilt.frequencies_hz[list(rebuilt.labels).index(labels[k])] for k in (y, z)}
    assert model.plant.frequencies_hz[y] < model.plant.frequencies_hz[z]
    assert want[y] > want[z] and ours[y] > ours[z]  # crossed in the FE rebuild, and in the FMU at the same index
    # Ritz is an upper bound; with the static corrections in its basis it is 1.1e-8 above the rebuild (on the
    # retained modes alone: +1.3 % and +0.8 % for twice the modulus)
    for k in (y, z):
        assert want[k] <= ours[k] <= (1 + 1e-6) * want[k]


@pytest.mark.parametrize("change", ["delay", "servo", "damping"])
def test_parameters_rebuild_the_same_model_as_volts_model(built, change):
    """A delay, a servo gain or a modal damping ratio set in the FMU gives the response of the
    model rebuilt by volts_model with that value (1e-8 of each output's range)."""
    from mace_fmu.parameters.sets import ParameterSet

    model, _, unzipped = built
    if change == "delay":
        start, values = {"delay_gimbal_primary_x": 6.0e-3}, {"delay_gimbal_primary_x": 6.0e-3}
    elif change == "servo":
        start, values = {"K_a": -1.5}, {"K_a": -1.5}
    else:
        k = list(model.plant.labels).index("1st Z bending")
        start, values = {f"damping_mode_{k + 1}": 0.05}, {"damping:1st Z bending": 0.05}
    rebuilt = volts_model(model.structure_modes, parameters=ParameterSet(values))
    t = np.arange(0.0, 0.4, 2e-3)
    u = make_inputs("multisine", t, model.system.ninputs)
    fmu = initialised_slave(model, unzipped, start)
    y = run_steps(model, fmu, unzipped, t, u)
    fmu.terminate()
    fmu.freeInstance()
    check_close(rebuilt, y, zoh_reference(rebuilt, t, u))
    assert np.max(np.abs(y - zoh_reference(model, t, u))) > 1e-6  # the parameter did change the response


def test_motion_outputs_equal_state_space_with_units(motion_fmu_0g):
    """Every grid's six motion outputs [m, rad] follow the state-space model like the sensors do."""
    model, fmu, unzipped = motion_fmu_0g
    grids = model.structure_modes.modes.dofs.grid_ids
    outs = list(model.system.output_labels)
    assert len(outs) == 20 + 6 * len(grids) and outs[20:26] == [f"grid_{grids[0]}_{c}" for c in MOTION_COMPONENTS]
    md = fmpy.read_model_description(str(fmu))
    units = {v.name: v.unit for v in md.modelVariables if v.causality == "output"}
    assert units[f"grid_{grids[5]}_ty"] == "m" and units[f"grid_{grids[5]}_rz"] == "rad"
    assert units["gyro_bus_x"] == "V" and validate_fmu(str(fmu)) == []
    step = 2e-3
    t = np.arange(0.0, 0.5 + step / 2, step)
    names = list(model.system.input_labels)
    u = make_inputs("multisine", t, len(names))
    table = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = t
    for i, n in enumerate(names):
        table[n] = u[i]
    res = fmpy.simulate_fmu(unzipped, start_time=0.0, stop_time=t[-1], output_interval=step, input=table)
    y = np.array([res[n] for n in outs])
    ref = zoh_reference(model, t, u)
    span = np.ptp(ref, axis=1)
    moving = span > 0
    # one grid carries no element and no mass (it rests); everything else moves
    assert moving.sum() >= len(outs) - 6
    assert np.max(np.abs(y - ref)[moving] / span[moving, None]) <= 1e-8
    assert np.all(y[~moving] == 0.0) and np.all(ref[~moving] == 0.0)


def test_motion_outputs_keep_the_centre_of_mass_at_rest_in_0g(motion_fmu_0g):
    """Internal torques cannot move the free-floating structure's centre of mass: r^T M u(t) = 0.

    u(t) is the whole displacement field read from the FMU's motion outputs, M the assembled
    mass matrix (an independent check: it is not used to build the outputs).
    """
    from mace_fmu.fmu.simulate import simulate_input_response

    model, _, unzipped = motion_fmu_0g
    sm = model.structure_modes
    grids = sm.modes.dofs.grid_ids
    run = simulate_input_response(unzipped, input_name="rwa_y", signal="chirp", duration_s=1.0, chirp_hz=(0.5, 20.0))
    u = np.stack([np.stack([run.outputs[f"grid_{g}_{c}"] for c in MOTION_COMPONENTS], axis=1) for g in grids], axis=1)
    u = u.reshape(len(run.times_s), -1)  # (n_samples, 6 n_grid), DOFs in DofMap order
    mass = sm.model.mass
    for axis in range(3):
        rigid = np.zeros(mass.shape[0])
        rigid[axis::6] = 1.0
        centre = u @ (mass @ rigid) / (rigid @ mass @ rigid)  # centre-of-mass displacement [m]
        assert np.max(np.abs(centre)) <= 1e-9 * np.max(np.abs(u[:, axis::6]))
    assert np.max(np.abs(u[:, 1::6])) > 1e-6  # the structure does move (metres per volt of wheel command)


def test_export_leaves_no_cached_implementation_behind(tmp_path):
    """The builder runs the entry script in the exporting process; its cache entry goes with it, so a
    long model-updating loop that exports many FMUs does not accumulate implementations."""
    import sys

    from mace_fmu.fmu.export import _CACHE_PREFIX

    before = {k for k in sys.modules if k.startswith(_CACHE_PREFIX)}
    export_fmu(volts_model(compute_modes(configuration="0g", max_hz=20.0)), out_dir=tmp_path, name="MACE_0g_small",
               runtime="pythonfmu")
    assert {k for k in sys.modules if k.startswith(_CACHE_PREFIX)} == before
