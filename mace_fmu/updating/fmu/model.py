"""An FMI 2.0 co-simulation FMU as the model inside a cost: parameters set through FMI, responses simulated.

:class:`FmuModel` offers what the time-domain and frequency-response costs call of a model
(``time_response``), so the updating engine needs no FE code: a MACE FMU re-analyses its own
physical parameters at initialisation, any other FMU does whatever it does with its parameters.
:class:`FmuFamily` maps parameter values to such a model (the engine's ``ModelFamily``).

Each process loads (extracts and instantiates) an FMU once per thread and reuses the instance, resetting it
between runs (``fmi2Reset``): a Dask worker pays the load once however many runs it gets, and two tasks
at once in a worker of several threads never share an instance. A worker reads the FMU's bytes the
client sent it (:meth:`~mace_fmu.util.runner.DaskRunner.ship`, by :func:`ship_fmu`), not the client's
path, which names nothing on another machine or in another folder. After a
pythonfmu FMU's instantiation the process-wide state its binary would write into after freeing it at
exit is released (:func:`mace_fmu.fmu.host.release_pythonfmu_state`: the workers' "corrupted
double-linked list"). FMUs written by pythonfmu are still run only in worker processes: their wrapper
releases the slave's Python objects a second time after any Python exception in it
(``PySlaveInstance::handle_py_exception``, then ``fmi2Reset`` or the destructor), a risk kept out of
the caller's process; native FMUs run anywhere.
"""

from __future__ import annotations

import ctypes
import dataclasses
import difflib
import functools
import hashlib
import os
import shutil
import tempfile
import threading
import weakref
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fmu.archive import check_cosimulation_fmu
from mace_fmu.fmu.host import collecting_callbacks, release_pythonfmu_state, status_name
from mace_fmu.util.shipping import sha256_of, shipped_copy

#: an output's gain as an update parameter, "gain:strain_strut2_y": the data are gain x the FMU's output
GAIN_PREFIX = "gain:"


def gain_parameter(output: str) -> str:
    """The update parameter of ``output``'s sensor gain (measured = gain x simulated), e.g. "gain:gyro_bus_x"."""
    return GAIN_PREFIX + output


