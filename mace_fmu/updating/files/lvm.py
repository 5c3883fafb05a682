"""Time histories in LabVIEW measurement files (``.lvm``), as LabVIEW's "Write To Measurement File" writes them.

The file (NI's "LabVIEW Measurement File Format") is text: a file header (``LabVIEW Measurement``, the
separator, the decimal separator, whether there is one time column, one per channel or none:
``X_Columns One|Multi|No``), then one or more segments, each with a header of one column per channel
(``Channels``, ``Samples``, ``Y_Unit_Label``, ``X_Dimension``, ``X0``, ``Delta_X``) and the data under a line of
channel names that starts with ``X_Value``. The parsing is ``lvm_read``'s; what this module adds is the
meaning: each channel's name and unit from the header, mapped through a channel map as a CSV file's columns
are; the time axis from the header's X0 and Delta_X (the X column keeps six decimals, coarser than the
sample time of a fast record), checked against the X column where there is one; segments joined in order;
errors that name the file, the line and the channel.

LabVIEW writes its units' names (DAQmx's "Volts", "Newtons"): those with an SI symbol are read as it
(:data:`UNIT_SYMBOLS`), so that the data meet an FMU's units; any other label is kept as written, unless the
channel map states the channel in an SI unit it converts to (:data:`CONVERSIONS`: "Pounds" read as N, "g" as
m/s^2, when the map's unit says N or m/s^2).

A file resampled after LabVIEW wrote it (every n-th row kept, the header left as it was) has an X column on a
clock of its own and a header whose ``Samples`` is not its number of rows: its times are the X column's, a
uniform clock to a quarter of its step; an X column that disagrees with a header that may be its own is refused,
naming both clocks.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import TimeHistory
from mace_fmu.updating.files.channels import PREFIXES, ChannelMap, Label

#: LabVIEW's (DAQmx's) unit names that have an SI symbol; other labels ("g", "m/s^2", "strain") are kept
UNIT_SYMBOLS = {"volts": "V", "volt": "V", "amps": "A", "amperes": "A", "newtons": "N", "newton": "N",
                "meters": "m", "metres": "m", "pascals": "Pa", "seconds": "s", "hertz": "Hz", "kilograms": "kg",
                "newton meters": "N m", "newton metres": "N m"}


#: (LabVIEW's unit label, lower case; the channel map's unit) -> the factor from the first to the second: a
#: record in pounds-force or in g read as N or m/s^2 when the map says so (exact by definition: the
#: international pound and standard gravity)
CONVERSIONS = {("pounds", "N"): 4.4482216152605, ("pound", "N"): 4.4482216152605, ("lbf", "N"): 4.4482216152605,
               ("lb", "N"): 4.4482216152605, ("g", "m/s^2"): 9.80665, ("g", "m/s2"): 9.80665,
               ("inches", "m"): 0.0254, ("in", "m"): 0.0254, ("millivolts", "V"): 1e-3, ("mv", "V"): 1e-3}


def unit_symbol(label: str) -> str:
    """The SI symbol of a LabVIEW unit name ("Volts" -> "V"); any other label as it is, stripped."""
    text = label.strip()
    return UNIT_SYMBOLS.get(text.lower(), text)


def read_lvm_time_history(path: str | Path, *, channel_map: ChannelMap | None = None,
                          sample_time_s: float | None = None) -> TimeHistory:
    """Measured inputs and outputs from a LabVIEW measurement file (module docstring).

    Each channel is named by the line of names over its data and has the unit of its ``Y_Unit_Label``
    (an SI symbol for LabVIEW's unit names: "Volts" is read as "V"). Without a channel map a channel's name
    carries its role, ``in:<signal>`` or ``out:<signal>``, as a CSV file's labels do; with one the map
    gives signal, role and unit, and the header's unit, where it states one, must be the map's or one that
    converts to it (:data:`CONVERSIONS`: "Pounds" to N, "g" to m/s^2). Times are X0 + k Delta_X of the header
    (the X column, where written, must agree to half a sample), or the X column's own uniform clock where the
    header's ``Samples`` is not the segment's number of rows (a file resampled after LabVIEW wrote it).

    Parameters
    ----------
    path : path
        The ``.lvm`` file.
    channel_map : ChannelMap, optional
        Data channel -> model signal, role and unit.
    sample_time_s : float, optional
        The sample time [s] the file must have.

    Returns
    -------
    TimeHistory
        Times [s], inputs and outputs by model signal name, each signal's unit.

    Raises
    ------
    MaceError
        A file that is not a LabVIEW measurement file, a channel without a unit and no map to state it, a
        unit that is not the map's, a time column that disagrees with the header, segments with different
        channels, a cell that is not a number: the message names the file, the line and the channel.
    """
    from mace_fmu.updating.files.timehistory import history_of_columns

    path = Path(path)
    lines = _lvm_text(path).splitlines()
    if not lines or not lines[0].startswith("LabVIEW Measurement"):
        first = lines[0][:40] if lines else ""
        raise MaceError(f"{path}:1: not a LabVIEW measurement file (its first line is {first!r}, expected "
                        "'LabVIEW Measurement')")
    separator = _separator(lines)
    import lvm_read

    try:
        lvm = lvm_read.read_lines([line + "\n" for line in lines], separator=separator)
    except (ValueError, SyntaxError, IndexError, KeyError) as exc:
        raise MaceError(f"{path}: not a readable LabVIEW measurement file ({type(exc).__name__}: {exc})") from None
    # each segment's data start under its line of names (lvm_read starts a segment at each blank line)
    name_lines = [k for k, line in enumerate(lines, start=1) if line.split(separator)[0] == "X_Value"]
    layout = str(lvm.get("X_Columns", "One")).strip()
    if len(name_lines) != lvm["Segments"]:
        raise MaceError(f"{path}: {lvm['Segments']} segments but {len(name_lines)} lines of channel names "
                        "('X_Value ...'): a segment header without data, or data without a header")
    times, columns, line_of_sample = [], None, []
    first_names: list[str] = []
    units: dict[str, str | None] = {}
    for s in range(lvm["Segments"]):
        segment, at = lvm[s], name_lines[s]
        names, seg_times, seg_columns, seg_units = _segment(path, segment, at=at, layout=layout)
        if s == 0:
            first_names, units = names, seg_units
            columns = [[] for _ in names]
        elif names != first_names:
            raise MaceError(f"{path}:{at}: this segment's channels {names} are not the first segment's "
                            f"{first_names} (line {name_lines[0]}): one record, one set of channels")
        times.append(seg_times)
        for store, values in zip(columns, seg_columns):
            store.append(values)
        line_of_sample.extend(range(at + 1, at + 1 + seg_times.size))
    t = np.concatenate(times)
    data = [np.concatenate(parts) for parts in columns]

    def row_at(sample: int | None) -> str:
        return f"{path}:{line_of_sample[sample]}" if sample is not None and sample < len(line_of_sample) else f"{path}"

    labels = [_label(path, name, units[name], channel_map=channel_map, at=name_lines[0]) for name in first_names]
    data = [values * _to_map_unit(units[name], channel_map=channel_map, name=name)
            for name, values in zip(first_names, data)]
    try:
        return history_of_columns(path, labels, t, data, channel_map=channel_map, sample_time_s=sample_time_s,
                                  header_at=f"{path}:{name_lines[0]}", row_at=row_at)
    except MaceError as exc:
        raise _with_cell(exc, lines, separator, line_of_sample, first_names, layout) from None


def _lvm_text(path: Path) -> str:
    """The file's text: UTF-8, else the Windows code page LabVIEW writes on Windows ("°C" as one byte)."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise MaceError(f"{path}: no such time-history file") from None
    except OSError as exc:
        raise MaceError(f"{path}: cannot read: {exc}") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")


def _separator(lines: list[str]) -> str:
    """The column separator the file header names (``Separator Tab`` or ``Separator Comma``; tab by default)."""
    for line in lines[:30]:
        if line.startswith("Separator") and len(line) > 9:
            return line[9]
        if line.startswith("***End_of_Header***"):
            break
    return "\t"


def _per_channel(segment: dict, key: str, count: int, layout: str) -> list:
    """The header row ``key`` of a segment, one entry per channel (None where it is absent or empty); with a
    time column per channel (``X_Columns Multi``) each channel's entry is every second one."""
    values = segment.get(key)
    if values is None:
        return [None] * count
    if isinstance(values, str):
        values = [values]
    step = 2 if layout == "Multi" else 1
    out = []
    for c in range(count):
        v = values[c * step] if c * step < len(values) else None
        if isinstance(v, str):
            v = v.strip() or None
        elif isinstance(v, float) and math.isnan(v):
            v = None
        out.append(v)
    return out


def _segment(path: Path, segment: dict, *, at: int, layout: str):
    """(channel names, times [s], columns, units by channel) of one segment; ``at``: the line of its names."""
    header = list(segment.get("Channel names", []))
    if header and header[-1] == "Comment":
        header = header[:-1]
    data = np.asarray(segment.get("data"), dtype=float)
    if data.ndim != 2 or data.shape[0] < 1:
        raise MaceError(f"{path}:{at}: a segment without data lines under its channel names")
    if data.shape[1] < len(header):
        data = np.hstack([data, np.full((data.shape[0], len(header) - data.shape[1]), np.nan)])
    x_columns = [j for j, name in enumerate(header) if name == "X_Value"]
    channels = [(j, name.strip()) for j, name in enumerate(header) if name != "X_Value"]
    names = [name for _, name in channels]
    if not names:
        raise MaceError(f"{path}:{at}: no channels in the line of names (expected 'X_Value' and a name per channel)")
    count = len(names)
    dimension = _per_channel(segment, "X_Dimension", count, layout)
    for name, dim in zip(names, dimension):
        if dim is not None and dim != "Time":
            raise MaceError(f"{path}:{at}: channel {name!r}: X_Dimension {dim!r}, expected 'Time' (a time history; "
                            "a spectrum is not one)")
    delta = _per_channel(segment, "Delta_X", count, layout)
    x0 = _per_channel(segment, "X0", count, layout)
    samples = _per_channel(segment, "Samples", count, layout)
    # a channel LabVIEW wrote no samples of (an empty column, "Samples 0") has a Delta_X of nothing
    written = [not (n_c == 0 or np.all(np.isnan(data[:, j]))) for n_c, (j, _) in zip(samples, channels)]
    steps = {d for d, w in zip(delta, written) if d is not None and w}
    if len(steps) > 1:
        raise MaceError(f"{path}:{at}: the channels' Delta_X differ ({', '.join(f'{d:g}' for d in sorted(steps))} "
                        "s): one record, one sample time")
    n = data.shape[0]
    column_of_time = x_columns[0] if x_columns else None
    if steps:
        dt = float(steps.pop())
        if not (math.isfinite(dt) and dt > 0):
            raise MaceError(f"{path}:{at}: Delta_X {dt!r}, expected a positive sample time [s]")
        start = next((float(v) for v, w in zip(x0, written) if v is not None and w), None)
        if start is None:
            start = float(data[0, column_of_time]) if column_of_time is not None else 0.0
        t = start + dt * np.arange(n)
        for j in x_columns:  # the X columns LabVIEW wrote, to their six decimals: within half a sample
            off = np.flatnonzero(~(np.abs(data[:, j] - t) <= 0.5 * dt))
            if off.size:
                t = _column_clock(path, data[:, j], header_dt=dt, header_samples=samples, k=int(off[0]), at=at,
                                  header_t=t)
    elif column_of_time is not None:
        t = data[:, column_of_time]
    else:
        raise MaceError(f"{path}:{at}: neither a Delta_X in the segment header nor an X_Value column: no times")
    units = dict(zip(names, _per_channel(segment, "Y_Unit_Label", count, layout)))
    return names, t, [data[:, j] for j, _ in channels], units


def _column_clock(path: Path, x: np.ndarray, *, header_dt: float, header_samples: list, k: int, at: int,
                  header_t: np.ndarray) -> np.ndarray:
    """The times of a segment whose X column is not the header's clock (``k``: its first sample off it by more
    than half a sample): the column's own uniform clock where the header is not this segment's (its ``Samples``
    is not the segment's number of rows: a file resampled or cut after LabVIEW wrote it, its header kept, as
    the downsampled files of a public record are); else a MaceError that names both clocks."""
    n = x.size
    step = float(x[-1] - x[0]) / (n - 1) if n > 1 else math.nan
    counts = {int(c) for c in header_samples if c is not None and not (isinstance(c, float) and math.isnan(c))}
    uniform = (math.isfinite(step) and step > 0
               and bool(np.all(np.abs(x - (x[0] + step * np.arange(n))) <= 0.25 * step)))
    line = f"{path}:{at + 1 + k}: channel 'time': X_Value {float(x[k]):.9g} s, but the header's X0 and Delta_X " \
           f"({header_dt:.9g} s) put this sample at {header_t[k]:.9g} s"
    if not uniform:
        raise MaceError(f"{line}: samples a uniform clock did not take")
    if counts and counts != {n}:
        return float(x[0]) + step * np.arange(n)
    said = f"Samples {counts.pop()}, the rows it has" if counts else "no Samples count to tell"
    raise MaceError(f"{line}: the X column is a uniform clock of {step:.6g} s ({1 / step:.5g} Hz), the header's "
                    f"Delta_X {header_dt:.9g} s ({1 / header_dt:.6g} Hz), and the header ({said}) gives no sign of "
                    "being another record's: one of them is wrong; correct Delta_X, or write the file without "
                    "an X column if the header is right")


def _label(path: Path, name: str, unit: str | None, *, channel_map: ChannelMap | None, at: int) -> Label:
    """The parsed label of channel ``name``: its role from an "in:"/"out:" prefix, its unit the header's (an SI
    symbol), or the map's where the header states none or names the same unit."""
    role, bare = None, name
    prefix, sep, rest = name.partition(":")
    if sep and prefix in PREFIXES and rest.strip():
        role, bare = PREFIXES[prefix], rest.strip()
    row = channel_map.find(bare) if channel_map is not None else None
    if channel_map is None and role is None:
        raise MaceError(f"{path}:{at}: channel {bare!r}: no role; give a channel map (--map CSV with columns "
                        f"channel, signal, role, unit) or name the channel 'in:{bare}' or 'out:{bare}' in LabVIEW")
    if unit is None:
        if row is None:
            raise MaceError(f"{path}:{at}: channel {bare!r} has no unit in the header (no Y_Unit_Label): give a "
                            "channel map (--map) that states each channel's unit")
        return Label(name=bare, unit=row.unit, role=role)
    symbol = unit_symbol(unit)
    if row is not None and (unit_symbol(row.unit) == symbol or (unit.strip().lower(), row.unit) in CONVERSIONS):
        symbol = row.unit
    return Label(name=bare, unit=symbol, role=role)


def _to_map_unit(unit: str | None, *, channel_map: ChannelMap | None, name: str) -> float:
    """The factor from a channel's unit in the header to the channel map's unit for it (:data:`CONVERSIONS`;
    1 where they are the same or the map does not name the channel)."""
    if unit is None or channel_map is None:
        return 1.0
    _, sep, rest = name.partition(":")
    row = channel_map.find(name) or (channel_map.find(rest.strip()) if sep else None)
    return CONVERSIONS.get((unit.strip().lower(), row.unit), 1.0) if row is not None else 1.0


def _with_cell(exc: MaceError, lines: list[str], separator: str, line_of_sample: list[int], names: list[str],
               layout: str) -> MaceError:
    """``exc`` with the cell that is not a number quoted, where it says a value is NaN (a cell lvm_read could not
    read: the message names the file, the line and the channel)."""
    text = str(exc)
    if "NaN or inf" not in text:
        return exc
    head, _, rest = text.partition(": channel ")
    try:
        number = int(head.rsplit(":", 1)[1])
        channel = rest.split("'")[1]
    except (IndexError, ValueError):
        return exc
    if channel not in names or number < 1 or number > len(lines):
        return exc
    c = names.index(channel)
    column = {"Multi": 2 * c + 1, "No": c + 1}.get(layout, c + 1)
    cells = lines[number - 1].split(separator)
    cell = cells[column] if column < len(cells) else ""
    what = "an empty cell" if not cell.strip() else f"{cell.strip()!r}"
    return MaceError(f"{head}: channel {channel!r}: {what} is not a number")
