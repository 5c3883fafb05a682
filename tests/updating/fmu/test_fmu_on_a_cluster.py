"""FMU updates, test planning and the robustness sweep on a cluster whose workers do not see the client's
files.

The scheduler and its worker are separate processes (``dask scheduler``, ``dask worker``) started in a
folder of their own: the FMU's relative path names nothing there, as any path names nothing on the
workers of another machine. The FMU's bytes must travel to the workers; the results must be the serial
ones bit for bit.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from support.paths import ROOT

from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.fmu.model import fmu_family
from mace_fmu.updating.fmu.planning import Candidate, TestDesign, predict_uncertainty
from mace_fmu.updating.fmu.update import fmu_cost, update_fmu
from mace_fmu.util.runner import DaskRunner

pytestmark = pytest.mark.slow  # a scheduler and a worker process, an FMU export and two small updates

INPUT, OUTPUT = "gimbal_secondary_z", "gyro_payload_z"
STEP = 0.002


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A scheduler and one worker of two threads, both in a folder where no FMU is: (address, that folder)."""
    elsewhere = tmp_path_factory.mktemp("worker_cwd")
    scheduler_file = elsewhere / "scheduler.json"
    # the workers import this checkout's code, as the client does (and this file, for its helpers run there);
    # nothing else of the client is shared
    code = os.pathsep.join([str(ROOT), str(ROOT / "tests"), str(Path(__file__).parent)])
    env = {**os.environ, "PYTHONPATH": code, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                                 cwd=elsewhere, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        deadline = time.monotonic() + 60.0
        while not scheduler_file.is_file() and time.monotonic() < deadline:
            time.sleep(0.2)
        address = json.loads(scheduler_file.read_text())["address"]
        # two threads: two tasks at once in one worker process must each get an FMU instance of their own
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "2",
                                   "--no-dashboard", "--no-nanny", "--local-directory", str(elsewhere)],
                                  cwd=elsewhere, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        yield address, elsewhere
    finally:
        for process in (worker, scheduler):
            if process is not None:
                process.terminate()
                try:
                    process.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    process.kill()


@pytest.fixture(scope="module")
def client_folder(tmp_path_factory) -> Path:
    """The client's folder: small native FMUs (modes to 20 Hz) of the 1-g structure (one gimbal in, one
    gyro out) and of the 0-g structure with the robustness loop's signals and one bounded mode."""
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.model_options import SignalSelection
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.zero_g.robust.loop import LoopSpec

    folder = tmp_path_factory.mktemp("client_cwd")
    model = volts_model(compute_modes(configuration="1g", max_hz=20.0),
                        signals=SignalSelection(inputs=[INPUT], outputs=[OUTPUT]))
    export_fmu(model, out_dir=folder, name="MACE_small", platforms=["x86_64-linux"])
    loop = LoopSpec()
    model_0g = volts_model(compute_modes(configuration="0g", max_hz=20.0),
                           signals=SignalSelection(inputs=[loop.control_input, loop.disturbance_input],
                                                   outputs=[loop.measurement]))
    export_fmu(model_0g, out_dir=folder, name="MACE_small_0g", platforms=["x86_64-linux"],
               frequency_bounds={len(model_0g.plant.labels): 0.02})
    return folder


def _started(runner: DaskRunner) -> DaskRunner:
    deadline = time.monotonic() + 60.0
    while runner.workers < 1 and time.monotonic() < deadline:
        time.sleep(0.2)
    return runner


def _fmu_loads() -> int:
    from mace_fmu.updating.fmu.model import _loaded

    return _loaded.cache_info().misses


def _extracted_copies(dask_worker) -> list[str]:
    """The shipped FMUs this worker extracted, as <sha256>/unzipped (``client.run`` passes ``dask_worker``)."""
    from mace_fmu.util.shipping import FOLDER

    root = Path(dask_worker.local_directory) / FOLDER
    return sorted(p.parent.relative_to(root).as_posix() for p in root.glob("*/unzipped/modelDescription.xml"))


def _history(family) -> TimeHistory:
    t = np.arange(501) * STEP
    u = {INPUT: np.random.default_rng(3).standard_normal(t.size)}
    truth = family.full({"E_lexan_center": 2.6e9}).time_response(t, u, outputs=[OUTPUT])
    return TimeHistory(t, u, {OUTPUT: truth[:, 0]}, source="truth")


