"""The tests' reference simulation of a discrete state-space system, a block of samples per matrix product.

x[k+1] = Ad x[k] + Bd u[k], y[k] = C x[k] + D u[k] from x[0] = 0, evaluated ``block`` samples at a time (the
lifted system: a block's outputs are the observability rows times the state at its start plus the Markov
parameters' Toeplitz matrix times its inputs). The same algebra as the step-by-step loop, in other order of
rounding: two orders of magnitude faster in Python, so that the references of the parameter-route and FMU tests
no longer spend most of the suite's time in an interpreter loop.
"""

from __future__ import annotations

import numpy as np


def lifted_response(ad: np.ndarray, bd: np.ndarray, c: np.ndarray, d: np.ndarray, u: np.ndarray, *,
                    block: int = 20) -> np.ndarray:
    """(len(u), n_outputs) outputs of the discrete system (ad, bd, c, d) from rest, u: (samples, n_inputs)."""
    samples, m = u.shape
    n, p = ad.shape[0], c.shape[0]
    length = max(1, min(block, samples))
    observe = np.empty((length, p, n))  # C Ad^j
    observe[0] = c
    for j in range(1, length):
        observe[j] = observe[j - 1] @ ad
    reach = np.empty((length, n, m))  # Ad^j Bd
    reach[0] = bd
    for j in range(1, length):
        reach[j] = ad @ reach[j - 1]
    markov = np.concatenate([d[None], observe[:-1] @ bd])  # D, C Bd, C Ad Bd, ...
    lag = np.subtract.outer(np.arange(length), np.arange(length))  # output i of a block from its input j <= i
    toeplitz = np.where((lag >= 0)[:, None, :, None], markov[np.maximum(lag, 0)].transpose(0, 2, 1, 3), 0.0)
    blocks = -(-samples // length)
    padded = np.zeros((blocks * length, m))
    padded[:samples] = u
    inputs = padded.reshape(blocks, length * m).T  # (length m, blocks), a block's inputs in time order
    forced = reach[::-1].transpose(1, 0, 2).reshape(n, length * m) @ inputs  # sum_j Ad^(L-1-j) Bd u_j
    power = np.linalg.matrix_power(ad, length)
    states = np.zeros((n, blocks))
    for b in range(1, blocks):
        states[:, b] = power @ states[:, b - 1] + forced[:, b - 1]
    y = observe.reshape(length * p, n) @ states + toeplitz.reshape(length * p, length * m) @ inputs
    return y.T.reshape(blocks * length, p)[:samples]
