"""The FMI 2.0 co-simulation slave that runs inside a MACE FMU (pythonfmu).

The FMU's entry script is this file with modelica_like.algebra and mace_fmu.iomodel's modal_core,
reanalysis and parametric pasted in front (pythonfmu cannot load a second module from the resources), and the class
renamed (MaceSlave -> e.g. MACE_1g). It imports nothing but numpy, scipy and pythonfmu: the FMU
runs without mace-fmu installed. Its data come from ``resources/model.npz``.

Parameters take effect at initialisation, when the system is rebuilt from its blocks by
:class:`mace_fmu.iomodel.parametric.ParametricSystem` (physical parameters by Ritz reanalysis on
the retained nominal modes, thesis eq. 4.6-4.9; damping ratios, delays and servo gains in the
blocks they belong to).
Stepping is an exact zero-order hold: over a communication step h with the inputs u held,
[x(t+h); u] = expm([[A, B], [0, 0]] h) [x(t); u], cached per step size.

A parameter value outside its declared range (or not finite) is refused where it is set, by
fmi2SetReal, with the reason logged at status fmi2Error, and nothing is set; the call returns
fmi2Fatal, the one failing status pythonfmu's wrapper can return for a call other than fmi2DoStep
(it turns a Python exception into fmi2Fatal), so that a host stops there: fmpy's simulate_fmu
raises, as it does for the native FMU's fmi2Error. The wrapper releases the instance's three Python
objects (its class, the instance, its log queue) once when it catches the exception and once more
when the instance is freed, which corrupted the heap ("corrupted double-linked list" at exit):
:meth:`MaceSlave._refuse` takes one reference more to each first, so that each is released exactly
once. Every later step is refused with the same reason, for a host that goes on regardless.

Other misuse is logged with status fmi2Error and a refused step returns False, which pythonfmu
reports as fmi2Discard with the state unchanged (last successful time = the start of the step): a
fixed parameter set after initialisation and unknown value references make every later step
refused with the same reason. pythonfmu forwards the log to the host only when the host enabled
debug logging (loggingOn).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.enums import Fmi2Status
from scipy.linalg import expm

from mace_fmu.iomodel.parametric import ParametricSystem  # fmu: inlined


class RefusedCall(Exception):
    """Raised out of an FMI call the slave refuses: pythonfmu's wrapper returns fmi2Fatal for it."""


