"""The thesis's acceptance tables and side-by-side comparisons with our results."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np

from mace_fmu.fe.pairing import pair_by_mac
from mace_fmu.pipeline import StructureModes


def thesis_data() -> dict[str, Any]:
    """Tables 3.15, 4.4 and 5.1 and the 1-g suspension frequencies (mace_fmu/data/thesis.toml)."""
    return tomllib.loads((resources.files("mace_fmu") / "data" / "thesis.toml").read_text())


@dataclass(frozen=True)
class ComparisonRow:
    """One mode: ours next to the thesis."""

    thesis_label: str
    thesis_hz: float
    ours_hz: float
    ours_label: str
    index: int  #: our mode index (0-based)
    mac: float | None = None  #: shape correlation used for the pairing (1-g only)

    @property
    def error_percent(self) -> float:
        return 100.0 * (self.ours_hz - self.thesis_hz) / self.thesis_hz


def table_5_1_0g(m0: StructureModes) -> list[ComparisonRow]:
    """0-g flexible modes in frequency order against Table 5.1's 0-g column (paired by label)."""
    rows = []
    for ref in thesis_data()["table_5_1"]:
        idx = [i for i, lab in enumerate(m0.modes.labels) if lab == ref["label"]]
        i = idx[0] if idx else int(np.argmin(np.abs(m0.modes.frequencies_hz - ref["g0"])))
        rows.append(ComparisonRow(ref["label"], ref["g0"], float(m0.modes.frequencies_hz[i]), m0.modes.labels[i], i))
    return rows


def table_5_1_1g(m1: StructureModes, m0: StructureModes) -> list[ComparisonRow]:
    """1-g structural modes against Table 5.1's 1-g column, paired by MAC with the 0-g modes."""
    ref_rows = table_5_1_0g(m0)
    pairs = pair_by_mac(m0.modes, m0.model, m1.modes, [r.index for r in ref_rows])
    data = thesis_data()["table_5_1"]
    return [ComparisonRow(ref["label"], ref["g1"], float(m1.modes.frequencies_hz[j]), m1.modes.labels[j], j, mac)
            for ref, (_, j, mac) in zip(data, pairs)]


def format_rows(rows: list[ComparisonRow], *, title: str) -> str:
    """Plain-text table: thesis label, thesis Hz, ours Hz, error %, our label (and MAC)."""
    has_mac = any(r.mac is not None for r in rows)
    head = f"{'thesis mode':24s} {'thesis Hz':>9s} {'ours Hz':>9s} {'error %':>8s}  {'our label':28s}" + \
        (" MAC" if has_mac else "")
    lines = [title, head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.thesis_label:24s} {r.thesis_hz:9.2f} {r.ours_hz:9.3f} {r.error_percent:8.2f}  "
                     f"{r.ours_label:28s}" + (f" {r.mac:.2f}" if r.mac is not None else ""))
    return "\n".join(lines)


def format_side_by_side(columns: dict[str, list[ComparisonRow]], *, title: str) -> str:
    """One row per thesis mode, one (Hz, error %) pair per result column (e.g. per preload)."""
    names = list(columns)
    head = f"{'thesis mode':24s} {'thesis Hz':>9s}" + "".join(f" {n + ' Hz':>12s} {'err %':>6s}" for n in names) + \
        "  label (ours)"
    lines = [title, head, "-" * len(head)]
    for i, first in enumerate(columns[names[0]]):
        cells = "".join(f" {columns[n][i].ours_hz:12.3f} {columns[n][i].error_percent:6.2f}" for n in names)
        labels = {columns[n][i].ours_label for n in names}
        lines.append(f"{first.thesis_label:24s} {first.thesis_hz:9.2f}{cells}  {' / '.join(sorted(labels))}")
    return "\n".join(lines)
