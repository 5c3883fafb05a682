"""Plots a person would rather look at than read: Bode overlays of the 1-g and 0-g models."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Mapping

import numpy as np
from matplotlib.figure import Figure  # no pyplot: the caller's backend and figures stay untouched

from mace_fmu.deck.cards import Deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.volts import VoltsModel, volts_model
from mace_fmu.structure.file import StructureFile
from mace_fmu.util.atomic import output_folder, save_figure_atomic

# Disturbance (secondary gimbal) to performance (payload gyro): thesis Figs. 4.15/5.1 and 4.16/5.2
CHANNELS = (
    ("gimbal_secondary_z", "gyro_payload_z", "in-plane: secondary Z gimbal -> payload Z gyro (Figs. 4.15, 5.1)"),
    ("gimbal_secondary_x", "gyro_payload_x", "out-of-plane: secondary X gimbal -> payload X gyro (Figs. 4.16, 5.2)"),
)


def channel_response(model: VoltsModel, response: np.ndarray, u: str, y: str) -> np.ndarray:
    """Complex response [V/V] of one named channel out of the model's all-channel ``response``."""
    i = list(model.system.input_labels).index(u)
    o = list(model.system.output_labels).index(y)
    return response[:, o, i]


def bode_report(deck: Deck | None = None, *, structure_file: StructureFile | str | os.PathLike | None = None,
                out_dir: str | Path = "report",
                frequencies_hz: np.ndarray | None = None, progress: Callable[[str], None] | None = None) -> list[Path]:
    """Write one PNG per channel of CHANNELS with the 1-g and 0-g models overlaid; return the paths.

    Parameters
    ----------
    deck : Deck, optional
        The deck (default: the bundled MACE deck).
    structure_file : StructureFile or path, optional
        The structure file (default: the bundled one for the bundled deck).
    out_dir : path
        Folder for the PNGs.
    frequencies_hz : numpy.ndarray, optional
        Frequencies [Hz] (default: 2000 from 0.1 to 250 Hz, log-spaced).
    progress : callable, optional
        Receives one line per stage.

    Returns
    -------
    list of Path
        The PNG files written.
    """
    out = output_folder(out_dir)  # one line naming it, not a traceback, if it cannot be made
    f = np.logspace(np.log10(0.1), np.log10(250.0), 2000) if frequencies_hz is None else frequencies_hz
    models, responses = {}, {}
    for kind in ("1g", "0g"):
        if progress:
            progress(f"{kind} volts-volts model")
        models[kind] = volts_model(compute_modes(deck, configuration=kind, structure_file=structure_file))
        responses[kind] = models[kind].frequency_response(f)  # all channels at once, then indexed
    paths = []
    for u, y, title in CHANNELS:
        curves = {f"{kind} model": channel_response(models[kind], responses[kind], u, y) for kind in ("1g", "0g")}
        paths.append(plot_bode(f, curves, title=title, path=out / f"bode_{u}_to_{y}.png"))
    return paths


def plot_bode(frequencies_hz: np.ndarray, curves: Mapping[str, np.ndarray], *, title: str, path: str | Path,
              styles: tuple[str, ...] = ("-", "--", ":", "-.")) -> Path:
    """Magnitude [V/V] and phase [deg] of several complex responses over ``frequencies_hz`` [Hz], as a PNG."""
    fig = Figure(figsize=(8, 6))
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    for (label, h), style in zip(curves.items(), styles * len(curves)):
        ax_m.loglog(frequencies_hz, np.abs(h), style, label=label)
        ax_p.semilogx(frequencies_hz, np.degrees(np.unwrap(np.angle(h))), style)
    ax_m.set_ylabel("magnitude [V/V]")
    ax_m.set_title(title, fontsize=10)
    ax_m.legend()
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [Hz]")
    ax_p.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return save_figure_atomic(fig, path, dpi=110)
