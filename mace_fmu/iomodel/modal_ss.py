"""Physical modal state-space model (thesis eq. 3.5-3.6): inputs [N m], outputs in physical units.

x = [eta; eta_dot] per retained mode; A = [[0, I], [-Omega^2, -2 zeta Omega]], B = [0; Phi^T b],
C = [c_d Phi, 0; 0, c_r Phi], D = 0; an acceleration sensor c_a reads eta'' (C = c_a Phi [-Omega^2,
-2 zeta Omega], D = c_a Phi Phi^T b). Besides the sensors, the model outputs the displacement
reading (``<name>_angle``) of each rate sensor a gimbal servo integrates (the encoders) and, on
request, the motion of named grids for animation (``grid_<id>_<tx|ty|tz|rx|ry|rz>``, basic axes,
metres and radians).

The zero-frequency cluster is reduced by rule (see mace_fmu.iomodel.modal_core).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import control as ct
import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fe.modal import Modes
from mace_fmu.iomodel.instruments import Instruments, influence_vector
from mace_fmu.iomodel.modal_core import modal_matrices
from mace_fmu.iomodel.motion import MOTION_COMPONENTS, motion_output_name

@dataclass(frozen=True)
class ModalPlant:
    """The physical modal model with the bookkeeping a reader needs."""

    system: ct.StateSpace  #: named inputs (actuators, N m), outputs (sensors; ``*_angle`` [rad])
    frequencies_hz: np.ndarray  #: of the retained modes
    damping: np.ndarray  #: open-loop damping ratio of each retained mode
    labels: tuple[str, ...]  #: label of each retained mode
    shapes: np.ndarray  #: (n_dof, n_modes) mode shapes behind the states (zero cluster rotated)
    removed_states: tuple[tuple[str, str], ...]  #: (state name, reason)
    motion_outputs: tuple[str, ...] = ()  #: grid motion outputs [m, rad] (see motion_output_name)
    motion_grids: tuple[int, ...] = ()  #: the grids behind them, in output order
    #: (n_sensors, n_actuators) residual flexibility on the sensors [sensor unit per actuator unit], sensor and
    #: actuator order: the static correction of modes the model lacks (None: none); a block beside the structure
    static_correction: np.ndarray | None = None


def modal_plant(modes: Modes, instruments: Instruments, damping: np.ndarray, *, max_hz: float,
                motion_grids: Sequence[int] = (), static_correction: np.ndarray | None = None) -> ModalPlant:
    """Modal state-space of the modes up to ``max_hz`` [Hz] with the instruments' DOFs (no gains).

    ``motion_grids`` adds the six motion components of each named grid as outputs. Directions of
    the zero-frequency cluster that only they read (wheel angles) keep their displacement states;
    the sensor outputs stay those of the model without them.

    Parameters
    ----------
    modes : Modes
        The structure's modes.
    instruments : Instruments
        Where the actuators push and the sensors read.
    damping : numpy.ndarray
        Modal damping ratio of each mode.
    max_hz : float
        Keep the modes up to this frequency [Hz].
    motion_grids : sequence of int
        Grids whose six motions are outputs too.
    static_correction : numpy.ndarray, optional
        (n_sensors, n_actuators) residual flexibility of the modes the model lacks, in the sensors' and
        actuators' physical units (:func:`mace_fmu.iomodel.modal_source.static_correction`).

    Returns
    -------
    ModalPlant
        The state space (inputs [N m], outputs in physical units) and its modes.
    """
    data = modal_data(modes, instruments, max_hz=max_hz, motion_grids=motion_grids)
    keep = modes.frequencies_hz <= max_hz
    a, b, c, d, states, labels, shapes, removed = modal_matrices(
        data.frequencies_hz, damping[keep], data.labels, data.shapes, data.modal_b, data.disp_out, data.rate_out,
        data.output_order, data.motion_out, data.acc_out)
    sys = ct.ss(a, b, c, d, inputs=[x.name for x in instruments.actuators], outputs=data.output_order, states=states,
                name="structure")
    return ModalPlant(system=sys, frequencies_hz=data.frequencies_hz, damping=damping[keep], labels=labels,
                      shapes=shapes, removed_states=tuple(removed), motion_outputs=data.motion_outputs,
                      motion_grids=tuple(motion_grids), static_correction=static_correction)


@dataclass(frozen=True)
class ModalData:
    """The retained modes projected on the instruments: what a modal model is built from."""

    frequencies_hz: np.ndarray
    labels: tuple[str, ...]
    shapes: np.ndarray  #: (n_dof, n_modes), mass-normalised
    modal_b: np.ndarray  #: (n_modes, n_actuators): Phi^T b, per N m
    disp_out: dict[str, np.ndarray]  #: displacement outputs: rows over the modes
    rate_out: dict[str, np.ndarray]  #: rate outputs: rows over the modes
    output_order: list[str]  #: the 20 sensors, the integrated encoders' "<name>_angle", the motion outputs
    motion_out: dict[str, np.ndarray] = field(default_factory=dict)  #: grid motion outputs: rows over the modes
    acc_out: dict[str, np.ndarray] = field(default_factory=dict)  #: acceleration outputs: rows over the modes

    @property
    def motion_outputs(self) -> tuple[str, ...]:
        """Names of the grid motion outputs, in output order."""
        return tuple(self.motion_out)


def modal_data(modes: Modes, instruments: Instruments, *, max_hz: float,
               motion_grids: Sequence[int] = ()) -> ModalData:
    """Project the modes up to ``max_hz`` [Hz] on the actuators, the sensors and the ``motion_grids``."""
    keep = modes.frequencies_hz <= max_hz
    phi = modes.shapes[:, keep]
    b = np.array([influence_vector(a.dofs, modes.dofs, modes.cd_frames) for a in instruments.actuators]).T
    rows = {s.name: influence_vector(s.dofs, modes.dofs, modes.cd_frames) @ phi for s in instruments.sensors}
    integrated = [s.name for s in instruments.sensors if s.name in instruments.servos.gimbals.values()]
    disp_out = {s.name: rows[s.name] for s in instruments.sensors if s.kind == "displacement"}
    disp_out.update({f"{n}_angle": rows[n] for n in integrated})
    rate_out = {s.name: rows[s.name] for s in instruments.sensors if s.kind == "rate"}
    acc_out = {s.name: rows[s.name] for s in instruments.sensors if s.kind == "acceleration"}
    order = [s.name for s in instruments.sensors] + [f"{n}_angle" for n in integrated]
    if len(set(motion_grids)) != len(motion_grids):
        raise MaceError(f"motion grids must be distinct, got {list(motion_grids)}")
    motion_out = {motion_output_name(grid, component): phi[index] for grid in motion_grids
                  for component, index in zip(MOTION_COMPONENTS, modes.dofs.indices(grid))}  # KeyError names a grid
    return ModalData(frequencies_hz=modes.frequencies_hz[keep], labels=tuple(lab for lab, k in zip(modes.labels, keep) if k),
                     shapes=phi, modal_b=phi.T @ b, disp_out=disp_out, rate_out=rate_out,
                     output_order=order + list(motion_out), motion_out=motion_out, acc_out=acc_out)
