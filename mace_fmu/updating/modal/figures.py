"""Figures of the modal-test route: the stabilisation diagram and the MAC matrix."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from mace_fmu.updating.modal.identify import Identification
from mace_fmu.util.atomic import save_figure_atomic


def plot_stabilisation(identification: Identification, path: str | Path) -> Path:
    """The stabilisation diagram: every physical pole by frequency and model order (stable in frequency and
    damping, in frequency only, new), the modes taken (vertical lines), over the FRFs' summed magnitude."""
    from matplotlib.figure import Figure

    s = identification.stabilisation
    fig = Figure(figsize=(10, 5.5))
    ax = fig.add_subplot()
    magnitude = np.nansum(np.abs(identification.measured), axis=(1, 2))
    back = ax.twinx()
    back.semilogy(identification.frequencies_hz, magnitude, color="0.6", lw=0.8)
    back.set_ylabel("sum of |H| over the FRFs", color="0.4")
    ax.set_zorder(back.get_zorder() + 1)
    ax.patch.set_visible(False)
    styles = ((0, "x", "0.55", "new"), (1, "o", "tab:blue", "stable in frequency"),
              (2, "s", "tab:red", "stable in frequency and damping"))
    for status, marker, colour, label in styles:
        k = s.status == status
        ax.plot(s.frequencies_hz[k], s.orders[k], marker, ms=3.5 if status else 3, mfc="none" if status < 2 else colour,
                color=colour, ls="none", label=label)
    for m in identification.modes:
        ax.axvline(m.frequency_hz, color="k", lw=0.7, ls="--")
        ax.text(m.frequency_hz, 1.01, f"{m.frequency_hz:.3f} Hz", rotation=90, va="bottom", ha="center", fontsize=7,
                transform=ax.get_xaxis_transform())
    lo, hi = identification.band_hz
    ax.set_xlim(lo, hi)
    ax.set_ylim(0, identification.max_order + 2)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    ax.legend(loc="lower right", fontsize=8, framealpha=0.9)
    fig.suptitle(f"Stabilisation diagram ({len(identification.modes)} modes; {identification.frf_form}, "
                 f"{len(identification.files)} file(s))", fontsize=10)
    fig.tight_layout()
    return save_figure_atomic(fig, path, dpi=110)


def plot_mac(mac: np.ndarray, *, measured: Sequence[str], model: Sequence[str], path: str | Path,
             title: str = "MAC: measured against model modes") -> Path:
    """The MAC matrix as a grid of shaded cells with their values (rows: measured modes, columns: model modes)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(1.6 + 0.9 * len(model), 1.4 + 0.6 * len(measured)))
    ax = fig.add_subplot()
    ax.imshow(mac, vmin=0.0, vmax=1.0, cmap="Blues", aspect="auto")
    for i in range(mac.shape[0]):
        for j in range(mac.shape[1]):
            ax.text(j, i, f"{mac[i, j]:.2f}", ha="center", va="center", fontsize=8,
                    color="white" if mac[i, j] > 0.6 else "black")
    ax.set_xticks(range(len(model)), model, rotation=60, ha="right", fontsize=7)
    ax.set_yticks(range(len(measured)), measured, fontsize=7)
    ax.set_xlabel("model mode")
    ax.set_ylabel("measured mode")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return save_figure_atomic(fig, path, dpi=110)
