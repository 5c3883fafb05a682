"""Seeded random FMI call sequences against a reference model of the standard's state machines.

Run as a program (tests/fmu/test_fmi_fuzz.py and benchmarks/bench_fmi_fuzz.py start it in a subprocess,
so that a crash of the FMU fails the run instead of killing the caller):

    python tests/support/fmi_fuzz.py FMI2_DIR FMI3_DIR FIRST_SEED N_SEEDS [--length L] [--interfaces cs2,me2,cs3]

FMI2_DIR / FMI3_DIR are extracted native FMUs of one model. Every seed drives one random sequence
of calls per interface (FMI 2 co-simulation, FMI 2 model exchange, FMI 3 co-simulation) on a fresh
instance through fmpy's low-level wrappers (fmu.fmi2DoStep(component, ...) etc.; a call of the other
interface goes through that interface's wrapper class on the same binary). Each call's status is
compared with the reference (``Reference.expect``): a call outside the states in which the standard's
state table allows it is fmiError; an allowed call with valid arguments is fmiOK; invalid arguments
(undeclared value references, non-finite inputs, wrong sizes, a step that does not start at the
FMU's time or is not > 0, a damaged or foreign FMU state) are fmiError. Gotten outputs must be
finite and the time read back must be the reference's. Progress ("seed N") goes to stderr, the
summary as one JSON line to stdout.

The tables (FMI 2.0.x sections 3.2.3 and 4.2.4, FMI 3.0 sections 3.2 and 4.2) restricted to the
states this FMU reaches: its steps never return Pending or Discard (no stepInProgress, stepFailed,
stepCanceled) and its FMI 3 instances have no event mode.
"""

from __future__ import annotations

import ctypes
import json
import math
import random
import sys
import time as clock
from dataclasses import dataclass, field

import fmpy
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Slave

OK, ERROR = 0, 3
INPUT_LIMIT_V = 1e6  # mace_instance.c MACE_INPUT_LIMIT_V, each input's declared min and max
TIME_TOLERANCE = 1e-9  # mace_instance.c: relative to max(1, |t|)
MAX_SAMPLES_PER_CALL = 1e6  # controller/mace_discrete.c: the samples one doStep of a controller FMU runs at most

INST, INIT, STEP, EVENT, CONT, TERM, ERR = "instantiated", "init", "step", "event", "continuous", "terminated", "error"
GETTABLE = {INIT, STEP, EVENT, CONT, TERM, ERR}
SETTABLE = {INST, INIT, STEP, EVENT, CONT}


@dataclass
class Variables:
    inputs: list[int]
    outputs: list[int]
    params: dict[int, tuple[float, float | None, float | None]]  # vr: (start, min, max)
    calculated: list[int]
    locals_: list[int]
    time: int | None
    undeclared: list[int]
    n_states: int

    @classmethod
    def read(cls, folder: str, other: str) -> Variables:
        md = fmpy.read_model_description(folder)
        by = lambda c: [v.valueReference for v in md.modelVariables if v.causality == c]  # noqa: E731
        params = {v.valueReference: (float(v.start), None if v.min is None else float(v.min),
                                     None if v.max is None else float(v.max))
                  for v in md.modelVariables if v.causality == "parameter"}
        mine = {v.valueReference for v in md.modelVariables}
        theirs = {v.valueReference for v in fmpy.read_model_description(other).modelVariables}
        top = max(mine | theirs)
        states = [v for v in md.modelVariables if v.causality == "local" and v.derivative is None]
        return cls(inputs=by("input"), outputs=by("output"), params=params, calculated=by("calculatedParameter"),
                   locals_=by("local"), time=(by("independent") or [None])[0],
                   undeclared=sorted(theirs - mine) + [top + 1, 10**6, 2**32 - 1], n_states=len(states))


@dataclass
class Model:
    """What the reference knows of an instance: its state-machine state, time and parameters."""

    phase: str = INST
    time: float = 0.0
    params: dict[int, float] = field(default_factory=dict)

    def copy(self) -> Model:
        return Model(self.phase, self.time, dict(self.params))


