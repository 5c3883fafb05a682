"""Run a MACE FMU in libcosim (the Open Simulation Platform's co-simulation library).
==================================================================================

    python examples/libcosim_import.py fmus/MACE_1g_native.fmu [--verbose]

Drives the secondary Z gimbal (the disturbance source) with a 1 deg step command and prints
the payload Z rate-gyro voltage every 0.1 s. ``run`` is also used by the tests, which compare
it with fmpy to 1e-10. libcosim's own log (FMI Library debug lines) shows only warnings and
errors unless ``--verbose``.
"""

from __future__ import annotations

import argparse

import fmpy
import numpy as np
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimManipulator import CosimManipulator
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave


def run(fmu_path: str, *, inputs: dict[str, np.ndarray], outputs: list[str], step_s: float,
        log_level: CosimLogLevel = CosimLogLevel.WARNING) -> np.ndarray:
    """Outputs (len(outputs), n_steps + 1) [V] after each libcosim step; inputs[name][k] holds over step k.

    ``log_level`` is the least severe message libcosim prints (its default would print debug lines).
    """
    log_output_level(log_level)
    md = fmpy.read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    n_steps = len(next(iter(inputs.values())))
    execution = CosimExecution.from_step_size(step_size=int(round(step_s * 1e9)))  # nanoseconds
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=fmu_path, instance_name="mace"))
    manipulator = CosimManipulator.create_override()
    observer = CosimObserver.create_last_value()
    execution.add_manipulator(manipulator)
    execution.add_observer(observer)
    out_vr = [vr[n] for n in outputs]
    in_vr = [vr[n] for n in inputs]
    rows = []
    for k in range(n_steps):
        manipulator.slave_real_values(index, in_vr, [float(inputs[n][k]) for n in inputs])
        execution.step()
        rows.append(observer.last_real_values(index, out_vr))
    execution.stop()
    return np.array(rows).T


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fmu", nargs="?", default="fmus/MACE_1g_native.fmu", help="a MACE FMU (default fmus/MACE_1g_native.fmu)")
    parser.add_argument("--verbose", action="store_true", help="also show libcosim's debug log")
    args = parser.parse_args()
    step = 2e-3
    n = 1000
    y = run(args.fmu, inputs={"gimbal_secondary_z": np.ones(n)}, outputs=["gyro_payload_z"], step_s=step,
            log_level=CosimLogLevel.DEBUG if args.verbose else CosimLogLevel.WARNING)
    for k in range(49, n, 50):
        print(f"t = {(k + 1) * step:5.2f} s   gyro_payload_z = {y[0, k]: .6f} V")


if __name__ == "__main__":
    main()
