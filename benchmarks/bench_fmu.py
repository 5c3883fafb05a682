"""FMUs against control.forced_response: 10 s at 2 ms, all 9 inputs driven, full 1-g model.

Side by side in one run: the native FMU through fmpy.simulate_fmu, through a bare fmpy FMU2Slave
loop and in a C host without Python (tests/support/native_host.c, compiled here); the pythonfmu FMU the
same two ways through fmpy; control.forced_response (ZOH discretisation included). Then the native
FMU's initialisation (instantiate to exitInitializationMode) with nominal and with physical
parameters changed.

Run by hand: ``cd benchmarks && python bench_fmu.py [--runs 9]``; results go into RESULTS.md.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import control as ct
import fmpy
import numpy as np
from fmpy.fmi2 import FMU2Slave

from common import machine_line
from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.fmu.native.compile import SOURCE_DIR
from mace_fmu.iomodel.volts import volts_model

HOST = Path(__file__).resolve().parents[1] / "tests" / "support" / "native_host.c"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=9)
    args = parser.parse_args()
    model = volts_model(compute_modes(configuration="1g"))
    tmp = Path(tempfile.mkdtemp(prefix="bench_fmu_"))  # kept until exit (pythonfmu pitfall)
    folders = {kind: fmpy.extract(str(export_fmu(model, runtime=kind, out_dir=tmp, name=f"MACE_1g_{kind}")),
                                  unzipdir=str(tmp / kind)) for kind in ("native", "pythonfmu")}
    step, stop = 2e-3, 10.0
    t = np.arange(0.0, stop + step / 2, step)
    n_steps = len(t) - 1
    names, outputs = list(model.system.input_labels), list(model.system.output_labels)
    u = 0.1 * np.random.default_rng(1).standard_normal((len(names), len(t)))
    table = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = t
    for i, n in enumerate(names):
        table[n] = u[i]
    md = fmpy.read_model_description(folders["native"])
    vr = {v.name: v.valueReference for v in md.modelVariables}
    in_vr, out_vr = [vr[n] for n in names], [vr[n] for n in outputs]
    u_rows = [list(col) for col in u.T]

    def run_simulate(kind):
        res = fmpy.simulate_fmu(folders[kind], start_time=0.0, stop_time=stop, step_size=step, output_interval=step,
                                input=table, output=outputs)
        return np.array([res[n] for n in outputs])

    def run_loop(kind):
        folder = folders[kind]
        m = fmpy.read_model_description(folder)
        slave = FMU2Slave(guid=m.guid, unzipDirectory=folder, modelIdentifier=m.coSimulation.modelIdentifier,
                          instanceName="bench")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        y = [slave.getReal(out_vr)]
        for k in range(n_steps):
            slave.setReal(in_vr, u_rows[k])
            slave.doStep(currentCommunicationPoint=t[k], communicationStepSize=step)
            y.append(slave.getReal(out_vr))
        slave.terminate()
        slave.freeInstance()
        return np.array(y).T

    host = tmp / "native_host"
    subprocess.run(["gcc", "-std=c99", "-O2", f"-I{SOURCE_DIR}", "-o", str(host), str(HOST), "-ldl"], check=True)
    inputs, result = tmp / "u.bin", tmp / "y.bin"
    np.ascontiguousarray(u[:, :-1].T, dtype="<f8").tofile(inputs)

    def run_host():
        done = subprocess.run([str(host), folders["native"], md.coSimulation.modelIdentifier, md.guid, repr(step),
                               str(n_steps), str(inputs), str(result), ",".join(map(str, in_vr)),
                               ",".join(map(str, out_vr))], capture_output=True, text=True, check=True)
        per_step = float(done.stdout.split()[-1])
        return per_step, np.fromfile(result, dtype="<f8").reshape(n_steps + 1, -1).T

    def run_control():
        # zero-order-hold inputs, as the FMUs hold them; the discretisation is part of the work timed
        return ct.forced_response(ct.sample_system(model.system, step, "zoh"), T=t, U=u).outputs

    def initialise(change: dict[str, float]) -> float:
        t0 = time.perf_counter()
        slave = FMU2Slave(guid=md.guid, unzipDirectory=folders["native"],
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="init")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        if change:
            slave.setReal([vr[k] for k in change], list(change.values()))
        slave.exitInitializationMode()
        elapsed = time.perf_counter() - t0
        slave.terminate()
        slave.freeInstance()
        return elapsed

    timed = {key: [] for key in ("native simulate", "native loop", "native host", "pythonfmu simulate",
                                 "pythonfmu loop", "control", "init nominal", "init physical")}
    results = {}
    e_center = float(next(v.start for v in md.modelVariables if v.name == "E_lexan_center"))
    physical = {"E_lexan_center": 1.05 * e_center, "E_aluminium": 0.9 * 6.89e10}
    for _ in range(args.runs):
        for key, fn in (("native simulate", lambda: run_simulate("native")), ("native loop", lambda: run_loop("native")),
                        ("pythonfmu simulate", lambda: run_simulate("pythonfmu")),
                        ("pythonfmu loop", lambda: run_loop("pythonfmu")), ("control", run_control)):
            t0 = time.perf_counter()
            results[key] = fn()
            timed[key].append(time.perf_counter() - t0)
        per_step, results["native host"] = run_host()
        timed["native host"].append(per_step * n_steps)
        timed["init nominal"].append(initialise({}))
        timed["init physical"].append(initialise(physical))
    med = {key: statistics.median(v) for key, v in timed.items()}
    ref = results["control"]
    span = np.ptp(ref, axis=1, keepdims=True)
    err = {key: float(np.max(np.abs(y - ref) / span)) for key, y in results.items() if key != "control"}
    us = {key: 1e6 * med[key] / n_steps for key in med}
    print(machine_line(fmpy=fmpy.__version__, control=ct.__version__))
    print(f"- date: {time.strftime('%Y-%m-%d')}, runs: {args.runs} (median), load average before: "
          f"{os.getloadavg()[0]:.1f}\n")
    print("| case | median [s] | per step [us] | notes |")
    print("|---|---|---|---|")
    rows = (("native FMU, fmpy.simulate_fmu", "native simulate"), ("native FMU, bare fmpy FMU2Slave loop", "native loop"),
            ("native FMU, C host (dlopen, no Python)", "native host"),
            ("pythonfmu FMU, fmpy.simulate_fmu", "pythonfmu simulate"),
            ("pythonfmu FMU, bare fmpy FMU2Slave loop", "pythonfmu loop"))
    for label, key in rows:
        print(f"| {label}, 1-g, {model.system.nstates} states, 10 s at 2 ms | {med[key]:.3f} | {us[key]:.1f} | "
              f"max error vs forced_response {err[key]:.1e} of each output's range; ratio to forced_response "
              f"{med[key] / med['control']:.2f} |")
    print(f"| control.forced_response, same model and inputs | {med['control']:.3f} | {us['control']:.1f} | |")
    print(f"\nnative in the C host vs pythonfmu through fmpy: {med['pythonfmu simulate'] / med['native host']:.0f}x "
          f"faster (simulate_fmu), {med['pythonfmu loop'] / med['native host']:.0f}x (bare loops)")
    print(f"native initialisation (instantiate .. exitInitializationMode): nominal {med['init nominal']:.3f} s, "
          f"with E_lexan_center and E_aluminium changed {med['init physical']:.3f} s (medians)")
    print(f"per step: simulate_fmu {us['native simulate']:.1f} us = C host {us['native host']:.1f} us + fmpy's "
          f"ctypes calls {us['native loop'] - us['native host']:.1f} us + simulate_fmu's bookkeeping "
          f"{us['native simulate'] - us['native loop']:.1f} us")


if __name__ == "__main__":
    main()
