"""A sampled-data controller as a native FMU (FMI 2.0 and 3.0 co-simulation) on the plants' C runtime.

The controller is a discrete state space with named signals, ``x[k+1] = A x[k] + B u[k]``,
``y[k] = C x[k] + D u[k]``, sampled every ``sample_time_s``. Its FMU is the plant FMUs' FMI layer
and state machine over a second implementation of the runtime's model interface
(``c/controller/mace_discrete.c``): a communication step runs a whole number of samples with
the inputs held, and any other step size is refused. Inputs and outputs are in volts, as the
plant FMUs' (a controller closes a loop around a volts-volts model).

Sources: a discrete ``control.StateSpace`` (``dt`` > 0, named signals), an ``.npz`` file with
arrays ``A, B, C, D``, ``sample_time_s``, ``inputs``, ``outputs``, or the Appendix A LQG
compensator of the 0-g loop (:func:`lqg_controller`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Literal

import control as ct
import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fmu.native import compile as runtime
from mace_fmu.fmu.native.export import runtime_token, write_native_fmu
from mace_fmu.fmu.native.model_description import (INPUT_LIMIT_V, FmuVariable, fmi2_model_description,
                                                   fmi3_model_description)
from mace_fmu.fmu.native.platforms import select_platforms
from mace_fmu.util.atomic import atomic_path
from mace_fmu.util.progress import ProgressCallback

FORMAT_VERSION = 1


@dataclass(frozen=True)
class DiscreteController:
    """x[k+1] = a x[k] + b u[k], y[k] = c x[k] + d u[k] every ``sample_time_s`` seconds; signals in volts."""

    a: np.ndarray  #: (n, n)
    b: np.ndarray  #: (n, m)
    c: np.ndarray  #: (p, n)
    d: np.ndarray  #: (p, m)
    sample_time_s: float  #: sample time of the discrete controller [s]
    inputs: tuple[str, ...]  #: m names, e.g. the plant outputs it reads ("gyro_payload_z")
    outputs: tuple[str, ...]  #: p names, e.g. the plant inputs it drives ("gimbal_primary_z")

    def __post_init__(self) -> None:
        a, b, c, d = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (self.a, self.b, self.c, self.d))
        n, m, p = a.shape[0], len(self.inputs), len(self.outputs)
        if n == 0:
            b, c = b.reshape(0, m), c.reshape(p, 0)
        expected = {"A": (a, (n, n)), "B": (b, (n, m)), "C": (c, (p, n)), "D": (d, (p, m))}
        for name, (x, shape) in expected.items():
            if x.shape != shape:
                raise MaceError(f"controller: {name} has shape {x.shape}, expected {shape} for {n} states, "
                                f"{m} inputs and {p} outputs")
            if not np.all(np.isfinite(x)):
                raise MaceError(f"controller: {name} has non-finite entries")
        if not (np.isfinite(self.sample_time_s) and self.sample_time_s > 0):
            raise MaceError(f"controller: sample time must be a positive number of seconds, got {self.sample_time_s!r}")
        names = [*self.inputs, *self.outputs]
        bad = [x for x in names if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", str(x))]
        if bad or len(set(names)) != len(names) or m == 0 or p == 0:
            raise MaceError(f"controller: needs at least one input and one output with distinct identifier names, got "
                            f"inputs {list(self.inputs)} and outputs {list(self.outputs)}")
        for name, x in zip("abcd", (a, b, c, d)):
            object.__setattr__(self, name, x)

    @classmethod
    def from_statespace(cls, system: ct.StateSpace) -> DiscreteController:
        """From a discrete ``control.StateSpace`` with a numeric sample time and named signals."""
        dt = system.dt
        if dt is None or dt is True or not dt or dt <= 0:
            raise MaceError(f"controller: expected a discrete-time system with a sample time in seconds, got dt={dt!r} "
                            "(sample a continuous design first, e.g. control.sample_system(K, 0.002, 'zoh'))")
        return cls(a=system.A, b=system.B, c=system.C, d=system.D, sample_time_s=float(dt),
                   inputs=tuple(system.input_labels), outputs=tuple(system.output_labels))

    @classmethod
    def read_npz(cls, path: str | Path) -> DiscreteController:
        """From an ``.npz`` with A, B, C, D, sample_time_s, inputs and outputs (names as string arrays)."""
        try:
            with np.load(path, allow_pickle=False) as f:
                missing = sorted({"A", "B", "C", "D", "sample_time_s", "inputs", "outputs"} - set(f.files))
                if missing:
                    raise MaceError(f"{path}: controller file lacks array(s) {', '.join(missing)}")
                return cls(a=f["A"], b=f["B"], c=f["C"], d=f["D"], sample_time_s=float(f["sample_time_s"]),
                           inputs=tuple(str(x) for x in np.atleast_1d(f["inputs"])),
                           outputs=tuple(str(x) for x in np.atleast_1d(f["outputs"])))
        except (OSError, ValueError) as exc:
            raise MaceError(f"{path}: not a controller .npz file: {exc}") from None
        except MaceError as exc:
            raise MaceError(f"{path}: {exc}".replace(f"{path}: {path}: ", f"{path}: ")) from None

    def write_npz(self, path: str | Path) -> Path:
        """Write the controller as :meth:`read_npz` reads it (atomically)."""
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez(f, A=self.a, B=self.b, C=self.c, D=self.d, sample_time_s=self.sample_time_s,
                         inputs=np.array(self.inputs), outputs=np.array(self.outputs))
        return Path(path)

    def statespace(self) -> ct.StateSpace:
        """The controller as a discrete ``control.StateSpace`` (dt = sample time) with its signal names."""
        return ct.ss(self.a, self.b, self.c, self.d, self.sample_time_s, inputs=list(self.inputs),
                     outputs=list(self.outputs), name="controller")


def controller_data(controller: DiscreteController) -> dict:
    """The runtime's data (``c/controller/mace_discrete.c`` reads them) of ``controller``."""
    return {"controller_format_version": np.array([FORMAT_VERSION], dtype=np.int64),
            "controller_counts": np.array([len(controller.inputs), len(controller.outputs), controller.a.shape[0]],
                                          dtype=np.int64),
            "sample_time_s": np.array([controller.sample_time_s]), "A": controller.a, "B": controller.b,
            "C": controller.c, "D": controller.d, "input_names": list(controller.inputs),
            "output_names": list(controller.outputs)}


