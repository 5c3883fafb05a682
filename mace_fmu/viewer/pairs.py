"""The 1-g and 0-g modes of thesis Table 5.1, paired by MAC, animated side by side in one scene.

Two copies of the article share one timeline: the 1-g (suspended) copy above the 0-g (free) one
as the picture shows them, one clip per Table 5.1 mode, with both frequencies and the 1-g to 0-g
change in the legend. Mode shapes have no sign of their own; the 0-g shape is turned to move in
phase with its 1-g partner (the sign of their mass-weighted cross product), so the two copies
swing together.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from meshcat.commands import SetTransform
from meshcat.path import Path

from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import StructureModes
from mace_fmu.fe.pairing import mac_matrix
from mace_fmu.thesis import table_5_1_0g, table_5_1_1g
from mace_fmu.util.frequency import hz_text
from mace_fmu.viewer.camera import camera_axes, framing_position
from mace_fmu.viewer.frames import Clip, Frames
from mace_fmu.viewer.html import ShownInline
from mace_fmu.viewer.meshcat_scene import (ROOT, Y_UP_TO_Z_UP, body_animations, body_commands, set_animation,
                                           surroundings_commands)
from mace_fmu.viewer.modes import ModeAnimation, animate_modes

#: Gap between the two copies' article boxes, in article lengths.
PAIR_GAP = 0.25
#: Scene paths of the two copies, under ROOT.
COPY_PATHS = {"1g": ROOT.append("one_g"), "0g": ROOT.append("zero_g")}


@dataclass(frozen=True)
class ModePair:
    """One row of Table 5.1: the same physical mode in the 1-g and the 0-g structure."""

    label: str  #: Table 5.1's name
    index_1g: int  #: 1-based, as ``mace-fmu modes 1g`` numbers it
    index_0g: int  #: 1-based, as ``mace-fmu modes 0g`` numbers it
    hz_1g: float  #: the 1-g mode's frequency [Hz]
    hz_0g: float  #: the 0-g mode's frequency [Hz]
    mac: float  #: mass-weighted MAC of the two shapes on their common grids
    sign: float  #: +1 or -1: the 0-g shape as drawn, so that it moves in phase with the 1-g one

    @property
    def change_percent(self) -> float:
        """Frequency change from 1-g to 0-g [%]: 100 (f_0g - f_1g) / f_1g."""
        return 100.0 * (self.hz_0g - self.hz_1g) / self.hz_1g

    @property
    def title(self) -> str:
        """The legend's text of this pair."""
        return (f"{self.label}: 1-g {hz_text(self.hz_1g, decimals=3)} Hz (mode {self.index_1g}) -> "
                f"0-g {hz_text(self.hz_0g, decimals=3)} Hz (mode {self.index_0g}), "
                f"{self.change_percent:+.1f} %, MAC {self.mac:.2f}")


@dataclass(frozen=True)
class PairAnimation(ShownInline):
    """Two mode animations on one timeline, and where each copy is drawn."""

    one_g: ModeAnimation  #: 1-g copy (its clips are those of ``frames``)
    zero_g: ModeAnimation  #: 0-g copy, shapes turned by each pair's sign
    pairs: tuple[ModePair, ...]  #: the pairs shown, one clip each, in order
    frames: Frames  #: the shared timeline: times and clips (displacements: the 1-g copy's)
    offsets_m: dict[str, np.ndarray]  #: "1g"/"0g": shift [m] of that copy's article centre, deck axes
    extent_m: np.ndarray  #: (3,) size of the box holding both articles, deck axes, centred on the origin
    length_m: float  #: the article's size (motion scale, camera clearance)
    view: str  #: the camera view the copies are stacked for


def table_5_1_pairs(one_g: StructureModes, zero_g: StructureModes) -> tuple[ModePair, ...]:
    """Table 5.1's rows as 1-g/0-g mode pairs, paired as ``mace-fmu build`` prints them (MAC).

    Parameters
    ----------
    one_g, zero_g : StructureModes
        The modes of the 1-g (suspended) and of the 0-g (free) structure.

    Returns
    -------
    tuple of ModePair
        One pair per row of Table 5.1, in its order.
    """
    rows_0g = table_5_1_0g(zero_g)
    rows_1g = table_5_1_1g(one_g, zero_g)
    mac = mac_matrix(zero_g.modes, zero_g.model, one_g.modes)
    common = [g for g in zero_g.modes.dofs.grid_ids if g in set(one_g.modes.dofs.grid_ids)]
    rows0 = np.concatenate([zero_g.modes.dofs.indices(g) for g in common])
    rows1 = np.concatenate([one_g.modes.dofs.indices(g) for g in common])
    weight = zero_g.model.mass[np.ix_(rows0, rows0)]
    pairs = []
    for r0, r1 in zip(rows_0g, rows_1g):
        cross = zero_g.modes.shapes[rows0, r0.index] @ weight @ one_g.modes.shapes[rows1, r1.index]
        pairs.append(ModePair(label=r0.thesis_label, index_1g=r1.index + 1, index_0g=r0.index + 1,
                              hz_1g=r1.ours_hz, hz_0g=r0.ours_hz, mac=float(mac[r0.index, r1.index]),
                              sign=1.0 if cross >= 0.0 else -1.0))
    return tuple(pairs)


def stacking_axis(view: str) -> tuple[int, float]:
    """(deck axis Y = 1 or Z = 2, sign) that points up in the picture of ``view``: the copies stack along it."""
    _, _, up = camera_axes(view)
    axis = 1 if abs(up[1]) >= abs(up[2]) else 2
    return axis, float(np.sign(up[axis]))


