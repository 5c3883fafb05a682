"""Run one misuse scenario on a MACE FMU through fmpy's FMI 2.0 API; print statuses and the FMU's log as JSON.

Run as a separate process (``python fmu_misuse_worker.py FMU_FOLDER SCENARIO``) so that whatever
the FMU does to its process cannot touch the test process. Every FMI call is recorded with the
status it returned; the logger collects the FMU's messages (debug logging on, as pythonfmu needs).
"""

from __future__ import annotations

import json
import math
import os
import sys
from ctypes import byref, c_double

import fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, calloc, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2LastSuccessfulTime, free)

folder, scenario = sys.argv[1], sys.argv[2]
description = fmpy.read_model_description(folder)
vr = {v.name: v.valueReference for v in description.modelVariables}
inputs = [v.name for v in description.modelVariables if v.causality == "input"]
outputs = [v.name for v in description.modelVariables if v.causality == "output"]
log: list[list] = []
calls: list[list] = []


def logger(component, instance, status, category, message):
    log.append([int(status), (message or b"").decode()])


callbacks = fmi2CallbackFunctions()
callbacks.logger = fmi2CallbackLoggerTYPE(logger)
callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
fmu = FMU2Slave(guid=description.guid, unzipDirectory=folder,
                modelIdentifier=description.coSimulation.modelIdentifier, instanceName="misuse")
fmu.instantiate(callbacks=callbacks, loggingOn=True)
raw = fmu._functions  # the C functions themselves: they return the status instead of raising


def call(name: str, *args):
    """Call an FMI function; record (name, status, new log lines); return its value (None on failure)."""
    before = len(log)
    try:
        value = getattr(fmu, name)(*args)
        status = 0
    except FMICallException as exc:
        value, status = None, int(exc.status)
    calls.append([name, status, log[before:]])
    return value


def last_successful_time() -> float:
    t = c_double(math.nan)
    status = raw["fmi2GetRealStatus"](fmu.component, fmi2LastSuccessfulTime, byref(t))
    return t.value if status == 0 else None


def initialise(**parameters: float) -> None:
    for name, value in parameters.items():
        call("setReal", [vr[name]], [value])
    call("setupExperiment", None, 0.0)
    call("enterInitializationMode")
    call("exitInitializationMode")


result: dict = {}
u = [0.1 * (k + 1) for k in range(len(inputs))]
if scenario == "nan_input":
    initialise()
    call("setReal", [vr[n] for n in inputs], u)
    call("doStep", 0.0, 0.002)
    before = call("getReal", [vr[n] for n in outputs])
    call("setReal", [vr[inputs[2]]], [math.nan])
    call("doStep", 0.002, 0.002)
    result["time_after_refusal"] = last_successful_time()
    call("setReal", [vr[inputs[2]]], [math.inf])
    call("doStep", 0.002, 0.002)
    call("setReal", [vr[n] for n in inputs], u)
    result["state_unchanged"] = call("getReal", [vr[n] for n in outputs]) == before  # same x, same u
    call("doStep", 0.002, 0.002)  # a finite input again: the run goes on
elif scenario == "before_init":
    call("doStep", 0.0, 0.002)
    initialise()
    call("doStep", 0.0, 0.002)
elif scenario.startswith("parameter:"):
    _, name, value = scenario.split(":")
    initialise(**{name: float(value)})
    call("doStep", 0.0, 0.002)
    call("doStep", 0.002, 0.002)
elif scenario.startswith("simulate:"):  # simulate:NAME:VALUE: fmpy's own loop, as a user runs an FMU
    _, name, value = scenario.split(":")
    fmu.freeInstance()  # this scenario's FMUs are simulate_fmu's own
    for debug in (False, True):
        try:
            fmpy.simulate_fmu(folder, stop_time=0.01, step_size=0.002, start_values={name: float(value)},
                              debug_logging=debug, logger=logger)
            result[f"raised_{debug}"] = ""
        except FMICallException as exc:
            result[f"raised_{debug}"] = str(exc)
    result["log"] = log
    # the process goes on: a run with the FMU's own values is whole
    result["rows_after"] = len(fmpy.simulate_fmu(folder, stop_time=0.01, step_size=0.002))
    print(json.dumps({"calls": calls, "outputs": outputs, **result}), flush=True)
    sys.stderr.flush()
    os._exit(0)
elif scenario.startswith("lifetime:"):  # lifetime:NAME:VALUE: the slave object across a refused call and the free
    import gc

    _, name, value = scenario.split(":")

    def slaves() -> int:
        gc.collect()
        return sum(type(o).__name__ == description.coSimulation.modelIdentifier for o in gc.get_objects())

    result["alive"] = [slaves()]
    call("setReal", [vr[name]], [float(value)])
    result["alive"].append(slaves())  # pythonfmu's wrapper has released it once: still held by the wrapper
    fmu.freeInstance()
    result["alive"].append(slaves())  # released again by the free: gone, exactly once
    for _ in range(3):  # a heap the double release damaged fails in allocations after it
        _ = [list(range(100)) for _ in range(50_000)]
        gc.collect()
    print(json.dumps({"calls": calls, "outputs": outputs, **result}), flush=True)
    sys.stderr.flush()
    os._exit(0)
elif scenario == "fixed_after_init":
    initialise()
    call("doStep", 0.0, 0.002)
    call("setReal", [vr["K_a"]], [-3.0])
    call("doStep", 0.002, 0.002)
    result["K_a"] = call("getReal", [vr["K_a"]])
elif scenario == "unknown_reference":
    initialise()
    result["value"] = call("getReal", [987654])
    call("setReal", [987654], [1.0])
    call("doStep", 0.0, 0.002)
elif scenario == "after_terminate":
    initialise()
    call("setReal", [vr[n] for n in inputs], u)
    call("doStep", 0.0, 0.002)
    result["before"] = call("getReal", [vr[n] for n in outputs])
    call("terminate")
    result["after"] = call("getReal", [vr[n] for n in outputs])
    call("doStep", 0.002, 0.002)
elif scenario == "bad_step":
    initialise()
    call("doStep", 0.0, -0.002)
    call("doStep", 0.0, math.nan)
    call("doStep", 0.0, math.inf)
elif scenario.startswith("steps:"):  # steps:INPUT:h1,h2,...: constant 1 V on INPUT from x = 0
    _, name, sizes = scenario.split(":")
    initialise()
    call("setReal", [vr[name]], [1.0])
    t, samples = 0.0, []
    for h in (float(s) for s in sizes.split(",")):
        call("doStep", t, h)
        t += h
        samples.append(call("getReal", [vr[n] for n in outputs]))
    result["samples"] = samples
elif scenario.startswith("many:"):  # many:INPUT:h:n: n steps of h, outputs at the end only
    _, name, h, n = scenario.split(":")
    initialise()
    call("setReal", [vr[name]], [1.0])
    h, n = float(h), int(n)
    statuses = set()
    for k in range(n):
        statuses.add(raw["fmi2DoStep"](fmu.component, k * h, h, 1))
    result["statuses"] = sorted(int(s) for s in statuses)
    result["samples"] = [call("getReal", [vr[n] for n in outputs])]
else:
    raise SystemExit(f"unknown scenario {scenario!r}")
if scenario != "after_terminate":
    call("terminate")
fmu.freeInstance()
print(json.dumps({"calls": calls, "outputs": outputs, **result}), flush=True)
# pythonfmu's teardown pitfall (README, "Teardown"): after a 10^6-step run the interpreter's
# finalisation once aborted ("corrupted double-linked list") with the results already printed.
sys.stderr.flush()
os._exit(0)