@dataclass(frozen=True)
class FmuInterface:
    """What a host needs to know of an FMU to drive it: signals, parameters and their start values."""

    path: str  #: the .fmu file
    guid: str
    model_identifier: str
    generation_tool: str
    inputs: tuple[str, ...]  #: Real inputs
    outputs: tuple[str, ...]  #: Real outputs
    parameters: Mapping[str, float]  #: Real parameters (fixed or tunable) and their start values
    references: Mapping[str, int]  #: value reference of every input, output and parameter
    units: Mapping[str, str]  #: unit of each of them ("" when the FMU declares none)
    description: str = ""  #: the model description's description attribute ("MACE 1g volts-volts model: ...")
    #: the declared [min, max] of each parameter (-inf, inf where the FMU declares none) [FMU units]
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    descriptions: Mapping[str, str] = field(default_factory=dict)  #: of each parameter, as the FMU gives them
    sha256: str = ""  #: of the file's bytes, by which a Dask worker finds the copy sent to it

    @property
    def configuration(self) -> str:
        """"1g" or "0g" for a MACE FMU (from its description), else ""."""
        words = self.description.split()
        return words[1] if len(words) > 1 and words[0] == "MACE" and words[1] in ("1g", "0g") else ""

    @property
    def written_by_pythonfmu(self) -> bool:
        return "pythonfmu" in self.generation_tool.lower()

    def check_parameters(self, names: Sequence[str]) -> None:
        """MaceError naming every ``names`` entry the FMU has no Real parameter of."""
        unknown = [n for n in names if n not in self.parameters]
        if unknown:
            import difflib

            close = sorted({c for n in unknown for c in difflib.get_close_matches(n, list(self.parameters), n=4)})
            hint = f"; closest: {', '.join(close)}" if close else ""
            raise MaceError(f"{self.path}: no parameter(s) {', '.join(unknown)}{hint} (all {len(self.parameters)} "
                            f"parameters: mace-fmu params list {self.path})")

    @property
    def mode_labels(self) -> tuple[str, ...]:
        """The label of each mode the FMU has per-mode parameters of (``damping_mode_<k>``), mode 1 first, read from
        the parameters' descriptions (a MACE FMU's say each mode's label; "" where they do not); empty for an FMU
        without such parameters."""
        from mace_fmu.parameters.kinds import DAMPING, FREQUENCY_SCALE, mode_reference

        labels: dict[int, str] = {}
        for name in self.parameters:
            ref, text = mode_reference(name), self.descriptions.get(name, "")
            if ref is None or ref.number is None:
                continue
            label = ""
            if ref.kind is DAMPING and ": " in text:  # "open-loop damping ratio of mode 14: 1st Z bending"
                label = text.split(": ", 1)[1].strip()
            elif ref.kind is FREQUENCY_SCALE and "(" in text:  # "... frequency of mode 14 (1st Z bending) relative ..."
                label = text.split("(", 1)[1].split(")", 1)[0].strip()
            labels[ref.number] = labels.get(ref.number) or label
        return tuple(labels.get(k, "") for k in range(1, max(labels, default=0) + 1))

    def values_by_fmu_name(self, values: Mapping[str, float], *, source: str) -> dict[str, float]:
        """``values`` by this FMU's names: a per-mode name by label (``damping:<label>``) becomes the FMU's
        parameter of every mode with that label, one by number (``damping_mode_<k>``) is checked against the
        FMU's modes (:func:`~mace_fmu.parameters.per_mode.resolve_mode_names`); other names are kept. A
        MaceError names ``source``, the parameter and what the FMU has."""
        from mace_fmu.parameters.per_mode import resolve_mode_names

        return resolve_mode_names(values, mode_labels=self.mode_labels, model=f"FMU {self.path}", source=source,
                                  available=set(self.parameters),
                                  hint=f" (its parameters: mace-fmu params list {self.path})")

    def check_signals(self, *, inputs: Sequence[str], outputs: Sequence[str], where: str,
                      units: Mapping[str, str] | None = None) -> None:
        """MaceError naming every input and output channel of ``where`` the FMU does not have and, with the
        data's ``units``, every one whose unit is not the one the FMU declares for it."""
        bad = [_unknown_signal("input", n, self.inputs) for n in inputs if n not in self.inputs] + \
            [_unknown_signal("output", n, self.outputs) for n in outputs if n not in self.outputs]
        if bad:
            raise MaceError(f"{where}: channel(s) {', '.join(bad)} not in {self.path} (inputs: "
                            f"{', '.join(self.inputs)}; outputs: {', '.join(self.outputs)})")
        for name in (*inputs, *outputs):
            given, declared = (units or {}).get(name), self.units.get(name, "")
            if given is not None and declared and given != declared:
                role = "input" if name in self.inputs else "output"
                raise MaceError(f"{where}: channel {name!r}: unit {given!r}, but the FMU's {role} {name} is in "
                                f"{declared!r}: the data must be in the FMU's units")


def _unknown_signal(role: str, name: str, known: Sequence[str]) -> str:
    """``output 'gyro_bus_xx' (did you mean 'gyro_bus_x'?)``: a misspelt channel is named with the FMU's closest
    signals first, ahead of the FMU's whole list (fifty names and more for MACE)."""
    close = difflib.get_close_matches(name, list(known), n=3)
    return f"{role} {name!r}" + (f" (did you mean {' or '.join(map(repr, close))}?)" if close else "")


def read_fmu_interface(path: str | os.PathLike) -> FmuInterface:
    """The interface of the FMI 2.0 co-simulation FMU at ``path`` (checked as an archive first)."""
    import fmpy

    path = check_cosimulation_fmu(path)
    md = fmpy.read_model_description(os.fspath(path))
    digest = sha256_of(path.read_bytes())
    real = [v for v in md.modelVariables if v.type == "Real"]
    parameters = {v.name: float(v.start) for v in real
                  if v.causality == "parameter" and v.variability in ("fixed", "tunable") and v.start is not None}
    used = [v for v in real if v.causality in ("input", "output") or v.name in parameters]
    return FmuInterface(path=os.fspath(path), guid=md.guid, model_identifier=md.coSimulation.modelIdentifier,
                        generation_tool=md.generationTool or "",
                        inputs=tuple(v.name for v in real if v.causality == "input"),
                        outputs=tuple(v.name for v in real if v.causality == "output"),
                        parameters=parameters, references={v.name: int(v.valueReference) for v in used},
                        units={v.name: v.unit or "" for v in used}, description=md.description or "",
                        ranges={v.name: (float(v.min) if v.min is not None else -np.inf,
                                         float(v.max) if v.max is not None else np.inf)
                                for v in real if v.name in parameters},
                        descriptions={v.name: v.description or "" for v in real if v.name in parameters},
                        sha256=digest)


