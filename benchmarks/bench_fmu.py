"""FMU through fmpy against control.forced_response: 10 s at 2 ms, all 9 inputs driven, full 1-g model.

Run by hand: ``cd benchmarks && python bench_fmu.py [--runs 3]``; results go into RESULTS.md.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

import control as ct
import fmpy
import numpy as np
from fmpy.fmi2 import FMU2Slave

from common import machine_line
from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.volts import volts_model


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    model = volts_model("1g")
    tmp = tempfile.mkdtemp(prefix="bench_fmu_")  # kept until exit (pythonfmu pitfall)
    fmu = export_fmu(model, out_dir=tmp)
    unzipped = fmpy.extract(str(fmu), unzipdir=os.path.join(tmp, "unzipped"))
    step, stop = 2e-3, 10.0
    t = np.arange(0.0, stop + step / 2, step)
    names = list(model.system.input_labels)
    rng = np.random.default_rng(1)
    u = 0.1 * rng.standard_normal((len(names), len(t)))
    table = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = t
    for i, n in enumerate(names):
        table[n] = u[i]

    def run_fmu():
        return fmpy.simulate_fmu(unzipped, start_time=0.0, stop_time=stop, step_size=step, output_interval=step,
                                 input=table, output=list(model.system.output_labels))

    md = fmpy.read_model_description(unzipped)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    in_vr = [vr[n] for n in names]
    out_vr = [vr[n] for n in model.system.output_labels]
    u_rows = [list(col) for col in u.T]

    def run_loop():
        # the FMU alone: fmpy's FMU2Slave stepped by a bare loop, without simulate_fmu's bookkeeping
        slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName="bench")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        y = [slave.getReal(out_vr)]
        for k in range(len(t) - 1):
            slave.setReal(in_vr, u_rows[k])
            slave.doStep(currentCommunicationPoint=t[k], communicationStepSize=step)
            y.append(slave.getReal(out_vr))
        slave.terminate()
        slave.freeInstance()
        return np.array(y).T

    def run_control():
        # zero-order-hold inputs, as the FMU holds them (a continuous forced_response would
        # interpolate them linearly); the discretization is part of the work timed
        return ct.forced_response(ct.sample_system(model.system, step, "zoh"), T=t, U=u)

    fmu_times, ctl_times, loop_times = [], [], []
    for _ in range(args.runs):
        t0 = time.perf_counter()
        res = run_fmu()
        fmu_times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        y_loop = run_loop()
        loop_times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ref = run_control()
        ctl_times.append(time.perf_counter() - t0)
    y = np.array([res[n] for n in model.system.output_labels])
    err = np.max(np.abs(y - ref.outputs) / np.ptp(ref.outputs, axis=1, keepdims=True))
    err_loop = np.max(np.abs(y_loop - ref.outputs) / np.ptp(ref.outputs, axis=1, keepdims=True))
    f, c, lp = statistics.median(fmu_times), statistics.median(ctl_times), statistics.median(loop_times)
    n_steps = len(t) - 1
    print(machine_line(fmpy=fmpy.__version__, control=ct.__version__))
    print(f"- date: {time.strftime('%Y-%m-%d')}, runs: {args.runs} (median)\n")
    print("| case | median [s] | per step [us] | notes |")
    print("|---|---|---|---|")
    print(f"| FMU (fmpy.simulate_fmu), 1-g, {model.system.nstates} states, 10 s at 2 ms | {f:.3f} | "
          f"{1e6 * f / n_steps:.0f} | max error vs forced_response {err:.1e} of each output's range |")
    print(f"| FMU (fmpy FMU2Slave, bare setReal/doStep/getReal loop), same | {lp:.3f} | {1e6 * lp / n_steps:.0f} | "
          f"max error {err_loop:.1e}; ratio to forced_response = {lp / c:.2f} |")
    print(f"| control.forced_response, same model and inputs | {c:.3f} | {1e6 * c / n_steps:.0f} | "
          f"ratio FMU / forced_response = {f / c:.2f} |")


if __name__ == "__main__":
    main()
