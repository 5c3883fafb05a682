"""Square-root balanced truncation of a stable state-space model (Laub et al. 1987), numpy/scipy only.

The same method as control.balred(method="truncate") (SLICOT AB09AD, JOB = 'B'), without slycot:
installing slycot switches python-control's frequency response to SLICOT's Hessenberg (Laub)
evaluation project-wide, which is 6.5e-7 off on the MACE volts model where the direct solve meets
the 1e-9 check of tests/iomodel/test_volts.py. tests/control_studies/test_control_studies.py compares both where slycot
is installed.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as sla

from mace_fmu.errors import MaceError


@dataclass(frozen=True)
class BalancedTruncation:
    """The reduced model and the full model's Hankel singular values (largest first)."""

    reduced: ct.StateSpace  #: balanced coordinates: both gramians equal diag(hankel_singular_values[:n])
    hankel_singular_values: np.ndarray


def _gramian_factor(a: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """L with L L^T = W, the (semidefinite) gramian solving A W + W A^T + rhs = 0, from W's eigen-decomposition.

    Not a Cholesky factor: that refuses the uncontrollable or unobservable states a model's
    channels often have; the square-root method needs only L L^T = W.
    """
    w = sla.solve_continuous_lyapunov(a, -rhs)
    w, v = np.linalg.eigh(0.5 * (w + w.T))
    return v * np.sqrt(np.clip(w, 0.0, None))


def balanced_truncation(system: ct.StateSpace, *, states: int) -> BalancedTruncation:
    """Keep the ``states`` largest Hankel singular values of the stable ``system`` (D kept).

    ``states`` may not exceed the numerical order (Hankel singular values above 1e-12 of the
    largest): beyond it the balancing transformation does not exist.
    """
    a, b, c = system.A, system.B, system.C
    if np.max(np.linalg.eigvals(a).real) >= 0.0:
        raise MaceError("balanced truncation: the model is not asymptotically stable")
    lc = _gramian_factor(a, b @ b.T)
    lo = _gramian_factor(a.T, c.T @ c)
    u, hsv, vt = sla.svd(lo.T @ lc)
    order = int(np.sum(hsv > 1e-12 * hsv[0]))
    if not 0 < states <= order:
        raise MaceError(f"balanced truncation: states must be 1-{order} (the model's numerical order: "
                        f"{a.shape[0] - order} of its {a.shape[0]} states are uncontrollable or unobservable), "
                        f"got {states}")
    scale = hsv[:states] ** -0.5
    right = lc @ vt[:states].T * scale  # x = right z
    left = (scale[:, None] * u[:, :states].T) @ lo.T  # z = left x, left right = I
    reduced = ct.ss(left @ a @ right, left @ b, c @ right, system.D, inputs=list(system.input_labels),
                    outputs=list(system.output_labels), name=f"{system.name}_balanced")
    return BalancedTruncation(reduced=reduced, hankel_singular_values=hsv)
