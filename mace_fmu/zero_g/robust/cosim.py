"""One closed loop by co-simulation: the FMU (fmpy FMU2Slave) and the sampled compensator, stepped together.

At each communication point t_k the FMU's measurement y_k is read, the compensator gives the
control u_k = C x_k + D y_k and moves to x_{k+1} = A x_k + B y_k, u_k and the disturbance w_k are
set, and the FMU steps to t_k + h (it holds its inputs over the step). Parameter values are set
in initialisation mode, as any FMI importer sets tunable parameters before a run.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from mace_fmu.fmu.host import collecting_callbacks, release_pythonfmu_state
from mace_fmu.zero_g.robust.loop import LoopSpec, LoopVerdict, judge


@dataclass(frozen=True)
class SampledCompensator:
    """x_{k+1} = a x_k + b y_k, u_k = c x_k + d y_k (SISO, plain arrays: cheap to send to workers)."""

    a: np.ndarray
    b: np.ndarray  #: (n,)
    c: np.ndarray  #: (n,)
    d: float

    @classmethod
    def of(cls, system) -> SampledCompensator:
        """From a SISO discrete ``control.StateSpace``."""
        return cls(a=np.array(system.A, dtype=float), b=np.array(system.B, dtype=float).ravel(),
                   c=np.array(system.C, dtype=float).ravel(), d=float(np.asarray(system.D).ravel()[0]))


@dataclass(frozen=True)
class LoopRun:
    """Samples of one closed-loop run and its verdict."""

    measurement_v: np.ndarray  #: y_k at the communication points [V]
    control_v: np.ndarray  #: u_k [V]
    verdict: LoopVerdict
    failure: str = ""  #: the FMU's refusal (e.g. its state overflowed), if the run stopped early


def run_fmu_loop(unzipped: str | os.PathLike, *, loop: LoopSpec, compensator: SampledCompensator,
                 parameters: dict[str, float]) -> LoopRun:
    """Close ``compensator`` around the extracted FMU in ``unzipped`` with ``parameters`` set; see the module."""
    import fmpy
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave

    messages: list[str] = []  # the FMU's messages are kept for the failure text, not printed
    callbacks = collecting_callbacks(messages)
    unzipped = os.fspath(unzipped)
    md = fmpy.read_model_description(unzipped)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="robust")
    w = loop.disturbance()
    y_out, u_out = np.full(loop.steps, np.nan), np.full(loop.steps, np.nan)
    x = np.zeros(compensator.a.shape[0])
    y_ref, in_refs = [vr[loop.measurement]], [vr[loop.control_input], vr[loop.disturbance_input]]
    failure = ""
    # one BLAS thread: the compensator's products then sum in one order, serial or on a Dask worker
    with threadpool_limits(limits=1, user_api="blas"):
        try:
            fmu.instantiate(callbacks=callbacks)
        finally:  # else a pythonfmu binary writes into a freed block at exit (a failed instantiation too)
            if "pythonfmu" in (md.generationTool or "").lower():
                release_pythonfmu_state(fmu.dll)
        try:
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
            if parameters:
                fmu.setReal([vr[n] for n in parameters], [float(v) for v in parameters.values()])
            fmu.exitInitializationMode()
            for k in range(loop.steps):
                y = fmu.getReal(y_ref)[0]
                u = float(compensator.c @ x) + compensator.d * y
                x = compensator.a @ x + compensator.b * y
                y_out[k], u_out[k] = y, u
                if not (np.isfinite(y) and np.isfinite(u)):
                    break
                fmu.setReal(in_refs, [u, float(w[k])])
                fmu.doStep(currentCommunicationPoint=k * loop.step_s, communicationStepSize=loop.step_s)
            fmu.terminate()
        except FMICallException as exc:  # e.g. the FMU refuses a state that overflowed: the loop diverged
            failure = " ".join([str(exc), *messages[-3:]])
        finally:
            fmu.freeInstance()
    return LoopRun(measurement_v=y_out, control_v=u_out, verdict=judge(y_out, loop), failure=failure)
