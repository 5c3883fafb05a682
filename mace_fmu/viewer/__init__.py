"""meshcat views of the MACE structure: mode shapes and FMU time responses, as standalone HTML or live."""

from mace_fmu.viewer.camera import CAMERA_VIEWS, camera_position
from mace_fmu.viewer.frames import BodyMotion, Clip, Frames, body_motion
from mace_fmu.viewer.html import standalone_html, write_html
from mace_fmu.viewer.meshcat_scene import scene_commands, send_to_visualizer
from mace_fmu.viewer.modes import ModeAnimation, animate_mode, animate_modes, mode_index
from mace_fmu.viewer.pairs import ModePair, PairAnimation, animate_pairs, pair_commands, table_5_1_pairs
from mace_fmu.viewer.response import ResponseAnimation, animate_response, grid_motion, plot_response
from mace_fmu.viewer.scene import Scene, build_scene
from mace_fmu.viewer.still import chromium_executable, render_page, write_still

__all__ = ["CAMERA_VIEWS", "BodyMotion", "Clip", "Frames", "ModeAnimation", "ModePair", "PairAnimation",
           "ResponseAnimation", "Scene", "animate_mode", "animate_modes", "animate_pairs", "animate_response",
           "animation_commands", "body_motion", "build_scene", "camera_position", "chromium_executable",
           "grid_motion", "mode_index", "pair_commands", "plot_response", "render_page", "scene_commands",
           "send_to_visualizer", "standalone_html", "table_5_1_pairs", "write_animation_html", "write_html",
           "write_still"]


def animation_commands(animation: ModeAnimation | ResponseAnimation | PairAnimation, *, camera: str = "iso") -> list:
    """The meshcat commands of any of the viewer's animations, seen from ``camera``.

    Parameters
    ----------
    animation : ModeAnimation, ResponseAnimation or PairAnimation
        The animation.
    camera : str
        A ``CAMERA_VIEWS`` key.

    Returns
    -------
    list
        meshcat commands, in the order they are to be sent.
    """
    if isinstance(animation, PairAnimation):
        return pair_commands(animation, camera=camera)
    return scene_commands(animation.scene, animation.frames, camera=camera)


def write_animation_html(animation: ModeAnimation | ResponseAnimation | PairAnimation, path, *, title: str,
                         camera: str = "iso") -> int:
    """Write a mode, response or mode-pair animation as one standalone HTML file; returns its size in bytes.

    Parameters
    ----------
    animation : ModeAnimation, ResponseAnimation or PairAnimation
        The animation.
    path : str or os.PathLike
        The HTML file to write (replaced atomically).
    title : str
        The page's title.
    camera : str
        A ``CAMERA_VIEWS`` key: the view the page opens with.

    Returns
    -------
    int
        The page's size [bytes].
    """
    return write_html(path, animation_commands(animation, camera=camera), title=title, clips=animation.frames.clips)
