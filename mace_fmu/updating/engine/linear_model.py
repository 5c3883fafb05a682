"""A linear model as the costs read it: named signals, labelled poles, frequency and time responses."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.signal as signal

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.frf import frequency_response
from mace_fmu.iomodel.poles import ClosedLoopPole, label_poles

#: H[k, output, input] of some outputs and inputs at frequencies [Hz]; replaces the generic route
FrequencyResponseFunction = Callable[[np.ndarray, Sequence[str], Sequence[str]], np.ndarray]


@dataclass(frozen=True, eq=False)
class LinearModel:
    """x' = A x + B u, y = C x + D u with named inputs, outputs and states.

    States of structural modes are named "structure.mode<k>_disp|vel" (k 1-based into
    ``mode_labels``), so poles are labelled by the modes they live in. ``frequency_function``
    optionally replaces the generic frequency response (e.g. a volts-volts model's exact one,
    which keeps its Bessel filters out of the eigen-decomposition).
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d: np.ndarray
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    state_names: tuple[str, ...]
    mode_labels: tuple[str, ...] = ()
    frequency_function: FrequencyResponseFunction | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        n, m, p = self.a.shape[0], len(self.inputs), len(self.outputs)
        for name, arr, shape in (("A", self.a, (n, n)), ("B", self.b, (n, m)), ("C", self.c, (p, n)),
                                 ("D", self.d, (p, m))):
            if arr.shape != shape:
                raise MaceError(f"LinearModel: {name} has shape {arr.shape}, expected {shape}")
        if len(self.state_names) != n:
            raise MaceError(f"LinearModel: {len(self.state_names)} state names for {n} states")

    @functools.cached_property
    def _poles(self) -> list[ClosedLoopPole]:
        return label_poles(self.a, state_names=self.state_names, mode_labels=self.mode_labels)

    def poles(self, *, max_hz: float | None = None) -> list[ClosedLoopPole]:
        """Poles with Im >= 0, sorted by frequency [Hz], labelled by participation factors."""
        return [p for p in self._poles if max_hz is None or p.frequency_hz <= max_hz]

    def _index(self, names: Sequence[str] | None, table: tuple[str, ...], what: str) -> list[int]:
        if names is None:
            return list(range(len(table)))
        unknown = [n for n in names if n not in table]
        if unknown:
            raise MaceError(f"unknown {what} signal(s) {unknown}; the model has: {', '.join(table)}")
        return [table.index(n) for n in names]

    def frequency_response(self, frequencies_hz: np.ndarray, *, inputs: Sequence[str] | None = None,
                           outputs: Sequence[str] | None = None) -> np.ndarray:
        """Complex H[k, output, input] at ``frequencies_hz`` [Hz] for the named channels (default all)."""
        i = self._index(inputs, self.inputs, "input")
        o = self._index(outputs, self.outputs, "output")
        f = np.asarray(frequencies_hz, dtype=float)
        if self.frequency_function is not None:
            return self.frequency_function(f, [self.inputs[k] for k in i], [self.outputs[k] for k in o])
        import control as ct

        sub = ct.ss(self.a, self.b[:, i], self.c[o], self.d[np.ix_(o, i)])
        return frequency_response(sub, f)

    def time_response(self, times_s: np.ndarray, inputs: Mapping[str, np.ndarray], *,
                      outputs: Sequence[str] | None = None) -> np.ndarray:
        """Outputs y[k, output] [model units] from rest, inputs held over each sample (zero-order hold).

        ``times_s`` must be uniformly spaced; inputs not given are zero.
        """
        t = np.asarray(times_s, dtype=float)
        dt = np.diff(t)
        if t.ndim != 1 or len(t) < 2 or not np.allclose(dt, dt[0], rtol=1e-9, atol=0.0) or dt[0] <= 0:
            raise MaceError("time_response: times must be increasing and uniformly spaced")
        unknown = set(inputs) - set(self.inputs)
        if unknown:
            raise MaceError(f"unknown input signal(s) {sorted(unknown)}; the model has: {', '.join(self.inputs)}")
        o = self._index(outputs, self.outputs, "output")
        used = [k for k, name in enumerate(self.inputs) if name in inputs]
        u = np.column_stack([np.asarray(inputs[self.inputs[k]], dtype=float) for k in used]) if used else \
            np.zeros((len(t), 0))
        if u.shape[0] != len(t):
            raise MaceError(f"time_response: inputs have {u.shape[0]} samples, times have {len(t)}")
        phi, gamma = zoh_transition(self.a, self.b[:, used], float(dt[0]))
        return simulate_discrete(phi, gamma, self.c[o], self.d[np.ix_(o, used)], u)


def zoh_transition(a: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, Gamma) of the exact zero-order-hold discretisation over ``dt`` [s]."""
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a, b
    e = sla.expm(aug * dt)
    return e[:n, :n], e[:n, n:]


_MAX_CONDITION = 1e6  # eigenvector conditioning up to which the modal route keeps ~1e-10 accuracy


def simulate_discrete(phi: np.ndarray, gamma: np.ndarray, c: np.ndarray, d: np.ndarray, u: np.ndarray) -> np.ndarray:
    """y[k] = C x[k] + D u[k], x[k+1] = Phi x[k] + Gamma u[k], x[0] = 0.

    In the eigen-coordinates of Phi each state is a first-order recursion, which
    scipy.signal.lfilter runs in compiled code; an ill-conditioned Phi is stepped directly.
    """
    n_steps = u.shape[0]
    drive = u @ gamma.T
    lam, v = np.linalg.eig(phi) if phi.size else (np.zeros(0), np.eye(0))
    if phi.size and np.linalg.cond(v) < _MAX_CONDITION:
        q = np.linalg.solve(v, drive.T)  # (state, step): the drive in eigen-coordinates
        z = np.empty((len(lam), n_steps), dtype=complex)
        for i, li in enumerate(lam):  # z[k+1] = lam z[k] + q[k], z[0] = 0
            z[i] = signal.lfilter([0.0, 1.0], [1.0, -li], q[i])
        return ((c @ v) @ z).real.T + u @ d.T
    x = np.zeros((n_steps, phi.shape[0]))
    for k in range(n_steps - 1):  # the recursion itself: one mat-vec per sample
        x[k + 1] = phi @ x[k] + drive[k]
    return x @ c.T + u @ d.T
