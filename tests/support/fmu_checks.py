"""Shared checks of FMUs (pythonfmu and native) against the models' exact zero-order-hold responses."""

from __future__ import annotations

import functools
import os

import control as ct
import fmpy
import numpy as np
from fmpy.fmi2 import FMU2Slave
from support.lifted import lifted_response

DURATION = 1.0


def make_inputs(kind: str, t: np.ndarray, n_inputs: int) -> np.ndarray:
    """(n_inputs, len(t)) test inputs [V], a different one on every channel."""
    k = np.arange(n_inputs)[:, None]
    if kind == "step":
        return (0.1 + 0.05 * k) * (t[None, :] >= 0.01)
    if kind == "chirp":  # 0.1 -> 250 Hz, linear sweep over the run
        f0, f1 = 0.1, 250.0
        phase = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / DURATION * t**2)
        return 0.2 * np.sin(phase[None, :] + k)
    rng = np.random.default_rng(7)
    freqs = np.geomspace(0.2, 200.0, 15)
    phases = rng.uniform(0, 2 * np.pi, (n_inputs, len(freqs)))
    return 0.1 * np.sum(np.sin(2 * np.pi * freqs[None, :, None] * t[None, None, :] + phases[:, :, None]), axis=1)


def zoh_reference(model, t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Exact ZOH response of the state-space model, sampled where the FMU reports."""
    steps = np.diff(t)
    if np.allclose(steps, steps[0]):
        discrete = ct.sample_system(model.system, steps[0], "zoh")
        return lifted_response(discrete.A, discrete.B, discrete.C, discrete.D, np.asarray(u).T).T
    x = np.zeros(model.system.nstates)
    y = [model.system.C @ x + model.system.D @ u[:, 0]]
    discrete = {}  # an independent discretization for every distinct step size [s]
    for k, h in enumerate(steps):
        d = discrete.get(h) or discrete.setdefault(h, ct.sample_system(model.system, h, "zoh"))
        x = d.A @ x + d.B @ u[:, k]
        y.append(model.system.C @ x + model.system.D @ u[:, k])
    return np.array(y).T


def check_close(model, y: np.ndarray, ref: np.ndarray) -> None:
    span = np.ptp(ref, axis=1, keepdims=True)
    assert np.all(span > 0), "every output must move, or the comparison proves nothing"
    assert np.max(np.abs(y - ref) / span) <= 1e-8


@functools.lru_cache(maxsize=32)
def _read_description(xml: str, modified_ns: int, size: int):
    return fmpy.read_model_description(xml)


def model_description(unzipped):
    """fmpy's model description of the FMU extracted in ``unzipped``, read once per version of its XML (a test
    that runs one FMU a hundred times parsed it each time: 40 ms of a 0.3 s run)."""
    xml = os.path.join(str(unzipped), "modelDescription.xml")
    stat = os.stat(xml)
    return _read_description(xml, stat.st_mtime_ns, stat.st_size)


def nominal_slave(model, unzipped, name="instance") -> FMU2Slave:
    md = model_description(unzipped)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=name)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu


def value_references(unzipped):
    md = model_description(unzipped)
    return ({v.name: v.valueReference for v in md.modelVariables if v.causality == "input"},
            {v.name: v.valueReference for v in md.modelVariables if v.causality == "output"})


def run_steps(model, fmu, unzipped, t, u):
    """y[output, k] of an initialised co-simulation FMU (FMI 2 or 3), u[input, k] held over each step."""
    ins, outs = value_references(unzipped)
    in_vr = [ins[n] for n in model.system.input_labels]
    out_vr = [outs[n] for n in model.system.output_labels]
    get, put = (fmu.getFloat64, fmu.setFloat64) if hasattr(fmu, "getFloat64") else (fmu.getReal, fmu.setReal)
    y = [get(out_vr)]
    for k in range(len(t) - 1):
        put(in_vr, list(u[:, k]))
        fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=t[k + 1] - t[k])
        y.append(get(out_vr))
    return np.array(y).T


def rss_bytes() -> int:
    """Resident set size of this process (Linux)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * __import__("os").sysconf("SC_PAGE_SIZE")


def initialised_slave(model, unzipped, start: dict[str, float], name="params") -> FMU2Slave:
    """An FMU instance initialised with the given parameter values."""
    md = model_description(unzipped)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=name)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr[k] for k in start], list(start.values()))
    fmu.exitInitializationMode()
    return fmu


def run_in_libcosim(fmu, *, model, u: np.ndarray, step_s: float, exchange) -> np.ndarray:
    """Outputs y[output, k] of ``fmu`` driven by ``u[input, k]`` in libcosim, run in its own process.

    Its own process: libcosim unpacks the FMU into a cache it deletes when the execution ends, and
    deleting a loaded pythonfmu FMU's folder in a process that goes on loading pythonfmu FMUs has
    aborted Python at exit. ``exchange`` is the .npz file that carries the data across.
    """
    import subprocess
    import sys
    from pathlib import Path

    names, outputs = list(model.system.input_labels), list(model.system.output_labels)
    np.savez(exchange, u=u, names=np.array(names), outputs=np.array(outputs))
    script = ("import sys, numpy as np\n"
              "sys.path.insert(0, sys.argv[3])\n"
              "from libcosim_import import run\n"
              "d = np.load(sys.argv[2])\n"
              "y = run(sys.argv[1], inputs={str(k): d['u'][i] for i, k in enumerate(d['names'])},\n"
              "        outputs=[str(k) for k in d['outputs']], step_s=float(sys.argv[4]))\n"
              "np.save(sys.argv[2] + '.y.npy', y)\n"
              "import os; os._exit(0)\n")  # skip teardown, where unloading pythonfmu FMUs has aborted (conftest)
    examples = Path(__file__).resolve().parents[2] / "examples"
    done = subprocess.run([sys.executable, "-c", script, str(fmu), str(exchange), str(examples), repr(step_s)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, f"libcosim run ended with status {done.returncode}: {done.stderr[-2000:]}"
    return np.load(str(exchange) + ".y.npy")
