"""LabVIEW measurement files (.lvm) written as LabVIEW's "Write To Measurement File" writes them.

The layout is NI's "LabVIEW Measurement File Format" (ni.com/tutorial/4139) as the files of lvm_read's own test
data show it (github.com/ladisk/lvm_read, data/short.lvm, multi_time_column.lvm, with_empty_fields.lvm): a file
header ending in ``***End_of_Header***``, a blank line, then per segment a channel header (Channels, Samples,
Date, Time, Y_Unit_Label, X_Dimension, X0, Delta_X), its own ``***End_of_Header***``, the line of names that
starts with ``X_Value`` and ends with ``Comment``, and the data; a blank line between segments. The X column
keeps six decimals, as LabVIEW's default format does; the other cells six decimals too (``%.6f``), here
``%.9g`` so that a test's numbers survive the file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np


def write_lvm(path: Path, times_s: np.ndarray, channels: Mapping[str, tuple[str, np.ndarray]], *,
              segments: int = 1, decimal: str = ".", x_columns: str = "One",
              cells: Mapping[tuple[int, str], str] | None = None
              ) -> Path:
    """Write ``channels`` (name -> (unit label, samples)) over ``times_s`` [s] as LabVIEW does.

    ``segments`` splits the record into that many segments, each with its own header (X0 its first time);
    ``decimal`` is the decimal separator (LabVIEW writes the system's); ``x_columns`` "One" (a time column),
    "No" (none: times from X0 and Delta_X) or "Multi" (one before each channel); ``cells`` replaces the text
    of (sample, channel) cells, for broken files.
    """
    names = list(channels)
    dt = float(times_s[1] - times_s[0])
    sep = "\t"

    def number(x: float) -> str:
        return f"{x:.9g}".replace(".", decimal)

    def per_channel(values: list[str]) -> str:
        if x_columns == "Multi":
            return sep.join(v + sep for v in values)
        return sep.join(values) + sep

    lines = ["LabVIEW Measurement" + sep, "Writer_Version" + sep + "2", "Reader_Version" + sep + "2",
             "Separator" + sep + "Tab", "Decimal_Separator" + sep + decimal,
             "Multi_Headings" + sep + ("Yes" if x_columns == "Multi" else "No"), "X_Columns" + sep + x_columns,
             "Time_Pref" + sep + "Relative", "Operator" + sep + "lab", "Date" + sep + "2026/01/15",
             "Time" + sep + "10:21:07" + decimal + "25", "***End_of_Header***" + sep, ""]
    bounds = np.linspace(0, times_s.size, segments + 1).astype(int)
    for s in range(segments):
        a, b = bounds[s], bounds[s + 1]
        count = len(names)
        lines += [f"Channels{sep}{count}{sep * (count if x_columns != 'Multi' else 2 * count - 1)}",
                  "Samples" + sep + per_channel([str(b - a)] * count),
                  "Date" + sep + per_channel(["2026/01/15"] * count),
                  "Time" + sep + per_channel(["10:21:07" + decimal + "25"] * count),
                  "Y_Unit_Label" + sep + per_channel([channels[n][0] for n in names]),
                  "X_Dimension" + sep + per_channel(["Time"] * count),
                  "X0" + sep + per_channel([f"{times_s[a]:.16E}".replace(".", decimal)] * count),
                  "Delta_X" + sep + per_channel([number(dt)] * count),
                  "***End_of_Header***" + sep * (count + 1)]
        if x_columns == "One":
            head = ["X_Value", *names]
        elif x_columns == "No":
            head = ["X_Value", *names]
        else:
            head = [x for n in names for x in ("X_Value", n)]
        lines.append(sep.join([*head, "Comment"]))
        for k in range(a, b):
            row = [(cells or {}).get((k, n), number(float(channels[n][1][k]))) for n in names]
            x = f"{times_s[k]:.6f}".replace(".", decimal)
            if x_columns == "One":
                cells_out = [x, *row]
            elif x_columns == "No":
                cells_out = ["", *row]
            else:
                cells_out = [c for v in row for c in (x, v)]
            lines.append(sep.join(cells_out))
        if s < segments - 1:
            lines.append("")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
