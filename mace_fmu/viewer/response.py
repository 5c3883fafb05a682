"""Time-response animations: an FMU's grid motion outputs played on the mesh, and a plot of the signals."""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import StructureModes
from mace_fmu.iomodel.motion import MOTION_COMPONENTS, motion_output_name
from mace_fmu.util.atomic import save_figure_atomic
from mace_fmu.viewer.frames import Clip, Frames
from mace_fmu.viewer.html import ShownInline
from mace_fmu.viewer.scene import Scene, build_scene

if TYPE_CHECKING:  # fmpy is imported only where an FMU runs
    from mace_fmu.fmu.simulate import FmuRun


@dataclass(frozen=True)
class ResponseAnimation(ShownInline):
    """A scene, its key frames, and which FMU samples they show at which magnification."""

    scene: Scene  #: the drawn bodies
    frames: Frames  #: key frames of the run, one clip
    sample_indices: np.ndarray  #: the FMU communication point behind each frame
    scale: float  #: drawn metres per metre of computed motion (and radians per radian)
    playback_speed: float  #: simulated seconds per second of playback


def grid_motion(run: FmuRun, scene: Scene) -> np.ndarray:
    """(n_samples, n_grid, 6) motion [m, rad] of the scene's grids from the ``grid_<id>_<c>`` outputs.

    Every grid a body is drawn from must have its six outputs; other grids stay at rest.

    Parameters
    ----------
    run : FmuRun
        An FMU run whose outputs include the grids' motion.
    scene : Scene
        The drawn structure: its grids, in its order.

    Returns
    -------
    numpy.ndarray
        (n_samples, n_grid, 6) translations [m] and rotations [rad], basic axes.

    Raises
    ------
    MaceError
        A drawn grid without its motion outputs.
    """
    drawn = sorted({r for s in scene.segments for r in (s.row_a, s.row_b)} | {m.row for m in scene.masses})
    motion = np.zeros((run.times_s.size, len(scene.grid_ids), 6))
    missing = []
    for row, grid in enumerate(scene.grid_ids):
        names = [motion_output_name(grid, c) for c in MOTION_COMPONENTS]
        if all(n in run.outputs for n in names):
            motion[:, row] = np.stack([run.outputs[n] for n in names], axis=1)
        elif row in drawn:
            missing.append(grid)
    if missing:
        raise MaceError(f"the FMU has no motion outputs for grid(s) {missing[:10]}{' ...' if len(missing) > 10 else ''}"
                        "; export it with motion outputs (mace-fmu export --motion-grids all)")
    return motion


def animate_response(structure_modes: StructureModes, run: FmuRun, *, scale: float | None = None,
                     fraction_of_length: float = 0.08, playback_speed: float = 1.0, fps: float = 50.0,
                     segments_per_bar: int = 4) -> ResponseAnimation:
    """Key frames of an FMU run: each frame is one communication point's motion x ``scale``.

    Playback runs at ``playback_speed`` simulated seconds per second (1 = real time, 0.1 = ten
    times slower). Frames are every k-th communication point, with k chosen so the frame rate is
    as close to ``fps`` as the step allows. ``scale`` defaults to the magnification that makes the
    largest translation over the run ``fraction_of_length`` of the structure's size.

    Parameters
    ----------
    structure_modes : StructureModes
        The structure the FMU was exported from (its scene is drawn).
    run : FmuRun
        The FMU run, with the grids' motion outputs.
    scale : float, optional
        Drawn metres per metre of computed motion (default: from ``fraction_of_length``).
    fraction_of_length : float
        Largest drawn translation over the run, as a fraction of the structure's size.
    playback_speed : float
        Simulated seconds per second of playback.
    fps : float
        The frame rate aimed at [frames per second of playback].
    segments_per_bar : int
        Pieces each bar is drawn in.

    Returns
    -------
    ResponseAnimation
        The scene, the key frames (one clip) and the samples they show.
    """
    if not (playback_speed > 0 and fps > 0):
        raise MaceError(f"playback_speed and fps must be > 0, got {playback_speed} and {fps}")
    if scale is not None and not np.isfinite(scale):
        raise MaceError(f"scale must be a finite magnification, got {scale}")
    scene = build_scene(structure_modes, segments_per_bar=segments_per_bar)
    motion = grid_motion(run, scene)
    step_s = float(run.times_s[1] - run.times_s[0]) if run.times_s.size > 1 else 1.0
    stride = max(1, int(round(playback_speed / (fps * step_s))))
    samples = np.arange(0, run.times_s.size, stride)
    largest = float(np.linalg.norm(motion[..., :3], axis=-1).max())
    if scale is None:
        scale = fraction_of_length * scene.length_m / largest if largest > 0 else 1.0
    frame_fps = playback_speed / (stride * step_s)
    times = run.times_s[samples] / playback_speed
    inputs = ", ".join(run.inputs)
    clip = Clip(title=f"response to {inputs}: {run.times_s[-1]:.3g} s simulated at {playback_speed:g}x",
                start_s=0.0, end_s=float(times[-1]), motion_scale=float(scale), simulated_s_per_s=float(playback_speed))
    frames = Frames(times_s=times, displacements=float(scale) * motion[samples], fps=frame_fps, clips=(clip,))
    return ResponseAnimation(scene=scene, frames=frames, sample_indices=samples, scale=float(scale),
                             playback_speed=float(playback_speed))


def plot_response(run: FmuRun, *, output_name: str, path: str | Path, title: str = "") -> Path:
    """PNG of the driven input [V] and one output over time [s], stacked.

    Parameters
    ----------
    run : FmuRun
        The FMU run.
    output_name : str
        The output to plot under the input.
    path : str or pathlib.Path
        The PNG to write (replaced atomically).
    title : str
        The figure's title.

    Returns
    -------
    pathlib.Path
        The PNG written.
    """
    if output_name not in run.outputs:
        raise MaceError(f"no output {output_name!r} in this run; outputs: {', '.join(list(run.outputs)[:30])}")
    fig = Figure(figsize=(8, 5))  # no pyplot: the caller's matplotlib backend stays as it is
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1, sharex=True)
    (input_name, held), shown = next(iter(run.inputs.items())), run.outputs[output_name]
    axes[0].step(run.times_s, held, where="post", lw=1.0)  # the FMU holds its input over each step
    axes[1].plot(run.times_s, shown, lw=1.0)
    for ax, name in zip(axes, (input_name, output_name)):
        ax.set_ylabel(f"{name} [{run.units.get(name, '')}]")
        ax.set_title(textwrap.shorten(run.descriptions.get(name, ""), width=110), fontsize=8, loc="left")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return save_figure_atomic(fig, path, dpi=110)
