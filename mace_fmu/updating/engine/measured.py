"""Measured data the costs compare a model with: modal parameters, frequency responses, time histories."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.util.textfile import read_text


@dataclass(frozen=True)
class MeasuredMode:
    """One mode of a measurement model: frequency [Hz] and damping ratio, and which model poles it can be.

    ``pattern`` is an fnmatch pattern of model pole labels ("a|b" for either), e.g. "* Y bending".
    """

    label: str
    pattern: str
    frequency_hz: float
    damping: float
    weight: float = 1.0  #: weight of this mode's residuals

    def __post_init__(self) -> None:
        if not (math.isfinite(self.frequency_hz) and self.frequency_hz > 0):
            raise MaceError(f"measured mode {self.label!r}: frequency must be a positive number, got "
                            f"{self.frequency_hz!r}")
        if not (math.isfinite(self.damping) and 0.0 <= self.damping < 1.0):
            raise MaceError(f"measured mode {self.label!r}: damping ratio must be in [0, 1), got {self.damping!r}")
        if not (math.isfinite(self.weight) and self.weight >= 0):
            raise MaceError(f"measured mode {self.label!r}: weight must be >= 0, got {self.weight!r}")


MEASURED_COLUMNS = ("label", "pattern", "frequency_hz", "damping")


def read_measured_modes(path: str | Path) -> tuple[MeasuredMode, ...]:
    """A measurement model's modes from CSV: columns label, pattern, frequency_hz, damping [, weight].

    Parameters
    ----------
    path : path
        The CSV file. ``pattern`` says which model poles a row can be paired with (fnmatch of pole
        labels, "a|b" for either), e.g. "* Y bending"; ``frequency_hz`` [Hz], ``damping`` (ratio),
        ``weight`` (default 1).

    Returns
    -------
    tuple of MeasuredMode
        One per row, in the file's order.

    Raises
    ------
    MaceError
        A missing column, an empty file, a value that is not a number or out of range: the message
        names the file, the row and the column.
    """
    import csv

    path = Path(path)
    text = read_text(path, what="measured-modes")
    rows = list(csv.DictReader(text.splitlines()))
    expected = f"a header with columns {', '.join(MEASURED_COLUMNS)} [, weight]"
    if not rows:
        raise MaceError(f"{path}: no measured modes (expected {expected} and a row per mode)")
    missing = [c for c in MEASURED_COLUMNS if c not in rows[0]]
    if missing:
        raise MaceError(f"{path}: missing column(s) {', '.join(missing)} (expected {expected})")
    modes = []
    for k, row in enumerate(rows, start=2):  # row 1 is the header
        try:
            numbers = {c: float(row[c]) for c in ("frequency_hz", "damping")}
            weight = float(row["weight"]) if row.get("weight") not in (None, "") else 1.0
        except (TypeError, ValueError):
            raise MaceError(f"{path}:{k}: frequency_hz, damping and weight must be numbers, got "
                            f"{row.get('frequency_hz')!r}, {row.get('damping')!r}, {row.get('weight')!r}") from None
        try:
            modes.append(MeasuredMode(label=row["label"], pattern=row["pattern"], weight=weight, **numbers))
        except MaceError as exc:
            raise MaceError(f"{path}:{k}: {exc}") from None
    return tuple(modes)


class DataError(MaceError):
    """Bad samples in measured data, located by ``channel`` and ``row`` (the 0-based sample index).

    File readers catch it and say where the sample sits in the file (line, dataset); ``what`` is
    the message without the location, e.g. "is not finite (NaN or inf)".
    """

    def __init__(self, message: str, *, source: str, what: str, channel: str | None = None,
                 row: int | None = None) -> None:
        self.source = source
        self.what = what  #: the problem, without the location
        self.channel = channel  #: the channel or signal, None for the time or frequency column
        self.row = row  #: 0-based sample index, None when not about one sample
        super().__init__(message)

    def __reduce__(self):  # keep keyword-only arguments picklable
        return (_rebuild_data_error, (str(self), self.source, self.what, self.channel, self.row))


def _rebuild_data_error(message: str, source: str, what: str, channel: str | None, row: int | None) -> DataError:
    return DataError(message, source=source, what=what, channel=channel, row=row)


def _finite(name: str, values: np.ndarray, source: str, channel: str | None = None) -> None:
    bad = np.flatnonzero(~np.isfinite(values).reshape(values.shape[0], -1).all(axis=1))
    if bad.size:
        what = f"value is NaN or inf ({bad.size} of {values.shape[0]} rows)"
        raise DataError(f"{source}: {name} is not finite (NaN or inf) at row {int(bad[0])} "
                        f"({bad.size} rows in all)", source=source, what=what, channel=channel, row=int(bad[0]))


def _units(units: Mapping[str, str], signals: tuple[str, ...], source: str) -> dict[str, str]:
    """Every signal's unit, "V" (the model boundary) where ``units`` does not say."""
    unknown = sorted(set(units) - set(signals))
    if unknown:
        raise MaceError(f"{source}: units given for unknown signal(s) {', '.join(unknown)}")
    return {name: str(units.get(name, "V")) for name in signals}


