"""Package a volts-volts model as a native FMU: the versioned C runtime plus the model as data.

No code is generated per model: the runtime (``mace_fmu/fmu/native/c``, compiled once per
process) reads ``resources/mace_model.bin`` (see :mod:`mace_fmu.fmu.native.resource`) and rebuilds
the model for its parameters at initialisation. FMI 2.0 FMUs offer co-simulation and model
exchange; FMI 3.0 FMUs co-simulation. Each carries ``binaries/`` for Linux, Windows and macOS on x86-64
and ARM (:mod:`mace_fmu.fmu.native.platforms`, compiled with zig from its FMI version's entry points only,
so that they export that version's functions), ``sources/`` so that a host on another
platform can build its own binary (e.g. ``fmpy.build.build_platform_binary`` or a plain ``cc``), and
``sources/build_info.json``, the command that made each binary.
"""

from __future__ import annotations

import hashlib
import re
import uuid
from collections.abc import Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Literal

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fmu.native import compile as runtime
from mace_fmu.fmu.native.model_description import (fmi2_model_description, fmi3_build_description,
                                                   fmi3_model_description, fmu_variables)
from mace_fmu.fmu.native.platforms import Platform, binary_entries, select_platforms
from mace_fmu.fmu.native.resource import count_of, resource_bytes, runtime_arrays
from mace_fmu.fmu.parametric import ParametricModel
from mace_fmu.util.atomic import atomic_zip
from mace_fmu.util.progress import ProgressCallback

FmiVersion = Literal[2, 3]
RESOURCE_NAME = "mace_model.bin"


def runtime_token(data: Mapping[str, np.ndarray | list[str]], *, salt: str, sources: list[Path]) -> str:
    """A GUID / instantiation token that changes with the model data, ``salt`` (FMI version, FMU kind), the runtime."""
    h = hashlib.sha256(salt.encode())
    for path in sources:
        h.update(path.read_bytes())
    h.update(resource_bytes(data))
    return "{" + str(uuid.UUID(bytes=h.digest()[:16])) + "}"


def write_native_fmu(final: Path, *, name: str, fmi_version: int, description: bytes,
                     data: Mapping[str, np.ndarray | list[str]], binaries: dict[Platform, bytes], sources: list[Path], c_files: tuple[str, ...]) -> Path:
    """Zip a native FMU atomically: its model description, runtime data, binaries and C sources.

    Parameters
    ----------
    final : Path
        The .fmu file to write.
    name : str
        The model identifier (names the binaries).
    fmi_version : int
        2 or 3 (the binary folder names differ).
    description : bytes
        modelDescription.xml.
    data : dict
        The runtime's arrays (resources/mace_model.bin).
    binaries : dict
        Platform -> shared library bytes (:func:`~mace_fmu.fmu.native.compile.compile_runtimes`).
    sources : list of Path
        The C sources shipped in ``sources/``.
    c_files : tuple of str
        The runtime's C files in the order they were compiled (recorded in ``sources/build_info.json``).

    Returns
    -------
    Path
        ``final``, written atomically.
    """
    source_names = [p.name for p in sources if p.suffix == ".c"]
    with atomic_zip(final) as z:
        z.writestr("modelDescription.xml", description)
        z.writestr(f"resources/{RESOURCE_NAME}", resource_bytes(data))
        for entry, binary in binary_entries(binaries, fmi_version=fmi_version, name=name).items():
            z.writestr(entry, binary)
        for path in sources:
            z.write(path, f"sources/{path.name}")
        z.writestr(f"sources/{runtime.BUILD_INFO}",
                   runtime.build_info(binaries, c_files=c_files, fmi_version=fmi_version, name=name))
        if fmi_version == 3:
            z.writestr("sources/buildDescription.xml",
                       fmi3_build_description(model_identifier=name, source_files=source_names))
    return final


def export_native_fmu(model: ParametricModel, *, name: str, out_dir: str | Path = ".", fmi_version: FmiVersion = 2,
                      platforms: Sequence[str] | None = None, progress: ProgressCallback | None = None) -> Path:
    """Write a native FMU (the C runtime, compiled here) of ``model`` and return its path.

    Parameters
    ----------
    model : ParametricModel
        What the volts-volts model's FMUs carry (:func:`~mace_fmu.fmu.parametric.parametric_model`): its
        inputs and outputs [V] become the FMU's, its physical parameters, damping ratios, frequency scales,
        delays [s] and servo gains its tunable parameters.
    name : str
        The FMU's model identifier, a C identifier (e.g. MACE_1g, :func:`~mace_fmu.fmu.naming.model_fmu_name`).
    out_dir : path
        Folder the FMU is written to (created if needed).
    fmi_version : {2, 3}
        FMI 2.0 (co-simulation and model exchange) or FMI 3.0 (co-simulation).
    platforms : sequence of str, optional
        The platforms to carry binaries for, FMI 3 tuples (``"x86_64-linux"``, ``"aarch64-linux"``,
        ``"x86_64-windows"``, ``"x86_64-darwin"``, ``"aarch64-darwin"``); default all five. One named here
        that cannot be built is an error; without zig the default set is one warning and sources/ only.
    progress : callable, optional
        Native runtime: told of the runtime's compilation, step by step, when it has to be compiled (not
        prebuilt or cached: see :func:`~mace_fmu.fmu.native.compile.compile_runtimes`).

    Returns
    -------
    Path
        ``out_dir/<name>.fmu``, written atomically.

    Raises
    ------
    MaceError
        A name that is not a C identifier, an FMI version other than 2 or 3, an unknown platform, a
        compiler failure.
    """
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise MaceError(f"FMU name must be a C identifier (it names the model and its binary), got {name!r}")
    if fmi_version not in (2, 3):
        raise MaceError(f"native FMUs are FMI 2 or FMI 3, got FMI version {fmi_version!r}")
    targets = select_platforms(platforms)
    data = runtime_arrays(model)
    if count_of(data, "states") != len(model.state_names):
        raise MaceError(f"native FMU: the runtime data describe {count_of(data, 'states')} states, the model has "
                        f"{len(model.state_names)}")
    c_files = runtime.C_FILES[fmi_version]
    sources = runtime.source_files(c_files)
    token = runtime_token(data, salt=f"fmi{fmi_version}", sources=sources)
    data["guid"] = [token]
    variables = fmu_variables(model)
    version = metadata.version("mace-fmu")
    binaries = runtime.compile_runtimes(targets, c_files=c_files, requested=platforms is not None, progress=progress)
    if fmi_version == 2:
        description = fmi2_model_description(variables, model_identifier=name, guid=token,
                                             description=model.summary, version=version,
                                             source_files=[p.name for p in sources if p.suffix == ".c"],
                                             jacobian=model.jacobian,
                                             state_order=[int(k) for k in data["me_order"]])
    else:
        description = fmi3_model_description(variables, model_identifier=name, token=token,
                                             description=model.summary, version=version)
    return write_native_fmu(Path(out_dir) / f"{name}.fmu", name=name, fmi_version=fmi_version,
                            description=description, data=data, binaries=binaries, sources=sources,
                            c_files=c_files)
