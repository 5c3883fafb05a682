"""Frequency responses of every channel at once: one eigen-decomposition, then batched products.

H(jw) = C (jw I - A)^-1 B + D = (C V) diag(1 / (jw - lambda)) (V^-1 B) + D for A = V Lambda V^-1.
A is balanced first (a diagonal similarity, scipy.linalg.matrix_balance): the 13 identical Bessel
filters give repeated eigenvalues whose eigenvectors are ill-conditioned (cond(V) = 3e8 for the
1-g model), and balancing brings that to ~5e5. When V is still too ill-conditioned for ~1e-9
relative accuracy, a direct solve per frequency is used instead.
"""

from __future__ import annotations

import control as ct
import numpy as np
import scipy.linalg as sla

_MAX_CONDITION = 1e6  # error ~ cond(V) * eps stays below ~1e-9 relative


def frequency_response(system: ct.StateSpace, frequencies_hz: np.ndarray) -> np.ndarray:
    """Complex response H[k, output, input] at ``frequencies_hz`` [Hz], same convention as control.

    Parameters
    ----------
    system : control.StateSpace
        A continuous-time model.
    frequencies_hz : numpy.ndarray
        Frequencies [Hz].

    Returns
    -------
    numpy.ndarray
        Complex H[k, output, input] in the model's units (V/V for a volts-volts model).
    """
    a, b, c, d = system.A, system.B, system.C, system.D
    s = 2j * np.pi * np.asarray(frequencies_hz, dtype=float)
    if len(a):
        a, (scale, _) = sla.matrix_balance(a, permute=False, separate=True)  # a <- T^-1 A T, T = diag(scale)
        b, c = b / scale[:, None], c * scale[None, :]
    lam, v = sla.eig(a)
    if np.linalg.cond(v) > _MAX_CONDITION:
        return np.array([c @ np.linalg.solve(sk * np.eye(len(a)) - a, b) + d for sk in s])
    cv = c @ v
    vb = sla.solve(v, b)
    resolvent = 1.0 / (s[:, None] - lam[None, :])  # (k, n)
    return (cv[None, :, :] * resolvent[:, None, :]) @ vb + d[None, :, :]
