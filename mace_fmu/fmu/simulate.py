"""Run a MACE FMU (through fmpy) with a test signal on one input; inputs [V], outputs in their units.

pythonfmu pitfalls: its native wrapper writes into a block it has freed when a process that loaded
it exits ("corrupted double-linked list" after all work was done, some runs in several); every
simulation here releases that block at once (:func:`mace_fmu.fmu.host.release_pythonfmu_state`).
The wrapper also releases the slave's Python objects a second time after a Python exception in it.
The simulation therefore runs, by default, in a fresh worker process that returns the samples: the
caller's process never loads the FMU's native code.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Sequence

import fmpy
import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fmu.archive import check_fmu
from mace_fmu.fmu.host import fmpy_logger_restored, release_pythonfmu_state, status_name

log = logging.getLogger(__name__)

SignalKind = Literal["step", "chirp", "impulse"]
SIGNALS: tuple[str, ...] = ("step", "chirp", "impulse")


@dataclass(frozen=True)
class FmuRun:
    """One simulation: the signals at the communication points [s]."""

    times_s: np.ndarray  #: (n,) communication points, uniform, from 0
    inputs: dict[str, np.ndarray]  #: the driven input [V], held over the step that starts at t (others 0 V)
    outputs: dict[str, np.ndarray]  #: every recorded output, in ``units``
    units: dict[str, str]  #: unit of each input and output, from the model description
    descriptions: dict[str, str]  #: of each input and output, from the model description


def input_signal(kind: SignalKind, times_s: np.ndarray, *, amplitude_v: float = 1.0,
                 chirp_hz: tuple[float, float] = (0.1, 10.0)) -> np.ndarray:
    """A test signal [V] at ``times_s``, held over each step (zero-order hold).

    step: ``amplitude_v`` from t = 0 on; impulse: ``amplitude_v`` over the first step, then 0;
    chirp: ``amplitude_v`` sin of a linear sweep from ``chirp_hz[0]`` to ``chirp_hz[1]`` [Hz]
    over the run.
    """
    t = np.asarray(times_s, dtype=float)
    if kind == "step":
        return np.full(t.shape, float(amplitude_v))
    if kind == "impulse":
        u = np.zeros(t.shape)
        u[0] = amplitude_v
        return u
    if kind == "chirp":
        f0, f1 = chirp_hz
        if not (f0 >= 0.0 and f1 > 0.0):
            raise MaceError(f"chirp frequencies must be >= 0 Hz and the end > 0 Hz, got {chirp_hz}")
        duration = max(float(t[-1] - t[0]), 1e-300)
        return amplitude_v * np.sin(2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / duration * t**2))
    raise MaceError(f"signal must be one of {', '.join(SIGNALS)}, got {kind!r}")


def communication_times(*, duration_s: float, step_s: float) -> np.ndarray:
    """Communication points [s] from 0 to ``duration_s`` at ``step_s``; the duration must be whole steps."""
    if not (duration_s > 0 and step_s > 0 and duration_s >= step_s):
        raise MaceError(f"need duration_s >= step_s > 0 [s], got duration {duration_s} s, step {step_s} s")
    n_steps = int(round(duration_s / step_s))
    if abs(n_steps * step_s - duration_s) > 1e-9 * duration_s:
        raise MaceError(f"duration {duration_s} s is not a whole number of {step_s} s steps; "
                        f"use e.g. {n_steps * step_s:g} s or {(n_steps + 1) * step_s:g} s")
    return np.arange(n_steps + 1) * step_s


def simulate_input_response(fmu: str | os.PathLike, *, input_name: str, signal: SignalKind = "step",
                            duration_s: float = 2.0, step_s: float = 0.002, amplitude_v: float = 1.0,
                            chirp_hz: tuple[float, float] = (0.1, 10.0),
                            outputs: Sequence[str] | None = None, in_subprocess: bool = True) -> FmuRun:
    """Simulate ``fmu`` (an .fmu file or an extracted folder) with ``signal`` on ``input_name``.

    All other inputs stay at 0 V. ``outputs`` None records every output. The FMU is stepped at
    ``step_s`` [s] for ``duration_s`` [s] and sampled at every step; ``in_subprocess`` runs fmpy
    in a fresh worker process (see the module docstring).

    Parameters
    ----------
    fmu : path
        An .fmu file or an extracted folder.
    input_name : str
        The driven input.
    signal : {"step", "impulse", "chirp"}
        The input's shape.
    duration_s : float
        Simulated time [s].
    step_s : float
        Communication step [s].
    amplitude_v : float
        The input's amplitude [V].
    chirp_hz : tuple of float
        Start and end frequency [Hz] of a chirp.
    outputs : sequence of str, optional
        The outputs to record (None: every one).
    in_subprocess : bool
        Run fmpy in a fresh worker process.

    Returns
    -------
    FmuRun
        Times [s], the driven input [V] and the recorded outputs with their units.

    Raises
    ------
    MaceError
        An unknown input or output, a non-positive duration or step, an FMU that fails.
    """
    t = communication_times(duration_s=duration_s, step_s=step_s)
    check_fmu(fmu)
    md = fmpy.read_model_description(str(fmu))
    variables = {v.name: v for v in md.modelVariables}
    ins = [v.name for v in md.modelVariables if v.causality == "input"]
    outs = [v.name for v in md.modelVariables if v.causality == "output"]
    if input_name not in ins:
        raise MaceError(f"{os.fspath(fmu)} has no input {input_name!r}; inputs: {', '.join(ins)}")
    recorded = list(outs if outputs is None else outputs)
    unknown = [n for n in recorded if n not in outs]
    if unknown:
        raise MaceError(f"{os.fspath(fmu)} has no output(s) {', '.join(unknown)}; outputs: {', '.join(outs)}")
    u = input_signal(signal, t, amplitude_v=amplitude_v, chirp_hz=chirp_hz)
    table = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in ins])
    table["time"], table[input_name] = t, u
    run = _simulate_in_subprocess if in_subprocess else _simulate
    result = run(os.fspath(fmu), table, recorded, step_s)
    if len(result) != len(t) or not np.allclose(result["time"], t, rtol=0, atol=1e-9 * step_s):
        raise MaceError(f"{os.fspath(fmu)}: fmpy reported {len(result)} samples, expected {len(t)} at {step_s} s")
    named = [input_name] + recorded
    return FmuRun(times_s=t, inputs={input_name: u},
                  outputs={n: np.asarray(result[n], dtype=float) for n in recorded},
                  units={n: variables[n].unit or "" for n in named},
                  descriptions={n: variables[n].description or "" for n in named})


def _simulate(fmu: str, table: np.ndarray, outputs: list[str], step_s: float) -> np.ndarray:
    """fmpy's co-simulation with the input table, sampled at every step; MaceError with the FMU's logged reason.

    Debug logging is switched on because pythonfmu forwards an FMU's messages, errors included,
    only then; messages of warning level and above go to this module's logger. A pythonfmu FMU's
    process-wide state is released after the run (see the module docstring).
    """
    messages: list[str] = []

    def collect(component, instance, status, category, message) -> None:
        if status >= 1:
            text = (message or b"").decode("utf-8", "replace")
            messages.append(f"{status_name(status)}: {text}")
            log.log(logging.WARNING if status == 1 else logging.ERROR, "%s: %s", fmu, text)

    with tempfile.TemporaryDirectory(prefix="mace_fmu_sim_") as tmp:
        folder, md = fmu, None
        try:
            md = fmpy.read_model_description(fmu)
            if not os.path.isdir(fmu):  # unpacked here, not in simulate_fmu's own folder: its binary's path is known
                folder = fmpy.extract(fmu, unzipdir=tmp)
            with fmpy_logger_restored():
                result = fmpy.simulate_fmu(folder, start_time=0.0, stop_time=float(table["time"][-1]),
                                           output_interval=step_s, input=table, output=outputs, debug_logging=True,
                                           logger=collect)
        except Exception as exc:  # fmpy raises a bare Exception naming the FMI call and its status
            raise MaceError(f"{fmu}: {exc}" + (f" FMU log: {' | '.join(messages)}" if messages else "")) from None
        finally:  # a failed run has instantiated the FMU all the same
            if md is not None and md.coSimulation is not None and "pythonfmu" in (md.generationTool or "").lower():
                release_pythonfmu_state(_binary_path(folder, md.coSimulation.modelIdentifier))
    if len(result) != len(table) and messages:  # fmpy stops quietly at a discarded step: say why
        raise MaceError(f"{fmu}: the simulation stopped at t = {result['time'][-1]:g} s of "
                        f"{table['time'][-1]:g} s. FMU log: {' | '.join(messages)}")
    return result


def _binary_path(folder: str, model_identifier: str) -> str:
    """The path fmpy loads an extracted FMU's binary from (``fmpy.fmi1._FMU``), for this platform."""
    from fmpy import platform, sharedLibraryExtension

    directory = os.path.abspath(os.path.join(folder, "binaries", platform))
    return os.path.join(directory, model_identifier + sharedLibraryExtension)


