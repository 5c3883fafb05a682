"""Standalone HTML: meshcat's viewer script and the scene's commands in one file, no server."""

from __future__ import annotations

import base64
import html as html_text
import os
from pathlib import Path as FilePath

import meshcat
import umsgpack

from mace_fmu.atomic import write_text_atomic
from viewer.frames import Clip

_VIEWER_JS = FilePath(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"


def _overlay(title: str, clips: tuple[Clip, ...]) -> str:
    rows = "".join(f"<tr><td>{c.start_s:.1f}-{c.end_s:.1f} s</td><td>{html_text.escape(c.title)}</td></tr>"
                   for c in clips)
    return (f'<div id="mace-legend"><b>{html_text.escape(title)}</b>'
            f"<table>{rows}</table></div>")


def standalone_html(commands: list, *, title: str, clips: tuple[Clip, ...] = ()) -> str:
    """The page: meshcat's viewer, each command as a base64 msgpack blob, a legend of the clips."""
    blobs = ",\n".join('"' + base64.b64encode(umsgpack.packb(cmd.lower())).decode("ascii") + '"'
                       for cmd in commands)
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{html_text.escape(title)}</title>
<style>body {{margin: 0;}} #meshcat-pane {{width: 100vw; height: 100vh; overflow: hidden;}}
#mace-legend {{position: absolute; left: 8px; bottom: 8px; max-height: 40vh; overflow: auto;
 font: 12px sans-serif; background: rgba(255,255,255,0.85); padding: 6px;}}</style></head>
<body><div id="meshcat-pane"></div>{_overlay(title, clips)}
<script>{_VIEWER_JS.read_text()}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var blobs = [{blobs}];
for (const b of blobs) {{
  const bytes = Uint8Array.from(atob(b), c => c.charCodeAt(0));
  viewer.handle_command_bytearray(bytes);
}}
</script></body></html>
"""


def write_html(path: str | os.PathLike, commands: list, *, title: str, clips: tuple[Clip, ...] = ()) -> int:
    """Write the standalone page to ``path``; returns its size in bytes."""
    text = standalone_html(commands, title=title, clips=clips)
    write_text_atomic(path, text)  # an interrupted run leaves the previous page, not half of a new one
    return len(text.encode("utf-8"))
