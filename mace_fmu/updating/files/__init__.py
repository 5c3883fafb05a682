"""Measured data files test labs write: time histories (CSV, npz, LabVIEW's lvm), frequency responses (CSV, UFF 58),
H1.

Signals are named as the model's and are in its units at the boundary (volts for MACE, N or m/s^2
for a force input or an accelerometer without a gain); a channel map translates a data acquisition's
channel names and states each channel's unit. Bad data raise ``MaceError`` naming
the file, the channel and the row.
"""

from __future__ import annotations

from pathlib import Path

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.h1 import h1_estimate
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory
from mace_fmu.updating.files.channels import Channel, ChannelMap, read_channel_map
from mace_fmu.updating.files.frequency import FRF_SUFFIXES, read_frequency_response, write_frequency_response
from mace_fmu.updating.files.signals import check_model_signals
from mace_fmu.updating.files.timehistory import TIME_SUFFIXES, read_time_history, write_time_history

__all__ = ["Channel", "ChannelMap", "read_channel_map", "read_time_history", "write_time_history",
           "read_frequency_response", "write_frequency_response", "h1_estimate", "read_measured_data",
           "check_model_signals"]


def read_measured_data(path: str | Path, *, channel_map: ChannelMap | None = None,
                       sample_time_s: float | None = None) -> TimeHistory | MeasuredFrf:
    """A time history (``.npz``, LabVIEW's ``.lvm``, CSV from ``time [s]``) or a frequency response (UFF, CSV from
    ``frequency [Hz]``).

    Parameters
    ----------
    path : path
        ``.npz``, ``.lvm``, ``.uff``, ``.unv`` or ``.csv`` (its first column says which).
    channel_map : ChannelMap, optional
        Data channel -> model signal, role and unit.
    sample_time_s : float, optional
        For a time history: the sample time [s] it must have.

    Returns
    -------
    TimeHistory or MeasuredFrf
        What the file holds.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".uff", ".unv"):
        return read_frequency_response(path, channel_map=channel_map)
    if suffix in (".npz", ".lvm"):
        return read_time_history(path, channel_map=channel_map, sample_time_s=sample_time_s)
    if suffix == ".csv":
        if _first_label(path).startswith("frequency"):
            return read_frequency_response(path, channel_map=channel_map)
        return read_time_history(path, channel_map=channel_map, sample_time_s=sample_time_s)
    raise MaceError(f"{path}: unknown measured-data format {path.suffix!r} (expected one of "
                    f"{', '.join(sorted(set(TIME_SUFFIXES + FRF_SUFFIXES)))})")


def _first_label(path: Path) -> str:
    """The first column label of a CSV file (after '#' comment lines), lower case; "" when there is none."""
    try:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                if line.strip() and not line.lstrip().startswith("#"):
                    return line.split(",")[0].strip().lower()
    except FileNotFoundError:
        raise MaceError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MaceError(f"{path}: cannot read: {exc}") from None
    return ""
