"""Time histories in CSV (``time [s]`` then ``in:``/``out:`` channels) and NumPy ``.npz`` files."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Callable

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import DataError, TimeHistory
from mace_fmu.updating.files.channels import ChannelMap, Label, check_present, format_label, parse_label, resolve
from mace_fmu.util.atomic import atomic_path
from mace_fmu.util.textfile import read_text

TIME_SUFFIXES = (".csv", ".npz", ".lvm")
#: what write_time_history writes (a LabVIEW measurement file is read only)
WRITTEN_SUFFIXES = (".csv", ".npz")
#: relative tolerance on the time step: the same as TimeHistory's uniform-spacing check
STEP_RTOL = 1e-6


def read_time_history(path: str | Path, *, channel_map: ChannelMap | None = None,
                      sample_time_s: float | None = None) -> TimeHistory:
    """Measured inputs and outputs from ``.csv``, ``.npz`` or LabVIEW's ``.lvm``; times [s], signals in the units
    their labels state.

    The first column (CSV) or array (npz) is ``time [s]``; each other one is labelled
    ``name [unit]``. Without a channel map the name carries the role, ``in:<signal>`` or
    ``out:<signal>``, and the unit travels with the data, to be checked against the model's where
    they meet it (an FMU update: the FMU's units); with a map the name is the data channel and the
    map gives signal, role and unit. ``sample_time_s``, when given, must be the file's time step.
    Errors name the file, the channel and the row (CSV: the line; npz: the 0-based sample). A LabVIEW
    measurement file names its channels and units in its header (:mod:`~mace_fmu.updating.files.lvm`).

    Parameters
    ----------
    path : path
        A ``.csv``, ``.npz`` or ``.lvm`` file.
    channel_map : ChannelMap, optional
        Data channel -> model signal, role and unit.
    sample_time_s : float, optional
        The sample time [s] the file must have.

    Returns
    -------
    TimeHistory
        Times [s], inputs and outputs by model signal name.

    Raises
    ------
    MaceError
        Naming the file, the channel and the row.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".lvm":
        from mace_fmu.updating.files.lvm import read_lvm_time_history

        return read_lvm_time_history(path, channel_map=channel_map, sample_time_s=sample_time_s)
    if suffix == ".csv":
        labels, columns, lines, header_line = read_csv_columns(path)
        row_at = lambda sample: f"{path}:{lines[sample]}"  # noqa: E731
        header_at = f"{path}:{header_line}"
    elif suffix == ".npz":
        labels, columns = _read_npz_columns(path)
        row_at = lambda sample: f"{path}: row {sample}"  # noqa: E731
        header_at = f"{path}"
    else:
        raise MaceError(f"{path}: unknown time-history format {path.suffix!r} (expected one of "
                        f"{', '.join(TIME_SUFFIXES)})")
    time_label = parse_label(labels[0], where=header_at)
    if time_label.name != "time" or time_label.role is not None:
        raise MaceError(f"{header_at}: the first column is {labels[0]!r}, expected 'time [s]'")
    if time_label.unit != "s":
        raise MaceError(f"{header_at}: channel 'time': unit {time_label.unit!r}, expected 's'")
    return history_of_columns(path, [parse_label(text, where=header_at) for text in labels[1:]], columns[0],
                              columns[1:], channel_map=channel_map, sample_time_s=sample_time_s, header_at=header_at,
                              row_at=row_at)


def history_of_columns(path: Path, labels: list[Label], times_s: np.ndarray, columns: list[np.ndarray], *,
                       channel_map: ChannelMap | None, sample_time_s: float | None,
                       header_at: str | Callable[[str], str], row_at: Callable[[int], str]) -> TimeHistory:
    """A file's channels (their parsed labels and columns) as a TimeHistory: each resolved through the channel
    map (or its role prefix), the map's channels checked present, bad samples located by ``row_at`` (sample ->
    the file and its line) and header errors by ``header_at`` (a place, or channel name -> place)."""
    where = header_at if callable(header_at) else (lambda channel: header_at)  # noqa: E731
    inputs: dict[str, np.ndarray] = {}
    outputs: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    found: set[str] = set()
    channel_of: dict[str, str] = {}
    for label, values in zip(labels, columns):
        if label.name in found:
            raise MaceError(f"{where(label.name)}: channel {label.name!r} appears twice")
        found.add(label.name)
        signal, role, unit = resolve(label, channel_map=channel_map, where=where(label.name))
        if role == "ignore":
            continue
        if signal in inputs or signal in outputs:
            raise MaceError(f"{where(label.name)}: signal {signal!r} comes from two channels ({channel_of[signal]!r} "
                            f"and {label.name!r})")
        (inputs if role == "input" else outputs)[signal] = values
        units[signal] = unit
        channel_of[signal] = label.name
    check_present(found, channel_map=channel_map, where=where(""))
    try:
        history = TimeHistory(times_s, inputs, outputs, source=str(path), units=units)
    except DataError as exc:
        channel = "time" if exc.channel is None else channel_of.get(exc.channel, exc.channel)
        raise MaceError(f"{row_at(exc.row)}: channel {channel!r}: {exc.what}") from None
    if sample_time_s is not None:
        _check_step(history.times_s, sample_time_s, row_at)
    return history


def _check_step(times_s: np.ndarray, sample_time_s: float, row_at) -> None:
    if not (np.isfinite(sample_time_s) and sample_time_s > 0):
        raise MaceError(f"sample time must be a positive number of seconds, got {sample_time_s!r}")
    dt = np.diff(times_s)
    bad = np.flatnonzero(np.abs(dt - sample_time_s) > STEP_RTOL * sample_time_s)
    if bad.size:
        k = int(bad[0]) + 1
        raise MaceError(f"{row_at(k)}: channel 'time': time step {dt[k - 1]:.9g} s ({1 / dt[k - 1]:.6g} Hz), "
                        f"expected the sample time {sample_time_s:.9g} s ({1 / sample_time_s:.6g} Hz)")


def read_csv_columns(path: Path, *, dtype: type = float) -> tuple[list[str], list[np.ndarray], list[int], int]:
    """Column labels, columns, each sample's line number and the header's; '#' lines and blank lines skipped.

    The delimiter is the header's: ``;`` where the header has one (as European spreadsheets and some
    acquisition software write), ``,`` otherwise. With ``dtype=complex`` a cell may also be a complex
    literal as Python and NumPy write it (``-0.05+0.05j``, ``(1-2j)``).
    """
    text = read_text(path)
    lines = text.splitlines()
    numbers = [k for k, line in enumerate(lines, start=1)
               if line.strip(" \t,;") and not line.lstrip().startswith("#")]
    if not numbers:
        raise MaceError(f"{path}: empty (expected a header of 'name [unit]' labels and a row per sample)")
    header_line, data_lines = numbers[0], numbers[1:]
    delimiter = ";" if ";" in lines[header_line - 1] else ","
    labels = [c.strip() for c in next(csv.reader([lines[header_line - 1]], delimiter=delimiter))]
    for k in data_lines:
        if lines[k - 1].count(delimiter) != len(labels) - 1:
            raise MaceError(f"{path}:{k}: {lines[k - 1].count(delimiter) + 1} fields, the header has {len(labels)}")
    try:  # numpy's parser reads the whole table at once; quoted cells or a bad one need the slow route
        data = np.loadtxt([lines[k - 1] for k in data_lines], delimiter=delimiter, dtype=dtype, ndmin=2,
                          comments=None).reshape(len(data_lines), len(labels)) if data_lines else \
            np.empty((0, len(labels)), dtype=dtype)
    except ValueError:
        data = np.empty((len(data_lines), len(labels)), dtype=dtype)
        for n, k in enumerate(data_lines):
            for j, (label, cell) in enumerate(zip(labels, next(csv.reader([lines[k - 1]], delimiter=delimiter)))):
                try:
                    data[n, j] = dtype(cell.strip().replace(" ", ""))
                except ValueError:
                    raise MaceError(f"{path}:{k}: channel {label!r}: {cell!r} is not a number") from None
    return labels, [data[:, j] for j in range(len(labels))], data_lines, header_line


def _read_npz_columns(path: Path) -> tuple[list[str], list[np.ndarray]]:
    try:
        with np.load(path, allow_pickle=False) as archive:
            labels = list(archive.files)
            arrays = [archive[name] for name in labels]
    except FileNotFoundError:
        raise MaceError(f"{path}: no such time-history file") from None
    except (OSError, ValueError) as exc:
        raise MaceError(f"{path}: not a NumPy .npz archive: {exc}") from None
    if not labels:
        raise MaceError(f"{path}: no arrays (expected 'time [s]' and a 1-D array per channel)")
    columns = []
    for label, a in zip(labels, arrays):
        if a.ndim != 1 or a.dtype.kind not in "fiu":
            raise MaceError(f"{path}: array {label!r} has shape {a.shape} and dtype {a.dtype}, expected a 1-D "
                            "array of numbers")
        if a.size != arrays[0].size:
            raise MaceError(f"{path}: channel {label!r} has {a.size} samples, time has {arrays[0].size}")
        columns.append(a.astype(float))
    return labels, columns


def _labelled_columns(history: TimeHistory) -> tuple[list[str], list[np.ndarray]]:
    labels = ["time [s]"]
    columns = [history.times_s]
    for role, table in (("input", history.inputs), ("output", history.outputs)):
        for name, values in table.items():
            labels.append(format_label(name, history.unit(name), role))
            columns.append(values)
    return labels, columns


def write_time_history(history: TimeHistory, path: str | Path) -> Path:
    """Write ``history`` to ``.csv`` ('%.17g': reads back exactly) or ``.npz``, atomically; returns the path.

    Parameters
    ----------
    history : TimeHistory
        The record.
    path : path
        A ``.csv`` or ``.npz`` file.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in WRITTEN_SUFFIXES:
        raise MaceError(f"{path}: cannot write a time history as {path.suffix!r} (expected one of "
                        f"{', '.join(WRITTEN_SUFFIXES)})")
    labels, columns = _labelled_columns(history)
    with atomic_path(path) as tmp:
        if suffix == ".csv":
            np.savetxt(tmp, np.column_stack(columns), fmt="%.17g", delimiter=",", header=",".join(labels),
                       comments="")
        else:
            with open(tmp, "wb") as fh:  # a file object: np.savez would append ".npz" to the temporary name
                np.savez(fh, **dict(zip(labels, columns)))
    return path
