"""Updating through FMU simulation (on a small case): the FMU as the model in the cost,
its runs side by side on a Dask LocalCluster, bit for bit the serial answer."""

from __future__ import annotations

import numpy as np
import pytest
from support.cli import run_cli
from support.paths import EXAMPLES

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.engine.sensitivity import cost_sensitivities
from mace_fmu.updating.engine.simulated_frf import H1Estimator
from mace_fmu.updating.files import h1_estimate
from mace_fmu.updating.fmu.model import fmu_family
from mace_fmu.updating.fmu.update import fmu_cost, update_fmu
from mace_fmu.updating.mace.update import pre_update_parameters, table_4_4_moduli

pytestmark = pytest.mark.slow  # updates simulate the FMU; the module builds its FMUs first

GIMBALS = ("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z")
GYROS = ("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z")
STEP = 0.002


@pytest.fixture(scope="module")
def fmu(native_fmu_1g):
    """The 1-g native FMU of the bundled deck (the truth and, with other start values, the model)."""
    return native_fmu_1g


def _noise_inputs(seconds: float, seed: int = 1) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    t = np.arange(int(round(seconds / STEP)) + 1) * STEP
    rng = np.random.default_rng(seed)
    out = {}
    for name in GIMBALS:  # white noise band-limited to 0.5-60 Hz, the thesis's update band
        spectrum = np.fft.rfft(rng.standard_normal(t.size))
        f = np.fft.rfftfreq(t.size, STEP)
        spectrum[(f < 0.5) | (f > 60.0)] = 0.0
        out[name] = np.fft.irfft(spectrum, t.size)
    return t, out


#: the FMU inputs the measured records leave out (held at 0 V, said explicitly)
UNRECORDED = "rwa_x=0,rwa_y=0,rwa_z=0,active_strut_y=0,active_strut_z=0"


def _measured(fmu, seconds: float, noise: float = 0.02) -> TimeHistory:
    t, u = _noise_inputs(seconds)
    y = fmu_family(fmu).full({}).time_response(t, u, outputs=GYROS)
    rng = np.random.default_rng(7)
    y = y + noise * np.sqrt(np.mean(y**2, axis=0)) * rng.standard_normal(y.shape)
    return TimeHistory(t, u, {o: y[:, k] for k, o in enumerate(GYROS)}, source="truth FMU")


def test_fmu_response_is_the_python_models_at_nominal_moduli_and_a_changed_delay(fmu):
    """Second route: the FMU run through FMI against the Python volts-volts model's exact ZOH simulation."""
    from mace_fmu.updating.mace.family import MaceFamily

    t, u = _noise_inputs(1.0)
    values = {"delay_gyro_bus_x": 0.0071, "delay_gimbal_primary_z": 0.0035}
    y_fmu = fmu_family(fmu).full(values).time_response(t, u, outputs=GYROS)
    y_py = MaceFamily().full(values).time_response(t, u, outputs=list(GYROS))
    assert np.max(np.abs(y_fmu - y_py)) < 1e-9 * np.max(np.abs(y_py))


def test_reset_between_runs_repeats_a_run_bit_for_bit(fmu):
    """One loaded instance, reset between runs: a run after another with other parameters is the same run."""
    family = fmu_family(fmu)
    t, u = _noise_inputs(0.5)
    first = family.full({"E_cable_1": 1.9e11}).time_response(t, u, outputs=GYROS)
    other = family.full({"E_cable_1": 1.7e11}).time_response(t, u, outputs=GYROS)
    again = family.full({"E_cable_1": 1.9e11}).time_response(t, u, outputs=GYROS)
    assert np.array_equal(first, again) and not np.array_equal(first, other)


