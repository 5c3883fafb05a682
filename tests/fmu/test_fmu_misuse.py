"""The pythonfmu FMU used wrongly, as a new user would: statuses per FMI 2.0, reasons in the log, exact otherwise.

Each scenario runs in its own worker process (tests/support/fmu_misuse_worker.py) through fmpy's FMI 2.0
API with a logger, so the statuses and messages are those any host sees. What the FMU answers:
- a step it cannot take (NaN or infinite input, not initialised, terminated, negative or
  non-finite step size) returns fmi2Discard with the state unchanged and the last successful time
  at the start of the step; the reason is logged with status fmi2Error;
- a parameter value outside its declared range is refused by fmi2SetReal, logged with status fmi2Error and
  failed with fmi2Fatal (the one failing status pythonfmu's wrapper can return there: a Python exception,
  whose objects the slave keeps alive for the wrapper's second release, see mace_fmu/fmu/slave.py), so that
  fmpy's simulate_fmu raises; every later step is refused (fmi2Discard) with the same reason;
- other errors that end the run (a fixed parameter set after initialisation, an unknown value reference)
  are logged with status fmi2Error when they happen, and every later step is refused (fmi2Discard) with
  the same reason;
- getReal after fmi2Terminate returns the final values (the standard allows it).
Extreme step sizes and 10^6 steps are exact against the state-space zero-order hold.
"""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from scipy.linalg import expm
from support.paths import SUPPORT

from mace_fmu.cli import main
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.archive import check_fmu
from mace_fmu.fmu.export import export_fmu
from mace_fmu.fmu.simulate import simulate_input_response
from mace_fmu.iomodel.model_options import SignalSelection
from mace_fmu.iomodel.volts import volts_model

pytestmark = pytest.mark.slow  # a million steps and misuse in subprocesses

WORKER = SUPPORT / "fmu_misuse_worker.py"
OK, DISCARD, ERROR, FATAL = 0, 2, 3, 4


@pytest.fixture(scope="module")
def fmu_0g(tmp_path_factory):
    """(model, FMU file, extracted folder) of the 0-g model; the folder outlives every worker."""
    model = volts_model(compute_modes(configuration="0g"))
    fmu = export_fmu(model, out_dir=tmp_path_factory.mktemp("misuse_fmu"), runtime="pythonfmu")
    return model, fmu, fmpy.extract(str(fmu), unzipdir=str(tmp_path_factory.mktemp("misuse_unzipped")))


def run(folder: str, scenario: str) -> dict:
    done = subprocess.run([sys.executable, str(WORKER), folder, scenario], capture_output=True, text=True,
                          timeout=1800)
    assert done.returncode == 0, done.stderr
    assert "corrupted" not in done.stderr and "Traceback" not in done.stderr, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def statuses(result: dict, name: str) -> list[int]:
    return [status for call, status, _ in result["calls"] if call == name]


def messages(result: dict, name: str) -> list[tuple[int, str]]:
    return [(status, text) for call, _, log in result["calls"] if call == name for status, text in log]


def test_nan_and_infinite_inputs_discard_the_step_and_say_which_input(fmu_0g) -> None:
    model, _, folder = fmu_0g
    r = run(folder, "nan_input")
    assert statuses(r, "doStep") == [OK, DISCARD, DISCARD, OK]
    name = model.system.input_labels[2]
    assert messages(r, "doStep") == [(ERROR, f"fmi2DoStep at t = 0.002 s refused: non-finite input value(s): {name}")] * 2
    assert r["time_after_refusal"] == 0.002  # nothing of the refused step was computed
    assert r["state_unchanged"]


def test_step_before_initialisation_is_refused(fmu_0g) -> None:
    r = run(fmu_0g[2], "before_init")
    assert statuses(r, "doStep") == [DISCARD, OK]
    assert messages(r, "doStep") == [(ERROR, "fmi2DoStep at t = 0.0 s refused: the FMU is not initialised "
                                             "(call fmi2ExitInitializationMode first)")]