class Reference:
    """The standard's state machine for one interface ("cs2", "me2", "cs3")."""

    def __init__(self, interface: str, variables: Variables, sample_s: float | None = None):
        self.interface, self.v = interface, variables
        self.sample_s = sample_s  # a controller FMU's sample time: one call runs at most MAX_SAMPLES_PER_CALL
        self.cs = interface != "me2"
        self.fmi = 3 if interface == "cs3" else 2
        self.m = Model(params={vr: p[0] for vr, p in variables.params.items()})
        self.stop: float | None = None  # setupExperiment's stop time: no step or time past it (an instance's, not a state's)

    def params_valid(self, params: dict[int, float] | None = None) -> bool:
        for vr, value in (params or self.m.params).items():
            _, lo, hi = self.v.params[vr]
            if not math.isfinite(value) or (lo is not None and value < lo) or (hi is not None and value > hi):
                return False
        return True

    def group(self, vr: int) -> str:
        v = self.v
        if vr in v.inputs:
            return "input"
        if vr in v.outputs:
            return "output"
        if vr in v.params:
            return "param"
        if vr in v.calculated:
            return "calculated"
        if vr in v.locals_:
            return "local"
        if vr == v.time:
            return "time"
        return "undeclared"

    def reset(self) -> None:
        self.m = Model(params={vr: p[0] for vr, p in self.v.params.items()})
        self.stop = None

    def past_stop(self, t: float) -> bool:
        return self.stop is not None and t > self.stop + TIME_TOLERANCE * max(1.0, abs(self.stop))

    # each returns the expected status and applies the call's effect when it is OK
    def expect(self, call: str, args: dict) -> int:
        m, cs = self.m, self.cs
        p = m.phase
        if call in ("setDebugLogging", "getFMUstate", "freeFMUstate", "serializeRoundTrip"):
            return OK
        if call == "reset":
            self.reset()
            return OK
        if call == "setupExperiment" or (call == "enterInitializationMode" and self.fmi == 3):
            if p != INST or not _experiment_valid(args):
                return ERROR
            m.time, self.stop = args["start"], args["stop"]
            if call == "enterInitializationMode":
                m.phase = INIT
            return OK
        if call == "enterInitializationMode":
            if p != INST:
                return ERROR
            m.phase = INIT
            return OK
        if call == "exitInitializationMode":
            if p != INIT:
                return ERROR
            if not self.params_valid():
                m.phase = ERR
                return ERROR
            m.phase = STEP if cs else EVENT
            return OK
        if call == "terminate":
            if p in ({STEP} if cs else {EVENT, CONT}):
                m.phase = TERM
                return OK
            return ERROR
        if call == "getReal":
            if p not in GETTABLE:
                return ERROR
            groups = [self.group(vr) for vr in args["vr"]]
            if any(g == "undeclared" for g in groups):
                return ERROR
            if any(g in ("output", "calculated", "local") for g in groups) and not self.params_valid():
                return ERROR  # the build of the model refuses the parameters
            return OK
        if call == "setReal":
            if p not in SETTABLE:
                return ERROR
            for vr, value in zip(args["vr"], args["values"]):
                g = self.group(vr)
                if g == "input" and math.isfinite(value) and abs(value) <= INPUT_LIMIT_V:
                    continue  # beyond the declared +-1e6 V: refused where it is set
                if g == "param" and p in (INST, INIT) and math.isfinite(value):
                    continue  # a value outside the declared range is taken; the build refuses it
                return ERROR
            for vr, value in zip(args["vr"], args["values"]):
                if vr in m.params:
                    m.params[vr] = value
            return OK
        if call in ("getNoVariables", "setNoVariables"):
            allowed = GETTABLE if call == "getNoVariables" else SETTABLE
            return OK if p in allowed and args["n"] == 0 else ERROR
        if call == "doStep":
            t, h = args["t"], args["h"]
            if not cs or p != STEP:
                return ERROR
            if not (math.isfinite(t) and math.isfinite(h) and h > 0):
                return ERROR
            if abs(t - m.time) > TIME_TOLERANCE * max(1.0, abs(m.time)) or self.past_stop(t + h):
                return ERROR
            if self.sample_s is not None and h / self.sample_s > MAX_SAMPLES_PER_CALL + 1:
                return ERROR  # an invalid argument, refused before any work: the instance stays as it was
            m.time = t + h
            return OK
        if call in ("getRealStatus", "getBooleanStatus"):
            return OK if cs and self.fmi == 2 and p in (STEP, TERM) and args["known"] else ERROR
        if call == "getDirectionalDerivative" and self.fmi == 2 and not cs:
            # model exchange declares providesDirectionalDerivative (of outputs and derivatives with respect
            # to inputs and states): allowed where the FMI 2.0.x state table allows it, if the model builds
            return OK if p in (INIT, EVENT, CONT, TERM, ERR) and self.params_valid() else ERROR
        if call in ("getStatus", "getIntegerStatus", "getStringStatus", "cancelStep", "getDirectionalDerivative",
                    "enterEventMode3", "updateDiscreteStates3", "enterConfigurationMode3"):
            return ERROR
        if call == "setRealInputDerivatives":
            return OK if cs and self.fmi == 2 and p in (INST, INIT, STEP) and args["n"] == 0 else ERROR
        if call == "getOutputDerivatives":
            return OK if cs and p in (STEP, TERM, ERR) and args["n"] == 0 else ERROR
        # FMI 2 model exchange
        me = not cs
        if call == "enterEventMode":
            if me and p in (EVENT, CONT):
                m.phase = EVENT
                return OK
            return ERROR
        if call == "newDiscreteStates":
            return OK if me and p == EVENT else ERROR
        if call == "enterContinuousTimeMode":
            if me and p == EVENT:
                m.phase = CONT
                return OK
            return ERROR
        if call == "completedIntegratorStep":
            return OK if me and p == CONT else ERROR
        if call == "setTime":
            if me and p in (EVENT, CONT) and math.isfinite(args["t"]):  # integrators evaluate past the stop time
                m.time = args["t"]
                return OK
            return ERROR
        right_size = args.get("n") == self.v.n_states
        if call == "setContinuousStates":
            return OK if me and p == CONT and right_size and args["finite"] else ERROR
        if call == "getContinuousStates":
            return OK if me and p in (INIT, EVENT, CONT, TERM, ERR) and right_size else ERROR
        if call == "getDerivatives":
            return OK if me and p in (EVENT, CONT, TERM, ERR) and right_size and self.params_valid() else ERROR
        if call == "getNominals":
            return OK if me and p in (INST, EVENT, CONT, TERM, ERR) and right_size else ERROR
        if call == "getEventIndicators":
            return OK if me and p in (INIT, EVENT, CONT, TERM, ERR) and args["n"] == 0 else ERROR
        if call == "setFMUstate":
            if args["kind"] != "own":
                return ERROR
            self.m = args["model"].copy()
            return OK
        if call == "deserialize":
            return OK if args["kind"] == "own" else ERROR
        raise ValueError(call)