def _in_worker_process() -> bool:
    try:
        from distributed import get_worker

        get_worker()
    except (ImportError, ValueError):
        return False
    return True


def _extraction_folder() -> str:
    """A fresh folder under <tmp>/mace_fmu_cost/ named by this process; folders of processes that are gone
    (a worker killed, a test run that skipped interpreter exit) are removed here, so none pile up."""
    parent = Path(tempfile.gettempdir()) / "mace_fmu_cost"
    parent.mkdir(exist_ok=True)
    for old in parent.glob("pid*-*"):
        pid = old.name[3:].split("-", 1)[0]
        if pid.isdigit() and not Path(f"/proc/{pid}").exists() and os.path.exists("/proc/self"):
            shutil.rmtree(old, ignore_errors=True)
    return tempfile.mkdtemp(prefix=f"pid{os.getpid()}-", dir=parent)


class _LoadedFmu:
    """One extracted and instantiated FMU of this process, run again and again with ``fmi2Reset`` between runs.

    A native FMU of this package runs a whole record in one call of its runtime (``maceRunRecord``: the same
    FMI calls in C, outputs equal to the last bit), unless ``whole_record`` is False; any other FMU runs
    through FMI call by call.
    """

    def __init__(self, interface: FmuInterface, *, whole_record: bool = True, file: str | None = None):
        from fmpy import extract
        from fmpy.fmi2 import FMU2Slave

        self.interface = interface
        self.messages: list[str] = []
        folder = _extraction_folder()
        weakref.finalize(self, shutil.rmtree, folder, True)
        extract(file or interface.path, unzipdir=folder)
        self.slave = FMU2Slave(guid=interface.guid, unzipDirectory=folder, modelIdentifier=interface.model_identifier,
                               instanceName="mace_fmu_cost")

        callbacks = collecting_callbacks(self.messages)  # errors reach this instance's messages, not stdout
        self._callbacks = callbacks  # kept alive as long as the instance
        try:
            self.slave.instantiate(callbacks=callbacks)
        finally:  # else the binary writes into a freed block at exit (a failed instantiation too)
            if interface.written_by_pythonfmu:
                release_pythonfmu_state(self.slave.dll)
        self._fresh = True
        self._record = self._whole_record_function() if whole_record else None

    def _whole_record_function(self):
        """The runtime's ``maceRunRecord`` when this is a native FMU of this package, else None (the FMI route)."""
        if not (self.interface.generation_tool.startswith("mace-fmu") and "native" in self.interface.generation_tool):
            return None
        try:
            function = self.slave.dll.maceRunRecord
        except AttributeError:  # written by an older mace-fmu
            return None
        double_p, vr_p = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_uint)
        function.argtypes = [ctypes.c_void_p, vr_p, ctypes.c_size_t, vr_p, ctypes.c_size_t, ctypes.c_size_t,
                             ctypes.c_double, ctypes.c_double, double_p, double_p, ctypes.POINTER(ctypes.c_size_t)]
        function.restype = ctypes.c_int
        return function

    def _check(self, status: int, call: str) -> None:
        if status > 1:
            text = " | ".join(self.messages[-5:])
            self.messages.clear()
            raise MaceError(f"{self.interface.path}: {call} returned {status_name(status)}"
                            + (f" (FMU log: {text})" if text else ""))

    def run(self, values: Mapping[str, float], times_s: np.ndarray, u: np.ndarray, inputs: Sequence[str],
            outputs: Sequence[str]) -> np.ndarray:
        """Outputs y[k, output] at ``times_s`` with inputs u[k, input] held from t_k to t_k+1 and the
        parameters ``values`` set before initialisation; a failing FMI call raises MaceError with the FMU's log."""
        from fmpy.fmi1 import FMICallException

        self._now = None  # the sample whose calls are being made, for the message of a failing one
        try:
            return self._run(values, times_s, u, inputs, outputs)
        except FMICallException as exc:  # fmpy checks every call's status itself
            raise self._failure(str(exc).rstrip("."), values) from None

    def _failure(self, what: str, values: Mapping[str, float]) -> MaceError:
        """The error of a failed run: the call, the sample's time, the parameter values and the FMU's log."""
        text = " | ".join(self.messages[-5:])
        self.messages.clear()
        values_text = ", ".join(f"{n} = {v:g}" for n, v in values.items())
        at = f" at t = {self._now:g} s" if self._now is not None else ""
        return MaceError(f"{self.interface.path}: {what}{at} with {values_text or 'its start values'}"
                         + (f" (FMU log: {text})" if text else ""))

    def _run(self, values, times_s, u, inputs, outputs) -> np.ndarray:
        from fmpy.fmi2 import fmi2Real, fmi2ValueReference

        s, ref = self.slave, self.interface.references
        if not self._fresh:
            self._check(s.fmi2Reset(s.component), "fmi2Reset")
        self._fresh = False
        self.messages.clear()
        t0, dt = float(times_s[0]), float(times_s[1] - times_s[0])
        self._check(s.fmi2SetupExperiment(s.component, 0, 0.0, t0, 0, 0.0), "fmi2SetupExperiment")
        if values:
            names = list(values)
            vr = (fmi2ValueReference * len(names))(*[ref[n] for n in names])
            v = (fmi2Real * len(names))(*[float(values[n]) for n in names])
            self._check(s.fmi2SetReal(s.component, vr, len(names), v), "fmi2SetReal (parameters)")
        self._check(s.fmi2EnterInitializationMode(s.component), "fmi2EnterInitializationMode")
        self._check(s.fmi2ExitInitializationMode(s.component), "fmi2ExitInitializationMode")
        n_in, n_out = len(inputs), len(outputs)
        vr_in = (fmi2ValueReference * n_in)(*[ref[n] for n in inputs])
        vr_out = (fmi2ValueReference * n_out)(*[ref[n] for n in outputs])
        u = np.ascontiguousarray(u, dtype=np.float64)
        y = np.empty((len(times_s), n_out), dtype=np.float64)
        if self._record is not None:
            return self._run_record(t0, dt, times_s, u, y, vr_in, vr_out, values)
        in_ptr, out_ptr = u.ctypes.data, y.ctypes.data
        row_in, row_out = 8 * n_in, 8 * n_out
        real_p = ctypes.POINTER(fmi2Real)
        set_real, get_real, do_step, c = s.fmi2SetReal, s.fmi2GetReal, s.fmi2DoStep, s.component
        last = len(times_s) - 1
        for k in range(len(times_s)):  # the time points are t0 + k dt exactly, as the data's are
            self._now = float(times_s[k])
            if n_in:
                status = set_real(c, vr_in, n_in, ctypes.cast(in_ptr + k * row_in, real_p))
                if status > 1:
                    self._check(status, f"fmi2SetReal (inputs) at t = {times_s[k]:g} s")
            status = get_real(c, vr_out, n_out, ctypes.cast(out_ptr + k * row_out, real_p))
            if status > 1:
                self._check(status, f"fmi2GetReal at t = {times_s[k]:g} s")
            if k < last:
                status = do_step(c, t0 + k * dt, dt, 1)
                if status > 1:
                    self._check(status, f"fmi2DoStep at t = {times_s[k]:g} s")
        return y

    def _run_record(self, t0, dt, times_s, u, y, vr_in, vr_out, values) -> np.ndarray:
        """The record in one call of the runtime; a failing call is reported as the FMI route reports it."""
        double_p = ctypes.POINTER(ctypes.c_double)
        done = ctypes.c_size_t(0)
        status = self._record(self.slave.component, vr_in, len(vr_in), vr_out, len(vr_out), len(times_s), t0, dt,
                              u.ctypes.data_as(double_p), y.ctypes.data_as(double_p), ctypes.byref(done))
        if status > 1:  # the FMU's log names the FMI call that failed
            self._now = float(times_s[min(done.value, len(times_s) - 1)])
            raise self._failure(f"maceRunRecord (the FMI calls of a sample) returned {status_name(status)}", values)
        return y