def test_h1_estimate_of_a_two_input_delay_system_is_its_analytic_response():
    """MIMO H1 (both inputs driven at once): y1 = u1 + 2 u2[k-1], y2 = 3 u1[k-2] + 4 u2, so
    H = [[1, 2 z^-1], [3 z^-2, 4]] at z = exp(j 2 pi f dt)."""
    rng = np.random.default_rng(0)
    n, dt = 40_001, 0.002
    u1, u2 = rng.standard_normal(n), rng.standard_normal(n)
    y1 = u1 + 2.0 * np.concatenate([[0.0], u2[:-1]])
    y2 = 3.0 * np.concatenate([[0.0, 0.0], u1[:-2]]) + 4.0 * u2
    frd = h1_estimate(TimeHistory(np.arange(n) * dt, {"u1": u1, "u2": u2}, {"y1": y1, "y2": y2}),
                      segment_length=1000, band_hz=(1.0, 50.0))
    z = np.exp(2j * np.pi * frd.frequencies_hz * dt)
    exact = np.stack([np.stack([np.ones_like(z), 2.0 / z], -1), np.stack([3.0 / z**2, 4.0 * np.ones_like(z)], -1)], 1)
    # the only error: a delayed input leaks across segment edges (1-2 of 1000 samples): well under 1 % of the gain
    assert np.max(np.abs(frd.response - exact) / np.abs(exact)) < 0.01


@pytest.fixture(scope="module")
def pre_update_fmu(tmp_path_factory):
    """The 1-g FMU with the two lexan moduli at their pre-update values built in (a full re-solve): the model the
    updates start from, at its own nominal values; the data come from the deck's (Table 4.4's)."""
    from support.reexported import deck_moduli, fmu_with

    names = ("E_lexan_end", "E_lexan_center")
    deck = deck_moduli(names)
    return fmu_with(tmp_path_factory.mktemp("pre_update"), name="MACE_1g_pre_update",
                    factors={n: pre_update_parameters()[n] / deck[n] for n in names})


def test_time_domain_update_recovers_two_moduli_from_noisy_fmu_data(fmu, pre_update_fmu):
    """Truth: the bundled deck's lexan moduli (Table 4.4), its FMU's response; the model: the FMU with the
    pre-update moduli built in, from its own values; 2 % output noise, 4 s."""
    family = fmu_family(pre_update_fmu)
    names = ("E_lexan_end", "E_lexan_center")
    start = {n: family.interface.parameters[n] for n in names}
    truth = table_4_4_moduli()
    result = update_fmu(family=family, cost=fmu_cost("time", history=_measured(fmu, 4.0)), start=start, stages=[names])
    for n in names:
        assert abs(result.values[n] / truth[n] - 1.0) < 0.002, (n, result.values[n] / truth[n] - 1.0)
    assert result.reduction > 0.9


def test_log_frf_cost_is_zero_for_the_truth_without_noise_and_grows_away_from_it(fmu):
    """The same H1 estimator on data and model: the estimator's own errors cancel exactly."""
    family = fmu_family(fmu)
    history = _measured(fmu, 8.0, noise=0.0)
    cost = fmu_cost("log-frf", history=history, estimator=H1Estimator(segment_length=500, band_hz=(1.0, 60.0)),
                    weighting="none")
    assert np.max(np.abs(cost.residual(family.full({})))) < 1e-9
    assert np.max(np.abs(cost.residual(family.full({"E_lexan_center": 2.4e9})))) > 0.1


def _fmu_loads() -> int:
    from mace_fmu.updating.fmu.model import _loaded

    return _loaded.cache_info().misses


def _fmu_runs() -> int:
    from mace_fmu.updating.fmu.model import _loaded

    return _loaded.cache_info().hits + _loaded.cache_info().misses


def test_sensitivities_on_a_two_worker_local_cluster_are_the_serial_ones_bit_for_bit(fmu):
    from mace_fmu.util.runner import DaskRunner

    family = fmu_family(fmu)
    cost = fmu_cost("time", history=_measured(fmu, 2.0))
    names = ["E_lexan_end", "E_cable_1", "delay_gyro_bus_x"]
    base = {"E_lexan_end": 2.6e9, "E_cable_1": 1.9e11, "delay_gyro_bus_x": 0.006}
    serial = cost_sensitivities(cost, base_model=family.full(base), perturbed=family.full, base=base, names=names)
    steps = []
    with DaskRunner(workers=2, progress=steps.append, task="FMU runs") as runner:
        assert runner.workers == 2
        parallel = cost_sensitivities(cost, base_model=family.full(base), perturbed=family.full, base=base, names=names,
                                      runner=runner)
        again = update_fmu(family=family, cost=cost, start={"E_lexan_center": 2.45e9}, stages=[["E_lexan_center"]],
                           runner=runner)
        loads = runner.client.run(_fmu_loads)  # per worker: FMU instances made (each then reset between runs)
        runs = runner.client.run(_fmu_runs)
    assert all(n <= 1 for n in loads.values()) and sum(runs.values()) >= sum(loads.values()) + 3, (loads, runs)
    assert np.array_equal(serial.matrix, parallel.matrix) and np.array_equal(serial.j0, parallel.j0)
    assert [s.done for s in steps[:3]] == [1, 2, 3]
    alone = update_fmu(family=family, cost=cost, start={"E_lexan_center": 2.45e9}, stages=[["E_lexan_center"]])
    assert again.values == alone.values and np.array_equal(again.final_residual, alone.final_residual)


