"""Native FMUs against the FMI 2.0.x / 3.0 state machines (their state tables: which call in which state).

Each finding of the stress check as a short call sequence: FMU states checked against the instance
before anything is applied (interface, FMI version, GUID, checksum, state-machine value), including
deserialisation of garbage and of flipped bits; calls outside their states and value references the
FMU's own model description does not declare are errors; a step starts at the FMU's time and is > 0;
non-finite values are refused where they are set; variable communication steps are the exact
zero-order hold. The random call sequences are in test_fmi_fuzz.py.
"""

from __future__ import annotations

import ctypes
import struct

import fmpy
import numpy as np
import pytest
import scipy.linalg
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Slave
from test_native_fmu import Messages, _slave, _vr

from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.volts import volts_model

pytestmark = pytest.mark.slow  # the module builds native FMUs of both models first

ERROR = 3
HDR = 40  # the instance's header of an FMU state (mace_instance.c): tag, FMI version, kind, GUID print, checksum
PHASE_OFFSET = HDR + 8  # the model's phase field, after its magic (mace_model.c)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    model = volts_model(compute_modes(configuration="0g"))
    out = tmp_path_factory.mktemp("conform")
    fmi2 = export_fmu(model, out_dir=out, name="MACE_0g_conform")
    fmi3 = export_fmu(model, out_dir=out, name="MACE_0g_conform3", fmi_version=3)
    extract = lambda f: fmpy.extract(str(f), unzipdir=str(tmp_path_factory.mktemp(f.stem)))  # noqa: E731
    return type("F", (), {"model": model, "dir2": extract(fmi2), "dir3": extract(fmi3)})


def _status(call, *args, **kwargs) -> int:
    try:
        call(*args, **kwargs)
    except FMICallException as e:
        return int(e.status)
    return 0


def _raw(fmu, name: str, *args) -> int:
    """Status of an FMI function called straight through the binary (also one fmpy's class for this
    interface does not offer); floats are passed as doubles."""
    function = getattr(fmu.dll, name)
    function.restype = ctypes.c_int
    component = ctypes.c_void_p(fmu.component) if isinstance(fmu.component, int) else fmu.component
    return function(component, *(ctypes.c_double(a) if isinstance(a, float) else a for a in args))


def _ready(fmus, messages=None) -> FMU2Slave:
    fmu = _slave(fmus.dir2, messages=messages)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu


def _model(fmus, messages=None) -> FMU2Model:
    md = fmpy.read_model_description(fmus.dir2)
    fmu = FMU2Model(guid=md.guid, unzipDirectory=fmus.dir2, modelIdentifier=md.modelExchange.modelIdentifier,
                    instanceName="me")
    fmu.instantiate(callbacks=messages.callbacks if messages else None)
    return fmu


def _slave3(fmus, log=None) -> FMU3Slave:
    md = fmpy.read_model_description(fmus.dir3)
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=fmus.dir3, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="fmi3")
    fmu.instantiate(logMessage=log)
    return fmu


def _io(fmus, folder):
    vr = _vr(folder)
    return [vr[n] for n in fmus.model.system.input_labels], [vr[n] for n in fmus.model.system.output_labels]


def _fnv(data: bytes, h: int = 14695981039346656037) -> int:
    for b in data:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def _resum(blob: bytearray) -> None:
    """Recompute an edited state's checksum (the forger's best effort)."""
    blob[32:40] = b"\0" * 8
    blob[32:40] = struct.pack("<Q", _fnv(bytes(blob)))


# ---- 1. FMU states are checked before anything is applied -------------------------------------------