@functools.lru_cache(maxsize=8)
def _loaded(path: str, guid: str, sha256: str = "", thread: int = 0) -> _LoadedFmu:
    """This thread's instance of the FMU (a Dask worker loads it at its first run): from the copy the client
    shipped to this worker if there is one, else from ``path``. ``thread`` keys the instance: one instance
    runs one record at a time."""
    local = shipped_copy(sha256=sha256, name=Path(path).name)
    if local is None and _in_worker_process() and not os.path.isfile(path):
        raise MaceError(f"{path}: no such FMU file on the Dask worker (folder {os.getcwd()}), and none was sent "
                        "to it: run the FMU through update_fmu or plan_tests, which send it, or "
                        "call DaskRunner.ship(path) first")
    interface = read_fmu_interface(local or path)
    if interface.guid != guid:
        raise MaceError(f"{path}: the FMU changed while in use (GUID {interface.guid}, expected {guid})")
    if interface.written_by_pythonfmu and not _in_worker_process():
        raise MaceError(f"{path}: FMUs written by pythonfmu are simulated in worker processes only (their "
                        "wrapper releases a slave's Python objects twice after an error in it): pass a Dask runner "
                        "(CLI: --workers N or --scheduler ADDRESS), or export a native FMU")
    # messages name the FMU as the client does, wherever its bytes were read from
    return _LoadedFmu(dataclasses.replace(interface, path=path), file=os.fspath(local or path))


