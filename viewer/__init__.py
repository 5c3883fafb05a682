"""meshcat views of the MACE structure: mode shapes and FMU time responses, as standalone HTML or live."""

from viewer.camera import CAMERA_VIEWS, camera_position
from viewer.frames import BodyMotion, Clip, Frames, body_motion
from viewer.html import standalone_html, write_html
from viewer.meshcat_scene import scene_commands, send_to_visualizer
from viewer.modes import ModeAnimation, animate_mode, animate_modes, mode_index
from viewer.response import ResponseAnimation, animate_response, grid_motion, plot_response
from viewer.scene import Scene, build_scene
from viewer.still import chromium_executable, write_still

__all__ = ["CAMERA_VIEWS", "BodyMotion", "Clip", "Frames", "ModeAnimation", "ResponseAnimation", "Scene",
           "animate_mode", "animate_modes", "animate_response", "body_motion", "build_scene", "camera_position",
           "chromium_executable", "grid_motion", "mode_index", "plot_response", "scene_commands", "send_to_visualizer",
           "standalone_html", "write_animation_html", "write_html", "write_still"]


def write_animation_html(animation: ModeAnimation | ResponseAnimation, path, *, title: str,
                         camera: str = "iso") -> int:
    """Write a mode or response animation as one standalone HTML file; returns its size in bytes."""
    return write_html(path, scene_commands(animation.scene, animation.frames, camera=camera), title=title,
                      clips=animation.frames.clips)
