"""Host process of tests/fmu/test_pythonfmu_exit.py: run a pythonfmu FMU as our hosts do, then exit normally.

    python pythonfmu_exit_host.py FMU update|simulate

update: what a Dask worker of ``mace-fmu update fmu`` does (``mace_fmu.updating.fmu.model._LoadedFmu``: one
instance, loaded in a thread other than the main one as Dask's executor does, two runs with fmi2Reset
between them); simulate: ``mace_fmu.fmu.simulate._simulate`` in this process (fmpy.simulate_fmu). The FMU
takes an input ``u`` and an output ``y``. Prints the outputs as JSON, then leaves through the interpreter's
finalisation and the C library's exit handlers, where pythonfmu's wrapper used to write into freed memory:
no ``os._exit`` here, on purpose.
"""

from __future__ import annotations

import json
import sys
import threading

import numpy as np

STEP_S = 0.1
SAMPLES = 5


def run_as_update_worker(fmu: str) -> list[list[float]]:
    from mace_fmu.updating.fmu.model import _LoadedFmu, read_fmu_interface

    t = np.arange(SAMPLES) * STEP_S
    u = (1.0 + np.arange(SAMPLES, dtype=float))[:, None]
    runs: list[list[float]] = []

    def work() -> None:
        loaded = _LoadedFmu(read_fmu_interface(fmu))
        for _ in range(2):  # the second after fmi2Reset, as every later run of a worker
            runs.append(loaded.run({}, t, u, ["u"], ["y"])[:, 0].tolist())

    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    return runs


def run_as_simulate(fmu: str) -> list[list[float]]:
    from mace_fmu.fmu.simulate import _simulate

    table = np.zeros(SAMPLES, dtype=[("time", float), ("u", float)])
    table["time"], table["u"] = np.arange(SAMPLES) * STEP_S, 1.0 + np.arange(SAMPLES)
    result = _simulate(fmu, table, ["y"], STEP_S)
    return [np.asarray(result["y"], dtype=float).tolist()]


if __name__ == "__main__":
    path, pattern = sys.argv[1], sys.argv[2]
    outputs = {"update": run_as_update_worker, "simulate": run_as_simulate}[pattern](path)
    print(json.dumps(outputs), flush=True)