def test_a_co_simulation_state_is_refused_by_a_model_exchange_instance(fmus):
    cs, messages = _ready(fmus), Messages()
    cs.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    state = cs.getFMUstate()
    me = _model(fmus, messages)
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    assert _status(me.setFMUstate, state) == ERROR
    assert "a co-simulation FMU state cannot be set into a model-exchange instance" in messages.errors()[-1]
    blob = cs.serializeFMUstate(state)
    assert _status(me.deSerializeFMUstate, blob) == ERROR
    # the instance is unchanged: still in event mode, where DoStep is no call of it
    me.newDiscreteStates()
    me.enterContinuousTimeMode()
    assert _raw(me, "fmi2DoStep", 0.0, 0.01, 1) == ERROR
    cs.freeFMUstate(state)
    for fmu in (cs, me):
        fmu.freeInstance()


def test_edited_damaged_or_foreign_states_are_refused_and_change_nothing(fmus):
    messages = Messages()
    fmu = _ready(fmus, messages)
    ins, outs = _io(fmus, fmus.dir2)
    fmu.setReal(ins, [0.1] * len(ins))
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    state = fmu.getFMUstate()
    blob = bytearray(fmu.serializeFMUstate(state))
    fmu.doStep(currentCommunicationPoint=0.01, communicationStepSize=0.01)
    before = fmu.getReal(outs)
    # the state-machine field set to continuous-time mode (4), checksum left: damaged
    edited = bytearray(blob)
    edited[PHASE_OFFSET] = 4
    assert _status(fmu.deSerializeFMUstate, bytes(edited)) == ERROR
    assert "checksum" in messages.errors()[-1]
    # ... and with the checksum recomputed: not a state of a co-simulation instance
    _resum(edited)
    assert _status(fmu.deSerializeFMUstate, bytes(edited)) == ERROR
    assert "state-machine value 4 is not a state of this instance" in messages.errors()[-1]
    # the same edit in memory, straight into SetFMUstate
    raw = ctypes.cast(state, ctypes.POINTER(ctypes.c_ubyte * (8 + len(blob)))).contents
    raw[8 + PHASE_OFFSET] = 4
    assert _status(fmu.setFMUstate, state) == ERROR
    raw[8 + PHASE_OFFSET] = blob[PHASE_OFFSET]
    # every single flipped bit, garbage of the right size, truncated and empty: refused
    rng = np.random.default_rng(5)
    for position in rng.choice(len(blob) * 8, size=200, replace=False):
        flipped = bytearray(blob)
        flipped[position // 8] ^= 1 << (position % 8)
        assert _status(fmu.deSerializeFMUstate, bytes(flipped)) == ERROR, position
    assert _status(fmu.deSerializeFMUstate, rng.integers(0, 256, len(blob), dtype=np.uint8).tobytes()) == ERROR
    assert _status(fmu.deSerializeFMUstate, bytes(blob[:-8])) == ERROR
    # a state of an FMI 3 instance of the same model
    fmu3 = _slave3(fmus)
    blob3 = fmu3.serializeFMUState(fmu3.getFMUState())
    assert _status(fmu.deSerializeFMUstate, blob3) == ERROR
    fmu3.freeInstance()
    assert fmu.getReal(outs) == before  # nothing of the refused states was applied
    fmu.doStep(currentCommunicationPoint=0.02, communicationStepSize=0.01)  # and the instance runs on
    # the untouched state still restores
    fmu.setFMUstate(state)
    fmu.doStep(currentCommunicationPoint=0.01, communicationStepSize=0.01)
    assert fmu.getReal(outs) == before
    fmu.freeFMUstate(state)
    fmu.freeInstance()


def test_fmi3_states_are_checked_too(fmus):
    records = []
    fmu = _slave3(fmus, log=lambda env, status, category, message: records.append((status, message.decode())))
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.01)
    state = fmu.getFMUState()
    blob = bytearray(fmu.serializeFMUState(state))
    edited = bytearray(blob)
    edited[PHASE_OFFSET] = 3  # event mode
    _resum(edited)
    assert _status(fmu.deserializeFMUState, bytes(edited)) == ERROR
    assert "state-machine value 3" in records[-1][1]
    flipped = bytearray(blob)
    flipped[HDR + 30] ^= 0x10
    assert _status(fmu.deserializeFMUState, bytes(flipped)) == ERROR
    restored = fmu.deserializeFMUState(bytes(blob))
    fmu.setFMUState(restored)
    fmu.doStep(0.01, 0.01)
    fmu.freeFMUState(state)
    fmu.freeFMUState(restored)
    fmu.freeInstance()


