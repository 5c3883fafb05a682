"""The same closed loop without the FMU: the Python model at the same parameter values, sampled, in feedback.

The independent route of the cross-check: ``ParametricSystem`` (the Python reference the FMUs
are validated against) builds (A, B, C, D) for the parameter values, scipy samples it exactly
for inputs held over each step (zero-order hold, what the FMU's stepping does), and
``control.feedback`` closes the sampled compensator around the control -> measurement channel.
The closed loop's eigenvalues give stability outright (spectral radius < 1); its response to
the same disturbance gives the same samples as the co-simulation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import control as ct
import numpy as np
import scipy.signal

from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.zero_g.robust.loop import LoopSpec, LoopVerdict, judge


@dataclass(frozen=True)
class StateSpaceLoop:
    """The sampled closed loop: disturbance -> (measurement, control), and its eigenvalues."""

    system: ct.StateSpace  #: discrete, dt = loop.step_s
    eigenvalues: np.ndarray

    @property
    def spectral_radius(self) -> float:
        """Largest |eigenvalue|: below 1 means asymptotically stable."""
        return float(np.max(np.abs(self.eigenvalues)))


def state_space_loop(reference: ParametricSystem, *, loop: LoopSpec, compensator: ct.StateSpace,
                     parameters: Mapping[str, float]) -> StateSpaceLoop:
    """Close ``compensator`` (discrete, measurement -> control) around ``reference`` at ``parameters``."""
    values = np.array(reference.nominal, dtype=float)
    for name, value in parameters.items():
        values[reference.index(name)] = value
    a, b, c, d = reference.build(values)
    ins, outs = [str(n) for n in reference.data["inputs"]], [str(n) for n in reference.data["outputs"]]
    i = [ins.index(loop.control_input), ins.index(loop.disturbance_input)]
    o = [outs.index(loop.measurement)]
    ad, bd, cd, dd, _ = scipy.signal.cont2discrete((a, b[:, i], c[o, :], d[np.ix_(o, i)]), loop.step_s, method="zoh")
    plant = ct.ss(ad, bd, cd, dd, loop.step_s, inputs=["u", "w"], outputs=["y"], name="plant")
    comp = ct.ss(compensator.A, compensator.B, compensator.C, compensator.D, loop.step_s, inputs=["y"],
                 outputs=["u"], name="compensator")
    # positive feedback: the compensator's output is the control itself (u = K y), not a correction to subtract
    eigenvalues = np.linalg.eigvals(ct.feedback(plant[0, 0], comp, sign=1).A)
    closed = ct.interconnect([plant, comp], inplist=["plant.w"], outlist=["plant.y", "compensator.u"],
                             inputs=["w"], outputs=["y", "u"],
                             connections=[["plant.u", "compensator.u"], ["compensator.y", "plant.y"]], dt=loop.step_s)
    return StateSpaceLoop(system=closed, eigenvalues=eigenvalues)


def simulate_state_space(closed: StateSpaceLoop, loop: LoopSpec) -> tuple[np.ndarray, np.ndarray, LoopVerdict]:
    """(measurement, control, verdict) of the sampled closed loop under the loop's disturbance."""
    response = ct.forced_response(closed.system, T=loop.times_s(), U=loop.disturbance()[None, :])
    y, u = np.asarray(response.outputs)
    return y, u, judge(y, loop)