def _experiment_valid(a: dict) -> bool:
    if not math.isfinite(a["start"]):
        return False
    if a["stop"] is not None and not (math.isfinite(a["stop"]) and a["stop"] >= a["start"]):
        return False
    if a["tol"] is not None and not (math.isfinite(a["tol"]) and a["tol"] > 0):
        return False
    return True


def _doubles(values):
    return (ctypes.c_double * max(1, len(values)))(*values)


def _vrs(values):
    return (ctypes.c_uint32 * max(1, len(values)))(*values)


class Driver:
    """One instance of one interface, its fmpy wrappers and the reference; runs random calls."""

    def __init__(self, interface: str, folders: dict[str, str], variables: Variables, rng: random.Random,
                 foreign: bytes, peer_state=None, sample_s: float | None = None):
        self.interface, self.rng, self.v = interface, rng, variables
        self.ref = Reference(interface, variables, sample_s)
        folder = folders["fmi3" if interface == "cs3" else "fmi2"]
        md = fmpy.read_model_description(folder)
        self.errors_logged = 0

        def logged(*args):
            self.errors_logged += 1

        if interface == "cs3":
            self.fmu = FMU3Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                                 instanceName="fuzz")
            self.fmu.instantiate(logMessage=lambda env, status, category, message: logged())
            self.other = None
        else:
            cls, other = (FMU2Slave, FMU2Model) if interface == "cs2" else (FMU2Model, FMU2Slave)
            self.fmu = cls(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                           instanceName="fuzz")
            self.fmu.instantiate(callbacks=_quiet_callbacks(logged))
            # the other interface's wrappers on the same binary: its calls on this instance
            self.other = other(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                               instanceName="wrappers")
        self.c = self.fmu.component
        self.states: list[tuple[ctypes.c_void_p, Model]] = []
        self.foreign, self.peer_state = foreign, peer_state
        self.calls = 0
        self.phases: dict[str, int] = {}  # calls made in each state of the reference

    # ---- calling -------------------------------------------------------------------------------

    def status(self, name: str, *args) -> int:
        wrapper = getattr(self.fmu, name, None) or getattr(self.other, name)
        try:
            wrapper(self.c, *args)
        except FMICallException as e:
            return int(e.status)
        return OK

    def free(self) -> None:
        for state, _ in self.states:
            self.status(self.p + "FreeFMUstate" if self.interface != "cs3" else "fmi3FreeFMUState", ctypes.byref(state))
        self.fmu.freeInstance()

    @property
    def p(self) -> str:
        return "fmi3" if self.interface == "cs3" else "fmi2"

    # ---- one random call -------------------------------------------------------------------------

    def random_value(self, vr: int) -> float:
        r = self.rng.random()
        if vr in self.v.params:
            start, lo, hi = self.v.params[vr]
            if r < 0.8:
                return start
            if r < 0.9 and hi is not None:
                return hi * 2 + 1
            return math.nan
        if r < 0.85:
            return self.rng.uniform(-1, 1)
        if r < 0.9:  # finite, beyond the declared range (1e308 made model exchange's derivatives NaN with OK)
            return self.rng.choice([1e308, -1e308, 2e6])
        return self.rng.choice([math.nan, math.inf, -math.inf])

    def random_vrs(self, settable: bool) -> list[int]:
        v, r = self.v, self.rng.random()
        pool = v.inputs + list(v.params) if settable else v.inputs + v.outputs + list(v.params) + v.calculated
        vrs = self.rng.sample(pool, self.rng.randint(1, min(6, len(pool))))
        if r < 0.1:
            vrs.append(self.rng.choice(v.undeclared))
        elif r < 0.2:
            vrs.append(self.rng.choice(v.outputs + v.locals_ + ([v.time] if v.time is not None else [])))
        return vrs

    def step_args(self) -> dict:
        t, r = self.ref.m.time, self.rng.random()
        h = self.rng.choice([1e-3, 2e-3, 1e-2]) if r < 0.5 else 10 ** self.rng.uniform(-6, -1)
        r2 = self.rng.random()
        if r2 < 0.06:
            h = self.rng.choice([0.0, -1e-3, math.nan, math.inf])
        elif r2 < 0.07:  # finite and huge: a controller's sample count overflowed (1e20) or ran 250 s (1e6)
            h = self.rng.choice([1e20, 1e6, 2.5e3])
        elif r2 < 0.09:
            t = t - 1e-3  # backwards
        elif r2 < 0.12:
            t = t + 1e-4 * max(1.0, abs(t))  # a gap
        elif r2 < 0.2:
            t = t * (1 + 1e-13) if t else 1e-13  # rounding: within the tolerance
        return {"t": t, "h": h}

    def experiment_args(self) -> dict:
        r = self.rng.random()
        a = {"start": self.rng.choice([0.0, 0.0, 1.5, -2.0]), "stop": None, "tol": None}
        if self.rng.random() < 0.4:
            a["stop"] = a["start"] + self.rng.choice([0.01, 10.0, 100.0])  # 0.01: a few steps reach it
        if self.rng.random() < 0.3:
            a["tol"] = 1e-6
        if r < 0.08:
            a["start"] = self.rng.choice([math.nan, math.inf])
        elif r < 0.14:
            a["stop"] = self.rng.choice([math.nan, a["start"] - 1.0])
        elif r < 0.2:
            a["tol"] = self.rng.choice([math.nan, -1e-6])
        return a

    def one(self) -> tuple[str, dict, int, int]:
        """(call, arguments, expected, got) of one random call."""
        rng, p, v = self.rng, self.p, self.v
        fmi3 = self.interface == "cs3"
        lifecycle = ["enterInitializationMode", "exitInitializationMode", "doStep", "doStep", "doStep", "getReal",
                     "getReal", "setReal", "setReal", "terminate", "getFMUstate", "setFMUstate"]
        if not fmi3:
            lifecycle += ["setupExperiment"]
        if self.interface == "me2":
            lifecycle += ["newDiscreteStates", "enterContinuousTimeMode", "enterEventMode", "setTime",
                          "setContinuousStates", "getDerivatives", "completedIntegratorStep"]
        others = ["reset", "getNoVariables", "setNoVariables", "getOutputDerivatives", "getStatus", "cancelStep",
                  "getDirectionalDerivative", "serializeRoundTrip", "deserialize", "setDebugLogging",
                  "getContinuousStates", "getNominals", "getEventIndicators", "setContinuousStates", "setTime",
                  "enterEventMode", "newDiscreteStates", "enterContinuousTimeMode", "completedIntegratorStep",
                  "getDerivatives", "getRealStatus", "getBooleanStatus", "getIntegerStatus", "getStringStatus",
                  "setRealInputDerivatives", "freeFMUstate"]
        if fmi3:
            others = ["reset", "getNoVariables", "setNoVariables", "getOutputDerivatives", "getDirectionalDerivative",
                      "serializeRoundTrip", "deserialize", "setDebugLogging", "enterEventMode3",
                      "updateDiscreteStates3", "enterConfigurationMode3", "freeFMUstate"]
        r = rng.random()
        if r < 0.35:  # the call that takes the state machine on, so that every state is reached often
            phase = self.ref.m.phase
            advance = {INST: ["enterInitializationMode"] + ([] if fmi3 else ["setupExperiment"]),
                       INIT: ["exitInitializationMode", "setReal", "getReal"],
                       STEP: ["doStep", "doStep", "setReal", "getReal", "getFMUstate", "setFMUstate"],
                       EVENT: ["newDiscreteStates", "enterContinuousTimeMode", "setReal", "getReal"],
                       CONT: ["setTime", "setContinuousStates", "getDerivatives", "completedIntegratorStep",
                              "enterEventMode", "getReal", "setFMUstate"],
                       TERM: ["reset", "getReal", "setFMUstate"], ERR: ["reset", "getReal", "setFMUstate"]}[phase]
            call = rng.choice(advance)
        else:
            call = rng.choice(lifecycle if r < 0.75 else others)
        self.phases[self.ref.m.phase] = self.phases.get(self.ref.m.phase, 0) + 1
        args: dict = {}
        n = v.n_states
        got: int
        if call == "setupExperiment":
            args = self.experiment_args()
            expected = self.ref.expect(call, args)
            got = self.status("fmi2SetupExperiment", int(args["tol"] is not None), args["tol"] or 0.0, args["start"],
                              int(args["stop"] is not None), args["stop"] or 0.0)
            return call, args, expected, got
        if call == "enterInitializationMode":
            if fmi3:
                args = self.experiment_args()
                expected = self.ref.expect(call, args)
                got = self.status("fmi3EnterInitializationMode", int(args["tol"] is not None), args["tol"] or 0.0,
                                  args["start"], int(args["stop"] is not None), args["stop"] or 0.0)
                return call, args, expected, got
            return call, args, self.ref.expect(call, args), self.status("fmi2EnterInitializationMode")
        if call in ("exitInitializationMode", "terminate", "reset", "newDiscreteStates", "enterContinuousTimeMode",
                    "enterEventMode", "cancelStep"):
            expected = self.ref.expect(call, args)
            if call == "newDiscreteStates":
                from fmpy.fmi2 import fmi2EventInfo
                info = fmi2EventInfo()
                return call, args, expected, self.status("fmi2NewDiscreteStates", ctypes.byref(info))
            return call, args, expected, self.status(p + call[0].upper() + call[1:])
        if call == "completedIntegratorStep":
            a, b = ctypes.c_int(), ctypes.c_int()
            return call, args, self.ref.expect(call, args), self.status(
                "fmi2CompletedIntegratorStep", 1, ctypes.byref(a), ctypes.byref(b))
        if call == "doStep":
            args = self.step_args()
            expected = self.ref.expect(call, args)
            if fmi3:
                flags = [ctypes.c_bool() for _ in range(3)]
                last = ctypes.c_double()
                got = self.status("fmi3DoStep", args["t"], args["h"], True, *(ctypes.byref(f) for f in flags),
                                  ctypes.byref(last))
            else:
                got = self.status("fmi2DoStep", args["t"], args["h"], 1)
            return call, args, expected, got
        if call == "getReal":
            args = {"vr": self.random_vrs(False)}
            if rng.random() < 0.3 and v.time is not None:
                args["vr"].append(v.time)
            expected = self.ref.expect(call, args)
            out = (ctypes.c_double * len(args["vr"]))()
            got = self.status(p + ("GetFloat64" if fmi3 else "GetReal"), _vrs(args["vr"]), len(args["vr"]), out,
                              *([len(args["vr"])] if fmi3 else []))
            if got == OK:
                values = list(out)
                if not all(math.isfinite(x) for x in values):
                    return call, args, expected, -1  # a non-finite value gotten: a failure of its own
                if v.time in args["vr"]:
                    t = values[args["vr"].index(v.time)]
                    if abs(t - self.ref.m.time) > 1e-12 * max(1.0, abs(t)):
                        return call, args, expected, -2
            return call, args, expected, got
        if call == "setReal":
            vrs = self.random_vrs(True)
            args = {"vr": vrs, "values": [self.random_value(vr) for vr in vrs]}
            expected = self.ref.expect(call, args)
            got = self.status(p + ("SetFloat64" if fmi3 else "SetReal"), _vrs(vrs), len(vrs), _doubles(args["values"]),
                              *([len(vrs)] if fmi3 else []))
            return call, args, expected, got
        if call in ("getNoVariables", "setNoVariables"):
            args = {"n": rng.choice([0, 0, 1])}
            expected = self.ref.expect(call, args)
            if fmi3:
                prefix = "fmi3Get" if call == "getNoVariables" else "fmi3Set"
                name = prefix + rng.choice(["Int32", "Boolean", "UInt8"])
                ctype = {"Int32": ctypes.c_int32, "Boolean": ctypes.c_bool, "UInt8": ctypes.c_uint8}[name[7:]]
                got = self.status(name, _vrs([0]), args["n"], (ctype * 1)(), 1)
            else:
                name = ("fmi2Get" if call == "getNoVariables" else "fmi2Set") + rng.choice(["Integer", "Boolean"])
                got = self.status(name, _vrs([0]), args["n"], (ctypes.c_int * 1)())
            return call, args, expected, got
        if call == "getOutputDerivatives":
            args = {"n": rng.choice([0, 0, 1])}
            expected = self.ref.expect(call, args)
            if fmi3:
                got = self.status("fmi3GetOutputDerivatives", _vrs(v.outputs[:1]), args["n"], (ctypes.c_int32 * 1)(1),
                                  _doubles([0.0]), args["n"])
            else:
                got = self.status("fmi2GetRealOutputDerivatives", _vrs(v.outputs[:1]), args["n"],
                                  (ctypes.c_int * 1)(1), _doubles([0.0]))
            return call, args, expected, got
        if call == "setRealInputDerivatives":
            args = {"n": rng.choice([0, 0, 1])}
            return call, args, self.ref.expect(call, args), self.status(
                "fmi2SetRealInputDerivatives", _vrs(v.inputs[:1]), args["n"], (ctypes.c_int * 1)(1), _doubles([0.0]))
        if call in ("getStatus", "getIntegerStatus", "getStringStatus"):
            holder = {"getStatus": ctypes.c_int, "getIntegerStatus": ctypes.c_int, "getStringStatus": ctypes.c_char_p}
            value = holder[call]()
            return call, args, self.ref.expect(call, args), self.status(
                "fmi2" + call[0].upper() + call[1:], rng.choice([0, 1, 2, 3]), ctypes.byref(value))
        if call in ("getRealStatus", "getBooleanStatus"):
            kind = rng.choice([2, 2, 2, 0]) if call == "getRealStatus" else rng.choice([3, 3, 3, 0])
            args = {"known": kind != 0}
            expected = self.ref.expect(call, args)
            value = ctypes.c_double() if call == "getRealStatus" else ctypes.c_int()
            got = self.status("fmi2" + call[0].upper() + call[1:], kind, ctypes.byref(value))
            if got == OK and call == "getRealStatus" and abs(value.value - self.ref.m.time) > 1e-12 * max(
                    1.0, abs(value.value)):
                got = -2
            return call, args, expected, got
        if call == "getDirectionalDerivative":
            expected = self.ref.expect(call, args)
            if fmi3:
                got = self.status("fmi3GetDirectionalDerivative", _vrs(v.outputs[:1]), 1, _vrs(v.inputs[:1]), 1,
                                  _doubles([1.0]), 1, _doubles([0.0]), 1)
            else:
                got = self.status("fmi2GetDirectionalDerivative", _vrs(v.outputs[:1]), 1, _vrs(v.inputs[:1]), 1,
                                  _doubles([1.0]), _doubles([0.0]))
            return call, args, expected, got
        if call in ("enterEventMode3", "enterConfigurationMode3"):
            return call, args, self.ref.expect(call, args), self.status(
                "fmi3EnterEventMode" if call == "enterEventMode3" else "fmi3EnterConfigurationMode")
        if call == "updateDiscreteStates3":
            flags = [ctypes.c_bool() for _ in range(5)]
            t = ctypes.c_double()
            return call, args, self.ref.expect(call, args), self.status(
                "fmi3UpdateDiscreteStates", *(ctypes.byref(f) for f in flags), ctypes.byref(t))
        if call == "setDebugLogging":
            return call, args, self.ref.expect(call, args), self.status(
                p + "SetDebugLogging", rng.choice([0, 1]), 0, None)
        if call == "setTime":
            args = {"t": rng.choice([self.ref.m.time + 1e-3, self.ref.m.time, math.nan])}
            return call, args, self.ref.expect(call, args), self.status("fmi2SetTime", args["t"])
        if call in ("setContinuousStates", "getContinuousStates", "getDerivatives", "getNominals"):
            size = rng.choice([n, n, n, n - 1, n + 1])
            finite = rng.random() < 0.9
            args = {"n": size, "finite": finite}
            expected = self.ref.expect(call, args)
            buffer = (ctypes.c_double * (max(n, size) + 1))()
            if call == "setContinuousStates":
                for k in range(size):
                    buffer[k] = rng.uniform(-1e-6, 1e-6)
                if not finite and size > 0:
                    buffer[rng.randrange(size)] = math.nan
            name = {"setContinuousStates": "fmi2SetContinuousStates", "getContinuousStates": "fmi2GetContinuousStates",
                    "getDerivatives": "fmi2GetDerivatives", "getNominals": "fmi2GetNominalsOfContinuousStates"}[call]
            got = self.status(name, buffer, size)
            if got == OK and call != "setContinuousStates" and not all(math.isfinite(buffer[k]) for k in range(size)):
                got = -1
            return call, args, expected, got
        if call == "getEventIndicators":
            args = {"n": rng.choice([0, 0, 1])}
            return call, args, self.ref.expect(call, args), self.status("fmi2GetEventIndicators", _doubles([0.0]),
                                                                        args["n"])
        if call == "getFMUstate":
            state = ctypes.c_void_p()
            expected = self.ref.expect(call, args)
            got = self.status(p + ("GetFMUState" if fmi3 else "GetFMUstate"), ctypes.byref(state))
            if got == OK:
                self.states.append((state, self.ref.m.copy()))
            return call, args, expected, got
        if call == "freeFMUstate":
            expected = self.ref.expect(call, args)
            if not self.states:
                return call, args, expected, OK
            state, _ = self.states.pop(rng.randrange(len(self.states)))
            return call, args, expected, self.status(p + ("FreeFMUState" if fmi3 else "FreeFMUstate"),
                                                     ctypes.byref(state))
        if call == "setFMUstate":
            if self.peer_state is not None and rng.random() < 0.2:
                args = {"kind": "other interface"}
                return call, args, self.ref.expect(call, args), self.status(p + "SetFMUstate", self.peer_state)
            if not self.states:
                state = ctypes.c_void_p()
                self.status(p + ("GetFMUState" if fmi3 else "GetFMUstate"), ctypes.byref(state))
                self.states.append((state, self.ref.m.copy()))
            state, model = rng.choice(self.states)
            args = {"kind": "own", "model": model}
            expected = self.ref.expect(call, args)
            got = self.status(p + ("SetFMUState" if fmi3 else "SetFMUstate"), state)
            return call, {"kind": "own", "phase": model.phase}, expected, got
        if call in ("serializeRoundTrip", "deserialize"):
            if not self.states:
                state = ctypes.c_void_p()
                self.status(p + ("GetFMUState" if fmi3 else "GetFMUstate"), ctypes.byref(state))
                self.states.append((state, self.ref.m.copy()))
            state, model = rng.choice(self.states)
            size = ctypes.c_size_t()
            names = (("fmi3SerializedFMUStateSize", "fmi3SerializeFMUState", "fmi3DeserializeFMUState") if fmi3 else
                     ("fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate"))
            if self.status(names[0], state, ctypes.byref(size)) != OK:
                return call, args, OK, -3
            byte = ctypes.c_ubyte if fmi3 else ctypes.c_char  # fmi3Byte, fmi2Byte
            blob = (byte * size.value)()
            if self.status(names[1], state, blob, size.value) != OK:
                return call, args, OK, -3
            data = bytearray(bytes(blob))
            kind = "own"
            if call == "deserialize":
                r = rng.random()
                if r < 0.4:
                    position = rng.randrange(len(data) * 8)
                    data[position // 8] ^= 1 << (position % 8)
                    kind = "flipped bit"
                elif r < 0.6:
                    data = bytearray(rng.randbytes(len(data)))
                    kind = "garbage"
                elif r < 0.75:
                    data = data[:rng.randrange(len(data))]
                    kind = "truncated"
                elif r < 0.9:
                    data = bytearray(self.foreign)
                    kind = "foreign"
            args = {"kind": kind}
            expected = self.ref.expect("deserialize", args)
            new = ctypes.c_void_p()
            buffer = (byte * max(1, len(data))).from_buffer_copy(bytes(data).ljust(1, b"\0"))
            got = self.status(names[2], buffer, len(data), ctypes.byref(new))
            if got == OK:
                self.states.append((new, model.copy()))
            return call, args, expected, got
        raise ValueError(call)


def _quiet_callbacks(on_message):
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda *args: on_message())
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return callbacks


