"""Frequency responses in CSV (real and imaginary part per output/input pair) and UFF dataset 58 files."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import DataError, MeasuredFrf
from mace_fmu.updating.files.channels import ChannelMap, Label, check_present, format_label, parse_label, resolve
from mace_fmu.updating.files.timehistory import read_csv_columns
from mace_fmu.util.atomic import atomic_path
from mace_fmu.util.textfile import read_text

FRF_SUFFIXES = (".csv", ".uff", ".unv")
_COHERENCE = re.compile(r"^coherence:(.+?) \[1\]$")
#: a response column: "re:<output>/<input> [<unit>/<unit>]", "im:..." or, complex literals, "<output>/<input> [...]"
_PAIR = re.compile(r"^(?:(re|im):)?([^/\[\]]+)/([^/\[\]]+?) \[(.*)\]$")
#: the units of a response column: "V/V" or, where a unit has a slash itself, "(m/s^2)/(N)"
_UNITS = re.compile(r"^\(([^()]*)\)/\(([^()]*)\)$|^([^/()]*)/([^/()]*)$")
#: UFF dataset 58 function type of a frequency response function (FRF)
UFF_FRF = 4
#: UFF direction codes (record 6, fields 7 and 10) and the axis names used for channels named by node
UFF_DIRECTIONS = {1: "X", 2: "Y", 3: "Z", 4: "RX", 5: "RY", 6: "RZ"}
#: the ID lines (4 and 5) that carry the model's signal names, so that a file reads back by name
UFF_OUTPUT_ID, UFF_INPUT_ID = "output: ", "input: "
#: how exactly dataset 58 states a frequency (E13.5: six significant digits), relative: half a unit of the sixth
UFF_FREQUENCY_PRECISION = 5e-6
#: how a file states the number of averages behind its estimate: a CSV comment line ``# averages = 7`` before
#: the header, UFF 58's ID line 3 ``averages: 7`` (dataset 58 has no field of its own for it)
_CSV_AVERAGES = re.compile(r"^#\s*averages\s*[=:]\s*(\S+)\s*$")
_UFF_AVERAGES = re.compile(r"^averages\s*[=:]\s*(\S+)\s*$")


def _averages(text: str, *, at: str) -> int:
    """The number of averages a file states (``text``: what follows ``averages =``), checked."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1 or str(value) != text.strip():
        raise MaceError(f"{at}: averages {text!r}, expected a whole number >= 1 (the estimate's averages)")
    return value


# --- CSV ----------------------------------------------------------------------------------------

def _pair_units(text: str, *, at: str, label: str) -> tuple[str, str]:
    """(output unit, input unit) of a response column's ``[...]``: "V/V" or "(m/s^2)/(N)"."""
    m = _UNITS.match(text.strip())
    if not m:
        raise MaceError(f"{at}: column label {label!r}: units {text!r}, expected '<output unit>/<input unit>' or, "
                        "where a unit has a slash, '(m/s^2)/(N)'")
    out_unit, in_unit = (m.group(1), m.group(2)) if m.group(1) is not None else (m.group(3), m.group(4))
    return out_unit.strip(), in_unit.strip()