@pytest.mark.parametrize("name, value, reason", [
    ("damping_mode_7", "nan", "damping_mode_7 = nan is not a finite number"),
    ("damping_mode_7", "inf", "damping_mode_7 = inf is not a finite number"),
    ("damping_mode_7", "1.5", "damping_mode_7 = 1.5 is outside its declared range [0, 1]"),
    ("damping_mode_7", "-0.01", "damping_mode_7 = -0.01 is outside its declared range [0, 1]"),
    ("delay_gyro_payload_x", "-0.001", "delay_gyro_payload_x = -0.001 is outside its declared range [0, 1]"),
    ("K_a", "nan", "K_a = nan is not a finite number"),
    ("K_a", "1e308", "K_a = 1e+308 is outside its declared range [-2000, 2000]"),
    ("E_lexan_center", "-1.0", "E_lexan_center = -1 is outside its declared range [1634500000, 3502500000]"),
    # zero ran before, 0-g mode 14 at 0.92 Hz: the range is where the route was validated (0.7 to 1.5 x nominal)
    ("E_lexan_center", "0.0", "E_lexan_center = 0 is outside its declared range [1634500000, 3502500000]"),
    ("E_lexan_center", "1634000000.0", "E_lexan_center = 1634000000 is outside its declared range [1634500000, "
                                       "3502500000]"),
])
def test_invalid_parameters_are_refused_where_they_are_set(fmu_0g, name: str, value: str, reason: str) -> None:
    """Refused by fmi2SetReal with an error in the log and a failing status (they were logged at initialisation
    and only the steps were refused: fmpy's simulate_fmu returned two rows ending at t = 0, no exception)."""
    r = run(fmu_0g[2], f"parameter:{name}:{value}")
    assert statuses(r, "setReal") == [FATAL]
    assert messages(r, "setReal")[0] == (ERROR, f"fmi2SetReal: invalid parameter: {reason}; not set")
    assert statuses(r, "doStep") == [DISCARD, DISCARD]  # a host that goes on regardless
    assert all(reason in text for _, text in messages(r, "doStep"))


def test_fmpy_simulate_raises_for_an_invalid_parameter_and_the_process_goes_on(fmu_0g) -> None:
    r = run(fmu_0g[2], "simulate:E_lexan_center:2400")
    for debug in ("False", "True"):
        assert r[f"raised_{debug}"] == "fmi2SetReal failed with status 4 (fatal).", r
    reason = "E_lexan_center = 2400 is outside its declared range [1634500000, 3502500000]"
    assert [ERROR, f"fmi2SetReal: invalid parameter: {reason}; not set"] in r["log"]  # with debug logging
    assert r["rows_after"] == 6


def test_a_refused_call_releases_the_slave_exactly_once(fmu_0g) -> None:
    """pythonfmu's wrapper releases the slave after the exception and again when the instance is freed: alive
    after the refusal, gone after the free (without the slave's extra reference it was freed at the refusal,
    and the free released freed memory)."""
    r = run(fmu_0g[2], "lifetime:E_lexan_center:2400")
    assert statuses(r, "setReal") == [FATAL]
    assert r["alive"] == [1, 1, 0]


def test_declared_ranges_are_in_the_model_description(fmu_0g) -> None:
    description = fmpy.read_model_description(str(fmu_0g[1]))
    variables = {v.name: v for v in description.modelVariables}
    assert (variables["damping_mode_7"].min, variables["damping_mode_7"].max) == ("0.0", "1.0")
    assert (variables["delay_gyro_payload_x"].min, variables["delay_gyro_payload_x"].max) == ("0.0", "1.0")
    assert (variables["E_lexan_center"].min, variables["E_lexan_center"].max) == ("1634500000.0", "3502500000.0")
    assert (variables["K_a"].min, variables["K_a"].max) == ("-2000.0", "2000.0")


