"""Standalone HTML: meshcat's viewer script and the scene's commands in one file, no server."""

from __future__ import annotations

import base64
import html as html_text
import os
from pathlib import Path as FilePath
from typing import Any

import meshcat
import umsgpack

from mace_fmu.util.atomic import write_text_atomic
from mace_fmu.viewer.frames import Clip

_VIEWER_JS = FilePath(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"


def _overlay(title: str, clips: tuple[Clip, ...]) -> str:
    """The legend: one row per clip (playback span, what it shows, motion scale), and a line for the time."""
    rows = "".join(f'<tr data-start="{c.start_s!r}" data-end="{c.end_s!r}"'
                   + (f' data-rate="{c.simulated_s_per_s!r}"' if c.simulated_s_per_s is not None else "")
                   + f"><td>{c.start_s:.1f}-{c.end_s:.1f} s</td><td>{html_text.escape(c.title)}</td>"
                   f"<td>motion x {c.motion_scale:.3g}</td></tr>" for c in clips)
    return (f'<div id="mace-legend"><b>{html_text.escape(title)}</b>'
            f'<table>{rows}</table><div id="mace-now"></div></div>')


#: Marks the legend row of the clip playing now (meshcat's animator time, playback seconds) and,
#: for a response, states the simulated time. The time is also kept in data-time for tests.
_LEGEND_SCRIPT = """
const legend = document.getElementById("mace-legend");
const clipRows = Array.from(legend.querySelectorAll("tr[data-start]"));
function markClip() {
  const t = viewer.animator.time;
  legend.dataset.time = t;
  let now = "";
  clipRows.forEach((row, k) => {
    const last = k === clipRows.length - 1;
    const playing = t >= +row.dataset.start && (t < +row.dataset.end || (last && t <= +row.dataset.end));
    if (playing && !row.classList.contains("playing")) row.scrollIntoView({block: "nearest"});  // long lists
    row.classList.toggle("playing", playing);
    if (playing && row.dataset.rate) now = "t = " + (t * row.dataset.rate).toFixed(3) + " s simulated";
  });
  document.getElementById("mace-now").textContent = now;
}
markClip();
setInterval(markClip, 100);
"""


def standalone_html(commands: list[Any], *, title: str, clips: tuple[Clip, ...] = ()) -> str:
    """The page: meshcat's viewer, each command as a base64 msgpack blob, a legend of the clips.

    Parameters
    ----------
    commands : list
        meshcat commands, in the order the page replays them.
    title : str
        The page's title.
    clips : tuple of Clip
        The legend's rows.

    Returns
    -------
    str
        The standalone HTML page (meshcat's JavaScript included).
    """
    blobs = ",\n".join('"' + base64.b64encode(umsgpack.packb(cmd.lower())).decode("ascii") + '"'
                       for cmd in commands)
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{html_text.escape(title)}</title>
<style>body {{margin: 0;}} #meshcat-pane {{width: 100vw; height: 100vh; overflow: hidden;}}
#mace-legend {{position: absolute; left: 8px; bottom: 8px; max-height: 30vh; overflow: auto;
 font: 12px sans-serif; background: rgba(255,255,255,0.85); padding: 6px;}}
#mace-legend td {{padding: 0 4px;}} #mace-legend tr.playing {{background: #ffd54f; font-weight: bold;}}</style>
</head>
<body><div id="meshcat-pane"></div>{_overlay(title, clips)}
<script>{_VIEWER_JS.read_text()}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var blobs = [{blobs}];
for (const b of blobs) {{
  const bytes = Uint8Array.from(atob(b), c => c.charCodeAt(0));
  viewer.handle_command_bytearray(bytes);
}}
{_LEGEND_SCRIPT}</script></body></html>
"""


class ShownInline:
    """Mixin of the viewer's animations: a Jupyter notebook shows one inline (``_repr_html_``), as the
    standalone page in an iframe, so nothing needs a server or a meshcat process."""

    def _repr_html_(self) -> str:
        from mace_fmu.viewer.animation import animation_commands  # the module that knows every kind
        from mace_fmu.viewer.modes import ModeAnimation
        from mace_fmu.viewer.pairs import PairAnimation
        from mace_fmu.viewer.response import ResponseAnimation

        assert isinstance(self, (ModeAnimation, ResponseAnimation, PairAnimation))  # the mixin's classes
        page = standalone_html(animation_commands(self), title=type(self).__name__, clips=self.frames.clips)
        return (f'<iframe srcdoc="{html_text.escape(page, quote=True)}" '
                'style="width: 100%; height: 480px; border: 0;"></iframe>')


def write_html(path: str | os.PathLike[str], commands: list[Any], *, title: str, clips: tuple[Clip, ...] = ()) -> int:
    """Write the standalone page to ``path``; returns its size in bytes.

    Parameters
    ----------
    path : str or os.PathLike
        The HTML file to write (replaced atomically).
    commands : list
        meshcat commands, in the order the page replays them.
    title : str
        The page's title.
    clips : tuple of Clip
        The legend's rows.

    Returns
    -------
    int
        The page's size [bytes].
    """
    text = standalone_html(commands, title=title, clips=clips)
    write_text_atomic(path, text)  # an interrupted run leaves the previous page, not half of a new one
    return len(text.encode("utf-8"))