def test_unknown_parameter_and_channel_are_refused_naming_them(fmu):
    family = fmu_family(fmu)
    with pytest.raises(MaceError, match="E_unobtainium"):
        update_fmu(family=family, cost=fmu_cost("time", history=_measured(fmu, 0.2)), start={"E_unobtainium": 1.0},
                   stages=[["E_unobtainium"]])
    with pytest.raises(MaceError, match="gyro_nowhere"):
        family.interface.check_signals(inputs=GIMBALS, outputs=["gyro_nowhere"], where="data.csv")


# --- the CLI: mace-fmu update fmu ... (files from mace_fmu.updating.files) -----------------------------------

@pytest.fixture(scope="module")
def data_csv(fmu, tmp_path_factory):
    from mace_fmu.updating.files import write_time_history

    return write_time_history(_measured(fmu, 4.0), tmp_path_factory.mktemp("fmu_data") / "measured.csv")


@pytest.mark.parametrize("change, expected", [
    ({"--fmu": "nowhere.fmu"}, "nowhere.fmu: no such FMU file"),
    ({"--data": "nowhere.csv"}, "nowhere.csv: no such measured-data file"),
    ({"--update": "E_lexan_center,E_unobtainium"}, "no parameter(s) E_unobtainium"),
    ({"--cost": "log-frf", "--segment-s": "-1"}, "argument --segment-s: expected a finite number > 0, got '-1'"),
])
def test_cli_checks_arguments_before_any_simulation_exit_2(capsys, fmu, data_csv, tmp_path, change, expected):
    args = {"--fmu": str(fmu), "--data": str(data_csv), "--update": "E_lexan_center", "--cost": "time",
            "-o": str(tmp_path / "out"), "--hold-input": UNRECORDED}
    args.update(change)
    fmu_file = args.pop("--fmu")  # the FMU is update fmu's positional
    code, out, err = run_cli(capsys, ["update", "fmu", fmu_file] + [x for kv in args.items() for x in kv])
    assert code == 2 and expected in err and not (tmp_path / "out").exists()


def test_cli_refuses_data_channels_the_fmu_lacks(capsys, fmu, tmp_path):
    from mace_fmu.updating.files import write_time_history

    t = np.arange(200) * STEP
    bad = write_time_history(TimeHistory(t, {"gimbal_primary_x": np.sin(t)}, {"gyro_elsewhere": np.cos(t)}),
                             tmp_path / "bad.csv")
    code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(bad), "--update", "E_lexan_center",
                                 "-o", str(tmp_path / "out")])
    assert code == 2 and "output 'gyro_elsewhere'" in err


def test_cli_updates_an_fmu_parameter_and_writes_it_by_the_fmus_name(capsys, pre_update_fmu, data_csv, tmp_path):
    """Through a channel map (--map): the data file names its channels as a logger would (ai0, ai1, ...)."""
    import tomllib

    from mace_fmu.updating.files import read_time_history

    measured = read_time_history(data_csv)
    signals = [("input", k) for k in measured.inputs] + [("output", k) for k in measured.outputs]
    logger = {name: f"ai{k}" for k, (_, name) in enumerate(signals)}
    columns = [measured.times_s] + [{**measured.inputs, **measured.outputs}[name] for _, name in signals]
    logged = tmp_path / "logger.csv"
    np.savetxt(logged, np.column_stack(columns), delimiter=",", fmt="%.17g", comments="",
               header=",".join(["time [s]"] + [f"{logger[name]} [V]" for _, name in signals]))
    channel_map = tmp_path / "channels.csv"
    channel_map.write_text("channel,signal,role,unit\n" + "".join(f"{logger[name]},{name},{role},V\n"
                                                                  for role, name in signals))
    # the model: the FMU with the pre-update lexan moduli built in; the end one held at Table 4.4's through --start
    start = tmp_path / "start.toml"
    start.write_text(f"[values]\nE_lexan_end = {table_4_4_moduli()['E_lexan_end']!r}\n")
    fmu = pre_update_fmu
    code, out, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(logged), "--map", str(channel_map),
                                   "--update", "E_lexan_center", "--cost", "time", "--start", str(start),
                                   "--workers", "1", "-o", str(tmp_path / "o"), "--hold-input", UNRECORDED])
    assert code == 0, err  # converged; whether the model explains the data is convergence.toml's verdict
    written = tomllib.loads((tmp_path / "o" / "parameters.toml").read_text())
    assert written["provenance"]["configuration"] == "1g" and written["provenance"]["fitted_to"] == fmu.name
    values = written["values"]
    assert abs(values["E_lexan_center"] / table_4_4_moduli()["E_lexan_center"] - 1.0) < 0.002
    assert "E_lexan_center" in out and "% lower" in out


