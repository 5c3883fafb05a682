"""Thesis A.2: LQG on a reduced-order model of the cantilever, and the model's update under the LQG cost.

The full model (5 modes) is reduced to 4 modes (8 states) by square-root balanced truncation
(``balanced_truncation``: control.balred's method without slycot); LQG compensators designed on
the full, the balanced and the updated model are each closed around the full model, giving Table
A.1. The update frees the reduced model's pole frequencies, damping ratios and every entry of B
and C (the thesis's 24 parameters) and minimises the closed-loop cost on the full model by BFGS;
the constraint that the loop be stable is a barrier (an unstable loop costs BARRIER times J_full,
so line searches turn back). Unstated in the thesis, chosen here: theta = rho (the Kalman filter
is the regulator's dual and gets the same bandwidth), with rho set so that the full-order cost is
the thesis's 7.58e-6 (SI units); the loop's crossover then falls near the third mode, as the
thesis says (README).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import control as ct
import numpy as np
import scipy.optimize as so

from mace_fmu.control_studies.balanced_truncation import balanced_truncation
from mace_fmu.control_studies.lqg import LqgDesign, LqgWeights, closed_loop_cost, design_lqg
from mace_fmu.errors import MaceError

#: thesis Table A.1 [m^2 + rho N^2]
THESIS_COSTS = {"full": 7.58e-6, "balanced": 8.53e-6, "updated": 8.27e-6}
#: cost of an unstable loop during the update, relative to J_full
BARRIER = 1.0e3
#: finite-difference step of the update's gradient: the cost is accurate to about 1e-8 relative
#: (Riccati solutions of a lightly damped model; 1e-7 with slycot's), so steps below 1e-5 give
#: noise, not slopes
GRADIENT_STEP = 1.0e-4


@dataclass(frozen=True)
class ModalForm:
    """x' = A x + B u, y = C x with A = diag of [[0, 1], [-w^2, -2 zeta w]] blocks and free B, C."""

    omega: np.ndarray  #: pole frequencies [rad/s]
    zeta: np.ndarray  #: damping ratios
    b: np.ndarray  #: (2n,) input matrix, per block (displacement row, rate row)
    c: np.ndarray  #: (2n,) output matrix, per block (displacement column, rate column)

    def system(self, *, inputs: list[str], outputs: list[str], name: str) -> ct.StateSpace:
        """The state-space model with named signals."""
        n = len(self.omega)
        a = np.zeros((2 * n, 2 * n))
        for i, (w, z) in enumerate(zip(self.omega, self.zeta)):
            a[2 * i, 2 * i + 1] = 1.0
            a[2 * i + 1, 2 * i:2 * i + 2] = (-w * w, -2.0 * z * w)
        states = [f"{kind}_{i + 1}" for i in range(n) for kind in ("q", "q_dot")]
        return ct.ss(a, self.b[:, None], self.c[None, :], np.zeros((1, 1)), inputs=inputs, outputs=outputs,
                     states=states, name=name)


def modal_form(system: ct.StateSpace) -> ModalForm:
    """The same transfer function as ``system`` (SISO, D = 0, complex pole pairs only) in modal form.

    Each pair contributes (n1 s + n0) / (s^2 + 2 zeta w s + w^2); the block realises it with
    B = [0, 1] and C = [n0, n1].
    """
    if system.ninputs != 1 or system.noutputs != 1 or np.any(system.D != 0):
        raise MaceError("modal form: expected a strictly proper single-input single-output model")
    lam, vec = np.linalg.eig(system.A)
    residues = (system.C @ vec).ravel() * np.linalg.solve(vec, system.B).ravel()
    upper = np.flatnonzero(lam.imag > 0)
    if 2 * len(upper) != len(lam):
        raise MaceError(f"modal form: expected complex pole pairs only, got poles {np.round(lam, 6).tolist()}")
    upper = upper[np.argsort(np.abs(lam[upper]))]
    lam, residues = lam[upper], residues[upper]
    omega = np.abs(lam)
    n1 = 2.0 * residues.real
    n0 = -2.0 * (residues * lam.conj()).real
    b = np.tile([0.0, 1.0], len(omega))
    c = np.ravel(np.column_stack([n0, n1]))
    return ModalForm(omega=omega, zeta=-lam.real / omega, b=b, c=c)


@dataclass(frozen=True)
class UpdateParameters:
    """Maps the optimiser's vector p (zero at the start) to a ModalForm, each entry at its own scale.

    p = [log(w / w0) per mode, log(zeta / zeta0) per mode, B changes, C changes]; a B or C entry
    changes by p times its natural size (1/w for a displacement row of B, |n0| for a
    displacement column of C, |n0| / w for a rate column), so that the parameters are O(1).
    """

    start: ModalForm

    @property
    def size(self) -> int:
        """6 per mode: frequency, damping, two entries of B, two of C."""
        return 6 * len(self.start.omega)

    def _scales(self) -> tuple[np.ndarray, np.ndarray]:
        w0 = self.start.omega
        n0 = np.abs(self.start.c[0::2])
        return np.ravel(np.column_stack([1.0 / w0, np.ones_like(w0)])), np.ravel(np.column_stack([n0, n0 / w0]))

    def form(self, p: np.ndarray) -> ModalForm:
        """The modal form at parameter vector ``p``."""
        n = len(self.start.omega)
        b_scale, c_scale = self._scales()
        return ModalForm(omega=self.start.omega * np.exp(p[:n]), zeta=self.start.zeta * np.exp(p[n:2 * n]),
                         b=self.start.b + b_scale * p[2 * n:4 * n], c=self.start.c + c_scale * p[4 * n:6 * n])