def _digest(*arrays: np.ndarray) -> str:
    h = hashlib.sha1()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def _run_in_worker(path: str, guid: str, sha256: str, values: Mapping[str, float], t: np.ndarray, u: np.ndarray,
                   names: Sequence[str], outs: Sequence[str]) -> np.ndarray:
    """One FMU run where this function is executed (a Dask worker: see :class:`FmuModel`)."""
    return _loaded(path, guid, sha256, threading.get_ident()).run(values, t, u, names, outs)


def _run_packed(args: tuple) -> np.ndarray:
    return _run_in_worker(*args)


@dataclass(frozen=True, eq=False)
class FmuModel:
    """The FMU with parameter ``values`` [FMU units] set through FMI before initialisation.

    ``gains``: output -> factor the simulated output is multiplied by (a sensor's gain error, estimated as
    a nuisance parameter; outputs not named have gain 1). ``runner`` (a map-like callable, e.g. a
    :class:`~mace_fmu.util.runner.DaskRunner`): where the runs of an FMU that must not be loaded here go
    (pythonfmu FMUs run in worker processes only); it is not sent along when the model itself travels to
    a worker.
    """

    interface: FmuInterface
    values: Mapping[str, float]
    _memo: dict = field(default_factory=dict, repr=False, compare=False)
    runner: Callable | None = field(default=None, repr=False, compare=False)
    gains: Mapping[str, float] = field(default_factory=dict)

    def __reduce__(self):
        return FmuModel, (self.interface, self.values, {}, None, self.gains)

    @property
    def parameter_values(self) -> dict[str, float]:
        """Every parameter of this model by its update name: the FMU's values and the gains ("gain:<output>")."""
        return {**self.values, **{gain_parameter(o): g for o, g in self.gains.items()}}

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.interface.inputs

    @property
    def outputs(self) -> tuple[str, ...]:
        return self.interface.outputs

    def time_response(self, times_s: np.ndarray, inputs: Mapping[str, np.ndarray], *,
                      outputs: Sequence[str] | None = None) -> np.ndarray:
        """Outputs y[k, output] [FMU units] simulated from the FMU's initial state, inputs held over each
        sample (zero-order hold); ``times_s`` uniformly spaced, inputs not given are zero.

        The same model asked the same question again (the engine asks for the base point's residual
        more than once) answers from memory.
        """
        t = np.asarray(times_s, dtype=float)
        dt = np.diff(t)
        if t.ndim != 1 or len(t) < 2 or dt[0] <= 0 or not np.allclose(dt, dt[0], rtol=1e-9, atol=0.0):
            raise MaceError("time_response: times must be increasing and uniformly spaced")
        outs = list(self.outputs if outputs is None else outputs)
        self.interface.check_signals(inputs=list(inputs), outputs=outs, where="time_response")
        names = list(inputs)
        u = np.column_stack([np.asarray(inputs[n], dtype=float) for n in names]) if names else np.zeros((len(t), 0))
        if u.shape[0] != len(t):
            raise MaceError(f"time_response: inputs have {u.shape[0]} samples, times have {len(t)}")
        key = (_digest(t, u), tuple(names), tuple(outs))
        if key not in self._memo:
            args = (self.interface.path, self.interface.guid, self.interface.sha256, dict(self.values), t, u, names,
                    outs)
            if self.interface.written_by_pythonfmu and self.runner is not None and not _in_worker_process():
                (y,) = list(self.runner(_run_packed, [args]))
            else:
                y = _run_in_worker(*args)
            self._memo.clear()  # one answer kept: the engine repeats only its last question
            self._memo[key] = y
        scale = np.array([self.gains.get(o, 1.0) for o in outs])
        return self._memo[key] * scale


