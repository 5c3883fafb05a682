"""The updated nominal 0-g model as a table: beside Table 5.3, as CSV, TOML and data."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from mace_fmu.parameters.frequency_bounds import mode_rows, read_bounds, relative_bounds, toml_scalar
from mace_fmu.thesis import thesis_data
from mace_fmu.util.atomic import output_folder, write_text_atomic
from mace_fmu.zero_g.nominal import ZeroGPrediction, ZeroGRow

CSV_COLUMNS = ("label", "nominal_hz", "damping", "bound_percent", "heavy", "adjusted", "damping_reached", "mode",
               "mode_label", "frequency_scale", "open_loop_damping", "unaltered_hz", "unaltered_damping",
               "measured_1g_hz", "measured_1g_damping", "model_1g_hz", "model_1g_damping", "pole_label",
               "shift_at_lower_bound_percent", "shift_at_upper_bound_percent")


@dataclass(frozen=True)
class ThesisRow:
    """A row of Table 5.3: nominal frequency [Hz], damping ratio, frequency bound [%] as printed."""

    label: str
    hz: float
    zeta: float
    bound_percent: float


def table_5_3() -> tuple[ThesisRow, ...]:
    """Table 5.3 of the thesis as data.

    Returns
    -------
    tuple of ThesisRow
        Mode label, nominal frequency [Hz], damping ratio and frequency bound [%], as printed.
    """
    return tuple(ThesisRow(r["label"], r["hz"], r["zeta"], r["bound_percent"]) for r in thesis_data()["table_5_3"])


def beside_table_5_3(rows: tuple[ZeroGRow, ...]) -> list[tuple[ZeroGRow, ThesisRow | None]]:
    """Each of our rows with the Table 5.3 row of the same label (the n-th of that label to the n-th)."""
    pending = list(table_5_3())
    out = []
    for row in rows:
        hit = next((k for k, t in enumerate(pending) if t.label == row.label), None)
        out.append((row, None if hit is None else pending.pop(hit)))
    return out


def bound_text(bound: float) -> str:
    """A bound as Table 5.3 prints it: percent to one decimal, halves rounded up (1.05 -> 1.1)."""
    tenths = math.floor(bound * 1000.0 + 0.5 + 1e-9)  # 1e-9: the binary 0.0105 is a hair under 1.05 %
    return f"{tenths / 10:.1f}"


def rows_as_data(prediction: ZeroGPrediction) -> list[dict]:
    """The rows as JSON-ready dicts: label, nominal_hz, damping, bound_percent, then how each was made."""
    out = []
    for r in prediction.rows:
        out.append({"label": r.label, "nominal_hz": r.nominal_hz, "damping": r.nominal_damping,
                    "bound_percent": 100.0 * r.bound, "heavy": r.heavy, "adjusted": r.adjusted,
                    "damping_reached": r.damping_reached, "mode": r.mode, "mode_label": r.mode_label,
                    "frequency_scale": r.frequency_scale,
                    "open_loop_damping": None if math.isnan(r.open_loop_damping) else r.open_loop_damping,
                    "unaltered_hz": r.unaltered_hz, "unaltered_damping": r.unaltered_damping,
                    "measured_1g_hz": r.measured_1g_hz, "measured_1g_damping": r.measured_1g_damping,
                    "model_1g_hz": r.model_1g_hz, "model_1g_damping": r.model_1g_damping, "pole_label": r.pole_label,
                    "shift_at_lower_bound_percent": None if r.closed_loop_shift is None
                    else 100.0 * r.closed_loop_shift[0],
                    "shift_at_upper_bound_percent": None if r.closed_loop_shift is None
                    else 100.0 * r.closed_loop_shift[1]})
    return out


def format_table(prediction: ZeroGPrediction) -> str:
    """Plain-text table: ours (nominal Hz, zeta, bound %) beside Table 5.3, with the 1-g residual errors.

    Parameters
    ----------
    prediction : ZeroGPrediction
        The prediction.

    Returns
    -------
    str
        The table, one row per 0-g mode.
    """
    width = max([15] + [len(row.label) for row in prediction.rows])  # MACE's labels fit 15
    head = (f"{'mode':{width}s} {'Hz':>8s} {'zeta':>7s} {'bound %':>7s} | {'T5.3 Hz':>7s} {'zeta':>6s} {'bound %':>7s} | "
            f"{'err Hz %':>8s} {'1-g err %':>9s} {'FMU k':>5s} {'shift % -b/+b':>13s}  open-loop mode adjusted")
    lines = [f"Updated nominal 0-g model and frequency bounds (thesis Table 5.3); residual 1-g errors from the "
             f"{prediction.source}", head, "-" * len(head)]
    for row, ref in beside_table_5_3(prediction.rows):
        thesis = (f"{ref.hz:7.2f} {ref.zeta:6.3f} {ref.bound_percent:7.1f}" if ref is not None else f"{'-':>7s} "
                  f"{'-':>6s} {'-':>7s}")
        diff = f"{100 * (row.nominal_hz / ref.hz - 1):8.2f}" if ref is not None else f"{'-':>8s}"
        how = (f"{row.mode_label} x{row.frequency_scale:.4f}, zeta {row.open_loop_damping:.4f}"
               if row.adjusted else "(heavily damped: not adjusted)")
        note = "" if row.damping_reached else " (damping target out of reach)"
        fmu = (f"{row.mode:5d} {100 * row.closed_loop_shift[0]:6.2f}/{100 * row.closed_loop_shift[1]:+.2f}"
               if row.closed_loop_shift is not None else f"{'-':>5s} {'-':>13s}")
        lines.append(f"{row.label:{width}s} {row.nominal_hz:8.3f} {row.nominal_damping:7.4f} {bound_text(row.bound):>7s} | "
                     f"{thesis} | {diff} {100 * row.frequency_error:9.2f} {fmu}  {how}{note}")
    rule = prediction.rule
    lines.append(f"bounds: zeta < {rule.heavy_damping:g}: max({100 * rule.minimum_bound:g} %, {rule.error_fraction:g} "
                 f"|1-g error|); heavily damped: {100 * rule.heavy_bound:g} %")
    lines.append("FMU k: the mode's frequency_scale_mode_<k>, min/max 1 -+ bound; shift: of the closed-loop pole "
                 "with the scale at 1 - bound / 1 + bound (gimbal rows: servo mechanisms, no structural frequency)")
    if prediction.dropped:
        lines.append(f"no 0-g counterpart: {', '.join(prediction.dropped)}")
    return "\n".join(lines)


def as_csv(prediction: ZeroGPrediction) -> str:
    """The rows as CSV (CSV_COLUMNS; bounds in percent)."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=CSV_COLUMNS, lineterminator="\n")
    writer.writeheader()
    for row in rows_as_data(prediction):
        writer.writerow({k: "" if row[k] is None else row[k] for k in CSV_COLUMNS})
    return buffer.getvalue()