def _read_csv(path: Path, channel_map: ChannelMap | None) -> MeasuredFrf:
    labels, columns, lines, header_line = read_csv_columns(path, dtype=complex)
    at = f"{path}:{header_line}"
    averages = None
    for number, line in enumerate(read_text(path).splitlines()[:header_line - 1], start=1):
        m = _CSV_AVERAGES.match(line.strip())
        if m:
            averages = _averages(m.group(1), at=f"{path}:{number}")
    first = parse_label(labels[0], where=at)
    if first.name != "frequency" or first.role is not None or first.unit != "Hz":
        raise MaceError(f"{at}: the first column is {labels[0]!r}, expected 'frequency [Hz]'")
    parts: dict[tuple[str, str], dict[str, np.ndarray]] = {}
    outputs: list[str] = []
    inputs: list[str] = []
    units: dict[str, str] = {}
    channel_of: dict[str, str] = {}
    found: set[str] = set()
    coherence: dict[str, np.ndarray] = {}

    def real(text: str, values: np.ndarray) -> np.ndarray:
        """A column that must hold real numbers (frequency, coherence, re:, im:)."""
        if np.any(values.imag != 0.0):
            k = int(np.flatnonzero(values.imag != 0.0)[0])
            raise MaceError(f"{path}:{lines[k]}: column {text!r}: {values[k]} is complex, expected a real number")
        return values.real

    frequencies = real(labels[0], columns[0])
    for text, values in zip(labels[1:], columns[1:]):
        c = _COHERENCE.match(text)
        if c:
            coherence[c.group(1).strip()] = real(text, values)  # by channel; matched to the outputs below
            continue
        m = _PAIR.match(text)
        if not m:
            raise MaceError(f"{at}: column label {text!r} is not '<output>/<input> [<unit>/<unit>]' (complex values), "
                            "'re:<output>/<input> [...]' and 'im:...', or 'coherence:<output> [1]'")
        part, out_channel, in_channel = m.group(1) or "complex", m.group(2).strip(), m.group(3).strip()
        out_unit, in_unit = _pair_units(m.group(4), at=at, label=text)
        found |= {out_channel, in_channel}
        out = _signal(Label(out_channel, out_unit, "output"), channel_map, at, "output")
        inp = _signal(Label(in_channel, in_unit, "input"), channel_map, at, "input")
        if out is None or inp is None:
            continue  # a pair with an ignored channel
        for signal, unit, channel, table in ((out, out_unit, out_channel, outputs), (inp, in_unit, in_channel, inputs)):
            if signal not in table:
                table.append(signal)
            units[signal] = units.get(signal, unit)
            channel_of[signal] = channel
        pair = parts.setdefault((out, inp), {})
        if part in pair or (part == "complex" and pair) or (part != "complex" and "complex" in pair):
            raise MaceError(f"{at}: column {text!r}: the response {out_channel}/{in_channel} is given twice")
        pair[part] = values if part == "complex" else real(text, values)
    check_present(found, channel_map=channel_map, where=at)
    if not outputs:
        raise MaceError(f"{at}: no response columns (expected '<output>/<input> [<unit>/<unit>]' with complex values, "
                        "or 're:<output>/<input> [...]' and 'im:...')")
    response = np.empty((len(columns[0]), len(outputs), len(inputs)), dtype=complex)
    for i, out in enumerate(outputs):
        for j, inp in enumerate(inputs):
            pair = parts.get((out, inp), {})
            if "complex" in pair:
                response[:, i, j] = pair["complex"]
                continue
            missing = [p for p in ("re", "im") if p not in pair]
            if missing:
                raise MaceError(f"{at}: channel {channel_of[out]!r}/{channel_of[inp]!r}: no column "
                                f"{' or '.join(f'{p}:{channel_of[out]}/{channel_of[inp]}' for p in missing)} "
                                "(every output/input pair needs a complex column, or re: and im: columns)")
            response[:, i, j] = pair["re"] + 1j * pair["im"]
    by_channel = {channel_of[out]: out for out in outputs}
    unknown = sorted(set(coherence) - set(by_channel))
    if unknown:
        raise MaceError(f"{at}: channel {unknown[0]!r}: a coherence column for a channel with no response")
    if coherence and len(coherence) != len(outputs):
        raise MaceError(f"{at}: coherence columns for {len(coherence)} of {len(outputs)} outputs (all or none)")
    gamma2 = np.column_stack([coherence[channel_of[out]] for out in outputs]) if coherence else None
    return _frd(frequencies, inputs, outputs, response, units, source=str(path),
                row_at=lambda k: f"{path}:{lines[k]}", channel_of=channel_of, coherence=gamma2, averages=averages)


def _signal(label: Label, channel_map: ChannelMap | None, at: str, role: str) -> str | None:
    """The model signal of one end of a response, None for a channel the map ignores."""
    signal, mapped_role, _ = resolve(label, channel_map=channel_map, where=at)
    if mapped_role == "ignore":
        return None
    if mapped_role != role:
        raise MaceError(f"{at}: channel {label.name!r} is used as an {role} but the channel map says {mapped_role}")
    return signal


