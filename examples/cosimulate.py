"""The 1-g MACE FMU in closed loop with a controller written in Python, stepped by fmpy.
=====================================================================================

    python examples/cosimulate.py fmus/MACE_1g_native.fmu

Disturbance: a 0.5 deg square wave on the secondary Z gimbal command. Controller: the payload Z
rate-gyro voltage, times a gain, commands the primary Z gimbal angle, a damping loop on the
payload. (The payload Z gyro reads -theta_z, as mounted, hence the positive sign; the loop is
stable up to a gain of about 0.3 deg/V with this FMU's delays.) Prints the payload gyro RMS with
the loop open and closed. ``simulate`` is used by the tests. The FMU is unpacked once, for both
runs, into a temporary folder that ``main`` removes when they are done.
"""

from __future__ import annotations

import os
import sys
import tempfile

import fmpy
import numpy as np
from fmpy.fmi2 import FMU2Slave


def simulate(unzipped: str, *, gain: float, duration_s: float = 4.0, step_s: float = 2e-3) -> np.ndarray:
    """Payload Z gyro voltage [V] at every step, with the rate loop of ``gain`` [deg/V] (0: open loop).

    ``unzipped`` is the folder the FMU was extracted into (fmpy.extract).
    """
    md = fmpy.read_model_description(unzipped)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="mace")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    gyro = []
    for k in range(int(round(duration_s / step_s))):
        t = k * step_s
        disturbance = 0.5 if (t % 1.0) < 0.5 else -0.5
        y = fmu.getReal([vr["gyro_payload_z"]])[0]
        command = gain * y  # the measured payload rate commands the primary gimbal: a damping loop
        fmu.setReal([vr["gimbal_secondary_z"], vr["gimbal_primary_z"]], [disturbance, command])
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step_s)
        gyro.append(y)
    fmu.terminate()
    fmu.freeInstance()
    return np.array(gyro)


def main() -> None:
    fmu = sys.argv[1] if len(sys.argv) > 1 else "fmus/MACE_1g_native.fmu"
    with tempfile.TemporaryDirectory(prefix="mace_cosim_") as folder:
        unzipped = fmpy.extract(fmu, unzipdir=folder)
        open_loop = simulate(unzipped, gain=0.0)
        closed = simulate(unzipped, gain=0.2)
    rms = lambda y: float(np.sqrt(np.mean(y**2)))  # noqa: E731
    print(f"payload Z gyro RMS, loop open:   {rms(open_loop):.4f} V")
    print(f"payload Z gyro RMS, loop closed: {rms(closed):.4f} V  ({20 * np.log10(rms(closed) / rms(open_loop)):+.1f} dB)")


if __name__ == "__main__":
    main()
    # A pythonfmu FMU keeps its Python module alive after freeInstance (pythonfmu issue #229), and the
    # interpreter's finalisation has then aborted ("corrupted double-linked list", SIGABRT) after the
    # results were printed, in one run in several. Leave without finalisation, as the test suite does
    # (tests/conftest.py): the results are flushed and the unpacked FMU is already removed.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