def test_an_input_the_data_lack_is_refused_unless_held_explicitly(capsys, fmu, data_csv, tmp_path):
    """The data drive the four gimbals only: the wheels and the active strut must be named as held at 0."""
    code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(data_csv), "--update", "E_lexan_center",
                                 "-o", str(tmp_path / "out")])
    assert code == 2 and "no channel for the FMU input(s) rwa_x, rwa_y, rwa_z, active_strut_y, active_strut_z" in err
    assert "--hold-input NAME=0" in err and not (tmp_path / "out").exists()
    for bad, message in (("rwa_x=1", "expected NAME=0"), ("wheel_9=0", "wheel_9 is not an input of")):
        code, _, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(data_csv), "--update",
                                     "E_lexan_center", "--hold-input", bad, "-o", str(tmp_path / "out")])
        assert code == 2 and message in err


def test_example_update_from_test_data_quick(tmp_path):
    """examples/update_from_test_data.py --quick (8 s record, the two lexan moduli, two delays, serial): the
    full run (20 s, 8 moduli, 9 delays) is the benchmark's (benchmarks/RESULTS.md)."""
    import importlib.util

    path = EXAMPLES / "update_from_test_data.py"
    spec = importlib.util.spec_from_file_location("update_from_test_data", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    summary = example.main(["--out", str(tmp_path), "--quick", "--workers", "0"])
    for name, u in summary["updates"].items():
        assert u["reduction_percent"] >= 90.0, (name, u["reduction_percent"])
        if name.startswith("moduli"):
            assert max(abs(e) for e in u["final_error_percent"].values()) < 1.0, (name, u["final_error_percent"])
            assert max(u["frf_max_db"].values()) < 0.5, (name, u["frf_max_db"])
        else:
            assert max(abs(e) for e in u["final_error_ms"].values()) < 0.1, (name, u["final_error_ms"])
    png = tmp_path / "overlay.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    assert "E_lexan_center" in (tmp_path / "parameters.toml").read_text()


def test_pythonfmu_fmus_are_not_loaded_in_the_main_process(fmu, monkeypatch):
    """pythonfmu FMUs have corrupted the heap of the process that loaded them (mace_fmu/fmu/simulate.py): outside
    a Dask worker they are refused before any load."""
    import dataclasses

    from mace_fmu.updating.fmu import model as fmu_model

    real = fmu_model.read_fmu_interface(fmu)
    fake = dataclasses.replace(real, generation_tool="mace-fmu 0.1.0 (PythonFMU 0.7)")
    monkeypatch.setattr(fmu_model, "read_fmu_interface", lambda path: fake)
    fmu_model._loaded.cache_clear()
    t, u = _noise_inputs(0.1)
    with pytest.raises(MaceError, match="worker processes only"):
        fmu_model.FmuModel(interface=fake, values={}).time_response(t, u, outputs=GYROS)
    fmu_model._loaded.cache_clear()


def test_a_native_fmu_runs_a_whole_record_in_one_call_equal_to_the_fmi_route_to_the_last_bit(fmu):
    """maceRunRecord makes the FMI calls in C: every output of every sample equal to the call-by-call route's,
    with a changed modulus and delay, and a non-finite input refused at its sample by both routes alike."""
    from mace_fmu.updating.fmu.model import _LoadedFmu, read_fmu_interface

    interface = read_fmu_interface(fmu)
    one_call, by_fmi = _LoadedFmu(interface), _LoadedFmu(interface, whole_record=False)
    assert one_call._record is not None and by_fmi._record is None
    t = np.arange(1501) * STEP
    u = np.random.default_rng(4).standard_normal((t.size, len(interface.inputs)))
    values = {"E_cable_2": 1.05 * interface.parameters["E_cable_2"], "delay_gyro_bus_x": 0.006}
    y = one_call.run(values, t, u, interface.inputs, interface.outputs)
    assert np.array_equal(y, by_fmi.run(values, t, u, interface.inputs, interface.outputs)) and np.all(np.isfinite(y))
    u[700, 2] = np.nan
    for loaded in (one_call, by_fmi):
        with pytest.raises(MaceError, match=r"t = 1\.4 s.*non-finite value nan for input gimbal_secondary_x"):
            loaded.run(values, t, u, interface.inputs, interface.outputs)


def test_an_fmu_that_refuses_a_value_raises_with_its_log_and_runs_again_after(fmu):
    family = fmu_family(fmu)
    t, u = _noise_inputs(0.1)
    with pytest.raises(MaceError, match=r"E_lexan_center = -1 is outside its declared range"):
        family.full({"E_lexan_center": -1.0}).time_response(t, u, outputs=GYROS)
    good = family.full({}).time_response(t, u, outputs=GYROS)
    assert np.array_equal(good, fmu_family(fmu).full({"E_lexan_center": 2.335e9}).time_response(t, u, outputs=GYROS))


def test_any_tools_fmi2_cosimulation_fmu_is_accepted_and_a_non_fmu_refused(fmu, tmp_path):
    """The FMU route asks nothing of mace-fmu's own FMUs: the same FMU relabelled as another tool's runs alike."""
    import zipfile

    other = tmp_path / "Other.fmu"
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(other, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = data.replace(b'generationTool="mace-fmu', b'generationTool="SomeOtherTool')
            dst.writestr(item, data)
    family = fmu_family(other)
    assert family.interface.generation_tool.startswith("SomeOtherTool")
    t, u = _noise_inputs(0.2)
    assert np.array_equal(family.full({}).time_response(t, u, outputs=GYROS),
                          fmu_family(fmu).full({}).time_response(t, u, outputs=GYROS))
    text = tmp_path / "not.fmu"
    text.write_text("not a zip")
    with pytest.raises(MaceError, match="not a zip archive"):
        fmu_family(text)


def test_a_pythonfmu_fmu_is_updated_with_every_run_in_the_workers(capsys, data_csv, tmp_path):
    """pythonfmu FMUs must not be loaded in the process that runs the update (heap corruption): the base
    point's runs go to the Dask workers too, and the update gives the native FMU's answer."""
    import tomllib

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model

    fmu = export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=tmp_path, name="MACE_1g_pythonfmu",
                     runtime="pythonfmu")
    start = tmp_path / "start.toml"
    start.write_text(f"[values]\nE_lexan_center = {pre_update_parameters()['E_lexan_center']!r}\n")
    code, out, err = run_cli(capsys, ["update", "fmu", str(fmu), "--data", str(data_csv), "--update", "E_lexan_center",
                                   "--start", str(start), "--workers", "2", "--hold-input", UNRECORDED,
                                   "-o", str(tmp_path / "o")])
    assert code in (0, 3), err
    values = tomllib.loads((tmp_path / "o" / "parameters.toml").read_text())["values"]
    assert abs(values["E_lexan_center"] / table_4_4_moduli()["E_lexan_center"] - 1.0) < 0.002


def test_a_set_fitted_to_one_structures_fmu_is_refused_for_the_other(capsys, tmp_path):
    """What `update fmu` writes says which FMU it was fitted to; `model 1g` refuses a fit to the 0-g FMU."""
    path = tmp_path / "fitted.toml"
    path.write_text('[provenance]\ncreated = "2026-11-24T00:00:00+00:00"\ntool = "mace-fmu"\nconfiguration = "0g"\n'
                    'fitted_to = "MACE_0g_native.fmu"\n\n[values]\nE_lexan_center = 2.4e9\n')
    code, out, err = run_cli(capsys, ["model", "1g", "--parameters", str(path)])
    assert code == 2 and "fitted to the 0g FMU MACE_0g_native.fmu, not to the 1g model" in err