def _frd(f, inputs, outputs, response, units, *, source, row_at, channel_of, coherence=None,
         averages=None, frequency_precision=0.0) -> MeasuredFrf:
    # The response's NaN check, located per channel pair (MeasuredFrf only knows the row).
    for i, out in enumerate(outputs):
        for j, inp in enumerate(inputs):
            bad = np.flatnonzero(~np.isfinite(response[:, i, j]))
            if bad.size:
                raise MaceError(f"{row_at(int(bad[0]))}: channel {channel_of[out]!r}/{channel_of[inp]!r}: the "
                                f"response is NaN or inf ({bad.size} of {len(f)} rows)")
    try:
        return MeasuredFrf(f, tuple(inputs), tuple(outputs), response, source=source, units=units,
                                     coherence=coherence, averages=averages, frequency_precision=frequency_precision)
    except DataError as exc:
        channel = "frequency" if exc.channel is None else channel_of.get(exc.channel, exc.channel)
        raise MaceError(f"{row_at(exc.row)}: channel {channel!r}: {exc.what}") from None


def _write_csv(frd: MeasuredFrf, path: Path) -> None:
    labels = ["frequency [Hz]"]
    columns = [frd.frequencies_hz]
    for i, out in enumerate(frd.outputs):
        for j, inp in enumerate(frd.inputs):
            format_label(out, "V"), format_label(inp, "V")  # the names must fit the label grammar
            if "/" in out or "/" in inp:
                raise MaceError(f"signal names {out!r}, {inp!r} cannot be written as a CSV pair label (no '/')")
            units = (f"({frd.unit(out)})/({frd.unit(inp)})" if "/" in frd.unit(out) + frd.unit(inp)
                     else f"{frd.unit(out)}/{frd.unit(inp)}")
            for part, values in (("re", frd.response[:, i, j].real), ("im", frd.response[:, i, j].imag)):
                labels.append(f"{part}:{out}/{inp} [{units}]")
                columns.append(values)
    if frd.coherence is not None:
        for i, out in enumerate(frd.outputs):
            labels.append(f"coherence:{out} [1]")
            columns.append(frd.coherence[:, i])
    header = ",".join(labels)
    if frd.averages is not None:
        header = f"# averages = {frd.averages}\n{header}"
    with atomic_path(path) as tmp:
        np.savetxt(tmp, np.column_stack(columns), fmt="%.17g", delimiter=",", header=header, comments="")


# --- UFF dataset 58 -----------------------------------------------------------------------------

def _uff_channel(dataset: dict, role: str) -> str:
    """The channel name of one end of a dataset 58: the ID-line name, else "<node><sign><axis>", e.g. "101+Z"."""
    id_line, prefix = ((dataset.get("id4", ""), UFF_OUTPUT_ID) if role == "output"
                       else (dataset.get("id5", ""), UFF_INPUT_ID))
    if str(id_line).startswith(prefix):
        return str(id_line)[len(prefix):].strip()
    node, direction = (dataset["rsp_node"], dataset["rsp_dir"]) if role == "output" else \
        (dataset["ref_node"], dataset["ref_dir"])
    if direction == 0:
        return str(node)
    axis = UFF_DIRECTIONS.get(abs(int(direction)), str(abs(int(direction))))
    return f"{node}{'+' if direction > 0 else '-'}{axis}"


def _uff_unit(dataset: dict, key: str) -> str:
    unit = str(dataset.get(key, "")).strip()
    return "" if unit.upper() == "NONE" else unit