def test_an_update_on_workers_that_cannot_see_the_fmu_file_is_the_serial_one_bit_for_bit(cluster, client_folder,
                                                                                          monkeypatch):
    address, elsewhere = cluster
    monkeypatch.chdir(client_folder)
    family = fmu_family("MACE_small.fmu")  # relative: it names nothing in the workers' folder
    cost = fmu_cost("time", history=_history(family))
    kwargs = dict(family=family, cost=cost, start={"E_lexan_center": 2.45e9}, stages=[["E_lexan_center"]])
    serial = update_fmu(**kwargs)
    with _started(DaskRunner(scheduler=address, connect_timeout_s=30.0)) as runner:
        where = runner.client.run(os.getcwd)
        assert set(where.values()) == {str(elsewhere)} and not (elsewhere / "MACE_small.fmu").exists()
        spread = update_fmu(runner=runner, **kwargs)
        candidate = Candidate(name="one test", tests=(TestDesign(name="noise", inputs=(INPUT,), outputs=(OUTPUT,),
                                                                 seconds=1.0, band_hz=(1.0, 40.0)),))
        planned = predict_uncertainty(family=family, parameters=["E_lexan_center", "E_lexan_end"],
                                      candidate=candidate, runner=runner)
        loads = runner.client.run(_fmu_loads)
    assert all(n <= 2 for n in loads.values()), loads  # an instance per thread, each then reset between runs
    assert spread.values == serial.values and np.array_equal(spread.final_residual, serial.final_residual)
    alone = predict_uncertainty(family=family, parameters=["E_lexan_center", "E_lexan_end"], candidate=candidate)
    assert planned.standard_deviation_percent == alone.standard_deviation_percent


def test_a_robustness_sweep_on_workers_that_cannot_see_the_fmu_file_is_the_serial_one(cluster, client_folder,
                                                                                     monkeypatch):
    import control

    from mace_fmu.zero_g.robust.sweep import robust_sweep

    address, _ = cluster
    monkeypatch.chdir(client_folder)
    gain = control.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[-0.05]], STEP)
    kwargs = dict(compensator=gain, samples=2, seed=4, critical_count=1)
    serial = robust_sweep("MACE_small_0g.fmu", **kwargs)
    with _started(DaskRunner(scheduler=address, connect_timeout_s=30.0)) as runner:
        spread = robust_sweep("MACE_small_0g.fmu", runner=runner, **kwargs)
        extracted = runner.client.run(_extracted_copies)
    # the worker ran its own copy of the bytes (on this machine it could have read the client's extraction)
    digest = hashlib.sha256((client_folder / "MACE_small_0g.fmu").read_bytes()).hexdigest()
    assert all(folders == [f"{digest}/unzipped"] for folders in extracted.values()), extracted
    assert len(serial.runs) == 7 and not any(r.failure for r in serial.runs)
    assert spread.runs == serial.runs and spread.open_loop == serial.open_loop  # dataclass ==: exact floats


def test_an_fmu_not_sent_to_the_workers_is_one_error_that_says_so(cluster, client_folder, monkeypatch):
    """The engine's own map over a family, without update_fmu (which sends the FMU): one line on the worker."""
    import zipfile

    from mace_fmu.errors import MaceError
    from mace_fmu.updating.engine.sensitivity import cost_sensitivities

    address, _ = cluster
    monkeypatch.chdir(client_folder)
    unsent = client_folder / "MACE_unsent.fmu"  # other bytes than the shipped ones: no copy of it on the worker
    unsent.write_bytes((client_folder / "MACE_small.fmu").read_bytes())
    with zipfile.ZipFile(unsent, "a") as archive:
        archive.comment = b"not the shipped bytes"
    family = fmu_family(unsent.name)
    cost = fmu_cost("time", history=_history(family))
    base = {"E_lexan_center": 2.45e9}
    with _started(DaskRunner(scheduler=address, connect_timeout_s=30.0)) as runner:
        with pytest.raises(MaceError, match=r"^MACE_unsent.fmu: no such FMU file on the Dask worker \(folder .*\), and "
                                            r"none was sent to it: .*DaskRunner.ship\(path\) first$"):
            cost_sensitivities(cost, base_model=family.full(base), perturbed=family.full, base=base,
                               names=list(base), runner=runner)
