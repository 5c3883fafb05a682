"""``modes.toml``: identified modes as ``mace-fmu ema`` writes them and ``correlate`` and ``update modal`` read them.

One ``[identification]`` table (method, model order, band, FRF form, files, driving points), one ``[[dofs]]``
entry per measured DOF in the shapes' order (its name, unit and, where known, ``at = [[grid, component,
weight], ...]`` as a structure file's ``dofs``), and one ``[[modes]]`` entry per mode: ``frequency_hz``,
``damping``, ``shape_real`` (real-normalised, largest component +1), ``shape_complex_re``/``_im`` (largest
component 1) and, with a driving point, ``shape_mass_normalised`` [1/sqrt(kg) for FRFs in SI units]. A modes
file from elsewhere (another identification tool, a table) needs ``[[dofs]]`` with ``name`` and ``[[modes]]``
with ``frequency_hz``, ``damping`` and ``shape_real``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.parameters.sets import now_utc, tool_version, toml_key, toml_value
from mace_fmu.updating.modal.identify import Identification
from mace_fmu.util.atomic import write_text_atomic
from mace_fmu.util.textfile import read_toml

Dof = tuple[int, int, float]  #: (grid, component 1-6, weight), as a structure file's sensors name DOFs


@dataclass(frozen=True)
class MeasuredDof:
    """One measured DOF: the FRFs' output name, its unit and, where known, the model DOFs it reads."""

    name: str  #: the channel (the FRFs' output signal)
    unit: str = ""  #: its unit, e.g. "m/s^2"
    at: tuple[Dof, ...] = ()  #: () where the file does not say (the structure file's sensor or a DOF map will)


@dataclass(frozen=True)
class ModeRecord:
    """One mode of a modes file."""

    label: str  #: e.g. "mode 1"
    frequency_hz: float  #: [Hz]
    damping: float  #: damping ratio
    shape_real: np.ndarray  #: real-normalised, at the file's DOFs
    shape_mass_normalised: np.ndarray | None = None  #: [1/sqrt(kg)], None where not scaled
    shape_complex: np.ndarray | None = None  #: complex shape, None where the file gives none
    order: int | None = None  #: the model order the pole was taken at
    mpc: float | None = None  #: modal phase collinearity


@dataclass(frozen=True)
class ModesFile:
    """A modes file read: its DOFs, modes and what it says of how they were found."""

    dofs: tuple[MeasuredDof, ...]  #: the measured DOFs, in the shapes' order
    modes: tuple[ModeRecord, ...]  #: the modes, in the file's order
    identification: Mapping[str, Any]  #: the file's [identification] table (method, order, band, files)
    source: str = ""  #: the file

    @property
    def dof_names(self) -> tuple[str, ...]:
        return tuple(d.name for d in self.dofs)

    @property
    def scaled(self) -> bool:
        """Whether every mode has a mass-normalised shape."""
        return bool(self.modes) and all(m.shape_mass_normalised is not None for m in self.modes)


def _numbers(values: np.ndarray) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def modes_toml(identification: Identification, *, dofs: Sequence[MeasuredDof] | None = None) -> str:
    """The text of ``modes.toml`` for an identification (``dofs``: the outputs with what is known of them)."""
    dofs = list(dofs) if dofs is not None else [MeasuredDof(n, identification.units.get(n, ""))
                                                for n in identification.outputs]
    lines = ["# mace-fmu modes identified from measured FRFs (mace-fmu ema); frequencies [Hz], shapes at the [[dofs]]",
             "", "[identification]",
             f"created = {toml_value(now_utc())}", f"tool = {toml_value(tool_version())}",
             f"method = {toml_value(identification.method)}", f"max_order = {identification.max_order}",
             f"band_hz = {_numbers(identification.band_hz)}", f"frf_form = {toml_value(identification.frf_form)}",
             "files = [" + ", ".join(toml_value(f) for f in identification.files) + "]",
             "inputs = [" + ", ".join(toml_value(f) for f in identification.inputs) + "]",
             "driving_points = {" + ", ".join(f"{toml_key(k)} = {toml_value(v)}"
                                              for k, v in identification.driving_points.items()) + "}",
             f"fit_error = {toml_value(identification.fit_error)}  # ||H - H_modal|| / ||H|| over the band", ""]
    for d in dofs:
        lines += ["[[dofs]]", f"name = {toml_value(d.name)}", f"unit = {toml_value(d.unit)}"]
        if d.at:
            lines.append("at = [" + ", ".join(f"[{g}, {c}, {float(w)!r}]" for g, c, w in d.at) + "]")
        lines.append("")
    for k, m in enumerate(identification.modes, start=1):
        lines += ["[[modes]]", f'label = "mode {k}"', f"frequency_hz = {float(m.frequency_hz)!r}", f"damping = {float(m.damping)!r}",
                  f"order = {int(m.order)}", f"mpc = {float(m.mpc)!r}  # modal phase collinearity (1: a real mode)",
                  f"shape_real = {_numbers(m.shape_real)}",
                  f"shape_complex_re = {_numbers(m.shape_complex.real)}",
                  f"shape_complex_im = {_numbers(m.shape_complex.imag)}"]
        if m.shape_mass_normalised is not None:
            lines.append(f"shape_mass_normalised = {_numbers(m.shape_mass_normalised)}  # [1/sqrt(kg)]")
        lines.append("")
    return "\n".join(lines)


