"""Time of the robustness sweep of `mace-fmu study robust-0g`: 100 samples, the 16 corners and the
one-at-a-time runs of Table 5.3's bounds, serial and on a local Dask cluster of 2 workers.

Run: python benchmarks/bench_robust.py   (goal: corners + 50-200 samples in a minute or two on 2 cores)
"""

from __future__ import annotations

import importlib.metadata
import tempfile
import time

from common import machine_line

from mace_fmu.fmu.export import export_fmu
from mace_fmu.util.runner import DaskRunner
from mace_fmu.zero_g.nominal import predict_zero_g
from mace_fmu.zero_g.robust.design import design_compensator
from mace_fmu.zero_g.robust.study import prediction_bounds
from mace_fmu.zero_g.robust.sweep import robust_sweep


def main(samples: int = 100) -> None:
    t0 = time.perf_counter()
    prediction = predict_zero_g()
    t1 = time.perf_counter()
    bounds = prediction_bounds(prediction)
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export_fmu(prediction.model, out_dir=tmp, name="MACE_0g_native", frequency_bounds=bounds)
        t2 = time.perf_counter()
        design = design_compensator(prediction.model.system)
        t3 = time.perf_counter()
        serial = robust_sweep(fmu, compensator=design.compensator, samples=samples, seed=1)
        t4 = time.perf_counter()
        with DaskRunner(workers=2) as runner:
            t5 = time.perf_counter()
            parallel = robust_sweep(fmu, compensator=design.compensator, samples=samples, seed=1, runner=runner)
            t6 = time.perf_counter()
    runs = len(serial.runs) + 1
    print(machine_line(fmpy=importlib.metadata.version("fmpy"), dask=importlib.metadata.version("dask")))
    print(f"updated nominal 0-g model and bounds {t1 - t0:.1f} s; native FMU export {t2 - t1:.1f} s; "
          f"LQG design {t3 - t2:.1f} s")
    print(f"sweep of {runs} closed-loop runs (4 s at 2 ms each, {len(bounds)} bounded modes, {samples} samples): "
          f"serial {t4 - t3:.1f} s, Dask 2 workers {t6 - t5:.1f} s (+{t5 - t4:.1f} s cluster start); "
          f"identical results: {parallel.runs == serial.runs}")


if __name__ == "__main__":
    main()
