"""Frequency bounds: an open-loop mode's frequency known within +-b (thesis 5.3, Table 5.3).

A bound is written in percent (Table 5.3, ``table_5_3.toml``, SSV files, ``--bound MODE=PERCENT``) and used as a
relative bound b, the declared range [1 - b, 1 + b] of the mode's ``frequency_scale_mode_<k>``. The ``[[mode]]``
rows of a bounds file (``mode``, ``mode_label``, ``bound_percent``) are read and written here alone.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from mace_fmu.errors import MaceError


@dataclass(frozen=True)
class FrequencyBound:
    """The uncertainty of one open-loop mode's frequency (Table 5.3): +-``bound_percent`` % of it."""

    mode: int  #: 1-based open-loop mode number of the model
    mode_label: str  #: its label, checked against the model the bounds are applied to
    bound_percent: float  #: 1.1 for +-1.1 % (as Table 5.3 and table_5_3.toml give it)

    @property
    def relative(self) -> float:
        """The bound as a fraction (0.011 for +-1.1 %)."""
        return self.bound_percent / 100.0


def relative_bound(value: object, *, what: str) -> float:
    """``value`` as a relative bound b in [0, 1) (0.011 for +-1.1 %); a MaceError naming ``what`` otherwise."""
    number = float(value) if isinstance(value, numbers.Real) and not isinstance(value, bool) else math.nan
    if not 0.0 <= number < 1.0:
        raise MaceError(f"{what}: {value!r} is not a relative bound in [0, 1) (0.011 for +-1.1 %)")
    return number


def scale_range(bound: float) -> tuple[float, float]:
    """[1 - b, 1 + b]: the range of a frequency scale its mode's relative bound b declares."""
    return 1.0 - bound, 1.0 + bound


def relative_bounds(bounds: Iterable[FrequencyBound], *, mode_labels: Sequence[str] | None = None,
                    where: str = "frequency bounds") -> dict[int, float]:
    """1-based mode -> relative bound; with ``mode_labels`` (the open-loop labels of the model the bounds are for)
    each mode number must name the same mode there (a MaceError, naming ``where``, otherwise)."""
    out: dict[int, float] = {}
    for b in bounds:
        if mode_labels is not None and (b.mode > len(mode_labels) or mode_labels[b.mode - 1] != b.mode_label):
            have = mode_labels[b.mode - 1] if b.mode <= len(mode_labels) else "no such mode"
            raise MaceError(f"{where}: mode {b.mode} is {b.mode_label!r} there but {have!r} in this model (made "
                            "with other options or parameters?)")
        out[b.mode] = b.relative
    return out


def read_bounds(path: str | Path) -> tuple[FrequencyBound, ...]:
    """The bounds of a file of ``[[mode]]`` rows: a ``table_5_3.toml`` of ``mace-fmu predict-0g`` or what
    ``params from-ssv`` writes; rows without ``mode`` (servo mechanisms) carry none."""
    from mace_fmu.util.textfile import read_toml

    rows = read_toml(path, what="frequency-bounds").get("mode")
    if not isinstance(rows, list) or not rows:
        raise MaceError(f"{path}: no [[mode]] rows (expected the table_5_3.toml of mace-fmu predict-0g)")
    out = []
    for k, row in enumerate(rows, start=1):
        if "mode" not in row:
            continue  # a servo mechanism: no FMU mode, no bound to carry
        mode, label, percent = row.get("mode"), row.get("mode_label"), row.get("bound_percent")
        if isinstance(mode, bool) or not isinstance(mode, int) or mode < 1 or not isinstance(label, str) \
                or isinstance(percent, bool) or not isinstance(percent, (int, float)) or not 0.0 <= percent < 100.0:
            raise MaceError(f"{path}: [[mode]] {k}: expected mode >= 1, mode_label and bound_percent in [0, 100), "
                            f"got mode = {mode!r}, mode_label = {label!r}, bound_percent = {percent!r}")
        out.append(FrequencyBound(mode=mode, mode_label=label, bound_percent=float(percent)))
    return tuple(out)


def toml_scalar(value: object) -> str:
    """A bool, string, integer or float as a TOML value (floats to the last digit)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    return repr(float(value)) if isinstance(value, float) else str(value)


def mode_rows(rows: Iterable[Mapping[str, object]]) -> list[str]:
    """``[[mode]]`` rows as TOML lines, each row's keys in order (None values left out), a blank line before each."""
    lines: list[str] = []
    for row in rows:
        lines += ["", "[[mode]]"] + [f"{k} = {toml_scalar(v)}" for k, v in row.items() if v is not None]
    return lines


def bounds_toml(bounds: Iterable[FrequencyBound], *, comment: str) -> str:
    """The bounds as the ``[[mode]]`` rows :func:`read_bounds` reads, after a ``# comment`` line."""
    return "\n".join([f"# {comment}"] + mode_rows({"mode": b.mode, "mode_label": b.mode_label,
                                                   "bound_percent": float(b.bound_percent)} for b in bounds)) + "\n"
