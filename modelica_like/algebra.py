"""LTI algebra with numpy and scipy only: block interconnection and Pade delay realisations.

No imports beyond numpy, scipy and the standard library: this module is also copied verbatim
into FMUs, which rebuild their systems at initialisation without python-control.
"""

from __future__ import annotations

from math import factorial

import numpy as np
import scipy.linalg


def interconnect(blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]], wiring: np.ndarray,
                 entry: np.ndarray, exit_: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, C, D) of blocks wired by u_b = wiring @ y_b + entry @ r, y = exit_ @ y_b.

    With W = (I - wiring D_b)^-1: A = A_b + B_b W L C_b, B = B_b W E, C = F (C_b + D_b W L C_b),
    D = F D_b W E. W exists when the diagram has no algebraic loop.
    """
    a_b, b_b, c_b, d_b = (scipy.linalg.block_diag(*[b[k] for b in blocks]) for k in range(4))
    w = np.linalg.inv(np.eye(wiring.shape[0]) - wiring @ d_b)
    lc, we = w @ wiring @ c_b, w @ entry
    return a_b + b_b @ lc, b_b @ we, exit_ @ (c_b + d_b @ lc), exit_ @ d_b @ we


#: Shortest delay [s] realised by a Pade approximation; shorter ones are no delay (1e-9 of a ms step).
PADE_MIN_DELAY_S = 1e-12


def pade(delay: float, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """State-space (A, B, C, D) of the [order/order] Pade approximation of exp(-s delay).

    Realised in the scaled variable s * delay (companion form), rescaled and balanced, which
    keeps the matrices well conditioned for millisecond delays. A delay below
    :data:`PADE_MIN_DELAY_S` is a unit feedthrough: its poles (order / delay) would overflow the
    realisation long before the delay itself mattered against any sample time.
    """
    if delay < 0.0 or order < 1:
        raise ValueError(f"Pade delay needs delay >= 0 and order >= 1, got {delay}, {order}")
    if delay < PADE_MIN_DELAY_S:
        return np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.ones((1, 1))
    n = order
    c = np.array([factorial(2 * n - k) * factorial(n) / (factorial(2 * n) * factorial(k) * factorial(n - k))
                  for k in range(n + 1)])  # coefficient of (s T)^k
    den = c / c[n]  # monic in (s T)
    num = c * (-1.0) ** np.arange(n + 1) / c[n]
    d = num[n]  # leading coefficients are equal in size: |D| = 1
    a = np.zeros((n, n))
    a[:-1, 1:] = np.eye(n - 1)
    a[-1, :] = -den[:n]
    b = np.zeros((n, 1))
    b[-1, 0] = 1.0
    cc = (num[:n] - d * den[:n])[None, :]
    a, b = a / delay, b / delay
    _, (scale, _) = scipy.linalg.matrix_balance(a, permute=False, separate=True)
    return a * (1.0 / scale)[:, None] * scale[None, :], b / scale[:, None], cc * scale[None, :], np.array([[d]])
