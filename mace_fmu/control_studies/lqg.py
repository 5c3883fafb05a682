"""LQG design on a design model, and its closed-loop cost on an evaluation model (thesis eq. A.1-A.2).

Plant: x' = A x + B (w + u), y = C x + v, with white noises w (intensity 1) and v (intensity
theta); cost J = E[x^T C^T C x + rho u^2], the steady-state form of eq. A.2's integral for a
noise-driven loop. The design model gives the regulator (Q = C^T C, R = rho) and the Kalman
filter (process noise through B, intensity 1; sensor noise theta); the compensator is then closed
around the evaluation model and J follows from one Lyapunov equation of the closed loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as sla

from mace_fmu.errors import MaceError


@dataclass(frozen=True)
class LqgWeights:
    """Control weighting and sensor-noise intensity; process noise intensity is 1 (thesis eq. A.1)."""

    rho: float  #: control weighting R [1/N^2 in the cost's units]
    theta: float  #: sensor noise intensity [m^2 s]

    def __post_init__(self) -> None:
        if not (np.isfinite(self.rho) and self.rho > 0 and np.isfinite(self.theta) and self.theta > 0):
            raise MaceError(f"LQG weights must be positive and finite, got rho={self.rho!r}, theta={self.theta!r}")


@dataclass(frozen=True)
class LqgDesign:
    """An LQG compensator: regulator gain, Kalman gain, and the compensator y -> u (u = K(s) y)."""

    regulator_gain: np.ndarray  #: K, u = -K x_hat
    kalman_gain: np.ndarray  #: L, x_hat' = A x_hat + B u + L (y - C x_hat)
    weights: LqgWeights  #: the LQG weights the design was made with
    compensator: ct.StateSpace  #: inputs: the model's outputs; outputs: its inputs


def _check_siso_plant(model: ct.StateSpace, what: str) -> None:
    if model.ninputs != 1 or model.noutputs != 1 or np.any(model.D != 0):
        raise MaceError(f"{what}: expected a strictly proper single-input single-output model, got "
                        f"{model.ninputs} inputs, {model.noutputs} outputs, D = {np.asarray(model.D).tolist()}")


def design_lqg(model: ct.StateSpace, weights: LqgWeights, *, noise_input: np.ndarray | None = None) -> LqgDesign:
    """LQG compensator of ``model`` (force [N] in, displacement [m] out) for ``weights``.

    ``noise_input`` (n_states x 1): where the unit-intensity process noise enters the Kalman
    filter's model; default the control input's column B (thesis eq. A.1). A disturbance that
    enters elsewhere (another actuator) is better modelled through its own column.

    Parameters
    ----------
    model : control.StateSpace
        The design model, one input [N] and one output [m].
    weights : LqgWeights
        The control weighting rho and the sensor noise intensity theta [m^2 s] (thesis eq. A.1).
    noise_input : numpy.ndarray, optional
        (n_states x 1) column where the process noise enters (default: the control input's).

    Returns
    -------
    LqgDesign
        The regulator gain K, the Kalman gain L and the compensator (a ``control.StateSpace`` from the
        model's outputs to its inputs).
    """
    _check_siso_plant(model, "LQG design model")
    a, b, c = model.A, model.B, model.C
    g = b if noise_input is None else np.asarray(noise_input, dtype=float).reshape(a.shape[0], 1)
    try:
        k, _, _ = ct.lqr(a, b, c.T @ c, weights.rho * np.eye(1))
        ell, _, _ = ct.lqe(a, g, c, np.eye(1), weights.theta * np.eye(1))
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:  # slycot's errors are ArithmeticErrors
        raise MaceError(f"LQG design of {model.name!r} failed for rho = {weights.rho:g}, theta = {weights.theta:g}: "
                        f"{' '.join(str(exc).split())}") from None
    compensator = ct.ss(a - b @ k - ell @ c, ell, -k, np.zeros((1, 1)), inputs=list(model.output_labels),
                        outputs=list(model.input_labels), name="lqg_compensator")
    return LqgDesign(regulator_gain=np.asarray(k), kalman_gain=np.asarray(ell), weights=weights,
                     compensator=compensator)


def regulator_poles(model: ct.StateSpace, design: LqgDesign) -> np.ndarray:
    """Poles [rad/s] of the state-feedback loop A - B K of ``model``, sorted by magnitude."""
    poles = np.linalg.eigvals(model.A - model.B @ design.regulator_gain)
    return poles[np.argsort(np.abs(poles))]


def closed_loop_matrices(plant: ct.StateSpace, design: LqgDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, noise input matrix scaled by the noise intensities' square roots, cost output matrix).

    Closed-loop state [x; x_hat]; noise inputs [w; v]; cost outputs [C x; sqrt(rho) u], so that
    J is the squared H2 norm of this system.
    """
    _check_siso_plant(plant, "LQG evaluation model")
    comp = design.compensator
    if comp.ninputs != plant.noutputs or comp.noutputs != plant.ninputs:
        raise MaceError("the compensator's inputs and outputs do not fit the evaluation model")
    ap, bp, cp = plant.A, plant.B, plant.C
    ak, bk, ck = comp.A, comp.B, comp.C
    n, m = ap.shape[0], ak.shape[0]
    a = np.block([[ap, bp @ ck], [bk @ cp, ak]])
    noise = np.block([[bp, np.zeros((n, 1))], [np.zeros((m, 1)), bk * np.sqrt(design.weights.theta)]])
    cost_out = np.block([[cp, np.zeros((1, m))], [np.zeros((1, n)), np.sqrt(design.weights.rho) * ck]])
    return a, noise, cost_out


def closed_loop_cost(plant: ct.StateSpace, design: LqgDesign) -> float:
    """Steady-state LQG cost J [m^2 + rho N^2] of ``design`` closed around ``plant``; inf if unstable."""
    a, noise, cost_out = closed_loop_matrices(plant, design)
    if np.max(np.linalg.eigvals(a).real) >= 0.0:
        return float("inf")
    gram = sla.solve_continuous_lyapunov(a, -noise @ noise.T)
    return float(np.trace(cost_out @ gram @ cost_out.T))


def optimal_cost(plant: ct.StateSpace, weights: LqgWeights) -> float:
    """J of the LQG compensator designed on ``plant`` itself: the lowest any compensator reaches."""
    return closed_loop_cost(plant, design_lqg(plant, weights))