class MaceSlave(Fmi2Slave):
    """State-space model y = C x + D u, x' = A x + B u, rebuilt from parameters; exact ZOH stepping."""

    author = "mace-fmu"
    description = "MACE volts-volts model"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        # pythonfmu inserts the resources folder into sys.path on every instantiation: keep one entry
        if self.resources in sys.path:
            first = sys.path.index(self.resources)
            sys.path[first + 1:] = [p for p in sys.path[first + 1:] if p != self.resources]
        data = dict(np.load(Path(self.resources) / "model.npz", allow_pickle=False))
        self._system = ParametricSystem(data)
        self._inputs, self._outputs = self._system.inputs, self._system.outputs
        self._param_names = self._system.parameter_names
        self._nominal = self._system.nominal
        self._params = self._nominal.copy()
        self._built_with = None
        self._phase = "instantiated"  # -> "initialization" -> "stepping" -> "terminated"
        self._refusal: str | None = None  # why every step is refused (an error the standard calls fatal to the run)
        self._x = self._u = self._y = None
        self._cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._build()
        for k, (name, desc) in enumerate(zip(self._inputs, data["input_descriptions"])):
            self.register_variable(Real(name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                                        start=0.0, description=str(desc), getter=self._input_getter(k),
                                        setter=self._input_setter(k)))
        for k, (name, desc) in enumerate(zip(self._outputs, data["output_descriptions"])):
            self.register_variable(Real(name, causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                                        description=str(desc), getter=self._output_getter(k)))
        for k, (name, desc) in enumerate(zip(self._param_names, data["param_descriptions"])):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                        start=float(self._nominal[k]), description=str(desc),
                                        getter=self._param_getter(k), setter=self._param_setter(k)))
        for k, label in enumerate(data["mode_labels"]):
            # parameters.kinds.frequency_output_name(k + 1), spelled out: the FMU runs without mace_fmu installed
            self.register_variable(Real(f"frequency_mode_{k + 1}", causality=Fmi2Causality.calculatedParameter,
                                        variability=Fmi2Variability.fixed,
                                        description=f"natural frequency [Hz] of mode {k + 1} ({label}) after "
                                                "reanalysis and frequency scale (the mode it continues into, not the "
                                                "k-th lowest)",
                                        getter=self._frequency_getter(k)))

        self._input_of_vr = {vr: self._inputs.index(v.name) for vr, v in self.vars.items()
                             if v.causality == Fmi2Causality.input}
        self._output_of_vr = {vr: self._outputs.index(v.name) for vr, v in self.vars.items()
                              if v.causality == Fmi2Causality.output}
        self._param_of_vr = {vr: self._param_names.index(v.name) for vr, v in self.vars.items()
                             if v.causality == Fmi2Causality.parameter}
        self._index_cache: dict[tuple, np.ndarray | None] = {}
        self._last_step: tuple[float, tuple[np.ndarray, np.ndarray]] | None = None

    # --- variable access -------------------------------------------------------------------
    # Hosts write all inputs and read all outputs once per step: the vectorised paths below
    # replace pythonfmu's per-variable loop for those calls (other variables go through it).
    def _indices(self, vrs, table: dict[int, int], kind: str) -> np.ndarray | None:
        key = (kind, tuple(vrs))
        if key not in self._index_cache:
            index = [table.get(vr) for vr in vrs]
            self._index_cache[key] = None if None in index else np.array(index, dtype=int)
        return self._index_cache[key]

    def get_real(self, vrs):
        index = self._indices(vrs, self._output_of_vr, "out")
        if index is None:
            values = []
            for vr in vrs:
                var = self.vars.get(vr)
                if isinstance(var, Real):
                    values.append(float(var.getter()))
                else:
                    self._misuse(f"fmi2GetReal: {vr} is not the value reference of a Real variable")
                    values.append(math.nan)
            return values
        if self._y is None:
            self._y = self._c @ self._x + self._d @ self._u
        return self._y[index].tolist()

    def set_real(self, vrs, values):
        index = self._indices(vrs, self._input_of_vr, "in")
        if index is None:
            # every parameter value is checked before any is set: a refused call leaves the instance as it was
            for vr, value in zip(vrs, values):
                k = self._param_of_vr.get(vr)
                if k is not None and self._phase in ("instantiated", "initialization"):
                    problem = self._system.parameter_problem(k, float(value))
                    if problem is not None:
                        self._refuse(f"fmi2SetReal: invalid parameter: {problem}; not set")
                        return
            for vr, value in zip(vrs, values):
                var = self.vars.get(vr)
                if not isinstance(var, Real) or var.setter is None:
                    self._misuse(f"fmi2SetReal: {vr} is not the value reference of a Real variable that can be set")
                elif var.causality == Fmi2Causality.parameter and self._phase not in ("instantiated",
                                                                                       "initialization"):
                    self._misuse(f"fmi2SetReal: {var.name} is a fixed parameter and cannot change after "
                                 "initialisation (value ignored)")
                else:
                    var.setter(value)
            return
        self._u[index] = values
        self._y = None

    def _misuse(self, reason: str) -> None:
        """Log ``reason`` at error level; every later step is refused with it (FMI: fmi2Error ends the run)."""
        self.log(reason, status=Fmi2Status.error)
        self._refusal = self._refusal or reason

    def _refuse(self, reason: str) -> None:
        """Log ``reason`` at error level and fail the call (fmi2Fatal); every later step is refused with it.

        Without a reference of our own to give pythonfmu's wrapper for its second release, the call is not
        failed (the heap would be), and only the steps are refused.
        """
        self._misuse(reason)
        if self._held_for_the_wrapper():
            raise RefusedCall(reason)

    def _held_for_the_wrapper(self) -> bool:
        """One reference more to each object pythonfmu's wrapper releases twice after an exception.

        Its ``handle_py_exception`` (PySlaveInstance.cpp, 0.6.4 to 0.7.0) calls ``Py_XDECREF`` on the slave's
        class, the slave and the log queue it got from ``_get_log_queue`` without forgetting them, and its
        destructor (fmi2FreeInstance; fmi2Reset for the instance and the queue) releases them again. Held once
        more here, each is released exactly once in all; a host that never frees the instance leaks it.
        """
        try:
            import ctypes

            increment = ctypes.pythonapi.Py_IncRef
        except (ImportError, AttributeError):  # an interpreter whose C API ctypes cannot reach
            return False
        increment.argtypes, increment.restype = [ctypes.py_object], None
        for held in (type(self), self, self._get_log_queue()):
            increment(held)
        return True

    def _refuse_step(self, current_time: float, reason: str) -> bool:
        self.log(f"fmi2DoStep at t = {current_time} s refused: {reason}", status=Fmi2Status.error)
        return False

    def _input_getter(self, k):
        return lambda: float(self._u[k])

    def _input_setter(self, k):
        def setter(value):
            self._u[k] = value
            self._y = None
        return setter

    def _output_getter(self, k):
        def getter():
            if self._y is None:  # computed once per change of x or u; hosts read outputs one by one
                self._y = self._c @ self._x + self._d @ self._u
            return float(self._y[k])
        return getter

    def _param_getter(self, k):
        return lambda: float(self._params[k])

    def _param_setter(self, k):
        def setter(value):
            self._params[k] = value
        return setter

    def _frequency_getter(self, k):
        def getter():
            if self._system.parameter_problems(self._params):
                return math.nan  # the reasons are logged at initialisation
            self._build()
            return float(self._frequencies[k])
        return getter

    # --- building the system from its blocks --------------------------------------------------
    def _build(self) -> None:
        """(Re)build A, B, C, D when the parameters changed since the last build."""
        if self._built_with is not None and np.array_equal(self._built_with, self._params):
            return
        self._a, self._b, self._c, self._d = self._system.build(self._params)
        self._frequencies = self._system.frequencies_hz
        self._built_with = self._params.copy()
        self._cache.clear()
        self._last_step = None
        self._x = np.zeros(self._a.shape[0])
        self._u = np.zeros(len(self._inputs)) if self._u is None else self._u
        self._y = None

    def enter_initialization_mode(self):
        self._phase = "initialization"

    def exit_initialization_mode(self):
        self._phase = "stepping"
        problems = self._system.parameter_problems(self._params)  # fmi2SetReal refuses them: values set otherwise
        for problem in problems[1:]:
            self.log(f"invalid parameter: {problem}", status=Fmi2Status.error)
        if problems:
            self._refuse(f"invalid parameter: {problems[0]}")
            return
        try:
            self._build()
        except Exception as exc:  # noqa: BLE001 - an exception here would be fmi2Fatal and corrupt the heap
            self._misuse(f"the model could not be rebuilt with these parameters: {exc}")

    def terminate(self):
        self._phase = "terminated"

    # --- stepping ----------------------------------------------------------------------------
    def _transition(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        """(Phi, Gamma) of the zero-order hold over h seconds, cached.

        Keyed on h to 12 significant digits: hosts compute steps as t[k+1] - t[k], which gives a
        dozen round-off variants of one step size, each of which would cost a matrix exponential.
        """
        if self._last_step is not None and self._last_step[0] == h:
            return self._last_step[1]
        raw, h = h, float(f"{h:.12g}")
        if h not in self._cache:
            n, m = self._b.shape
            aug = np.zeros((n + m, n + m))
            aug[:n, :n], aug[:n, n:] = self._a, self._b
            e = expm(aug * h)
            if len(self._cache) > 64:  # a varying step size must not grow memory without bound
                self._cache.clear()
            self._cache[h] = (e[:n, :n].copy(), e[:n, n:].copy())
        self._last_step = (raw, self._cache[h])
        return self._cache[h]

    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._phase != "stepping":
            return self._refuse_step(current_time, "the FMU is not initialised (call fmi2ExitInitializationMode "
                                     "first)" if self._phase != "terminated" else "the FMU is terminated")
        if self._refusal is not None:
            return self._refuse_step(current_time, self._refusal)
        if not (math.isfinite(step_size) and step_size >= 0.0):
            return self._refuse_step(current_time, f"step size {step_size} s (expected a finite value >= 0)")
        if not np.isfinite(self._u).all():
            bad = [n for n, v in zip(self._inputs, self._u) if not math.isfinite(v)]
            return self._refuse_step(current_time, f"non-finite input value(s): {', '.join(bad)}")
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