def _variables(controller: DiscreteController) -> list[FmuVariable]:
    """Inputs, outputs and (FMI 3) time in the runtime's value-reference order."""
    out = [FmuVariable(name=n, value_reference=k, causality="input", variability="discrete",
                       description=f"controller input {n} [V], sampled every {controller.sample_time_s} s", start=0.0,
                       unit="V", minimum=-INPUT_LIMIT_V, maximum=INPUT_LIMIT_V)
           for k, n in enumerate(controller.inputs)]
    m = len(out)
    out += [FmuVariable(name=n, value_reference=m + k, causality="output", variability="discrete",
                        description=f"controller output {n} [V], held between samples", unit="V")
            for k, n in enumerate(controller.outputs)]
    out.append(FmuVariable(name="time", value_reference=len(out), causality="independent", variability="continuous",
                           description="simulation time", unit="s"))
    return out


def export_controller_fmu(controller: DiscreteController, *, out_dir: str | Path = ".", name: str | None = None,
                          fmi_version: Literal[2, 3] = 2, platforms: Sequence[str] | None = None,
                          progress: ProgressCallback | None = None) -> Path:
    """Write ``out_dir/<name>.fmu``, the controller as a native co-simulation FMU, and return its path.

    Parameters
    ----------
    controller
        The discrete state space and its sample time [s].
    out_dir
        Folder of the FMU.
    name
        Model identifier (a C identifier; names the binary too). Default ``controller`` for FMI 2 and
        ``controller_fmi3`` for FMI 3, as the plant FMUs' names carry ``_fmi3``: the two versions of one
        controller never replace each other in one folder.
    fmi_version
        2 or 3 (co-simulation either way).
    platforms
        The platforms to carry binaries for (FMI 3 tuples, see :mod:`mace_fmu.fmu.native.platforms`);
        default all five.
    progress
        Told of the runtime's compilation, step by step, when it has to be compiled (not prebuilt or cached:
        see :func:`~mace_fmu.fmu.native.compile.compile_runtimes`).

    Returns
    -------
    Path
        ``out_dir/<name>.fmu``.
    """
    if name is None:
        name = "controller_fmi3" if fmi_version == 3 else "controller"
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise MaceError(f"FMU name must be a C identifier (it names the model and its binary), got {name!r}")
    if fmi_version not in (2, 3):
        raise MaceError(f"controller FMUs are FMI 2 or FMI 3, got FMI version {fmi_version!r}")
    targets = select_platforms(platforms)
    data = controller_data(controller)
    c_files = runtime.CONTROLLER_C_FILES[fmi_version]
    sources = runtime.source_files(c_files)
    token = runtime_token(data, salt=f"controller fmi{fmi_version}", sources=sources)
    data["guid"] = [token]
    variables = _variables(controller)
    version = metadata.version("mace-fmu")
    summary = (f"sampled-data controller: {controller.a.shape[0]} states, {len(controller.inputs)} inputs, "
               f"{len(controller.outputs)} outputs, sample time {controller.sample_time_s} s")
    binaries = runtime.compile_runtimes(targets, c_files=c_files, requested=platforms is not None, progress=progress)
    if fmi_version == 2:
        c_names = [p.name for p in sources if p.suffix == ".c"]
        description = fmi2_model_description(variables, model_identifier=name, guid=token, description=summary,
                                             version=version, source_files=c_names, model_exchange=False,
                                             step_size_s=controller.sample_time_s)
    else:
        description = fmi3_model_description(variables, model_identifier=name, token=token, description=summary,
                                             version=version, step_size_s=controller.sample_time_s)
    return write_native_fmu(Path(out_dir) / f"{name}.fmu", name=name, fmi_version=fmi_version,
                            description=description, data=data, binaries=binaries, sources=sources,
                            c_files=c_files)