@dataclass(frozen=True)
class MeasuredFrf:
    """Measured H[k, output, input] at ``frequencies_hz`` [Hz], signals named as the model's.

    Frequency first: not python-control's ``FrequencyResponseData``, whose responses are (output, input, k).
    """

    frequencies_hz: np.ndarray  #: frequencies [Hz]
    inputs: tuple[str, ...]  #: input names of the columns
    outputs: tuple[str, ...]  #: output names of the rows
    response: np.ndarray  #: complex (k, output, input)
    source: str = "<memory>"  #: the file it was read from
    units: Mapping[str, str] = field(default_factory=dict)  #: signal -> unit; "V" where not given
    coherence: np.ndarray | None = None  #: (k, output) multiple coherence of each output with all inputs
    #: the number of averages (Welch segments) behind the estimate and its coherence; None where not stated
    averages: int | None = None
    #: how exactly the file states each frequency, relative: half a unit of the last digit it keeps (5e-6 for UFF
    #: 58's E13.5, six significant digits); 0 for a file that keeps them exactly (CSV '%.17g', an estimate in memory)
    frequency_precision: float = 0.0

    def __post_init__(self) -> None:
        f = np.asarray(self.frequencies_hz, dtype=float)
        h = np.asarray(self.response, dtype=complex)
        object.__setattr__(self, "frequencies_hz", f)
        object.__setattr__(self, "response", h)
        object.__setattr__(self, "inputs", tuple(self.inputs))
        object.__setattr__(self, "outputs", tuple(self.outputs))
        if f.ndim != 1 or f.size == 0:
            raise MaceError(f"{self.source}: frequencies must be a non-empty vector")
        _finite("frequency", f, self.source)
        if np.any(np.diff(f) <= 0) or f[0] < 0:
            k = int(np.flatnonzero(np.diff(f) <= 0)[0]) + 1 if np.any(np.diff(f) <= 0) else 0
            raise DataError(f"{self.source}: frequencies must be >= 0 and increasing (row {k})", source=self.source,
                            what="frequencies must be >= 0 and increasing", row=k)
        if h.shape != (f.size, len(self.outputs), len(self.inputs)):
            raise MaceError(f"{self.source}: response has shape {h.shape}, expected "
                            f"({f.size}, {len(self.outputs)}, {len(self.inputs)}) (frequency, output, input)")
        _finite("the response", h, self.source)
        object.__setattr__(self, "units", _units(self.units, self.outputs + self.inputs, self.source))
        if self.coherence is not None:
            c = np.asarray(self.coherence, dtype=float)
            if c.shape != (f.size, len(self.outputs)):
                raise MaceError(f"{self.source}: coherence has shape {c.shape}, expected ({f.size}, "
                                f"{len(self.outputs)}) (frequency, output)")
            bad = ~np.isfinite(c) | (c < 0) | (c > 1)
            if bad.any():
                k, i = (int(x) for x in np.argwhere(bad)[0])
                what = f"coherence {float(c[k, i])!r}, expected a number in [0, 1]"
                raise DataError(f"{self.source}: output {self.outputs[i]!r}: {what} at row {k}", source=self.source,
                                what=what, channel=self.outputs[i], row=k)
            object.__setattr__(self, "coherence", c)
        if not (isinstance(self.frequency_precision, (int, float)) and 0.0 <= self.frequency_precision < 1e-2):
            raise MaceError(f"{self.source}: frequency_precision {self.frequency_precision!r}, expected a relative "
                            "precision in [0, 0.01) (5e-6 for six significant digits)")
        if self.averages is not None and not (isinstance(self.averages, (int, np.integer)) and self.averages >= 1):
            raise MaceError(f"{self.source}: averages {self.averages!r}, expected a whole number >= 1 (the Welch "
                            "segments or analyser averages behind the estimate)")

    def lines(self, keep: np.ndarray) -> MeasuredFrf:
        """The same data at the lines ``keep`` (a boolean mask or indices), coherence and averages kept."""
        return MeasuredFrf(self.frequencies_hz[keep], self.inputs, self.outputs, self.response[keep],
                                     source=self.source, units=self.units,
                                     coherence=None if self.coherence is None else self.coherence[keep],
                                     averages=self.averages, frequency_precision=self.frequency_precision)

    def unit(self, signal: str) -> str:
        """The unit of an input or output signal, e.g. "V"; the response's unit is output unit / input unit."""
        return self.units[signal]


