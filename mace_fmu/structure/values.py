"""The values of a structure file's plain tables, checked when the file is read: ``[damping]``, ``[parameters]``,
``[electronics]``, ``[servos]`` and ``[units]``.

A value outside what the physics allows is refused here, once, with the file, its line, the table and key and
what was expected, before any model is built from it: a damping ratio of 1.5 would otherwise reach an FMU
whose start value lies outside the [0, 1] it declares (every host refuses that FMU), -0.01 an unstable model.
The instruments (``[[actuators]]``, ``[[sensors]]``) are checked where they are read
(:func:`mace_fmu.iomodel.instruments.load_instruments`), the ``[modes]`` table by
:mod:`mace_fmu.structure.modes_table`; the IDs ``[parameters]`` names are checked against the deck by
:func:`mace_fmu.structure.file.check_parameters_against_deck`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mace_fmu.errors import MaceError

#: open-loop modal damping ratios: 0 (undamped) to below 1 (1 is critical damping: no vibration, no mode to
#: label); the FMUs declare their ``damping_mode_<k>`` parameters on [0, 1] (mace_fmu.parameters.kinds)
DAMPING_RANGE = (0.0, 1.0)
#: a delay [s] of a channel: from 0 up to the 1 s the FMUs declare their ``delay_<channel>`` parameters on
MAX_DELAY_S = 1.0
#: a name that becomes part of an FMU variable's name (E_<name>, k_<name>, m_<name>)
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: the keys each checked table takes
DAMPING_KEYS = ("default", "zero_frequency", "by_label", "violin_families")
PARAMETER_KEYS = {"materials": "MAT1", "springs": "CELAS2", "masses": "CONM2"}
ELECTRONICS_KEYS = ("filter_kind", "filter_order", "filter_cutoff_hz", "filter_equivalent_delay_s", "bessel_order",
                    "bessel_cutoff_hz", "bessel_equivalent_delay_s", "analog_sensors", "gyro_delays_s",
                    "actuator_delays_s")
SERVO_GAIN_KEYS = ("wheel_forward_gain", "wheel_backward_gain", "gimbal_angle_gain", "gimbal_rate_gain")
SERVO_KEYS = (*SERVO_GAIN_KEYS, "wheels", "gimbals")


def key_line(text: str, table: str, key: str | None = None) -> int:
    """1-based line of ``key`` inside ``[table]`` of a TOML text (of the table's header without a key, or when
    the key is written inline); 0 when the table is not found."""
    lines = text.splitlines()
    header = re.compile(r"^\s*\[\[?\s*" + re.escape(table) + r"\s*\]\]?\s*(#.*)?$")
    start = next((n for n, line in enumerate(lines) if header.match(line)), None)
    if start is None:
        return 0
    if key is not None:
        assignment = re.compile(r"^\s*\"?" + re.escape(key) + r"\"?\s*=")
        for n in range(start + 1, len(lines)):
            if lines[n].lstrip().startswith("["):
                break
            if assignment.match(lines[n]):
                return n + 1
    return start + 1


class _Checker:
    """One table's values, each refused with the file, its line, the table, the key and what was expected."""

    def __init__(self, path: Path, text: str, table: str) -> None:
        self.path, self.text, self.table = path, text, table

    def fail(self, key: str | None, problem: str) -> MaceError:
        line = key_line(self.text, self.table, key.split(".")[0] if key else None)
        where = f"{self.path}:{line}" if line else f"{self.path}"
        return MaceError(f"{where}: [{self.table}]{' ' + key if key else ''}: {problem}")

    def table_of(self, value: Any, key: str | None, keys: tuple[str, ...] | None = None) -> Mapping[str, Any]:
        if not isinstance(value, dict):
            raise self.fail(key, f"expected a table, got {value!r}")
        if keys is not None:
            unknown = sorted(set(value) - set(keys))
            if unknown:  # named where it is written: a key of the table itself has a line of its own
                raise self.fail(key if key else unknown[0], f"unknown key {unknown[0]!r}; expected {', '.join(keys)}")
        return value

    def number(self, value: Any, key: str, expected: str, *, low: float | None = None, high: float | None = None,
               low_open: bool = False, high_open: bool = False) -> float:
        """A finite number in [low, high] (an open end where said); else the one-line refusal."""
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(key, f"{value!r} is not a finite number (expected {expected})")
        if (low is not None and (value < low or (low_open and value == low))) or \
                (high is not None and (value > high or (high_open and value == high))):
            raise self.fail(key, f"{value!r} is out of range (expected {expected})")
        return float(value)

    def integer(self, value: Any, key: str, expected: str, *, low: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise self.fail(key, f"{value!r} (expected {expected})")
        return value


_RATIO = "a damping ratio in [0, 1): 1 or more is no vibration mode, below 0 an unstable one"


def check_damping(path: Path, text: str, table: Any) -> None:
    """``[damping]``: ``default`` and ``zero_frequency`` ratios, ``by_label`` label -> ratio, ``violin_families``
    (``order`` >= 1, ``cables`` a list of cable numbers, ``zeta`` a non-empty list of ratios)."""
    c = _Checker(path, text, "damping")
    table = c.table_of(table, None, DAMPING_KEYS)
    low, high = DAMPING_RANGE
    for key in ("default", "zero_frequency"):
        if key in table:
            c.number(table[key], key, _RATIO, low=low, high=high, high_open=True)
    by_label = c.table_of(table.get("by_label", {}), "by_label")
    for label, value in by_label.items():
        c.number(value, f"by_label.{label!r}", _RATIO, low=low, high=high, high_open=True)
    families = table.get("violin_families", [])
    if not isinstance(families, list):
        raise c.fail("violin_families", f"expected a list of tables (order, cables, zeta), got {families!r}")
    for k, family in enumerate(families, start=1):
        where = f"violin_families[{k}]"
        family = c.table_of(family, where, ("order", "cables", "zeta"))
        missing = [key for key in ("order", "cables", "zeta") if key not in family]
        if missing:
            raise c.fail(where, f"needs {', '.join(missing)} (order, cables, zeta)")
        c.integer(family["order"], f"{where}.order", "the violin order, an integer >= 1", low=1)
        cables = family["cables"]
        if not (isinstance(cables, list) and cables and all(isinstance(x, int) and not isinstance(x, bool) and x > 0
                                                            for x in cables)):
            raise c.fail(f"{where}.cables", f"{cables!r} (expected a list of cable numbers, integers >= 1)")
        zeta = family["zeta"]
        if not isinstance(zeta, list) or not zeta:
            raise c.fail(f"{where}.zeta", f"{zeta!r} (expected a non-empty list of damping ratios)")
        for value in zeta:
            c.number(value, f"{where}.zeta", _RATIO, low=low, high=high, high_open=True)


def check_parameters(path: Path, text: str, table: Any) -> None:
    """``[parameters]``: ``materials``, ``springs``, ``masses``, each a table of card ID (a positive integer, as a
    string) -> a name that can be part of an FMU variable's name, each name once per table."""
    c = _Checker(path, text, "parameters")
    table = c.table_of(table, None, tuple(PARAMETER_KEYS))
    for key, card in PARAMETER_KEYS.items():
        entries = c.table_of(table.get(key, {}), key)
        seen: dict[str, str] = {}
        for ident, name in entries.items():
            if not (ident.strip().isdigit() and int(ident) > 0):
                raise c.fail(key, f"key {ident!r} is no {card} ID (expected \"<ID>\" = \"<name>\", the ID a positive "
                                  "integer)")
            if not (isinstance(name, str) and _NAME.fullmatch(name)):
                raise c.fail(key, f"{card} {ident}: name {name!r} (expected letters, digits and '_', not starting "
                                  "with a digit: it becomes part of the FMU's parameter name)")
            if name in seen:
                raise c.fail(key, f"name {name!r} is given to {card} {seen[name]} and {card} {ident} (expected one "
                                  "card per name)")
            seen[name] = ident


def check_electronics(path: Path, text: str, table: Any) -> None:
    """``[electronics]``: the filter's order (an integer >= 0), cut-off (> 0 Hz) and equivalent delay, the sensors
    behind it (names or patterns), and the channels' delays [s]."""
    c = _Checker(path, text, "electronics")
    table = c.table_of(table, None, ELECTRONICS_KEYS)
    for key in ("filter_order", "bessel_order"):
        if key in table:
            c.integer(table[key], key, "the filter's order, an integer >= 0 (0: no filter)", low=0)
    for key in ("filter_cutoff_hz", "bessel_cutoff_hz"):
        if key in table:
            c.number(table[key], key, "the filter's -3.01 dB frequency, > 0 Hz", low=0.0, low_open=True)
    delay = f"a delay in [0, {MAX_DELAY_S:g}] s"
    for key in ("filter_equivalent_delay_s", "bessel_equivalent_delay_s"):
        if key in table:
            c.number(table[key], key, delay, low=0.0, high=MAX_DELAY_S)
    if "filter_kind" in table and not isinstance(table["filter_kind"], str):
        raise c.fail("filter_kind", f"{table['filter_kind']!r} (expected \"bessel\" or \"butterworth\")")
    sensors = table.get("analog_sensors", [])
    if not (isinstance(sensors, list) and all(isinstance(s, str) and s for s in sensors)):
        raise c.fail("analog_sensors", f"{sensors!r} (expected a list of sensor names or patterns such as \"gyro_*\")")
    for key in ("gyro_delays_s", "actuator_delays_s"):
        for channel, value in c.table_of(table.get(key, {}), key).items():
            c.number(value, f"{key}.{channel}", delay, low=0.0, high=MAX_DELAY_S)


def check_servos(path: Path, text: str, table: Any) -> None:
    """``[servos]``: the shared loop gains are finite numbers (of either sign: the sign is the loop's convention);
    the loops themselves are checked where the instruments are read."""
    c = _Checker(path, text, "servos")
    table = c.table_of(table, None, SERVO_KEYS)
    for key in SERVO_GAIN_KEYS:
        if key in table:
            c.number(table[key], key, "a finite gain")
    for key in ("wheels", "gimbals"):
        c.table_of(table.get(key, {}), key)


def check_units(path: Path, text: str, table: Any) -> None:
    """``[units]``: ``mass`` and ``length``, the labels of the units the deck is written in."""
    c = _Checker(path, text, "units")
    table = c.table_of(table, None, ("mass", "length"))
    for key, value in table.items():
        if not isinstance(value, str) or not value.strip():
            raise c.fail(key, f"{value!r} (expected a unit label such as \"kg\" or \"m\")")


#: table -> its check
CHECKS = {"damping": check_damping, "parameters": check_parameters, "electronics": check_electronics,
          "servos": check_servos, "units": check_units}


def check_values(path: Path, text: str, data: Mapping[str, Any]) -> None:
    """Every checked table of a parsed structure file (:data:`CHECKS`); the first bad value is a MaceError."""
    for table, check in CHECKS.items():
        if table in data:
            check(path, text, data[table])