# ---- 2. calls outside their states, undeclared value references ---------------------------------

def test_status_functions_are_co_simulation_calls_of_the_step_states(fmus):
    messages = Messages()
    fmu = _slave(fmus.dir2, messages=messages)
    for call in (fmu.getRealStatus, fmu.getBooleanStatus):
        assert _status(call, 2 if call == fmu.getRealStatus else 3) == ERROR  # before initialisation
    assert "must not be called in instantiated" in messages.errors()[-1]
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    assert _status(fmu.getRealStatus, 2) == ERROR
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    assert fmu.getRealStatus(2) == pytest.approx(0.01)  # fmi2LastSuccessfulTime
    assert not fmu.getBooleanStatus(3)  # fmi2Terminated: false
    fmu.freeInstance()
    messages = Messages()
    me = _model(fmus, messages)
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    value = ctypes.c_double()
    assert _raw(me, "fmi2GetRealStatus", 2, ctypes.byref(value)) == ERROR
    assert "is a co-simulation function and this is a model-exchange instance" in messages.errors()[-1]
    me.freeInstance()


def test_continuous_states_are_set_in_continuous_time_mode_only(fmus):
    messages = Messages()
    me = _model(fmus, messages)
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    n = fmus.model.system.nstates
    x = (ctypes.c_double * n)(*([0.0] * n))
    assert _status(me.setContinuousStates, x, n) == ERROR  # event mode
    assert "fmi2SetContinuousStates must not be called in event mode" in messages.errors()[-1]
    me.newDiscreteStates()
    me.enterContinuousTimeMode()
    me.setContinuousStates(x, n)
    x[0] = float("nan")
    assert _status(me.setContinuousStates, x, n) == ERROR
    me.freeInstance()


@pytest.mark.parametrize("first", ["getReal", "getDerivatives"])
def test_states_beyond_what_the_outputs_hold_are_refused_by_get_real_as_by_get_derivatives(fmus, first):
    """Continuous states of 1e307 are finite and are set, and the outputs C x overflow: GetReal returned inf and
    NaN with fmi2OK where GetDerivatives refused the same state. Both refuse it now with the reason, whichever
    comes first, and leave the instance in its error state (the model cannot go on from it), where a reset
    makes it usable again."""
    messages = Messages()
    me = _model(fmus, messages)
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    me.newDiscreteStates()
    me.enterContinuousTimeMode()
    n = fmus.model.system.nstates
    me.setContinuousStates((ctypes.c_double * n)(*([1e307] * n)), n)
    _, outs = _io(fmus, fmus.dir2)
    dx = (ctypes.c_double * n)()
    calls = {"getReal": lambda: me.getReal(outs), "getDerivatives": lambda: me.getDerivatives(dx, n)}
    assert _status(calls[first]) == ERROR
    said = messages.errors()[-1]
    if first == "getReal":
        assert said.startswith("fmi2GetReal: output ") and "at t = 0 s: the inputs or states are beyond what the " \
                                                              "model can represent" in said, said
    else:
        assert "the inputs or states are beyond what the model can represent" in said, said
    assert _status(me.setContinuousStates, (ctypes.c_double * n)(*([0.0] * n)), n) == ERROR  # the error state
    assert "must not be called in error" in messages.errors()[-1], messages.errors()[-1]
    me.reset()
    me.setupExperiment(startTime=0.0)
    me.enterInitializationMode()
    me.exitInitializationMode()
    assert np.all(np.isfinite(me.getReal(outs)))
    me.freeInstance()