def _uff_frf_datasets(path: Path) -> list[tuple[int, dict, np.ndarray, np.ndarray]]:
    """(dataset number, dataset, frequencies [Hz], complex response) of every FRF dataset 58 of a UFF file."""
    import pyuff

    if not path.is_file():
        raise MaceError(f"{path}: no such file")
    try:
        uff = pyuff.UFF(str(path))
        types = list(uff.get_set_types())
    except Exception as exc:  # pyuff raises bare Exception on files it cannot parse
        raise MaceError(f"{path}: malformed UFF file ({exc})") from None
    records = []
    for k, kind in enumerate(types, start=1):
        if int(kind) != 58:
            continue
        try:
            dataset = uff.read_sets(k - 1)
            f = np.asarray(dataset["x"], dtype=float)
            h = np.asarray(dataset["data"])
            func_type = int(dataset["func_type"])
        except Exception as exc:  # noqa: BLE001 -- pyuff's errors are bare Exceptions or KeyErrors
            raise MaceError(f"{path}: dataset {k} (type 58): malformed ({exc or type(exc).__name__})") from None
        if func_type != UFF_FRF:
            continue  # auto-spectra, coherence, time records next to the FRFs
        if f.shape != h.shape or f.ndim != 1:
            raise MaceError(f"{path}: dataset {k} (type 58): {f.size} frequencies but {h.size} values")
        if int(dataset.get("num_pts", f.size)) != f.size:
            raise MaceError(f"{path}: dataset {k} (type 58): {f.size} data points, its header (record 7) says "
                            f"{int(dataset['num_pts'])}: a truncated or malformed data block")
        if not np.iscomplexobj(h):
            raise MaceError(f"{path}: dataset {k} (type 58): real ordinate data, expected a complex FRF")
        records.append((k, dataset, f, h))
    if not records:
        raise MaceError(f"{path}: no frequency response (dataset 58 with function type {UFF_FRF}) in "
                        f"{len(types)} dataset(s) of types {sorted(set(int(t) for t in types))}")
    return records


class _UffSignals:
    """The model signals met so far in a UFF file's datasets, in order, with their units and channel names."""

    def __init__(self, channel_map: ChannelMap | None):
        self.channel_map = channel_map
        self.outputs: list[str] = []
        self.inputs: list[str] = []
        self.units: dict[str, str] = {}
        self.channel_of: dict[str, str] = {}
        self.found: set[str] = set()

    def end(self, dataset: dict, role: str, *, at: str) -> str | None:
        """The signal of one end (``role`` "output" or "input") of a dataset, None for an ignored channel."""
        unit_key, table = (("ordinate_axis_units_lab", self.outputs) if role == "output"
                           else ("orddenom_axis_units_lab", self.inputs))
        channel = _uff_channel(dataset, role)
        self.found.add(channel)
        row = self.channel_map.find(channel) if self.channel_map is not None else None
        if row is not None and row.role == "ignore":
            return None
        unit = _uff_unit(dataset, unit_key)
        if not unit:
            record = "9 (ordinate)" if role == "output" else "10 (ordinate denominator)"
            raise MaceError(f"{at}: channel {channel!r}: no units label in record {record}, expected e.g. 'V'")
        signal = _signal(Label(channel, unit, role), self.channel_map, at, role)
        if signal not in table:
            table.append(signal)
        elif self.units[signal] != unit:
            raise MaceError(f"{at}: channel {channel!r}: unit {unit!r}, an earlier dataset says {self.units[signal]!r}")
        self.units[signal] = unit
        self.channel_of[signal] = channel
        return signal

    def pair(self, out: str, inp: str) -> str:
        """``'<output channel>'/'<input channel>'`` as messages name a response."""
        return f"{self.channel_of[out]!r}/{self.channel_of[inp]!r}"


def _check_uff_response(f: np.ndarray, h: np.ndarray, *, first: tuple[int, np.ndarray], at: str) -> None:
    """A dataset's frequencies equal the first kept dataset's, and its response is finite."""
    k0, f0 = first
    if f.shape != f0.shape:
        raise MaceError(f"{at}: {f.size} frequencies, dataset {k0} has {f0.size}")
    if not np.array_equal(f, f0):
        row = int(np.flatnonzero(f != f0)[0])
        raise MaceError(f"{at}: frequency {f[row]:.6g} Hz at row {row}, dataset {k0} has {f0[row]:.6g} Hz "
                        "(every FRF needs the same frequencies)")
    bad = np.flatnonzero(~np.isfinite(h))
    if bad.size:
        raise MaceError(f"{at}: the response is NaN or inf at row {int(bad[0])} ({bad.size} of {h.size} rows)")


