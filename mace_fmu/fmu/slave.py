"""The FMI 2.0 co-simulation slave that runs inside a MACE FMU (pythonfmu).

This file is copied into the FMU with its class renamed (MaceSlave -> e.g. MACE_1g) and must
import nothing but numpy, scipy and pythonfmu: the FMU runs without mace-fmu installed. Its
matrices and signal names come from ``resources/model.npz``.

Stepping is an exact zero-order hold: over a communication step h with the inputs u held,
[x(t+h); u] = expm([[A, B], [0, 0]] h) [x(t); u]. The matrix exponential is cached per step size,
so any (also varying) step size is exact. Outputs are y = C x + D u at the communication points.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Status
from scipy.linalg import expm


class MaceSlave(Fmi2Slave):
    """State-space model y = C x + D u, x' = A x + B u with exact ZOH stepping."""

    author = "mace-fmu"
    description = "MACE volts-volts model"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        data = np.load(Path(self.resources) / "model.npz", allow_pickle=False)
        self._a, self._b, self._c, self._d = (np.asarray(data[k], dtype=np.float64) for k in "ABCD")
        self._inputs = [str(n) for n in data["inputs"]]
        self._outputs = [str(n) for n in data["outputs"]]
        in_desc = [str(n) for n in data["input_descriptions"]]
        out_desc = [str(n) for n in data["output_descriptions"]]
        self._x = np.zeros(self._a.shape[0])
        self._u = np.zeros(len(self._inputs))
        self._y = None  # outputs, computed once per change of x or u (hosts read them one by one)
        self._cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._failed = False
        for k, (name, desc) in enumerate(zip(self._inputs, in_desc)):
            self.register_variable(Real(name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                                        start=0.0, description=desc, getter=self._input_getter(k),
                                        setter=self._input_setter(k)))
        for k, (name, desc) in enumerate(zip(self._outputs, out_desc)):
            self.register_variable(Real(name, causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                                        description=desc, getter=self._output_getter(k)))

    def _input_getter(self, k):
        return lambda: float(self._u[k])

    def _input_setter(self, k):
        def setter(value):
            self._u[k] = value
            self._y = None
        return setter

    def _output_getter(self, k):
        def getter():
            if self._y is None:
                self._y = self._c @ self._x + self._d @ self._u
            return float(self._y[k])
        return getter

    def _transition(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """(Phi, Gamma) of the zero-order hold over h seconds, cached."""
        if h not in self._cache:
            n, m = self._b.shape
            aug = np.zeros((n + m, n + m))
            aug[:n, :n], aug[:n, n:] = self._a, self._b
            e = expm(aug * h)
            if len(self._cache) > 64:  # a varying step size must not grow memory without bound
                self._cache.clear()
            self._cache[h] = (e[:n, :n].copy(), e[:n, n:].copy())
        return self._cache[h]

    def do_step(self, current_time: float, step_size: float) -> bool:
        if not all(math.isfinite(v) for v in self._u):
            bad = [n for n, v in zip(self._inputs, self._u) if not math.isfinite(v)]
            self.log(f"non-finite input value(s) at t = {current_time}: {', '.join(bad)}", status=Fmi2Status.error)
            return False
        if step_size > 0.0:
            phi, gamma = self._transition(float(step_size))
            self._x = phi @ self._x + gamma @ self._u
            self._y = None
        return True

    # FMU state (fmi2GetFMUstate / fmi2SetFMUstate): the hidden state vector and the held inputs.
    def _get_fmu_state(self) -> dict:
        return {"x": self._x.tolist(), "u": self._u.tolist()}

    def _set_fmu_state(self, state: dict) -> None:
        self._x = np.array(state["x"], dtype=np.float64)
        self._u = np.array(state["u"], dtype=np.float64)
        self._y = None
