"""meshcat views of the MACE structure: mode shapes and FMU time responses, as standalone HTML or live."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mace_fmu.util.lazy import lazy_exports

if TYPE_CHECKING:  # what editors and type checkers follow; at run time a name is imported on first use (meshcat)
    from mace_fmu.viewer.animation import animation_commands, write_animation_html
    from mace_fmu.viewer.camera import CAMERA_VIEWS, camera_position
    from mace_fmu.viewer.frames import BodyMotion, Clip, Frames, body_motion
    from mace_fmu.viewer.html import standalone_html, write_html
    from mace_fmu.viewer.meshcat_scene import scene_commands, send_to_visualizer
    from mace_fmu.viewer.modes import ModeAnimation, animate_mode, animate_modes, mode_index
    from mace_fmu.viewer.pairs import ModePair, PairAnimation, animate_pairs, pair_commands, table_5_1_pairs
    from mace_fmu.viewer.response import ResponseAnimation, animate_response, grid_motion, plot_response
    from mace_fmu.viewer.scene import Scene, build_scene
    from mace_fmu.viewer.still import chromium_executable, render_page, write_still

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "CAMERA_VIEWS": "camera", "camera_position": "camera", "BodyMotion": "frames", "Clip": "frames",
    "Frames": "frames", "body_motion": "frames", "standalone_html": "html", "write_html": "html",
    "scene_commands": "meshcat_scene", "send_to_visualizer": "meshcat_scene", "ModeAnimation": "modes",
    "animate_mode": "modes", "animate_modes": "modes", "mode_index": "modes", "ModePair": "pairs",
    "PairAnimation": "pairs", "animate_pairs": "pairs", "pair_commands": "pairs", "table_5_1_pairs": "pairs",
    "ResponseAnimation": "response", "animate_response": "response", "grid_motion": "response",
    "plot_response": "response", "Scene": "scene", "build_scene": "scene", "chromium_executable": "still",
    "render_page": "still", "write_still": "still", "animation_commands": "animation",
    "write_animation_html": "animation",
})