def test_only_declared_value_references_are_variables(fmus):
    messages = Messages()
    fmu = _ready(fmus, messages)
    declared2 = {v.valueReference for v in fmpy.read_model_description(fmus.dir2).modelVariables}
    time_vr = max(v.valueReference for v in fmpy.read_model_description(fmus.dir3).modelVariables)
    assert time_vr not in declared2  # FMI 2 has no time variable
    assert _status(fmu.getReal, [time_vr]) == ERROR
    assert f"value reference {time_vr} is not a variable" in messages.errors()[-1]
    fmu.getReal(sorted(declared2))  # every declared one is
    fmu.freeInstance()
    fmu3 = _slave3(fmus)
    fmu3.enterInitializationMode(startTime=0.0)
    fmu3.exitInitializationMode()
    declared3 = {v.valueReference for v in fmpy.read_model_description(fmus.dir3).modelVariables}
    assert fmu3.getFloat64([time_vr]) == [0.0]
    for vr in sorted(declared2 - declared3):  # FMI 3 declares no continuous states or derivatives
        assert _status(fmu3.getFloat64, [vr]) == ERROR, vr
    fmu3.freeInstance()


# ---- 3. the communication point and step -------------------------------------------------------------

@pytest.mark.parametrize("t, h, ok", [(0.01, 0.01, True), (0.01 * (1 + 5e-10), 0.01, True), (0.0, 0.01, False),
                                      (0.02, 0.01, False), (0.011, 0.01, False), (0.01, 0.0, False),
                                      (0.01, -0.01, False)])
def test_a_step_starts_at_the_fmus_time_and_is_positive(fmus, t, h, ok):
    messages = Messages()
    fmu = _ready(fmus, messages)
    _, outs = _io(fmus, fmus.dir2)
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    before = fmu.getReal(outs)
    status = _status(fmu.doStep, currentCommunicationPoint=t, communicationStepSize=h)
    assert status == (0 if ok else ERROR), messages.errors()
    if not ok:
        assert fmu.getRealStatus(2) == 0.01 and fmu.getReal(outs) == before  # refused: nothing moved
        fmu.doStep(currentCommunicationPoint=0.01, communicationStepSize=0.01)  # and it runs on
    fmu.freeInstance()
    fmu3 = _slave3(fmus)
    fmu3.enterInitializationMode(startTime=0.0)
    fmu3.exitInitializationMode()
    fmu3.doStep(0.0, 0.01)
    assert _status(fmu3.doStep, t, h) == (0 if ok else ERROR)
    fmu3.freeInstance()


def test_no_step_or_time_goes_past_a_defined_stop_time(fmus):
    """FMI 2.0.x 2.1.6 / FMI 3.0 2.3.2: with stopTimeDefined, computing past stopTime is fmiError. A
    co-simulation step that ends on the stop time up to round-off is allowed; the refused one moves nothing."""
    messages = Messages()
    fmu = _slave(fmus.dir2, messages=messages)
    fmu.setupExperiment(startTime=0.0, stopTime=0.03)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    _, outs = _io(fmus, fmus.dir2)
    t = 0.0
    for _ in range(3):  # 0.01 + 0.01 + 0.01 ends on 0.03 up to round-off
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=0.01)
        t += 0.01
    before = fmu.getReal(outs)
    assert _status(fmu.doStep, currentCommunicationPoint=t, communicationStepSize=1e-3) == ERROR
    assert "passes the stop time 0.029999999999999999 s" in messages.errors()[-1]
    assert fmu.getReal(outs) == before
    fmu.reset()  # forgets the stop time with the rest of the experiment
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.05)
    fmu.freeInstance()
    fmu3 = _slave3(fmus)
    fmu3.enterInitializationMode(startTime=0.0, stopTime=0.02)
    fmu3.exitInitializationMode()
    fmu3.doStep(0.0, 0.02)
    assert _status(fmu3.doStep, 0.02, 0.01) == ERROR
    fmu3.freeInstance()
    # model exchange: an integrator evaluates the derivatives past its output time (fmpy's CVode sets times
    # past stopTime on a run that ends at it, tests/fmu/test_native_fmu.py), so fmi2SetTime is not refused
    me = _model(fmus)
    me.setupExperiment(startTime=0.0, stopTime=0.05)
    me.enterInitializationMode()
    me.exitInitializationMode()
    me.setTime(0.06)
    me.freeInstance()