def animate_pairs(one_g: StructureModes, zero_g: StructureModes, *, labels: list[str] | None = None,
                  view: str = "iso", fraction_of_length: float = 0.08, cycles: int = 1,
                  frames_per_cycle: int = 16, seconds_per_cycle: float = 1.0) -> PairAnimation:
    """Key frames of Table 5.1's mode pairs (all, or those whose label starts with one of ``labels``).

    Each copy's shape is scaled so that its largest translation is ``fraction_of_length`` of the
    article's size; both play ``seconds_per_cycle`` per cycle whatever their frequency.

    Parameters
    ----------
    one_g, zero_g : StructureModes
        The modes of the 1-g (suspended) and of the 0-g (free) structure.
    labels : list of str, optional
        The starts of the Table 5.1 labels to show (default: every pair).
    view : str
        The camera view (a ``CAMERA_VIEWS`` key) the two copies are stacked for: one above the other in it.
    fraction_of_length : float
        Largest drawn translation of each shape, as a fraction of the article's size.
    cycles : int
        Vibration cycles per pair.
    frames_per_cycle : int
        Key frames per cycle.
    seconds_per_cycle : float
        Playback time of one cycle [s].

    Returns
    -------
    PairAnimation
        Both copies on one timeline, one clip per pair.

    Raises
    ------
    MaceError
        A label that starts no Table 5.1 mode.
    """
    pairs = table_5_1_pairs(one_g, zero_g)
    if labels:
        unknown = [lab for lab in labels if not any(p.label.startswith(lab) for p in pairs)]
        if unknown:
            raise MaceError(f"no Table 5.1 mode starts with {', '.join(map(repr, unknown))}; the modes are "
                            + ", ".join(p.label for p in pairs))
        pairs = tuple(p for p in pairs if any(p.label.startswith(lab) for lab in labels))
    options: dict[str, Any] = dict(fraction_of_length=fraction_of_length, cycles=cycles,
                                   frames_per_cycle=frames_per_cycle, seconds_per_cycle=seconds_per_cycle)
    anim_1g = animate_modes(one_g, [p.index_1g for p in pairs], **options)
    anim_0g = animate_modes(zero_g, [p.index_0g for p in pairs], **options)
    per_mode = cycles * frames_per_cycle
    signs = np.append(np.repeat([p.sign for p in pairs], per_mode), 1.0)  # the closing frame is at rest
    clips = tuple(Clip(title=p.title, start_s=c.start_s, end_s=c.end_s, motion_scale=c.motion_scale)
                  for p, c in zip(pairs, anim_1g.frames.clips))
    shared = Frames(times_s=anim_1g.frames.times_s, displacements=anim_1g.frames.displacements,
                    fps=anim_1g.frames.fps, clips=clips)
    turned = Frames(times_s=anim_0g.frames.times_s, displacements=signs[:, None, None] * anim_0g.frames.displacements,
                    fps=anim_0g.frames.fps, clips=clips)
    anim_0g = ModeAnimation(scene=anim_0g.scene, frames=turned, mode_indices=anim_0g.mode_indices,
                            scales=anim_0g.scales)
    anim_1g = ModeAnimation(scene=anim_1g.scene, frames=shared, mode_indices=anim_1g.mode_indices,
                            scales=anim_1g.scales)
    axis, up = stacking_axis(view)
    length = max(anim_1g.scene.length_m, anim_0g.scene.length_m)
    extent = np.maximum(anim_1g.scene.extent_m, anim_0g.scene.extent_m)
    step = extent[axis] + PAIR_GAP * length  # centre to centre
    offsets = {"1g": np.zeros(3), "0g": np.zeros(3)}
    offsets["1g"][axis], offsets["0g"][axis] = 0.5 * up * step, -0.5 * up * step
    extent = extent.copy()
    extent[axis] += step
    return PairAnimation(one_g=anim_1g, zero_g=anim_0g, pairs=pairs, frames=shared, offsets_m=offsets,
                         extent_m=extent, length_m=length, view=view)


def _placement(animation: ModeAnimation, offset_m: np.ndarray) -> np.ndarray:
    """Copy's transform under ROOT (deck axes): its article centre moved to ``offset_m``."""
    t = np.eye(4)
    t[:3, 3] = offset_m - animation.scene.centre_m
    return t


def pair_commands(animation: PairAnimation, *, camera: str | None = None) -> list[Any]:
    """Both copies, the floor under them, the camera framing both, and one animation of every body.

    Parameters
    ----------
    animation : PairAnimation
        The pairs, from :func:`animate_pairs`.
    camera : str, optional
        A ``CAMERA_VIEWS`` key; by default the view the copies were stacked for (another view may show them
        overlapping).

    Returns
    -------
    list
        meshcat commands, in the order they are to be sent.
    """
    camera = animation.view if camera is None else camera
    cmds: list[Any] = [SetTransform(Y_UP_TO_Z_UP, ROOT)]  # the pair's box is centred on the orbit target
    tracks: list[dict[str, Any]] = []
    for kind, anim in (("1g", animation.one_g), ("0g", animation.zero_g)):
        path: Path = COPY_PATHS[kind]
        cmds += body_commands(anim.scene, root=path, placement=_placement(anim, animation.offsets_m[kind]))
        tracks += body_animations(anim.scene, anim.frames, root=path)
    cmds += surroundings_commands(centre_m=np.zeros(3), extent_m=animation.extent_m, length_m=animation.length_m,
                                  camera_m=framing_position(animation.extent_m, length_m=animation.length_m,
                                                            view=camera))
    return cmds + [set_animation(tracks)]
