"""Channel maps (data-acquisition channel -> model signal, role, unit) and the ``name [unit]`` column labels."""

from __future__ import annotations

import csv
import difflib
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from mace_fmu.errors import MaceError
from mace_fmu.util.textfile import read_text

Role = Literal["input", "output", "ignore"]
ROLES: tuple[str, ...] = ("input", "output", "ignore")
MAP_COLUMNS = ("channel", "signal", "role", "unit")
#: optional column: how well an output channel's gain is known [%] (blank: exactly)
GAIN_COLUMN = "gain_uncertainty_percent"
#: role prefixes of column labels when no channel map says the role, e.g. "in:gimbal_primary_x [V]"
PREFIXES = {"in": "input", "out": "output"}
_LABEL = re.compile(r"^\s*(?:(in|out):)?\s*([^\[\]]*?)\s*\[([^\[\]]*)\]\s*$")


@dataclass(frozen=True)
class Channel:
    """One row of a channel map: a data channel, the model signal it is, and its unit in the file."""

    channel: str  #: name in the data file, e.g. "ai3" or "101+Z"
    signal: str  #: the model's signal name, e.g. "gyro_payload_z"; empty for role "ignore"
    role: Role  #: "input" (actuator command), "output" (sensor) or "ignore" (a channel to skip)
    unit: str  #: unit the file must state for this channel, e.g. "V"
    line: int = 0  #: line of the map file (0: not from a file)
    gain_uncertainty_percent: float | None = None  #: standard deviation of the sensor's gain [%]; None: exact


@dataclass(frozen=True)
class ChannelMap:
    """Data channels mapped to model signals; ``source`` names the map file in error messages."""

    channels: tuple[Channel, ...]  #: one entry per column of the data file
    source: str = "<memory>"  #: the map file

    def __post_init__(self) -> None:
        object.__setattr__(self, "channels", tuple(self.channels))
        for kind in ("channel", "signal"):
            seen: dict[str, Channel] = {}
            for ch in self.channels:
                key = getattr(ch, kind)
                if ch.role == "ignore" and kind == "signal":
                    continue
                if key in seen:
                    raise MaceError(f"{self._at(ch)}: {kind} {key!r} is mapped twice (also on line {seen[key].line})")
                seen[key] = ch
        for ch in self.channels:
            if ch.role not in ROLES:
                raise MaceError(f"{self._at(ch)}: channel {ch.channel!r}: role {ch.role!r}, expected one of "
                                f"{', '.join(ROLES)}")

    def _at(self, ch: Channel) -> str:
        return f"{self.source}:{ch.line}" if ch.line else self.source

    def find(self, channel: str) -> Channel | None:
        """The map row of a data channel, None when the map does not name it."""
        return next((ch for ch in self.channels if ch.channel == channel), None)

    def where(self, channel: Channel) -> str:
        """Where a row of this map is, for error messages: "map.csv:4"."""
        return self._at(channel)

    @property
    def inputs(self) -> tuple[str, ...]:
        """Model input signals the map names, in map order."""
        return tuple(ch.signal for ch in self.channels if ch.role == "input")

    @property
    def outputs(self) -> tuple[str, ...]:
        """Model output signals the map names, in map order."""
        return tuple(ch.signal for ch in self.channels if ch.role == "output")


