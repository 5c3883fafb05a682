"""A process that simulates an FMU with mace-fmu (in this process), then logs through fmpy's default callbacks.

Run as ``python fmpy_logger_host.py FMU``; prints "refused: ..." and exits 0 when fmpy's logger proxy
still points at a live logger, dies of SIGSEGV when it points at the collected logger of the simulation
(see mace_fmu.fmu.host.fmpy_logger_restored). The FMU needs the signals gimbal_secondary_z and gyro_payload_z.
"""

import gc
import sys

import fmpy

from mace_fmu.fmu.simulate import simulate_input_response

fmu = sys.argv[1]
try:  # a NaN input: the FMU logs an error through the logger mace-fmu gives fmpy
    simulate_input_response(fmu, input_name="gimbal_secondary_z", signal="step", amplitude_v=float("nan"),
                            duration_s=0.01, outputs=["gyro_payload_z"], in_subprocess=False)
except Exception:  # noqa: BLE001 - the failure is expected; what follows is the point
    pass
gc.collect()
slave = fmpy.instantiate_fmu(fmpy.extract(fmu), fmpy.read_model_description(fmu), fmi_type="CoSimulation")
try:
    slave.setReal([999999], [0.0])  # refused: the FMU logs why, through fmpy's default callbacks
except Exception as exc:  # noqa: BLE001 - fmpy raises a bare Exception
    print("refused:", exc, flush=True)
