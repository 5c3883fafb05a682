"""The scene and its key frames as meshcat commands, for a live server or a standalone HTML."""

from __future__ import annotations

from typing import Any

import meshcat.geometry as g
import numpy as np
import umsgpack
from meshcat.commands import SetObject, SetProperty, SetTransform
from meshcat.path import Path

from mace_fmu.viewer.camera import camera_position
from mace_fmu.viewer.frames import BodyMotion, Frames, body_motion
from mace_fmu.viewer.scene import Scene, component_colour

ROOT = Path(("meshcat", "mace"))
#: Deck basic axes have Y up (gravity -Y, thesis Fig. 3.1); meshcat has Z up: turn +90 deg about X.
Y_UP_TO_Z_UP = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
CABLE_DRAW_RADIUS_M = 0.0015


class _Raw:
    """A command already lowered to its msgpack-ready dict (meshcat's own classes build it slowly)."""

    def __init__(self, data: dict[str, Any]):
        self.data = data

    def lower(self) -> dict[str, Any]:
        return self.data


def _material(component: str) -> g.MeshLambertMaterial:
    return g.MeshLambertMaterial(color=component_colour(component))


#: msgpack extension code of a Float32Array, as meshcat's geometry and its viewer's decoder use it
FLOAT32_EXT = 0x17


def _float32(values: np.ndarray) -> umsgpack.Ext:
    return umsgpack.Ext(FLOAT32_EXT, np.ascontiguousarray(values, dtype="<f4").tobytes())


def _track(name: str, jstype: str, values: np.ndarray) -> dict[str, Any]:
    """A three.js keyframe track in its flat form (times in frames, values row-major)."""
    return {"name": "." + name, "type": jstype, "times": _float32(np.arange(values.shape[0])),
            "values": _float32(values)}


def body_commands(scene: Scene, *, root: Path = ROOT, placement: np.ndarray | None = None) -> list[Any]:
    """Commands that draw the undeformed bodies under ``root``, placed by ``placement`` (4 x 4, meshcat axes).

    Default placement: the deck's Y-up axes turned to meshcat's Z-up, the article's centre at the origin.
    """
    if placement is None:
        shift = np.eye(4)
        shift[:3, 3] = -scene.centre_m
        placement = Y_UP_TO_Z_UP @ shift
    cmds: list[Any] = [SetTransform(placement, root)]
    for seg in scene.segments:
        a, b = scene.positions_m[seg.row_a], scene.positions_m[seg.row_b]
        length = (seg.s1 - seg.s0) * float(np.linalg.norm(b - a))
        radius = seg.radius_m if seg.radius_m > 0 else CABLE_DRAW_RADIUS_M
        cmds.append(SetObject(g.Cylinder(length, radius), _material(seg.component), root.append(seg.name)))
    for mass in scene.masses:
        cmds.append(SetObject(g.Sphere(mass.radius_m), _material(mass.component), root.append(mass.name)))
    return cmds


def surroundings_commands(*, centre_m: np.ndarray, extent_m: np.ndarray, length_m: float,
                          camera_m: np.ndarray) -> list[Any]:
    """A floor under the box ``centre_m`` +- ``extent_m`` / 2 (deck axes under ROOT), axes, no meshcat grid,
    and the camera at ``camera_m`` [m] from the orbit target (deck axes)."""
    cmds: list[Any] = []
    floor = np.eye(4)
    floor[:3, 3] = centre_m
    floor[1, 3] = centre_m[1] - 0.5 * extent_m[1] - 0.1 * length_m
    width = 1.6 * np.maximum(np.asarray(extent_m)[[0, 2]], 0.5 * length_m)
    cmds.append(SetObject(g.Box([width[0], 0.005, width[1]]),
                          g.MeshLambertMaterial(color=0xDDDDDD, opacity=0.6, transparent=True),
                          ROOT.append("ground")))
    cmds.append(SetTransform(floor, ROOT.append("ground")))
    cmds.append(SetObject(g.triad(0.3 * length_m), path=ROOT.append("axes")))
    cmds.append(SetProperty("visible", False, Path(("Grid",))))  # meshcat's 20 m grid would cut the article
    # meshcat's camera node is in three.js axes, which the Y-up turn above makes the deck's axes
    cmds.append(SetProperty("position", np.asarray(camera_m, dtype=float).tolist(),
                            Path(("Cameras", "default", "rotated", "<object>"))))
    return cmds


def static_commands(scene: Scene, *, camera: str = "iso") -> list[Any]:
    """Commands that draw the undeformed structure, a floor under it, axes, and the camera on it.

    The structure is shifted so the centre of the test article is the origin: meshcat's orbit
    control turns about the origin, so it turns about the article.
    """
    return body_commands(scene) + surroundings_commands(centre_m=scene.centre_m, extent_m=scene.extent_m,
                                                        length_m=scene.length_m,
                                                        camera_m=camera_position(scene, camera))


def body_animations(scene: Scene, frames: Frames, motion: BodyMotion | None = None, *,
                    root: Path = ROOT) -> list[dict[str, Any]]:
    """Key-frame tracks of every body under ``root``: one entry per body for a set_animation command."""
    motion = body_motion(scene, frames) if motion is None else motion
    animations = []
    ones = np.ones_like(motion.segment_stretch)
    for k, seg in enumerate(scene.segments):
        scale = np.stack([ones[:, k], motion.segment_stretch[:, k], ones[:, k]], axis=1)
        tracks = [_track("position", "vector3", motion.segment_positions_m[:, k]),
                  _track("quaternion", "quaternion", motion.segment_quaternions[:, k]),
                  _track("scale", "vector3", scale)]
        animations.append({"path": root.append(seg.name).lower(),
                           "clip": {"fps": frames.fps, "name": "default", "tracks": tracks}})
    for k, mass in enumerate(scene.masses):
        animations.append({"path": root.append(mass.name).lower(),
                           "clip": {"fps": frames.fps, "name": "default",
                                    "tracks": [_track("position", "vector3", motion.mass_positions_m[:, k])]}})
    return animations


def set_animation(animations: list[dict[str, Any]], *, repetitions: int = 1000) -> _Raw:
    """One set_animation command playing all ``animations`` on one timeline (a later one would replace it)."""
    return _Raw({"type": "set_animation", "animations": animations,
                 "options": {"play": True, "repetitions": repetitions}, "path": ""})


def animation_command(scene: Scene, frames: Frames, motion: BodyMotion | None = None,
                      repetitions: int = 1000) -> _Raw:
    """One set_animation command key-framing every body's transform at every frame."""
    return set_animation(body_animations(scene, frames, motion), repetitions=repetitions)


def scene_commands(scene: Scene, frames: Frames, *, camera: str = "iso") -> list[Any]:
    """All commands: the drawn structure seen from ``camera`` (a CAMERA_VIEWS key), then its animation.

    Parameters
    ----------
    scene : Scene
        The drawn bodies.
    frames : Frames
        Their key frames.
    camera : str
        A ``CAMERA_VIEWS`` key.

    Returns
    -------
    list
        meshcat commands, in the order they are to be sent.
    """
    return static_commands(scene, camera=camera) + [animation_command(scene, frames)]


def send_to_visualizer(visualizer: Any, commands: list[Any]) -> None:
    """Replay commands on a live ``meshcat.Visualizer`` (for interactive work).

    Parameters
    ----------
    visualizer : meshcat.Visualizer
        A running visualizer.
    commands : list
        meshcat commands, for example from :func:`scene_commands`.
    """
    for cmd in commands:
        visualizer.window.send(cmd)