def read_channel_map(path: str | Path) -> ChannelMap:
    """A channel map from CSV with columns channel, signal, role (input|output|ignore), unit and, optionally,
    gain_uncertainty_percent (an output sensor's gain known to that standard deviation [%]; blank: exactly).

    Parameters
    ----------
    path : path
        The CSV file.

    Returns
    -------
    ChannelMap
        One row per channel.

    Raises
    ------
    MaceError
        A missing column, an unknown role, an empty field, a channel or signal mapped twice, a gain
        uncertainty that is not a positive percentage or on an input: the message names the file and line.
    """
    path = Path(path)
    text = read_text(path, what="channel-map")
    lines = [(k, line) for k, line in enumerate(text.splitlines(), start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    expected = f"a header with columns {', '.join(MAP_COLUMNS)} and a row per channel"
    if not lines:
        raise MaceError(f"{path}: empty channel map (expected {expected})")
    header = [c.strip() for c in next(csv.reader([lines[0][1]]))]
    missing = [c for c in MAP_COLUMNS if c not in header]
    if missing:
        raise MaceError(f"{path}:{lines[0][0]}: missing column(s) {', '.join(missing)} (expected {expected})")
    channels = []
    for number, line in lines[1:]:
        cells = [c.strip() for c in next(csv.reader([line]))]
        if len(cells) != len(header):
            raise MaceError(f"{path}:{number}: {len(cells)} fields, the header has {len(header)}")
        row = dict(zip(header, cells))
        if row["role"] not in ROLES:
            raise MaceError(f"{path}:{number}: channel {row['channel']!r}: role {row['role']!r}, expected one of "
                            f"{', '.join(ROLES)}")
        empty = [c for c in MAP_COLUMNS if not row[c] and not (c == "signal" and row["role"] == "ignore")]
        if empty:
            raise MaceError(f"{path}:{number}: empty {', '.join(empty)} (every channel needs {', '.join(MAP_COLUMNS)})")
        channels.append(Channel(channel=row["channel"], signal=row["signal"], role=row["role"],  # type: ignore[arg-type]
                                unit=row["unit"], line=number,
                                gain_uncertainty_percent=_gain_percent(row, where=f"{path}:{number}")))
    if not channels:
        raise MaceError(f"{path}: no channels (expected {expected})")
    return ChannelMap(tuple(channels), source=str(path))


def _gain_percent(row: dict[str, str], *, where: str) -> float | None:
    """The row's gain uncertainty [%], None when the column is absent or blank; only outputs have one."""
    text = row.get(GAIN_COLUMN, "")
    if not text:
        return None
    try:
        value = float(text.rstrip("%").strip())
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise MaceError(f"{where}: {GAIN_COLUMN} {text!r} of channel {row['channel']!r}: expected a positive "
                        "percentage (or blank: the gain is exact)")
    if row["role"] != "output":
        raise MaceError(f"{where}: {GAIN_COLUMN} on channel {row['channel']!r} (role {row['role']}): only output "
                        "(sensor) gains are estimated")
    return value


@dataclass(frozen=True)
class Label:
    """A parsed column label ``[in:|out:]name [unit]``."""

    name: str
    unit: str
    role: Role | None  #: from an "in:"/"out:" prefix, None without one


def parse_label(text: str, *, where: str) -> Label:
    """``in:gimbal_primary_x [V]`` -> Label("gimbal_primary_x", "V", "input"); errors say ``where``."""
    m = _LABEL.match(text)
    if not m or not m.group(2):
        raise MaceError(f"{where}: column label {text!r} is not 'name [unit]' (e.g. 'time [s]', "
                        "'in:gimbal_primary_x [V]', 'out:gyro_bus_x [V]')")
    prefix, name, unit = m.groups()
    return Label(name=name, unit=unit.strip(), role=PREFIXES[prefix] if prefix else None)  # type: ignore[arg-type]


def format_label(name: str, unit: str, role: str | None = None) -> str:
    """The column label of a signal: ``out:gyro_bus_x [V]``; rejects names the label grammar cannot carry."""
    if not name or any(c in name for c in "[],\n\"") or name != name.strip():
        raise MaceError(f"signal name {name!r} cannot be written as a column label (no brackets, commas, quotes, "
                        "newlines or edge spaces)")
    prefix = {"input": "in:", "output": "out:"}.get(role or "", "")
    return f"{prefix}{name} [{unit}]"


def resolve(label: Label, *, channel_map: ChannelMap | None, where: str) -> tuple[str, Role, str]:
    """(model signal, role, unit) of a data column, its unit checked against the map where there is one (the
    model's units are checked where the data meet it, e.g. :meth:`FmuInterface.check_signals
    <mace_fmu.updating.fmu.model.FmuInterface.check_signals>`)."""
    if channel_map is None:
        if label.role is None:
            raise MaceError(f"{where}: channel {label.name!r}: no role; prefix it 'in:' or 'out:' "
                            f"(e.g. 'out:{label.name} [{label.unit}]') or give a channel map")
        return label.name, label.role, label.unit  # the unit travels with the data, checked against the model's
    row = channel_map.find(label.name)
    if row is None:
        close = difflib.get_close_matches(label.name, [ch.channel for ch in channel_map.channels], n=3)
        hint = f"did you mean {' or '.join(map(repr, close))}? Else add it" if close else "add it"
        raise MaceError(f"{where}: channel {label.name!r} is not in the channel map {channel_map.source} "
                        f"({hint}, with role 'ignore' to skip it)")
    if row.role == "ignore":
        return row.signal, row.role, row.unit  # skipped: neither its role nor its unit matters
    if label.role is not None and label.role != row.role:
        raise MaceError(f"{where}: channel {label.name!r} is marked {label.role}, the channel map "
                        f"{channel_map.where(row)} says {row.role}")
    if label.unit != row.unit:
        raise MaceError(f"{where}: channel {label.name!r}: unit {label.unit!r}, expected {row.unit!r} "
                        f"(channel map {channel_map.where(row)})")
    return row.signal, row.role, row.unit


def check_present(found: set[str], *, channel_map: ChannelMap | None, where: str) -> None:
    """Every channel the map names is in the file (``found``: the file's channel names)."""
    if channel_map is None:
        return
    for row in channel_map.channels:
        if row.role != "ignore" and row.channel not in found:
            raise MaceError(f"{where}: channel {row.channel!r} ({row.role} {row.signal}, channel map "
                            f"{channel_map.where(row)}) is missing from the file")