def _read_uff(path: Path, channel_map: ChannelMap | None) -> MeasuredFrf:
    signals = _UffSignals(channel_map)
    pairs: dict[tuple[str, str], tuple[int, np.ndarray]] = {}
    first: tuple[int, np.ndarray] | None = None  # the first kept dataset: its frequencies are everyone's
    datasets = _uff_frf_datasets(path)
    for k, dataset, f, h in datasets:
        at = f"{path}: dataset {k}"
        out, inp = (signals.end(dataset, role, at=at) for role in ("output", "input"))
        if out is None or inp is None:
            continue  # a pair with an ignored channel
        where = f"{at}: channel {signals.pair(out, inp)}"
        abscissa = _uff_unit(dataset, "abscissa_axis_units_lab")
        if abscissa and abscissa.lower() != "hz":
            raise MaceError(f"{where}: abscissa unit {abscissa!r}, expected 'Hz'")
        first = first or (k, f)
        _check_uff_response(f, h, first=first, at=where)
        if (out, inp) in pairs:
            raise MaceError(f"{where}: same pair as dataset {pairs[(out, inp)][0]}")
        pairs[(out, inp)] = (k, h)
    check_present(signals.found, channel_map=channel_map, where=str(path))
    if first is None:
        raise MaceError(f"{path}: every FRF dataset has a channel the channel map ignores")
    k0, f0 = first
    stated = {k: _averages(m.group(1), at=f"{path}: dataset {k} (ID line 3)") for k, dataset, _, _ in datasets
              for m in [_UFF_AVERAGES.match(str(dataset.get("id3", "")).strip())] if m}
    if len(set(stated.values())) > 1:
        raise MaceError(f"{path}: the datasets state different numbers of averages ("
                        + ", ".join(f"dataset {k}: {v}" for k, v in sorted(stated.items())) + "): one estimate has one")
    averages = next(iter(stated.values()), None)
    response = np.empty((f0.size, len(signals.outputs), len(signals.inputs)), dtype=complex)
    for i, out in enumerate(signals.outputs):
        for j, inp in enumerate(signals.inputs):
            if (out, inp) not in pairs:
                raise MaceError(f"{path}: channel {signals.pair(out, inp)}: no FRF dataset for this "
                                "output/input pair (every output needs one per input)")
            response[:, i, j] = pairs[(out, inp)][1]
    return _frd(f0, signals.inputs, signals.outputs, response, signals.units, source=str(path),
                row_at=lambda row: f"{path}: dataset {k0} row {row}", channel_of=signals.channel_of,
                averages=averages, frequency_precision=UFF_FREQUENCY_PRECISION)


def _uff_abscissa(f: np.ndarray) -> np.ndarray:
    """The frequencies as dataset 58 stores them (E13.5: six significant digits, UFF_FREQUENCY_PRECISION)."""
    return np.array([float(f"{x:13.5e}") for x in f])


