"""The LQG compensator a sweep tests: designed on the nominal 0-g model, reduced, sampled at the FMU's step.

Design model: the nominal model's channels from the control input and the disturbance input to
the measurement, reduced by square-root balanced truncation to ``reduced_states`` states. The
gramians are factored through their eigen-decomposition, not Cholesky: a channel of the full
volts model is far from minimal (195 states), and the factor of a semidefinite gramian is what
keeps the truncation defined (states beyond its numerical rank are refused). The LQG design is
Appendix A's (``control_studies.lqg.design_lqg``: regulator Q = C^T C, R = rho; Kalman filter with
sensor noise theta), with the unit process noise entering where the disturbance does (the
disturbance input's column), since that is what the loop must reject. The continuous compensator
is sampled by the bilinear (Tustin) rule at the FMU's communication step.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from mace_fmu.control_studies.balanced_truncation import balanced_truncation
from mace_fmu.control_studies.lqg import LqgDesign, LqgWeights, design_lqg
from mace_fmu.errors import MaceError
from mace_fmu.zero_g.robust.loop import LoopSpec

#: Default weights, chosen here (the thesis designs no 0-g compensator): theta = 10 rho, and rho ten
#: times the value (1e-3) at which the loop on the 0-g FMU before the update is unstable (spectral
#: radius 1.0013, tests/zero_g/test_robust.py); 2e-3 is stable there but settles slowly (0.975 per second).
DEFAULT_WEIGHTS = LqgWeights(rho=0.01, theta=0.1)
DEFAULT_REDUCED_STATES = 30


@dataclass(frozen=True)
class RobustDesign:
    """The compensator and what it was designed from."""

    loop: LoopSpec  #: the loop the controller closes
    weights: LqgWeights  #: the LQG weights
    channels: ct.StateSpace  #: nominal model, inputs (control, disturbance) -> measurement [V]
    reduced: ct.StateSpace  #: design model: control -> measurement, ``reduced_states`` states
    reduced_disturbance: np.ndarray  #: (n, 1) the disturbance input's column in the design model
    hankel_singular_values: np.ndarray  #: of ``channels``, largest first
    lqg: LqgDesign  #: continuous compensator measurement -> control
    compensator: ct.StateSpace  #: the same sampled at loop.step_s (Tustin): what runs with the FMU


def loop_channels(system: ct.StateSpace, loop: LoopSpec) -> ct.StateSpace:
    """The (control, disturbance) -> measurement channels of a volts model, by signal name."""
    ins, outs = list(system.input_labels), list(system.output_labels)
    missing = [n for n in (loop.control_input, loop.disturbance_input) if n not in ins] + \
        [n for n in (loop.measurement,) if n not in outs]
    if missing:
        raise MaceError(f"the model has no signal(s) {', '.join(missing)}; inputs: {', '.join(ins)}; "
                        f"outputs: {', '.join(outs)}")
    i = [ins.index(loop.control_input), ins.index(loop.disturbance_input)]
    o = [outs.index(loop.measurement)]
    return ct.ss(system.A, system.B[:, i], system.C[o, :], system.D[np.ix_(o, i)],
                 inputs=[loop.control_input, loop.disturbance_input], outputs=[loop.measurement], name="channels")


def design_compensator(system: ct.StateSpace, *, loop: LoopSpec = LoopSpec(), weights: LqgWeights = DEFAULT_WEIGHTS,
                       reduced_states: int = DEFAULT_REDUCED_STATES) -> RobustDesign:
    """LQG compensator of the nominal volts model ``system`` for ``loop`` (see the module docstring).

    Parameters
    ----------
    system : control.StateSpace
        The nominal 0-g volts model.
    loop : LoopSpec
        Control input, measurement and disturbance [V], the disturbance's square wave and the run.
    weights : LqgWeights
        The LQG weighting (rho, theta).
    reduced_states : int
        States of the balanced design model.

    Returns
    -------
    RobustDesign
        The channels, the reduced design model and the compensator (discrete, at the loop's step).
    """
    channels = loop_channels(system, loop)
    if np.any(channels.D != 0):
        raise MaceError("the loop's channels have a direct feedthrough; the co-simulation assumes none")
    truncation = balanced_truncation(channels, states=reduced_states)
    both, hsv = truncation.reduced, truncation.hankel_singular_values
    reduced = ct.ss(both.A, both.B[:, :1], both.C, np.zeros((1, 1)), inputs=[loop.control_input],
                    outputs=[loop.measurement], name="design_model")
    lqg = design_lqg(reduced, weights, noise_input=both.B[:, 1:])
    sampled = ct.sample_system(lqg.compensator, loop.step_s, method="tustin")
    compensator = ct.ss(sampled.A, sampled.B, sampled.C, sampled.D, loop.step_s, inputs=[loop.measurement],
                        outputs=[loop.control_input], name="compensator")
    return RobustDesign(loop=loop, weights=weights, channels=channels, reduced=reduced,
                        reduced_disturbance=both.B[:, 1:], hankel_singular_values=hsv, lqg=lqg,
                        compensator=compensator)