@dataclass(frozen=True)
class FmuFamily:
    """Parameter values -> the FMU with them set (the engine's ModelFamily); ``fixed`` values are set on every run.

    No :class:`~mace_fmu.updating.engine.inclusion.ReanalysisFamily`: an FMU has no modal basis to reanalyse on,
    its "reanalysis" is its own initialisation (the engine's reanalysis of it is :meth:`full`).

    ``gain_outputs``: outputs whose sensor gain is a parameter too, named "gain:<output>" (default 1:
    the data are gain x the FMU's output). ``runner``: where the runs of a pythonfmu FMU go from this
    process (see :class:`FmuModel`).
    """

    interface: FmuInterface
    fixed: Mapping[str, float] = field(default_factory=dict)
    runner: Callable | None = field(default=None, repr=False, compare=False)
    gain_outputs: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        unknown = [o for o in self.gain_outputs if o not in self.interface.outputs]
        if unknown:
            raise MaceError(f"{self.interface.path}: sensor gain(s) of {', '.join(unknown)}, which is not an output "
                            f"(outputs: {', '.join(self.interface.outputs)})")

    def __reduce__(self):
        return FmuFamily, (self.interface, self.fixed, None, self.gain_outputs)

    @property
    def gain_parameters(self) -> tuple[str, ...]:
        """The gains' parameter names, "gain:<output>"."""
        return tuple(gain_parameter(o) for o in self.gain_outputs)

    def check_parameters(self, names: Sequence[str]) -> None:
        """MaceError naming every one of ``names`` that is neither an FMU parameter nor one of the gains."""
        self.interface.check_parameters([n for n in names if n not in self.gain_parameters])

    def full(self, values: Mapping[str, float]) -> FmuModel:
        """The FMU at ``values`` (names the FMU has no parameter of are refused; gains default to 1)."""
        merged = {**self.fixed, **values}
        gains = {o: float(merged.pop(gain_parameter(o), 1.0)) for o in self.gain_outputs}
        self.interface.check_parameters(list(merged))
        return FmuModel(interface=self.interface, values=merged, runner=self.runner, gains=gains)


def fmu_family(path: str | os.PathLike, *, fixed: Mapping[str, float] | None = None) -> FmuFamily:
    """The family of the FMU at ``path`` (interface read and checked once)."""
    return FmuFamily(interface=read_fmu_interface(Path(path)), fixed=dict(fixed or {}))


def ship_fmu(interface: FmuInterface, runner: Callable) -> None:
    """Send the FMU's bytes to the workers of ``runner`` when it has workers (a
    :class:`~mace_fmu.util.runner.DaskRunner`: its ``ship``); ``map`` and other runners run where the path is
    read. Each worker then loads the FMU from its own copy, wherever it runs.

    Raises
    ------
    MaceError
        The file changed since ``interface`` was read from it, or the workers cannot store it.
    """
    ship = getattr(runner, "ship", None)
    if ship is not None:
        ship(interface.path, sha256=interface.sha256)