def _write_uff(frd: MeasuredFrf, path: Path) -> None:
    import pyuff

    stored = _uff_abscissa(frd.frequencies_hz)
    if np.any(np.diff(stored) <= 0):
        k = int(np.flatnonzero(np.diff(stored) <= 0)[0]) + 1
        raise MaceError(f"{path}: frequencies {float(frd.frequencies_hz[k - 1])!r} and "
                        f"{float(frd.frequencies_hz[k])!r} Hz (rows "
                        f"{k - 1}, {k}) are equal to the six digits UFF 58 keeps; write CSV instead")
    datasets = []
    for i, out in enumerate(frd.outputs):
        for j, inp in enumerate(frd.inputs):
            for name, prefix in ((out, UFF_OUTPUT_ID), (inp, UFF_INPUT_ID)):
                if len(prefix + name) > 80 or "\n" in name:
                    raise MaceError(f"{path}: signal name {name!r} does not fit an 80-character UFF ID line")
            for unit in (frd.unit(out), frd.unit(inp)):
                if len(unit) > 20 or not unit or unit.upper() == "NONE":
                    raise MaceError(f"{path}: unit {unit!r} does not fit a UFF units label (1 to 20 characters)")
            dataset = pyuff.prepare_58(
                binary=0, id1="frequency response function", id2=frd.source[:80],
                id3="NONE" if frd.averages is None else f"averages: {frd.averages}",
                id4=UFF_OUTPUT_ID + out, id5=UFF_INPUT_ID + inp, func_type=UFF_FRF,
                rsp_node=i + 1, rsp_dir=0, ref_node=j + 1, ref_dir=0,
                data=frd.response[:, i, j].astype(complex), x=frd.frequencies_hz, abscissa_spacing=0,
                abscissa_spec_data_type=18, abscissa_axis_units_lab="Hz",  # 18: frequency
                ordinate_spec_data_type=1, ordinate_axis_units_lab=frd.unit(out),  # 1: general (volts has no code)
                orddenom_spec_data_type=1, orddenom_axis_units_lab=frd.unit(inp))
            # The axis labels are optional fields that prepare_58 does not take but the writer does.
            dataset.update(abscissa_axis_lab="frequency", ordinate_axis_lab=out[:20], orddenom_axis_lab=inp[:20])
            datasets.append(dataset)
    with atomic_path(path) as tmp:
        pyuff.UFF(str(tmp)).write_sets(datasets, mode="overwrite")


# --- public -------------------------------------------------------------------------------------

def read_frequency_response(path: str | Path, *, channel_map: ChannelMap | None = None) -> MeasuredFrf:
    """A measured frequency response H[k, output, input] from ``.csv`` or UFF dataset 58 (``.uff``/``.unv``).

    CSV: ``frequency [Hz]``, then ``re:<output>/<input> [<unit>/<unit>]`` and ``im:...`` columns
    for every output/input pair. UFF: one dataset 58 with function type 4 (FRF) per pair; the
    channel names come from ID lines 4 and 5 (``output: <name>``, ``input: <name>``, as
    :func:`write_frequency_response` writes them), else from node and direction, e.g. ``101+Z``;
    units from the ordinate (numerator and denominator) unit labels. Without a channel map the
    names are the model's signals and units must be V; with one the map translates and checks.

    Parameters
    ----------
    path : path
        A ``.csv``, ``.uff`` or ``.unv`` file.
    channel_map : ChannelMap, optional
        Data channel -> model signal, role and unit.

    Returns
    -------
    MeasuredFrf
        Frequencies [Hz] and H[k, output, input].

    Raises
    ------
    MaceError
        Naming the file, the channel and the dataset or line.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".csv":
        return _read_csv(path, channel_map)
    if suffix in (".uff", ".unv"):
        return _read_uff(path, channel_map)
    raise MaceError(f"{path}: unknown frequency-response format {path.suffix!r} (expected one of "
                    f"{', '.join(FRF_SUFFIXES)})")


def write_frequency_response(frd: MeasuredFrf, path: str | Path) -> Path:
    """Write ``frd`` to ``.csv`` ('%.17g': exact) or UFF dataset 58 ASCII (``.uff``/``.unv``), atomically.

    UFF 58 keeps six significant digits of each frequency (E13.5) and twelve of each real and
    imaginary part (pyuff writes E20.11); the signal names travel in ID lines 4 and 5.

    Parameters
    ----------
    frd : MeasuredFrf
        The frequency response.
    path : path
        A ``.csv``, ``.uff`` or ``.unv`` file.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".csv":
        _write_csv(frd, path)
    elif suffix in (".uff", ".unv"):
        _write_uff(frd, path)
    else:
        raise MaceError(f"{path}: unknown frequency-response format {path.suffix!r} (expected one of "
                        f"{', '.join(FRF_SUFFIXES)})")
    return path