@dataclass(frozen=True)
class TimeHistory:
    """Measured inputs and outputs [model units] sampled at uniformly spaced ``times_s`` [s]."""

    times_s: np.ndarray  #: sample times [s]
    inputs: Mapping[str, np.ndarray]  #: input name -> samples [V]
    outputs: Mapping[str, np.ndarray]  #: output name -> samples [V]
    source: str = "<memory>"  #: the file it was read from
    units: Mapping[str, str] = field(default_factory=dict)  #: signal -> unit; "V" where not given

    def __post_init__(self) -> None:
        t = np.asarray(self.times_s, dtype=float)
        object.__setattr__(self, "times_s", t)
        if t.ndim != 1 or t.size < 2:
            raise MaceError(f"{self.source}: the time column needs at least two samples")
        _finite("time", t, self.source)
        dt = np.diff(t)
        if np.any(dt <= 0):
            k = int(np.flatnonzero(dt <= 0)[0]) + 1
            raise DataError(f"{self.source}: time is not increasing at row {k}", source=self.source,
                            what=f"time is not increasing ({float(t[k - 1])!r} s, then {float(t[k])!r} s)", row=k)
        uneven = ~np.isclose(dt, dt[0], rtol=1e-6, atol=0.0)
        if uneven.any():
            k = int(np.flatnonzero(uneven)[0]) + 1  # the first sample off the grid, as a file reader reports it
            raise DataError(f"{self.source}: samples are not uniformly spaced (step {dt[0]:.6g} s, but "
                            f"{dt[k - 1]:.6g} s at row {k})", source=self.source, row=k,
                            what=f"samples are not uniformly spaced (step {dt[0]:.6g} s, but {dt[k - 1]:.6g} s here)")
        for table in ("inputs", "outputs"):
            signals = {name: np.asarray(v, dtype=float) for name, v in getattr(self, table).items()}
            for name, v in signals.items():
                if v.shape != t.shape:
                    raise MaceError(f"{self.source}: channel {name!r} has {v.size} samples, time has {t.size}")
                _finite(f"channel {name!r}", v, self.source, channel=name)
            object.__setattr__(self, table, signals)
        if not self.outputs:
            raise MaceError(f"{self.source}: no output channels")
        both = set(self.inputs) & set(self.outputs)
        if both:
            raise MaceError(f"{self.source}: signal(s) {', '.join(sorted(both))} are both input and output")
        object.__setattr__(self, "units", _units(self.units, tuple(self.inputs) + tuple(self.outputs), self.source))

    def unit(self, signal: str) -> str:
        """The unit of an input or output signal, e.g. "V"."""
        return self.units[signal]

    @property
    def sample_time_s(self) -> float:
        return float(self.times_s[1] - self.times_s[0])

    def head(self, samples: int) -> TimeHistory:
        """The first ``samples`` samples of the record."""
        return TimeHistory(self.times_s[:samples], {k: v[:samples] for k, v in self.inputs.items()},
                           {k: v[:samples] for k, v in self.outputs.items()},
                           source=f"{self.source} (first {samples} samples)", units=self.units)