_DONE = "mace-fmu worker: samples written"
_FAILED = "mace-fmu worker: error: "


def _simulate_in_subprocess(fmu: str, table: np.ndarray, outputs: list[str], step_s: float) -> np.ndarray:
    """``_simulate`` in a fresh Python process (a plain subprocess: no re-import of the caller's script).

    The worker reports success on stdout after writing the samples, so a crash at its exit (the
    pitfall above) loses nothing; any earlier failure raises with the worker's error output.
    """
    with tempfile.TemporaryDirectory(prefix="mace_fmu_run_") as tmp:
        request, answer = Path(tmp) / "request.npz", Path(tmp) / "answer.npy"
        np.savez(request, table=table, outputs=np.array(outputs, dtype=str), step_s=step_s, fmu=fmu)
        code = f"from mace_fmu.fmu.simulate import _worker; _worker({str(request)!r}, {str(answer)!r})"
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        failed = [line.removeprefix(_FAILED) for line in done.stdout.splitlines() if line.startswith(_FAILED)]
        if failed:
            raise MaceError(failed[0])
        if _DONE not in done.stdout or not answer.exists():
            raise MaceError(f"simulating {fmu} failed in the worker process (exit status {done.returncode}):\n"
                            f"{done.stderr.strip()[-2000:]}")
        columns = np.load(answer, allow_pickle=False)
    result = np.zeros(columns.shape[1], dtype=[("time", float)] + [(n, float) for n in outputs])
    for k, name in enumerate(["time"] + outputs):
        result[name] = columns[k]
    return result


def _worker(request: str, answer: str) -> None:
    """Entry point of the worker process: read the request, simulate, write the samples."""
    with np.load(request, allow_pickle=False) as r:
        try:
            result = _simulate(str(r["fmu"]), r["table"], [str(n) for n in r["outputs"]], float(r["step_s"]))
        except MaceError as exc:
            print(_FAILED + " ".join(str(exc).splitlines()), flush=True)
            return
    np.save(answer, np.array([result[n] for n in result.dtype.names], dtype=float), allow_pickle=False)
    print(_DONE, flush=True)