def as_toml(prediction: ZeroGPrediction) -> str:
    """The rule and the rows as TOML ([rule], [[mode]]; bounds in percent; a mode without an FMU mode omits it)."""
    rule = prediction.rule
    lines = ["# mace-fmu predict-0g: updated nominal 0-g model and frequency bounds (thesis 5.3, Table 5.3)",
             f"source = {toml_scalar(prediction.source)}", "", "[rule]",
             f"heavy_damping = {toml_scalar(rule.heavy_damping)}", f"minimum_bound = {toml_scalar(rule.minimum_bound)}",
             f"error_fraction = {toml_scalar(rule.error_fraction)}", f"heavy_bound = {toml_scalar(rule.heavy_bound)}",
             f"correct_heavy = {toml_scalar(rule.correct_heavy)}"] + mode_rows(rows_as_data(prediction))
    return "\n".join(lines) + "\n"


def write_prediction(prediction: ZeroGPrediction, out_dir: str | Path) -> dict[str, Path]:
    """Write table_5_3.csv, table_5_3.toml, table_5_3.txt and zero_g_nominal.toml (the parameter set) into
    ``out_dir``, each atomically; returns the paths by kind.

    Parameters
    ----------
    prediction : ZeroGPrediction
        The prediction.
    out_dir : path
        The folder (created if needed).

    Returns
    -------
    dict of str to Path
        The written files by kind ("csv", "toml", "text", "parameters").
    """
    out = output_folder(out_dir)  # one line naming it, not a traceback, if it cannot be made
    return {"csv": write_text_atomic(out / "table_5_3.csv", as_csv(prediction)),
            "toml": write_text_atomic(out / "table_5_3.toml", as_toml(prediction)),
            "text": write_text_atomic(out / "table_5_3.txt", format_table(prediction) + "\n"),
            "parameters": prediction.parameters.write(out / "zero_g_nominal.toml")}


def read_frequency_bounds(path: str | Path, *, mode_labels: Sequence[str]) -> dict[int, float]:
    """The FMU frequency bounds (1-based open-loop mode -> relative bound) of a table_5_3.toml written by
    :func:`write_prediction`, checked against the open-loop ``mode_labels`` of the model they are for (the same
    mode numbers must name the same modes); rows without an FMU mode (servo mechanisms) carry none.

    Parameters
    ----------
    path : path
        A table_5_3.toml.
    mode_labels : sequence of str
        The open-loop mode labels of the model the bounds are for.

    Returns
    -------
    dict of int to float
        1-based mode -> relative bound.

    Raises
    ------
    MaceError
        A malformed file, or a mode number that names another mode in this model.
    """
    return relative_bounds(read_bounds(path), mode_labels=mode_labels, where=str(path))
