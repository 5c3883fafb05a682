"""Which sensor an actuator is collocated with: what a response to that input is first read on."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mace_fmu.iomodel.instruments import Instruments


def collocated_sensor(instruments: Instruments, actuator_name: str,
                      grid_positions_m: Mapping[int, np.ndarray]) -> str:
    """The sensor at the actuator: its servo's sensor (gimbal encoder, wheel tachometer), else the
    sensor that reads the same DOF components nearest to the actuator's grids [m] (the active
    strut's piezo patches: the strain gauge pair of strut 2 about the same axis).
    """
    actuator = instruments.actuator(actuator_name)  # raises for an unknown name
    servo = {**instruments.servos.gimbals, **instruments.servos.wheels}.get(actuator_name)
    if servo is not None:
        return servo

    def centre(dofs) -> np.ndarray:
        return np.mean([grid_positions_m[grid] for grid, _, _ in dofs], axis=0)

    components = {c for _, c, _ in actuator.dofs}
    candidates = [s for s in instruments.sensors if {c for _, c, _ in s.dofs} == components]
    if not candidates:
        return instruments.sensors[0].name
    here = centre(actuator.dofs)
    return min(candidates, key=lambda s: float(np.linalg.norm(centre(s.dofs) - here))).name
