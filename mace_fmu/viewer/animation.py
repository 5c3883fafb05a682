"""Any of the viewer's animations (modes, a response, mode pairs) as meshcat commands or one standalone page."""

from __future__ import annotations

import os
from typing import Any

from mace_fmu.viewer.html import write_html
from mace_fmu.viewer.meshcat_scene import scene_commands
from mace_fmu.viewer.modes import ModeAnimation
from mace_fmu.viewer.pairs import PairAnimation, pair_commands
from mace_fmu.viewer.response import ResponseAnimation


def animation_commands(animation: ModeAnimation | ResponseAnimation | PairAnimation, *,
                       camera: str = "iso") -> list[Any]:
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


def write_animation_html(animation: ModeAnimation | ResponseAnimation | PairAnimation, path: str | os.PathLike[str],
                         *, title: str, camera: str = "iso") -> int:
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
