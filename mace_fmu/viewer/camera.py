"""Where the camera starts: a standard view direction, at the distance that frames the test article."""

from __future__ import annotations

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.viewer.scene import Scene

#: Camera views: unit direction from the article's centre towards the camera, deck axes (Y up).
#: "iso" looks from 30 deg above the X-Z plane and 30 deg round from +Z, so the bus (along X)
#: spans the picture and bending in both planes (Y and Z) shows; x, y, z look along an axis.
CAMERA_VIEWS: dict[str, np.ndarray] = {
    "iso": np.array([np.sin(np.radians(30)) * np.cos(np.radians(30)), np.sin(np.radians(30)),
                     np.cos(np.radians(30)) * np.cos(np.radians(30))]),
    "x": np.array([1.0, 0.0, 0.0]),
    "y": np.array([0.0, 1.0, 1e-3]),  # from above, with +Z towards the bottom of the picture
    "z": np.array([0.0, 0.0, 1.0]),
}
#: meshcat's default camera: 75 deg vertical field of view. Framing assumes a 4:3 or wider page.
CAMERA_VERTICAL_FOV_DEG = 75.0
FRAMED_ASPECT = 4.0 / 3.0
#: Fraction of the picture's width (or height) the article's bounding box fills.
FRAME_FILL = 0.8
#: Least distance from the camera to the nearest face of the box, in article lengths: seen end-on
#: (--camera x) from closer, the near end of the bus would hide the rest in perspective.
NEAR_CLEARANCE = 0.45


def camera_axes(view: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (towards the camera, picture right, picture up) of a CAMERA_VIEWS view, deck axes."""
    if view not in CAMERA_VIEWS:
        raise MaceError(f"camera view must be one of {', '.join(CAMERA_VIEWS)}, got {view!r}")
    towards = CAMERA_VIEWS[view] / np.linalg.norm(CAMERA_VIEWS[view])
    right = np.cross(-towards, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    return towards, right, np.cross(right, -towards)


def camera_position(scene: Scene, view: str = "iso") -> np.ndarray:
    """Camera position [m] relative to the article's centre, deck axes, so the article fills the frame.

    The distance is the smallest at which every corner of the article's bounding box projects
    within ``FRAME_FILL`` of the half-width and half-height of a ``FRAMED_ASPECT`` picture, and
    the box's nearest face is ``NEAR_CLEARANCE`` article lengths away or more.

    Parameters
    ----------
    scene : Scene
        The drawn structure (its test article's box).
    view : str
        A ``CAMERA_VIEWS`` key.

    Returns
    -------
    numpy.ndarray
        (3,) camera position [m].
    """
    return framing_position(scene.extent_m, length_m=scene.length_m, view=view)


def framing_position(extent_m: np.ndarray, *, length_m: float, view: str) -> np.ndarray:
    """Camera position [m] relative to a box's centre that frames the box of size ``extent_m`` (deck axes);
    ``length_m`` sets the least clearance (see ``camera_position``)."""
    towards, right, up = camera_axes(view)
    half = 0.5 * np.maximum(np.asarray(extent_m, dtype=float), 1e-3 * length_m)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
    tan_v = np.tan(np.radians(CAMERA_VERTICAL_FOV_DEG) / 2) * FRAME_FILL
    tan_h = tan_v * FRAMED_ASPECT
    # a corner at depth (distance - towards.p) projects to |right.p| / depth of the tangent
    distance = max(np.max(corners @ towards + np.abs(corners @ right) / tan_h),
                   np.max(corners @ towards + np.abs(corners @ up) / tan_v),
                   np.max(corners @ towards) + NEAR_CLEARANCE * length_m)
    return float(distance) * towards