def test_fixed_parameter_after_initialisation_and_unknown_references(fmu_0g) -> None:
    r = run(fmu_0g[2], "fixed_after_init")
    assert statuses(r, "doStep") == [OK, DISCARD] and r["K_a"] == [-2.0]  # the value was not taken
    assert messages(r, "setReal") == [(ERROR, "fmi2SetReal: K_a is a fixed parameter and cannot change after "
                                              "initialisation (value ignored)")]
    r = run(fmu_0g[2], "unknown_reference")
    assert np.isnan(r["value"][0]) and statuses(r, "doStep") == [DISCARD]
    assert messages(r, "getReal") == [(ERROR, "fmi2GetReal: 987654 is not the value reference of a Real variable")]
    assert messages(r, "setReal") == [(ERROR, "fmi2SetReal: 987654 is not the value reference of a Real variable "
                                              "that can be set")]


def test_values_after_terminate_and_bad_step_sizes(fmu_0g) -> None:
    r = run(fmu_0g[2], "after_terminate")
    assert r["after"] == r["before"] and statuses(r, "getReal") == [OK, OK]
    assert statuses(r, "doStep") == [OK, DISCARD]
    r = run(fmu_0g[2], "bad_step")
    assert statuses(r, "doStep") == [DISCARD] * 3
    assert [text for _, text in messages(r, "doStep")] == [
        f"fmi2DoStep at t = 0.0 s refused: step size {h} s (expected a finite value >= 0)" for h in ("-0.002", "nan",
                                                                                                    "inf")]


def _zoh(model, x: np.ndarray, u: np.ndarray, h: float) -> np.ndarray:
    """x after h seconds with u held: the augmented matrix exponential, one step, no cache."""
    a, b = model.system.A, model.system.B
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a, b
    return (expm(aug * h) @ np.concatenate([x, u]))[:n]


def _compare(model, samples: list, states: list[np.ndarray], u: np.ndarray, outputs: list[str]) -> None:
    order = [list(model.system.output_labels).index(n) for n in outputs]
    for sample, x in zip(samples, states):
        expected = (model.system.C @ x + model.system.D @ u)[order]
        dynamic = (model.system.C @ x)[order]  # the part the step computes (D u is there from t = 0)
        scale = np.max(np.abs(dynamic))
        assert scale > 0
        assert np.max(np.abs(np.array(sample) - expected)) <= 1e-8 * scale


def test_step_sizes_of_a_nanosecond_and_ten_seconds_are_exact(fmu_0g) -> None:
    model, _, folder = fmu_0g
    r = run(folder, "steps:rwa_z:1e-9,10")
    u = np.zeros(model.system.ninputs)
    u[list(model.system.input_labels).index("rwa_z")] = 1.0
    x1 = _zoh(model, np.zeros(model.system.nstates), u, 1e-9)
    x2 = _zoh(model, x1, u, 10.0)
    assert statuses(r, "doStep") == [OK, OK]
    _compare(model, r["samples"], [x1, x2], u, r["outputs"])


def test_a_million_steps_end_where_the_zero_order_hold_ends(fmu_0g) -> None:
    """10^6 steps of 2 us (2 s): the FMU's recursion against one matrix exponential over the whole run."""
    model, _, folder = fmu_0g
    r = run(folder, "many:rwa_z:2e-6:1000000")
    assert r["statuses"] == [OK]
    u = np.zeros(model.system.ninputs)
    u[list(model.system.input_labels).index("rwa_z")] = 1.0
    _compare(model, r["samples"], [_zoh(model, np.zeros(model.system.nstates), u, 2.0)], u, r["outputs"])


def test_simulate_and_the_cli_raise_with_the_fmus_logged_reason(fmu_0g, tmp_path, capsys) -> None:
    model, fmu, _ = fmu_0g
    with pytest.raises(MaceError, match=r"stopped at t = 0 s of 0.01 s\. FMU log: error: fmi2DoStep at t = 0.0 s "
                                        r"refused: non-finite input value\(s\): rwa_z"):
        simulate_input_response(fmu, input_name="rwa_z", amplitude_v=float("nan"), duration_s=0.01)
    # the command line refuses a non-finite amplitude as it is parsed, before any FMU runs: one line naming it
    with pytest.raises(SystemExit) as refused:
        main(["view", "response", "0g", "--input", "rwa_z", "--amplitude", "nan", "--duration", "0.01",
              "--html", str(tmp_path / "r.html")])
    last = capsys.readouterr().err.splitlines()[-1]
    assert refused.value.code == 2 and "argument --amplitude: expected a finite number, got 'nan'" in last, last


