"""The thesis's acceptance tables and side-by-side comparisons with our results."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from mace_fmu.fe.modes import StructureModes
from mace_fmu.fe.pairing import pair_by_mac
from mace_fmu.util.textfile import read_toml


@functools.cache
def thesis_data() -> dict[str, Any]:
    """Tables 3.15, 4.4 and 5.1 and the 1-g suspension frequencies (mace_fmu/data/thesis.toml)."""
    return read_toml(Path(str(resources.files("mace_fmu") / "data" / "thesis.toml")), what="thesis tables")


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
        idx = [i for i, lab in enumerate(m0.labels) if lab == ref["label"]]
        i = idx[0] if idx else int(np.argmin(np.abs(m0.frequencies_hz - ref["g0"])))
        rows.append(ComparisonRow(ref["label"], ref["g0"], float(m0.frequencies_hz[i]), m0.labels[i], i))
    return rows


def table_5_1_1g(m1: StructureModes, m0: StructureModes) -> list[ComparisonRow]:
    """1-g structural modes against Table 5.1's 1-g column, paired by MAC with the 0-g modes."""
    ref_rows = table_5_1_0g(m0)
    pairs = pair_by_mac(m0.modes, m0.model, m1.modes, [r.index for r in ref_rows])
    data = thesis_data()["table_5_1"]
    return [ComparisonRow(ref["label"], ref["g1"], float(m1.frequencies_hz[j]), m1.labels[j], j, mac)
            for ref, (_, j, mac) in zip(data, pairs)]


@dataclass(frozen=True)
class MassRow:
    """One free-free mass property about the centre node: ours next to Table 3.15."""

    name: str  #: with its unit, e.g. "mass kg"
    ours: float
    thesis: float

    @property
    def error_percent(self) -> float:
        return 100.0 * (self.ours - self.thesis) / self.thesis


def table_3_15_comparison(m0: StructureModes) -> list[MassRow]:
    """Mass [kg] and principal inertias [kg m^2] about the centre node against Table 3.15."""
    ref = thesis_data()["table_3_15"]
    p = m0.mass_properties
    j = np.diag(p.inertia_about_reference_kgm2)
    return [MassRow("mass kg", p.mass_kg, ref["mass_kg"]), MassRow("Jxx kg m^2", j[0], ref["jxx"]),
            MassRow("Jyy kg m^2", j[1], ref["jyy"]), MassRow("Jzz kg m^2", j[2], ref["jzz"])]


def format_mass_rows(rows: list[MassRow], *, title: str) -> str:
    """Plain-text table of mass properties: thesis, ours, error %."""
    lines = [title] + [f"{r.name:12s} thesis {r.thesis:8.3f}  ours {r.ours:8.4f}  error {r.error_percent:6.2f} %"
                       for r in rows]
    return "\n".join(lines)


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


@dataclass(frozen=True)
class PoleRow:
    """A closed-loop mode of the thesis next to our pole with a matching label."""

    thesis_label: str
    thesis_hz: float
    thesis_zeta: float | None
    heavy: bool  #: zeta >= 10 % in the thesis (servo-dominated)
    ours_hz: float | None  #: None when no pole of ours carries a matching label
    ours_zeta: float | None
    ours_label: str

    @property
    def error_percent(self) -> float | None:
        return None if self.ours_hz is None else 100.0 * (self.ours_hz - self.thesis_hz) / self.thesis_hz


def _pair_poles(rows: list[tuple[str, str, float, float | None, bool]], poles) -> list[PoleRow]:
    """Each thesis row takes the nearest unused pole whose label matches its pattern ("a|b": either)."""
    from mace_fmu.iomodel.pole_pairing import pair_poles

    out = []
    for (label, _, hz, zeta, heavy), i in zip(rows, pair_poles([(r[1], r[2]) for r in rows], poles,
                                                                 damping=[r[3] for r in rows])):
        if i is None:
            out.append(PoleRow(label, hz, zeta, heavy, None, None, "(none)"))
        else:
            out.append(PoleRow(label, hz, zeta, heavy, poles[i].frequency_hz, poles[i].damping, poles[i].label))
    return out


def table_4_7_comparison(poles) -> list[PoleRow]:
    """Closed-loop 1-g poles against Table 4.7's FE columns."""
    rows = [(r["label"], r["ours"], r["fe_hz"], r["fe_zeta"], r["fe_zeta"] >= 0.1) for r in thesis_data()["table_4_7"]]
    return _pair_poles(rows, poles)


def table_5_2_comparison(poles, *, column: str) -> list[PoleRow]:
    """Closed-loop poles against Table 5.2's "g1" or "g0" column (damping not tabulated)."""
    rows: list[tuple[str, str, float, float | None, bool]] = [(r["label"], r["ours"], r[column], None, r["heavy"])
                                                               for r in thesis_data()["table_5_2"]]
    return _pair_poles(rows, poles)


def format_pole_rows(rows: list[PoleRow], *, title: str) -> str:
    """Plain-text table of closed-loop poles: thesis vs ours, frequency error, damping."""
    head = f"{'thesis mode':16s} {'Hz':>7s} {'zeta':>6s} | {'ours Hz':>8s} {'zeta':>6s} {'err %':>7s}  our label"
    lines = [title, head, "-" * len(head)]
    for r in rows:
        tz = f"{r.thesis_zeta:6.3f}" if r.thesis_zeta is not None else "     -"
        if r.ours_hz is None:
            lines.append(f"{r.thesis_label:16s} {r.thesis_hz:7.2f} {tz} | {'-':>8s} {'-':>6s} {'-':>7s}  (no match)")
            continue
        mark = " *" if r.heavy else ""
        lines.append(f"{r.thesis_label:16s} {r.thesis_hz:7.2f} {tz} | {r.ours_hz:8.3f} {r.ours_zeta:6.3f} "
                     f"{r.error_percent:7.2f}  {r.ours_label}{mark}")
    lines.append("* heavily damped in the thesis (zeta >= 10 %): servo-dominated, reported, not held to 3 %")
    return "\n".join(lines)
