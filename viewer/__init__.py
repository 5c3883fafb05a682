"""meshcat views of the MACE structure: mode-shape animations as standalone HTML or on a live server."""

from viewer.frames import BodyMotion, Clip, Frames, body_motion
from viewer.html import standalone_html, write_html
from viewer.meshcat_scene import scene_commands, send_to_visualizer
from viewer.modes import ModeAnimation, animate_mode, animate_modes, mode_index
from viewer.scene import Scene, build_scene

__all__ = ["BodyMotion", "Clip", "Frames", "ModeAnimation", "Scene", "animate_mode", "animate_modes", "body_motion",
           "build_scene", "mode_index", "scene_commands", "send_to_visualizer", "standalone_html", "write_html",
           "write_mode_html"]


def write_mode_html(animation: ModeAnimation, path, *, title: str) -> int:
    """Write a mode animation as one standalone HTML file; returns its size in bytes."""
    return write_html(path, scene_commands(animation.scene, animation.frames), title=title,
                      clips=animation.frames.clips)