def test_an_in_process_simulation_leaves_fmpys_logger_alive_for_the_next_fmu(tmp_path) -> None:
    """simulate_input_response(in_subprocess=False) gives fmpy a logger that is collected on return, and fmpy's
    C proxy keeps a pointer to it: the next FMU that logged through fmpy's default callbacks died of SIGSEGV
    (measured before the repair: exit -11). Now the refusal is reported and the process ends normally."""
    model = volts_model(compute_modes(configuration="0g", max_hz=5.0),
                        signals=SignalSelection(inputs=["gimbal_secondary_z"],
                                                                  outputs=["gyro_payload_z"]))
    fmu = export_fmu(model, out_dir=tmp_path)
    done = subprocess.run([sys.executable, str(SUPPORT / "fmpy_logger_host.py"), str(fmu)], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0 and "refused: fmi2SetReal failed with status 3" in done.stdout, \
        (done.returncode, done.stdout, done.stderr)


def _forged(fmu: Path, folder: Path, kind: str) -> Path:
    """An FMU file that is not ours, made from a real one."""
    path = folder / f"{kind}.fmu"
    data = fmu.read_bytes()
    if kind == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif kind == "text":
        path.write_text("not an archive\n")
    else:
        with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(path, "w") as target:
            for info in source.infolist():
                content = source.read(info)
                if kind == "foreign" and info.filename == "modelDescription.xml":
                    content = content.replace(b'generationTool="mace-fmu', b'generationTool="other-tool')
                if kind == "fmi1" and info.filename == "modelDescription.xml":
                    content = content.replace(b'fmiVersion="2.0"', b'fmiVersion="1.0"')
                if kind == "no-description" and info.filename == "modelDescription.xml":
                    continue
                target.writestr(info, content)
            if kind == "traversal":
                target.writestr("../../escaped.txt", "written outside")
            if kind == "absolute":
                target.writestr("/tmp/mace_fmu_absolute_escape.txt", "written outside")
            if kind == "symlink":
                link = zipfile.ZipInfo("resources/link")
                link.external_attr = (0o120777 << 16)
                target.writestr(link, "/etc/passwd")
    return path


@pytest.mark.parametrize("kind, phrase", [
    ("traversal", "entry '../../escaped.txt' climbs out of the folder with '..': refused (nothing was extracted)"),
    ("absolute", "entry '/tmp/mace_fmu_absolute_escape.txt' is an absolute path"),
    ("symlink", "entry 'resources/link' is a symbolic link"),
    ("truncated", "not a zip archive (an FMU is one; the file may be truncated)"),
    ("text", "not a zip archive"),
    ("foreign", "generated by 'other-tool"),
    ("fmi1", "not an FMI 2.0 model description"),
    ("no-description", "not a MACE FMU (expected modelDescription.xml"),
])
def test_foreign_and_malicious_fmus_are_refused(fmu_0g, tmp_path, capsys, kind: str, phrase: str) -> None:
    _, fmu, _ = fmu_0g
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    bad = _forged(fmu, work, kind)
    with pytest.raises(MaceError, match="refused|not a|generated by|damaged") as info:
        check_fmu(bad)
    assert phrase in str(info.value) and str(bad) in str(info.value)
    with pytest.raises(MaceError, match="refused|not a|generated by|damaged"):
        simulate_input_response(bad, input_name="rwa_z", duration_s=0.01)
    code = main(["view", "response", "0g", "--input", "rwa_z", "--duration", "0.01", "--fmu", str(bad),
                 "--html", str(work / "r.html")])
    err = capsys.readouterr().err
    assert code == 2 and phrase in err, err
    assert sorted(p.name for p in work.iterdir()) == [bad.name]  # no page, no plot, nothing unpacked
    assert not (tmp_path / "escaped.txt").exists() and not Path("/tmp/mace_fmu_absolute_escape.txt").exists()


def test_our_fmu_and_its_unpacked_folder_pass_the_check(fmu_0g) -> None:
    _, fmu, folder = fmu_0g
    assert check_fmu(fmu) == fmu and check_fmu(folder) == Path(folder)