@dataclass(frozen=True)
class ReducedOrderStudy:
    """Table A.1 and what produced it."""

    full: ct.StateSpace
    balanced: ct.StateSpace
    updated: ct.StateSpace
    weights: LqgWeights
    designs: dict[str, LqgDesign]  #: "full", "balanced", "updated"
    costs: dict[str, float]  #: closed-loop cost on the full model of each design [m^2 + rho N^2]
    hankel_singular_values: np.ndarray  #: of the full model
    iterations: int  #: BFGS iterations of the update
    evaluations: int  #: closed-loop costs computed by the update
    message: str  #: the optimiser's final message


def balanced_model(full: ct.StateSpace, *, states: int) -> tuple[ct.StateSpace, np.ndarray]:
    """Square-root balanced truncation of ``full`` to ``states`` states (named "balanced"), and the
    full model's Hankel singular values."""
    truncation = balanced_truncation(full, states=states)
    r = truncation.reduced
    return (ct.ss(r.A, r.B, r.C, r.D, inputs=list(full.input_labels), outputs=list(full.output_labels),
                  name="balanced"), truncation.hankel_singular_values)


def weights_for_full_cost(full: ct.StateSpace, *, target_cost: float) -> LqgWeights:
    """theta = rho with rho such that the full-order LQG cost on ``full`` is ``target_cost``."""
    def log_ratio(log_rho: float) -> float:
        w = LqgWeights(rho=10.0**log_rho, theta=10.0**log_rho)
        return float(np.log(closed_loop_cost(full, design_lqg(full, w)) / target_cost))

    low, high = -12.0, -4.0  # J grows with rho here; below 1e-12 the Riccati solutions lose accuracy
    if log_ratio(low) > 0 or log_ratio(high) < 0:
        raise MaceError(f"no rho = theta in 1e{low:g}..1e{high:g} gives a full-order LQG cost of {target_cost:g}")
    log_rho = so.brentq(log_ratio, low, high, xtol=1e-9)
    return LqgWeights(rho=10.0**log_rho, theta=10.0**log_rho)


def update_reduced_model(*, full: ct.StateSpace, reduced: ct.StateSpace, weights: LqgWeights, max_iterations: int,
                         progress: Callable[[int, float], None] | None = None
                         ) -> tuple[ct.StateSpace, so.OptimizeResult]:
    """The reduced model whose LQG compensator has the lowest closed-loop cost on ``full`` (BFGS).

    ``progress(iteration, J / J_full)`` after each iteration. Returns the model and scipy's result
    (with ``nfev``, ``nit``, ``message``).
    """
    j_full = closed_loop_cost(full, design_lqg(full, weights))
    params = UpdateParameters(start=modal_form(reduced))
    signals = dict(inputs=list(full.input_labels), outputs=list(full.output_labels))

    def model(p: np.ndarray) -> ct.StateSpace:
        return params.form(p).system(**signals, name="updated")

    def cost(p: np.ndarray) -> float:
        try:
            j = closed_loop_cost(full, design_lqg(model(p), weights)) / j_full
        except MaceError:  # no stabilising Riccati solution for this trial model: as bad as instability
            return BARRIER
        return j if np.isfinite(j) else BARRIER

    iteration = [0]

    def report(p: np.ndarray) -> None:
        iteration[0] += 1
        if progress:
            progress(iteration[0], cost(p))

    result = so.minimize(cost, np.zeros(params.size), method="BFGS", callback=report,
                         options=dict(maxiter=max_iterations, gtol=1e-5, eps=GRADIENT_STEP))
    if not result.fun < BARRIER:
        raise MaceError("the reduced-model update ended on an unstable loop")
    return model(result.x), result


def reduced_order_study(*, full: ct.StateSpace, weights: LqgWeights, reduced_states: int = 8,
                        max_iterations: int = 200,
                        progress: Callable[[int, float], None] | None = None) -> ReducedOrderStudy:
    """Table A.1: LQG on the full, the balanced and the updated reduced model, each closed around ``full``.

    Parameters
    ----------
    full : control.StateSpace
        The full model the compensators are closed around.
    weights : LqgWeights
        The LQG weighting (rho, theta) of every design.
    reduced_states : int
        States of the reduced models.
    max_iterations : int
        Of the reduced model's update (the optimiser's cap).
    progress : callable, optional
        ``progress(iteration, cost)`` during the update.

    Returns
    -------
    ReducedOrderStudy
        The full, balanced and updated reduced models, each one's LQG design, and each design's
        closed-loop cost on the full model (Table A.1's rows).
    """
    balanced, hsv = balanced_model(full, states=reduced_states)
    updated, result = update_reduced_model(full=full, reduced=balanced, weights=weights,
                                           max_iterations=max_iterations, progress=progress)
    models = {"full": full, "balanced": balanced, "updated": updated}
    designs = {k: design_lqg(m, weights) for k, m in models.items()}
    costs = {k: closed_loop_cost(full, d) for k, d in designs.items()}
    return ReducedOrderStudy(full=full, balanced=balanced, updated=updated, weights=weights, designs=designs,
                             costs=costs, hankel_singular_values=hsv, iterations=int(result.nit),
                             evaluations=int(result.nfev), message=str(result.message))