def _foreign_blob(interface: str, folders: dict[str, str], peer: str | None = None) -> tuple[bytes, object, object]:
    """A serialised state of another interface (FMI 2 CS for ME and FMI 3, FMI 2 ME for CS), and for
    FMI 2 an FMU state pointer of the other interface (the same binary) with its instance; with ``peer`` (an
    extracted FMI 2 FMU: for a controller FMU, which has no model exchange) that FMU's co-simulation state."""
    folder = peer or folders["fmi2"]
    md = fmpy.read_model_description(folder)
    cls = FMU2Model if interface == "cs2" and peer is None else FMU2Slave
    peer = cls(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
               instanceName="peer")
    peer.instantiate(callbacks=_quiet_callbacks(lambda: None))
    peer.setupExperiment(startTime=0.0)
    peer.enterInitializationMode()
    peer.exitInitializationMode()
    state = peer.getFMUstate()
    return bytes(peer.serializeFMUstate(state)), state, peer


def run(folders: dict[str, str], first_seed: int, n_seeds: int, length: int, interfaces: list[str], *,
        peer: str | None = None, sample_s: float | None = None) -> dict:
    """Random sequences on the FMUs in ``folders`` ("fmi2", "fmi3"): the plant's, or a controller's with its
    ``sample_s`` and a ``peer`` FMU for foreign states."""
    variables = {"cs2": Variables.read(folders["fmi2"], folders["fmi3"]),
                 "me2": Variables.read(folders["fmi2"], folders["fmi3"]),
                 "cs3": Variables.read(folders["fmi3"], folders["fmi2"])}
    peers = {i: _foreign_blob(i, folders, peer) for i in interfaces}
    summary = {"sequences": 0, "calls": 0, "ok": 0, "error": 0, "mismatches": [],
               "seeds": [first_seed, first_seed + n_seeds - 1], "interfaces": interfaces, "length": length,
               "by_interface": {}, "by_state": {}}
    start = clock.perf_counter()
    for seed in range(first_seed, first_seed + n_seeds):
        print(f"seed {seed}", file=sys.stderr, flush=True)
        for interface in interfaces:
            rng = random.Random(f"{seed}-{interface}")
            blob, peer_state, _ = peers[interface]
            driver = Driver(interface, folders, variables[interface], rng, blob,
                            peer_state if interface != "cs3" else None, sample_s)
            history = []
            for k in range(length):
                call, args, expected, got = driver.one()
                history.append(f"{call}{_short(args)} -> {got}")
                summary["calls"] += 1
                summary["ok" if got == OK else "error"] += 1
                if got != expected:
                    summary["mismatches"].append({"seed": seed, "interface": interface, "call": k, "name": call,
                                                  "args": _short(args), "expected": expected, "got": got,
                                                  "phase": driver.ref.m.phase, "history": history[-8:]})
                    break  # the reference no longer knows the instance's state
            driver.free()
            for phase, count in driver.phases.items():
                summary["by_state"][f"{interface} {phase}"] = summary["by_state"].get(f"{interface} {phase}", 0) + count
            summary["sequences"] += 1
            counts = summary["by_interface"].setdefault(interface, {"sequences": 0, "calls": 0})
            counts["sequences"] += 1
            counts["calls"] += len(history)
    summary["seconds"] = round(clock.perf_counter() - start, 2)
    for _, state, peer in peers.values():
        peer.freeFMUstate(state)
        peer.freeInstance()
    return summary


def _short(args: dict) -> str:
    return "(" + ", ".join(f"{k}={v!r}" for k, v in args.items() if k != "model") + ")"


def main(argv: list[str]) -> int:
    import argparse
    parser = argparse.ArgumentParser()
    parser.add_argument("fmi2")
    parser.add_argument("fmi3")
    parser.add_argument("first_seed", type=int)
    parser.add_argument("n_seeds", type=int)
    parser.add_argument("--length", type=int, default=40)
    parser.add_argument("--interfaces", default="cs2,me2,cs3")
    parser.add_argument("--peer", help="an extracted FMI 2 FMU whose states are the foreign ones (a controller's)")
    parser.add_argument("--sample-s", type=float, help="a controller FMU's sample time [s]")
    a = parser.parse_args(argv)
    summary = run({"fmi2": a.fmi2, "fmi3": a.fmi3}, a.first_seed, a.n_seeds, a.length, a.interfaces.split(","),
                  peer=a.peer, sample_s=a.sample_s)
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
