"""Mode-shape animations: each mode as sin(w t) of its scaled mass-normalised shape."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import StructureModes
from mace_fmu.util.frequency import hz_text
from mace_fmu.viewer.frames import Clip, Frames
from mace_fmu.viewer.html import ShownInline
from mace_fmu.viewer.scene import Scene, build_scene


@dataclass(frozen=True)
class ModeAnimation(ShownInline):
    """A scene and its key frames, plus which mode each clip shows and the scale used."""

    scene: Scene  #: the drawn bodies
    frames: Frames  #: key frames of every mode, one clip per mode
    mode_indices: tuple[int, ...]  #: 1-based, as ``mace-fmu modes`` prints them
    scales: tuple[float, ...]  #: metres of drawn displacement per unit of mass-normalised shape


def mode_index(structure_modes: StructureModes, mode: int | str) -> int:
    """1-based index of a mode given by index or by label (exact, then unique prefix).

    Parameters
    ----------
    structure_modes : StructureModes
        The modes, with their labels.
    mode : int or str
        A 1-based index (or its digits), or a label or the unique start of one.

    Returns
    -------
    int
        The mode's 1-based index.

    Raises
    ------
    MaceError
        No such mode, or a label that names none or several.
    """
    labels = structure_modes.labels
    count = structure_modes.frequencies_hz.size
    if isinstance(mode, (int, np.integer)) or (isinstance(mode, str) and mode.isdigit()):
        index = int(mode)
        if not 1 <= index <= count:
            raise MaceError(f"mode {index} does not exist: modes are numbered 1 to {count}")
        return index
    exact = [i for i, lab in enumerate(labels) if lab == mode]
    matches = exact or [i for i, lab in enumerate(labels) if lab.startswith(mode)]
    if len(matches) != 1:
        found = ", ".join(f"{i + 1}: {labels[i]}" for i in matches[:8]) or "none"
        raise MaceError(f"mode label {mode!r} must name exactly one mode; matches: {found}")
    return matches[0] + 1


def grid_shape(structure_modes: StructureModes, index: int) -> np.ndarray:
    """(n_grid, 6) mass-normalised shape of 1-based mode ``index``, basic axes."""
    return structure_modes.modes.shapes[:, index - 1].reshape(-1, 6)


def readable_scale(scene: Scene, shape: np.ndarray, fraction_of_length: float) -> float:
    """Scale that makes the largest grid translation ``fraction_of_length`` of the structure's size."""
    largest = float(np.linalg.norm(shape[:, :3], axis=1).max())
    return fraction_of_length * scene.length_m / largest if largest > 0 else 0.0


def animate_modes(structure_modes: StructureModes, modes: Sequence[int | str], *, scale: float | None = None,
                  fraction_of_length: float = 0.08, cycles: int = 1, frames_per_cycle: int = 16,
                  seconds_per_cycle: float = 1.0, segments_per_bar: int = 4) -> ModeAnimation:
    """Key frames of several modes, one after the other on one timeline (one clip per mode).

    Playback is slowed to ``seconds_per_cycle`` per vibration cycle whatever the frequency, so
    the drawn displacement is shape x scale x sin(2 pi t / seconds_per_cycle). ``scale`` [m per
    unit shape] defaults to the one that makes the largest translation ``fraction_of_length`` of
    the structure's size.

    Parameters
    ----------
    structure_modes : StructureModes
        The computed modes and the structure they belong to.
    modes : sequence of int or str
        The modes to play, in order: 1-based indices or labels (see :func:`mode_index`).
    scale : float, optional
        Drawn displacement [m] per unit of mass-normalised shape, the same for every mode; by default
        each mode's own, from ``fraction_of_length``.
    fraction_of_length : float
        Largest drawn translation of each mode, as a fraction of the structure's size.
    cycles : int
        Vibration cycles per mode (1 or more).
    frames_per_cycle : int
        Key frames per cycle (4 or more).
    seconds_per_cycle : float
        Playback time of one cycle [s].
    segments_per_bar : int
        Pieces each bar is drawn in.

    Returns
    -------
    ModeAnimation
        The scene, the key frames (one clip per mode) and the scales used.
    """
    if cycles < 1 or frames_per_cycle < 4 or not seconds_per_cycle > 0:
        raise MaceError(f"need cycles >= 1, frames_per_cycle >= 4 and seconds_per_cycle > 0 [s], got {cycles}, "
                        f"{frames_per_cycle} and {seconds_per_cycle}")
    if scale is not None and not np.isfinite(scale):
        raise MaceError(f"scale must be a finite number of metres per unit shape, got {scale}")
    scene = build_scene(structure_modes, segments_per_bar=segments_per_bar)
    indices = tuple(mode_index(structure_modes, m) for m in modes)
    if not indices:
        raise MaceError("no modes to animate")
    per_mode = cycles * frames_per_cycle  # the last frame of a clip equals the first of the next
    phase = 2.0 * np.pi * np.arange(per_mode) / frames_per_cycle
    blocks, scales, clips = [], [], []
    fps = frames_per_cycle / seconds_per_cycle
    for k, index in enumerate(indices):
        shape = grid_shape(structure_modes, index)
        sc = readable_scale(scene, shape, fraction_of_length) if scale is None else float(scale)
        scales.append(sc)
        blocks.append(np.sin(phase)[:, None, None] * (sc * shape)[None])
        hz = structure_modes.frequencies_hz[index - 1]
        label = structure_modes.labels[index - 1] if structure_modes.labels else ""
        label = "" if label == f"mode {index}" else label  # NASTRAN's modes: the label says nothing more
        clips.append(Clip(title=f"mode {index}: {hz_text(hz, decimals=3)} Hz {label}".rstrip(),
                          start_s=k * per_mode / fps, end_s=(k + 1) * per_mode / fps, motion_scale=sc))
    blocks.append(np.zeros((1,) + blocks[0].shape[1:]))  # close the loop at rest
    displacements = np.concatenate(blocks)
    frames = Frames(times_s=np.arange(displacements.shape[0]) / fps, displacements=displacements, fps=fps,
                    clips=tuple(clips))
    return ModeAnimation(scene=scene, frames=frames, mode_indices=indices, scales=tuple(scales))


def animate_mode(structure_modes: StructureModes, mode: int | str, *, scale: float | None = None,
                 cycles: int = 3, **options: Any) -> ModeAnimation:
    """Key frames of one mode (by 1-based index or label).

    Parameters
    ----------
    structure_modes : StructureModes
        The computed modes and the structure they belong to.
    mode : int or str
        The 1-based index or the label of the mode (see :func:`mode_index`).
    scale : float, optional
        Drawn displacement [m] per unit of mass-normalised shape (default: from the structure's size).
    cycles : int
        Vibration cycles to play.
    **options
        The other options of :func:`animate_modes`.

    Returns
    -------
    ModeAnimation
        The scene and the key frames of the mode.
    """
    return animate_modes(structure_modes, [mode], scale=scale, cycles=cycles, **options)
