"""Where a model-exchange run of the native 1-g FMU spends its time in fmpy (CVode), against co-simulation.

Run by hand: ``python benchmarks/bench_model_exchange.py [--seconds 1.0]``; results in RESULTS.md.
Both runs take the same inputs: every input a band-unlimited random signal sampled every 2 ms
(0.1 V rms, seed 0), interpolated linearly by fmpy; outputs every 2 ms. The model-exchange run is
profiled: calls and time of the FMU's derivative function, the rest being CVode and fmpy.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import tempfile
import time
from pathlib import Path

import numpy as np
from fmpy import read_model_description, simulate_fmu

from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.volts import volts_model


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated time [s]")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        fmu = str(export_fmu(volts_model("1g"), kind="native", out_dir=Path(tmp), name="MACE_1g_native"))
        md = read_model_description(fmu)
        inputs = [v.name for v in md.modelVariables if v.causality == "input"]
        t = np.arange(0.0, args.seconds + 1e-9, 0.002)
        rng = np.random.default_rng(0)
        signal = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in inputs])
        signal["time"] = t
        for n in inputs:
            signal[n] = 0.1 * rng.standard_normal(len(t))
        run = dict(stop_time=args.seconds, output_interval=0.002, input=signal)
        t0 = time.perf_counter()
        simulate_fmu(fmu, fmi_type="CoSimulation", **run)
        cs = time.perf_counter() - t0
        profile = cProfile.Profile()
        t0 = time.perf_counter()
        profile.runcall(simulate_fmu, fmu, fmi_type="ModelExchange", **run)
        me = time.perf_counter() - t0
        stats = pstats.Stats(profile).stats
        calls, seconds = next(((v[1], v[3]) for k, v in stats.items() if k[2] == "fmi2GetDerivatives"), (0, 0.0))
        print(f"{md.numberOfContinuousStates if hasattr(md, 'numberOfContinuousStates') else len(md.derivatives)} "
              f"states; {args.seconds:g} s simulated")
        print(f"co-simulation: {cs:.2f} s; model exchange (profiled): {me:.1f} s = {me / cs:.0f} x")
        print(f"fmi2GetDerivatives: {calls} calls, {seconds:.1f} s ({1e6 * seconds / max(calls, 1):.0f} us each); "
              f"the rest ({me - seconds:.1f} s) is CVode and fmpy")


if __name__ == "__main__":
    main()