# ---- 4. non-finite values are refused where they are set ---------------------------------------------

def test_non_finite_inputs_are_refused_by_set_real_and_not_stored(fmus):
    messages = Messages()
    fmu = _ready(fmus, messages)
    ins, outs = _io(fmus, fmus.dir2)
    fmu.setReal(ins[:1], [0.5])
    for bad in (float("nan"), float("inf"), -float("inf")):
        assert _status(fmu.setReal, ins[:2], [0.25, bad]) == ERROR
        assert "non-finite value" in messages.errors()[-1] and fmus.model.system.input_labels[1] in \
            messages.errors()[-1]
        assert fmu.getReal(ins[:2]) == [0.5, 0.0]  # neither value of the refused call was stored
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    assert np.all(np.isfinite(fmu.getReal(outs)))
    fmu.freeInstance()
    fmu3 = _slave3(fmus)
    fmu3.enterInitializationMode(startTime=0.0)
    fmu3.exitInitializationMode()
    assert _status(fmu3.setFloat64, ins[:1], [float("nan")]) == ERROR
    fmu3.freeInstance()


@pytest.mark.parametrize("kwargs", [dict(startTime=float("nan")), dict(startTime=float("inf")),
                                    dict(startTime=0.0, stopTime=float("nan")), dict(startTime=1.0, stopTime=0.5),
                                    dict(startTime=0.0, tolerance=float("nan")), dict(startTime=0.0, tolerance=-1.0)])
def test_a_non_finite_or_inconsistent_experiment_is_refused(fmus, kwargs):
    messages = Messages()
    fmu = _slave(fmus.dir2, messages=messages)
    assert _status(fmu.setupExperiment, **kwargs) == ERROR
    assert messages.errors()[-1].startswith("fmi2SetupExperiment: ")
    fmu.setupExperiment(startTime=0.0)  # refused: still instantiated
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
    fmu.freeInstance()
    fmu3 = _slave3(fmus)
    assert _status(fmu3.enterInitializationMode, **kwargs) == ERROR
    fmu3.enterInitializationMode(startTime=0.0)
    fmu3.freeInstance()


# ---- 5. variable communication steps are the exact zero-order hold -----------------------------------

def test_random_variable_steps_equal_the_exact_zoh_to_1e_10(fmus):
    """canHandleVariableCommunicationStepSize: 120 random steps from 10 us to 20 ms, random held inputs,
    against the ZOH of (A, B, C, D) by scipy.linalg.expm of each step, to 1e-10 of each output's range."""
    sys_ = fmus.model.system
    rng = np.random.default_rng(23)
    steps = np.exp(rng.uniform(np.log(1e-5), np.log(2e-2), 120))
    u = rng.uniform(-1.0, 1.0, (sys_.ninputs, len(steps)))
    ins, outs = _io(fmus, fmus.dir2)
    fmu = _ready(fmus)
    n, m = sys_.A.shape[0], sys_.ninputs
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = sys_.A, sys_.B
    x, t, y, ref = np.zeros(n), 0.0, [], []
    for k, h in enumerate(steps):
        fmu.setReal(ins, list(u[:, k]))
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        e = scipy.linalg.expm(aug * h)
        x = e[:n, :n] @ x + e[:n, n:] @ u[:, k]
        y.append(fmu.getReal(outs))
        ref.append(sys_.C @ x + sys_.D @ u[:, k])
    fmu.freeInstance()
    y, ref = np.array(y).T, np.array(ref).T
    span = np.ptp(ref, axis=1)
    assert np.all(span > 0)
    error = np.max(np.abs(y - ref) / span[:, None])
    print(f"largest difference over 120 random steps: {error:.2e} of the output's range")
    assert error <= 1e-10
