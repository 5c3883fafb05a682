"""A seeded state-machine fuzz of the native FMUs (the driver and the reference
model of the standard's state tables are in support/fmi_fuzz.py).

Random call sequences for FMI 2 co-simulation, FMI 2 model exchange and FMI 3 co-simulation run in a
subprocess with a time limit: a crash or a hang fails the test instead of taking pytest down, and
every call's status must be the reference's. The long run is benchmarks/bench_fmi_fuzz.py.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import fmpy
import pytest
from support.paths import ROOT, SUPPORT

from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.volts import volts_model

pytestmark = pytest.mark.slow  # random call sequences, some under valgrind

WORKER = SUPPORT / "fmi_fuzz.py"
C_HOST = SUPPORT / "native_fuzz_host.c"
RUNTIME_DIR = ROOT / "mace_fmu" / "fmu" / "native" / "c"
SEEDS, LENGTH = 30, 40  # 90 sequences, 3,600 calls


@pytest.fixture(scope="module")
def folders(tmp_path_factory) -> dict[str, str]:
    model = volts_model(compute_modes(configuration="0g"))
    out = tmp_path_factory.mktemp("fuzz")
    fmi2 = export_fmu(model, out_dir=out, name="MACE_0g_fuzz")
    fmi3 = export_fmu(model, out_dir=out, name="MACE_0g_fuzz3", fmi_version=3)
    return {"fmi2": fmpy.extract(str(fmi2), unzipdir=str(out / "fmi2")),
            "fmi3": fmpy.extract(str(fmi3), unzipdir=str(out / "fmi3"))}


def run_fuzz(folders: dict[str, str], first_seed: int, n_seeds: int, length: int, timeout: float,
             extra: tuple[str, ...] = ()) -> dict:
    """The worker's summary; fails with the last seed it reached if it crashed or hung."""
    command = [sys.executable, str(WORKER), folders["fmi2"], folders["fmi3"], str(first_seed), str(n_seeds),
               "--length", str(length), *extra]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired as e:
        seeds = (e.stderr or b"").decode() if isinstance(e.stderr, bytes) else (e.stderr or "")
        pytest.fail(f"the fuzz hung (no result in {timeout} s); last: {seeds.strip().splitlines()[-1:]}")
    last = done.stderr.strip().splitlines()[-3:]
    assert done.returncode == 0, f"the fuzz worker died (exit status {done.returncode}); last: {last}"
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_random_call_sequences_follow_the_standards_state_machines(folders):
    summary = run_fuzz(folders, 1, SEEDS, LENGTH, timeout=600)
    print(f"{summary['sequences']} sequences, {summary['calls']} calls ({summary['ok']} OK, {summary['error']} "
          f"errors) in {summary['seconds']} s")
    assert summary["mismatches"] == [], json.dumps(summary["mismatches"][:5], indent=1)
    assert summary["sequences"] == 3 * SEEDS
    # both sides of the state machine are exercised
    assert summary["ok"] > 0.3 * summary["calls"] and summary["error"] > 0.1 * summary["calls"]


def test_the_controller_fmu_s_random_call_sequences_follow_the_state_machine_with_any_step(folders, tmp_path):
    """The controller FMU (FMI 2 and 3 co-simulation) under the same fuzz, with the steps that once went wrong:
    a step that is no whole number of samples (it was refused and left the instance in its error state), a
    step of 1e20 s (its sample count overflowed and it returned OK without stepping) and of 1e6 s (it ran 250 s):
    a step beyond the million samples one call runs is refused, at once, as an invalid argument that leaves
    the instance as it was (it was a failed step, into the error state). Foreign states come from the plant
    FMU (a controller has no model exchange)."""
    import control as ct
    import numpy as np

    from mace_fmu.fmu.controller import DiscreteController, export_controller_fmu

    rng = np.random.default_rng(3)
    a = rng.normal(size=(5, 5))
    a *= 0.97 / np.max(np.abs(np.linalg.eigvals(a)))
    system = ct.ss(a, rng.normal(size=(5, 2)), rng.normal(size=(3, 5)), rng.normal(size=(3, 2)), 0.002,
                   inputs=["gyro_a", "gyro_b"], outputs=["cmd_x", "cmd_y", "cmd_z"])
    controller = DiscreteController.from_statespace(system)
    ctl = {f"fmi{v}": fmpy.extract(str(export_controller_fmu(controller, out_dir=tmp_path, name=f"ctl{v}",
                                                              fmi_version=v)), unzipdir=str(tmp_path / f"ctl{v}"))
           for v in (2, 3)}
    summary = run_fuzz(ctl, 1, SEEDS, LENGTH, timeout=600,
                       extra=("--interfaces", "cs2,cs3", "--peer", folders["fmi2"], "--sample-s", "0.002"))
    assert summary["mismatches"] == [], json.dumps(summary["mismatches"][:5], indent=1)
    assert summary["sequences"] == 2 * SEEDS and summary["ok"] > 0.3 * summary["calls"]
    # a controller has no parameters to refuse and every refused call is an invalid argument: no sequence
    # reaches the error state (the over-long steps took them there), and the refusals are many
    assert not any(state.endswith(" error") for state in summary["by_state"]), summary["by_state"]
    assert summary["error"] > 0.1 * summary["calls"]


def test_random_call_sequences_from_c_are_clean_under_valgrind(folders, tmp_path):
    """The same kind of sequences from a C host (tests/support/native_fuzz_host.c: FMI 2 co-simulation and
    model exchange, the other interface's states, flipped, garbage and truncated serialised states)
    in memcheck: no invalid access, every heap block freed."""
    if shutil.which("valgrind") is None:
        pytest.fail("valgrind is a test dependency (.ci/run installs it)")
    exe = tmp_path / "native_fuzz_host"
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Werror", f"-I{RUNTIME_DIR}", "-o", str(exe), str(C_HOST),
                    "-ldl", "-lm"], check=True)
    md = fmpy.read_model_description(folders["fmi2"])
    n_states = sum(1 for v in md.modelVariables if v.derivative is not None)
    max_vr = max(v.valueReference for v in md.modelVariables)
    done = subprocess.run(["valgrind", "--error-exitcode=9", "--leak-check=full", "--errors-for-leak-kinds=all",
                           str(exe), folders["fmi2"], md.coSimulation.modelIdentifier, md.guid, str(n_states),
                           str(max_vr), "20", "40", "23"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "ERROR SUMMARY: 0 errors" in done.stderr, done.stderr[-3000:]
    assert "All heap blocks were freed" in done.stderr, done.stderr[-3000:]
    assert done.stdout.startswith("sequences 20 calls 800 ")
