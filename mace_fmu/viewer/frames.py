"""Key frames: grid displacements over playback time, and the body transforms they give."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mace_fmu.viewer.kinematics import points_along_bars
from mace_fmu.viewer.scene import Scene


@dataclass(frozen=True)
class Clip:
    """A named stretch of the playback timeline (one mode, or one response)."""

    title: str  #: the legend's text
    start_s: float  #: playback time where the clip starts [s]
    end_s: float  #: playback time where it ends [s]
    motion_scale: float = 1.0  #: drawn metres per unit of the motion (mode: per unit mass-normalised shape)
    simulated_s_per_s: float | None = None  #: responses: simulated seconds per second of playback


@dataclass(frozen=True)
class Frames:
    """Grid displacements at playback times; translations [m] and rotations [rad] in basic axes."""

    times_s: np.ndarray  #: (n_frames,) playback time [s], uniform at ``fps``
    displacements: np.ndarray  #: (n_frames, n_grid, 6), grid rows as in Scene.grid_ids
    fps: float  #: frames per second of playback
    clips: tuple[Clip, ...]  #: the named stretches of the timeline, in order


@dataclass(frozen=True)
class BodyMotion:
    """Transforms of every body at every frame, in the deck's basic axes."""

    segment_positions_m: np.ndarray  #: (n_frames, n_segments, 3) segment mid-points
    segment_quaternions: np.ndarray  #: (n_frames, n_segments, 4) x, y, z, w: cylinder Y axis -> segment
    segment_stretch: np.ndarray  #: (n_frames, n_segments) deformed / undeformed segment length
    mass_positions_m: np.ndarray  #: (n_frames, n_masses, 3)


def _quaternions_from_y(directions: np.ndarray) -> np.ndarray:
    """Shortest-arc unit quaternions (x, y, z, w) turning +Y onto each unit direction."""
    y = np.array([0.0, 1.0, 0.0])
    axis = np.cross(y, directions)  # (…, 3)
    w = 1.0 + directions[..., 1]
    q = np.concatenate([axis, w[..., None]], axis=-1)
    # antiparallel: any axis normal to Y; X is one
    flipped = w < 1e-12
    q[flipped] = np.array([1.0, 0.0, 0.0, 0.0])
    unit: np.ndarray = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return unit


def body_motion(scene: Scene, frames: Frames) -> BodyMotion:
    """Segment mid-points, orientations and stretches, and mass positions, for every frame.

    Parameters
    ----------
    scene : Scene
        The drawn bodies.
    frames : Frames
        Grid displacements at each frame.

    Returns
    -------
    BodyMotion
        Every body's transform at every frame.
    """
    seg = scene.segments
    row_a = np.array([s.row_a for s in seg])
    row_b = np.array([s.row_b for s in seg])
    s0 = np.array([s.s0 for s in seg])
    s1 = np.array([s.s1 for s in seg])
    p0 = points_along_bars(scene, frames.displacements, s0, row_a, row_b)
    p1 = points_along_bars(scene, frames.displacements, s1, row_a, row_b)
    d = p1 - p0
    length = np.linalg.norm(d, axis=-1)
    length0 = (s1 - s0) * np.linalg.norm(scene.positions_m[row_b] - scene.positions_m[row_a], axis=-1)
    rows = np.array([m.row for m in scene.masses], dtype=int)
    return BodyMotion(segment_positions_m=0.5 * (p0 + p1),
                      segment_quaternions=_quaternions_from_y(d / length[..., None]),
                      segment_stretch=length / length0,
                      mass_positions_m=scene.positions_m[rows] + frames.displacements[:, rows, :3])