def write_modes_file(identification: Identification, path: str | Path, *,
                     dofs: Sequence[MeasuredDof] | None = None) -> Path:
    """Write ``modes.toml`` atomically.

    Parameters
    ----------
    identification : Identification
        What :func:`~mace_fmu.updating.modal.identify.identify_modes` found.
    path : path
        The file to write.
    dofs : sequence of MeasuredDof, optional
        The outputs with their units and model DOFs where known (default: names and units only).

    Returns
    -------
    Path
        ``path``.
    """
    return write_text_atomic(path, modes_toml(identification, dofs=dofs))


def _vector(entry: Mapping[str, Any], key: str, n: int, where: str) -> np.ndarray:
    value = entry.get(key)
    if not isinstance(value, list) or len(value) != n or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value):
        raise MaceError(f"{where}: {key} must be a list of {n} finite numbers (one per [[dofs]] entry)")
    return np.array(value, dtype=float)


def _number(entry: Mapping[str, Any], key: str, where: str, *, low: float, high: float) -> float:
    value = entry.get(key)
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not (low <= value < high):
        raise MaceError(f"{where}: {key} = {value!r}, expected a number in [{low:g}, {high:g})")
    return float(value)


def _at(value: Any, where: str) -> tuple[Dof, ...]:
    ok = isinstance(value, list) and all(
        isinstance(x, list) and len(x) == 3 and isinstance(x[0], int) and isinstance(x[1], int) and 1 <= x[1] <= 6
        and isinstance(x[2], (int, float)) for x in value)
    if not ok:
        raise MaceError(f"{where}: at must be [[grid, component 1-6, weight], ...]")
    return tuple((int(g), int(c), float(w)) for g, c, w in value)


def read_modes_file(path: str | Path) -> ModesFile:
    """Read a modes file (see the module docstring); errors name the file, the entry and the key.

    Parameters
    ----------
    path : path
        A ``modes.toml``.

    Returns
    -------
    ModesFile
        Its DOFs, its modes (frequencies [Hz], damping ratios, shapes) and its ``[identification]`` table.
    """
    data = read_toml(path, what="modes")
    raw_dofs = data.get("dofs")
    if not isinstance(raw_dofs, list) or not raw_dofs:
        raise MaceError(f"{path}: no [[dofs]] entries (each with a name: the measured DOFs, in the shapes' order)")
    dofs = []
    for k, d in enumerate(raw_dofs, start=1):
        where = f"{path}: [[dofs]] entry {k}"
        if not isinstance(d, dict) or not isinstance(d.get("name"), str) or not d["name"]:
            raise MaceError(f"{where}: needs a name")
        dofs.append(MeasuredDof(d["name"], str(d.get("unit", "")), _at(d["at"], where) if "at" in d else ()))
    names = [d.name for d in dofs]
    if len(set(names)) != len(names):
        raise MaceError(f"{path}: DOF {next(n for n in names if names.count(n) > 1)!r} is listed twice")
    raw_modes = data.get("modes")
    if not isinstance(raw_modes, list) or not raw_modes:
        raise MaceError(f"{path}: no [[modes]] entries")
    modes = []
    for k, m in enumerate(raw_modes, start=1):
        where = f"{path}: [[modes]] entry {k}"
        if not isinstance(m, dict):
            raise MaceError(f"{where}: not a table")
        label = str(m.get("label", f"mode {k}"))
        n = len(dofs)
        complex_shape = None
        if "shape_complex_re" in m or "shape_complex_im" in m:
            complex_shape = _vector(m, "shape_complex_re", n, where) + 1j * _vector(m, "shape_complex_im", n, where)
        real = _vector(m, "shape_real", n, where)
        if not np.any(real):
            raise MaceError(f"{where}: shape_real is zero everywhere")
        modes.append(ModeRecord(
            label=label, frequency_hz=_number(m, "frequency_hz", where, low=1e-300, high=math.inf),
            damping=_number(m, "damping", where, low=0.0, high=1.0), shape_real=real,
            shape_mass_normalised=_vector(m, "shape_mass_normalised", n, where) if "shape_mass_normalised" in m
            else None, shape_complex=complex_shape, order=m.get("order"), mpc=m.get("mpc")))
    labels = [m.label for m in modes]
    if len(set(labels)) != len(labels):
        raise MaceError(f"{path}: mode label {next(n for n in labels if labels.count(n) > 1)!r} is used twice")
    return ModesFile(dofs=tuple(dofs), modes=tuple(modes), identification=dict(data.get("identification", {})),
                     source=str(path))
