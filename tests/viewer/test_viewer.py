"""Viewer: the scene against the deck, key frames against shape x scale x sin, and a real browser."""

from __future__ import annotations

import base64
import html as html_text
import os
import re

from pathlib import Path

import numpy as np
import pytest
import umsgpack
from support.paths import ROOT
from support.printed import printed_in

from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import compute_modes
from mace_fmu.viewer import (animate_mode, animate_modes, animate_response, build_scene, scene_commands, standalone_html,
                    write_animation_html)
from mace_fmu.viewer.frames import body_motion
from mace_fmu.viewer.meshcat_scene import FLOAT32_EXT
from mace_fmu.viewer.scene import tube_outer_radius_m
from mace_fmu.viewer.still import chromium_executable, render_page, write_still

pytestmark = pytest.mark.slow  # renders pages in a browser

BUILD = ROOT / "build"


@pytest.fixture(scope="module")
def modes_0g():
    return compute_modes(configuration="0g", max_hz=60.0)


@pytest.fixture(scope="module")
def modes_1g():
    return compute_modes(configuration="1g", max_hz=20.0)


def _decoded_commands(html: str) -> list[dict]:
    blobs = re.search(r"var blobs = \[(.*?)\];", html, re.S).group(1)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in re.findall(r'"([A-Za-z0-9+/=]+)"', blobs)]


def _track_values(animation: dict, path_suffix: str, name: str) -> np.ndarray:
    for entry in animation["animations"]:
        if entry["path"].endswith(path_suffix):
            for track in entry["clip"]["tracks"]:
                if track["name"] == "." + name:
                    ext = track["values"]
                    assert ext.type == FLOAT32_EXT
                    return np.frombuffer(ext.data, dtype="<f4")
    raise AssertionError(f"no {name} track for {path_suffix}")


def test_tube_radius_from_area_and_inertia():
    ro, ri = 0.02, 0.017
    area = np.pi * (ro**2 - ri**2)
    inertia = np.pi * (ro**4 - ri**4) / 4
    assert tube_outer_radius_m(area, inertia) == pytest.approx(ro, rel=1e-12)


def test_scene_bodies_match_the_deck(modes_0g, modes_1g):
    for sm in (modes_0g, modes_1g):
        deck = sm.structure.deck
        scene = build_scene(sm, segments_per_bar=3)
        assert len(scene.segments) == 3 * len(deck.bars)
        assert {s.bar_id for s in scene.segments} == set(deck.bars)
        assert len(scene.masses) == sum(1 for c in deck.conm2s.values() if c.mass > 0)
        for body in scene.masses:
            grid = deck.conm2s[int(body.name.split("/")[1])].grid
            np.testing.assert_allclose(scene.positions_m[body.row], sm.model.positions[sm.model.dofs.grid_index(grid)])
    # 1-g carries the suspension cables (CBAR 103-126), 0-g does not
    cables_1g = {s.bar_id for s in build_scene(modes_1g).segments if s.radius_m == 0.0}
    assert cables_1g == set(range(103, 127))
    assert not any(s.radius_m == 0.0 for s in build_scene(modes_0g).segments)


def test_mode_frames_are_shape_times_scale_times_sine(modes_0g):
    anim = animate_mode(modes_0g, "1st Z bending", cycles=2, frames_per_cycle=16)
    index = anim.mode_indices[0]
    shape = modes_0g.modes.shapes[:, index - 1].reshape(-1, 6)
    t = anim.frames.times_s[:-1]
    expected = np.sin(2 * np.pi * t)[:, None, None] * anim.scales[0] * shape[None]
    np.testing.assert_allclose(anim.frames.displacements[:-1], expected, atol=1e-15)
    largest = anim.scales[0] * np.linalg.norm(shape[:, :3], axis=1).max()
    assert largest == pytest.approx(0.08 * anim.scene.length_m, rel=1e-12)


def _look_at_projection(eye: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, 2) tangents (right, up) of points seen from ``eye`` looking at the origin, Y up (three.js lookAt)."""
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = points - eye
    depth = rel @ forward
    return np.stack([rel @ right / depth, rel @ up / depth], axis=1)


def test_camera_frames_the_article_not_the_cables(modes_0g, modes_1g):
    """Each view: the article's box projects within 80 % of a 4:3 picture, touching that bound or kept
    0.45 article lengths from the camera (end-on); the iso and z views are bound by the picture."""
    from mace_fmu.viewer import CAMERA_VIEWS, camera_position

    tan_v = np.tan(np.radians(75.0 / 2))
    for sm in (modes_0g, modes_1g):
        scene = build_scene(sm)
        # the article (bus, gimbals, wheels) is 1.710 m along X (Table 3.15); the 1-g cables reach 4.9 m up
        assert scene.extent_m[0] == pytest.approx(1.710, abs=1e-3) and scene.length_m == scene.extent_m[0]
        assert scene.positions_m[:, 1].max() - scene.positions_m[:, 1].min() > (4.5 if sm is modes_1g else 0.0)
        half = 0.5 * scene.extent_m
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
        for view in CAMERA_VIEWS:
            eye = camera_position(scene, view)
            tangents = np.abs(_look_at_projection(eye, corners))
            used = max(tangents[:, 0].max() / (0.8 * tan_v * 4 / 3), tangents[:, 1].max() / (0.8 * tan_v))
            clearance = np.min(np.linalg.norm(eye) - corners @ (eye / np.linalg.norm(eye))) / scene.length_m
            assert used <= 1.0 + 1e-9 and clearance >= 0.45 - 1e-9, view
            assert used == pytest.approx(1.0, rel=1e-6) or clearance == pytest.approx(0.45, rel=1e-6), view
            if view in ("iso", "z"):
                assert used == pytest.approx(1.0, rel=1e-6), view
    with pytest.raises(MaceError, match="camera view must be one of iso, x, y, z"):
        camera_position(build_scene(modes_0g), "top")


def test_page_centres_the_article_and_aims_the_camera(modes_1g):
    """The page shifts the article's centre to the orbit target (origin) and hides meshcat's 20 m grid."""
    from mace_fmu.viewer import camera_position

    anim = animate_mode(modes_1g, "1st Z bending", frames_per_cycle=8)
    commands = _decoded_commands(standalone_html(scene_commands(anim.scene, anim.frames, camera="z"), title="t"))
    root = next(c for c in commands if c["type"] == "set_transform" and c["path"] == "/meshcat/mace")
    matrix = np.array(root["matrix"], dtype=float).reshape(4, 4).T  # three.js stores column-major
    centre = np.append(anim.scene.centre_m, 1.0)
    np.testing.assert_allclose(matrix @ centre, [0, 0, 0, 1], atol=1e-12)
    camera = next(c for c in commands if c["type"] == "set_property" and c["path"].startswith("/Cameras"))
    np.testing.assert_allclose(camera["value"], camera_position(anim.scene, "z"))
    assert camera["value"][0] == 0.0 and camera["value"][1] == 0.0
    grid = next(c for c in commands if c["type"] == "set_property" and c["path"] == "/Grid")
    assert grid["property"] == "visible" and grid["value"] is False


def test_exported_key_frames_reproduce_grid_motion(modes_0g):
    """Decode the HTML's animation: masses move by shape x scale x sin, bar ends follow their grids."""
    anim = animate_modes(modes_0g, ["1st Y bending", "torsion, primary"], frames_per_cycle=12)
    html = standalone_html(scene_commands(anim.scene, anim.frames), title="t", clips=anim.frames.clips)
    animation = [c for c in _decoded_commands(html) if c["type"] == "set_animation"][0]
    n_frames = anim.frames.times_s.size
    for body in anim.scene.masses[::5]:
        got = _track_values(animation, body.name, "position").reshape(n_frames, 3)
        want = anim.scene.positions_m[body.row] + anim.frames.displacements[:, body.row, :3]
        np.testing.assert_allclose(got, want, atol=2e-7)
    # first segment of each bar: its start point is grid A displaced, in position, orientation and length
    motion = body_motion(anim.scene, anim.frames)
    for k, seg in enumerate(anim.scene.segments):
        if seg.s0 != 0.0 or k % 7:
            continue
        pos = _track_values(animation, seg.name, "position").reshape(n_frames, 3)
        quat = _track_values(animation, seg.name, "quaternion").reshape(n_frames, 4)
        stretch = _track_values(animation, seg.name, "scale").reshape(n_frames, 3)[:, 1]
        np.testing.assert_allclose(pos, motion.segment_positions_m[:, k], atol=2e-7)
        x, y, z, w = quat.T.astype(float)
        axis_dir = np.stack([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)], axis=1)  # R @ e_y
        length0 = (seg.s1 - seg.s0) * np.linalg.norm(anim.scene.positions_m[seg.row_b] - anim.scene.positions_m[seg.row_a])
        start = pos - 0.5 * length0 * stretch[:, None] * axis_dir
        want = anim.scene.positions_m[seg.row_a] + anim.frames.displacements[:, seg.row_a, :3]
        np.testing.assert_allclose(start, want, atol=1e-6)


def test_rigid_rotation_moves_every_bar_point_rigidly(modes_0g):
    """A rigid-body rotation mode is a linear field u = a + theta x x: the cubic bars reproduce it exactly."""
    anim = animate_mode(modes_0g, "rigid body: Y rotation", frames_per_cycle=8)
    shape = modes_0g.modes.shapes[:, anim.mode_indices[0] - 1].reshape(-1, 6) * anim.scales[0]
    on_bars = sorted({s.row_a for s in anim.scene.segments} | {s.row_b for s in anim.scene.segments})
    theta = shape[on_bars[0], 3:]
    a = shape[on_bars[0], :3] - np.cross(theta, anim.scene.positions_m[on_bars[0]])
    np.testing.assert_allclose(shape[on_bars, 3:], np.broadcast_to(theta, (len(on_bars), 3)), atol=1e-12)
    np.testing.assert_allclose(shape[on_bars, :3], a + np.cross(theta, anim.scene.positions_m[on_bars]), atol=1e-12)
    motion = body_motion(anim.scene, anim.frames)
    mids0 = motion.segment_positions_m[0]  # frame 0 is undeformed (sin 0)
    sine = np.sin(2 * np.pi * anim.frames.times_s)
    want = mids0[None] + sine[:, None, None] * (a + np.cross(theta, mids0))[None]
    np.testing.assert_allclose(motion.segment_positions_m, want, atol=1e-12)


def test_bad_mode_names_say_what_exists(modes_0g):
    with pytest.raises(MaceError, match="exactly one mode"):
        animate_mode(modes_0g, "no such mode")
    with pytest.raises(MaceError, match="numbered 1 to"):
        animate_mode(modes_0g, 999)
    with pytest.raises(MaceError, match="seconds_per_cycle > 0"):
        animate_mode(modes_0g, 14, seconds_per_cycle=0.0)


needs_chromium = pytest.mark.skipif(chromium_executable() is None and not os.environ.get("MACE_REQUIRE_CHROMIUM"),
                                    reason="Debian chromium not installed (.ci/run installs it and requires this test)")


#: hue [deg] of each component drawn in the gimbal and wheel colours (mace_fmu.viewer.scene.COMPONENT_COLOURS)
_ARTICLE_HUES = {"primary_gimbal": 29.0, "secondary_gimbal": 351.0, "reaction_wheels": 127.0}


def _component_mask(pixels: np.ndarray, hue_deg: float) -> np.ndarray:
    """Pixels of one shaded component colour: hue within 12 deg, saturation of a lit matte surface.

    Lambert shading scales the three channels alike, so hue and saturation survive it; the axis
    triad's pure red and green lines (saturation 1) and the grey floor (saturation 0) do not pass.
    """
    top, bottom = pixels.max(axis=-1), pixels.min(axis=-1)
    saturation = np.where(top > 0, (top - bottom) / np.maximum(top, 1e-9), 0.0)
    r, g, b = (pixels[..., k] / 255.0 for k in range(3))
    hue = np.degrees(np.arctan2(np.sqrt(3.0) * (g - b), 2.0 * r - g - b)) % 360.0
    distance = np.abs((hue - hue_deg + 180.0) % 360.0 - 180.0)
    return (distance < 12.0) & (saturation > 0.35) & (saturation < 0.9) & (top > 60)


def _article_span(pixels: np.ndarray) -> tuple[float, dict[str, int]]:
    """Fraction of the image width the gimbal and wheel pixels span (1st-99th percentile), and counts."""
    masks = {name: _component_mask(pixels, hue) for name, hue in _ARTICLE_HUES.items()}
    cols = np.nonzero(np.logical_or.reduce(list(masks.values())))[1]
    span = (np.percentile(cols, 99) - np.percentile(cols, 1)) / pixels.shape[1] if cols.size else 0.0
    return float(span), {name: int(m.sum()) for name, m in masks.items()}


@pytest.fixture(params=["modes_1g", "modes_0g", "response_0g"])
def framed_page(request, modes_0g, modes_1g, motion_fmu_0g, step_run_0g, tmp_path):
    """(page, screenshot path): a 1-g and a 0-g mode page, and the 0-g step response of the secondary gimbal."""
    if request.param == "modes_1g":
        anim = animate_modes(modes_1g, ["1st Z bending", "1st Y bending"], frames_per_cycle=12)
    elif request.param == "modes_0g":
        anim = animate_modes(modes_0g, [14, 15], frames_per_cycle=12)
    else:
        anim = animate_response(motion_fmu_0g[0].structure_modes, step_run_0g)
    page = tmp_path / f"{request.param}.html"
    write_animation_html(anim, page, title=f"MACE {request.param}")
    return page, BUILD / f"viewer_{request.param}_600x400.png"


@needs_chromium
def test_pages_open_framed_on_the_test_article(framed_page):
    """At 600 x 400 the structure is drawn in its colours, and the gimbals and wheels span >= 40 % of the width
    (framing is relative to the picture: software WebGL draws a quarter of the pixels of the CLI's 1200 x 800
    in about 40 % of the time, and the same fractions come out)."""
    from PIL import Image

    page, shot = framed_page
    write_still(page, shot, width_px=600, height_px=400)
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert pixels.shape == (400, 600, 3)
    assert pixels.std() > 20.0  # not blank
    bus = _component_mask(pixels, 213.0)  # 0x4A7FC1
    assert bus.sum() > 500, f"bus pixels: {bus.sum()}"
    span, counts = _article_span(pixels)
    assert min(counts.values()) > 75, f"gimbal and wheel pixels: {counts}"
    assert span >= 0.40, f"gimbals and wheels span {100 * span:.1f} % of the width ({counts} pixels)"


@needs_chromium
def test_legend_marks_the_clip_playing_now(modes_0g, motion_fmu_0g, step_run_0g, tmp_path):
    """In Chromium the legend marks the row whose span holds the animator's time; a response states t x speed."""
    for name, anim in (("modes", animate_modes(modes_0g, [14, 15, 16], frames_per_cycle=12)),
                       ("response", animate_response(motion_fmu_0g[0].structure_modes, step_run_0g,
                                                     playback_speed=0.5))):
        page = tmp_path / f"{name}.html"
        write_animation_html(anim, page, title=name)
        dom = render_page(page, png=tmp_path / f"{name}.png", width_px=400, height_px=300)
        time_s = float(re.search(r'id="mace-legend" data-time="([0-9.e-]+)"', dom).group(1))
        assert time_s > 0.0
        rows = re.findall(r'<tr data-start="([^"]+)" data-end="([^"]+)"(?: data-rate="[^"]+")?(?: class="(\w*)")?'
                          r'><td>[^<]*</td><td>([^<]*)</td><td>motion x ([^<]*)</td>', dom)
        assert len(rows) == len(anim.frames.clips)
        playing = [title for start, end, mark, title, _ in rows if mark == "playing"]
        holding = [c.title for c in anim.frames.clips if c.start_s <= time_s < c.end_s]
        assert playing == holding and len(playing) == 1
        for (_, _, _, _, scale), clip in zip(rows, anim.frames.clips):
            assert float(scale) == pytest.approx(clip.motion_scale, rel=5e-3)
        now = re.search(r'<div id="mace-now">([^<]*)</div>', dom).group(1)
        if name == "response":
            assert now == f"t = {time_s * 0.5:.3f} s simulated"
        else:
            assert now == ""


def test_cli_writes_the_html_and_lists_the_clips(tmp_path, capsys):
    from mace_fmu.cli import main

    out = tmp_path / "m.html"
    assert main(["view", "modes", "0g", "--mode", "1st Z bending", "--mode", "15", "--html", str(out)]) == 0
    printed = capsys.readouterr().out
    assert printed_in("mode 14: 2.100 Hz 1st Z bending", printed) and "mode 15:" in printed
    commands = _decoded_commands(out.read_text())
    assert sum(c["type"] == "set_object" for c in commands) > 100
    assert main(["view", "modes", "0g", "--mode", "no such", "--html", str(out)]) == 2
    assert "exactly one mode" in capsys.readouterr().err


@needs_chromium
def test_cli_png_writes_a_still_from_the_chosen_camera(tmp_path, capsys):
    """--png alone renders a temporary page; the x view looks along the bus, so it is narrow and tall."""
    from PIL import Image

    from mace_fmu.cli import main
    from mace_fmu.cli.view import CAMERA_CHOICES
    from mace_fmu.viewer import CAMERA_VIEWS

    assert CAMERA_CHOICES == tuple(CAMERA_VIEWS)
    spans = {}
    for camera in ("z", "x"):
        png = tmp_path / f"{camera}.png"
        assert main(["view", "modes", "0g", "--mode", "14", "--png", str(png), "--camera", camera,
                     "--png-size", "600", "400"]) == 0
        assert f"wrote {png} (still from headless Chromium, {camera} view)" in capsys.readouterr().out
        spans[camera] = _article_span(np.asarray(Image.open(png).convert("RGB"), dtype=float))[0]
    assert spans["z"] >= 0.4 and spans["x"] < 0.5 * spans["z"], spans
    assert Image.open(tmp_path / "z.png").size == (600, 400)
    assert not list(tmp_path.glob("*.html"))


def test_cli_png_without_chromium_says_so_before_any_work(tmp_path, monkeypatch, capsys):
    from mace_fmu.cli import main

    monkeypatch.setenv("PATH", str(tmp_path))  # no chromium on PATH
    assert main(["view", "modes", "0g", "--png", str(tmp_path / "m.png")]) == 2
    err = capsys.readouterr().err
    assert "--png needs headless Chromium, which is not installed" in err and "apt-get install chromium" in err
    assert main(["view", "modes", "0g"]) == 2
    assert "--html OUT.html, --png OUT.png, --live" in capsys.readouterr().err


def test_live_meshcat_server_receives_the_same_animation(modes_0g):
    """The live path (a real meshcat server) stores exactly the commands the standalone page embeds."""
    meshcat = pytest.importorskip("meshcat")
    from mace_fmu.viewer import send_to_visualizer

    anim = animate_modes(modes_0g, [14], frames_per_cycle=8)
    commands = scene_commands(anim.scene, anim.frames)
    visualizer = meshcat.Visualizer()
    try:
        send_to_visualizer(visualizer, commands)
        served = visualizer.static_html()
    finally:
        visualizer.window.server_proc.kill()
    blobs = {base64.b64decode(b) for b in re.findall(r"base64,([A-Za-z0-9+/=]+)", served)}
    ours = [umsgpack.packb(c.lower()) for c in commands]
    assert len(ours) > 100
    assert all(blob in blobs for blob in ours)  # every body, transform, property and the animation


@pytest.fixture(scope="module")
def step_run_0g(motion_fmu_0g):
    from mace_fmu.fmu.simulate import simulate_input_response

    _, _, unzipped = motion_fmu_0g
    return simulate_input_response(unzipped, input_name="gimbal_secondary_z", signal="step", duration_s=1.0)


def test_response_frames_are_the_fmu_outputs_times_the_scale(motion_fmu_0g, step_run_0g):
    """Every frame is one communication point: grid motion = scale x the FMU's grid_<id>_<c> outputs."""
    model, _, _ = motion_fmu_0g
    run = step_run_0g
    anim = animate_response(model.structure_modes, run, playback_speed=0.5, fps=25.0)
    stride = 10  # 0.5 simulated s per s / (25 frames/s x 2 ms)
    np.testing.assert_array_equal(anim.sample_indices, np.arange(0, run.times_s.size, stride))
    np.testing.assert_allclose(anim.frames.times_s, run.times_s[::stride] / 0.5, rtol=0, atol=1e-12)
    assert anim.frames.fps == pytest.approx(25.0)
    for row, grid in enumerate(anim.scene.grid_ids):
        for c, comp in enumerate(("tx", "ty", "tz", "rx", "ry", "rz")):
            np.testing.assert_array_equal(anim.frames.displacements[:, row, c],
                                          anim.scale * run.outputs[f"grid_{grid}_{comp}"][::stride])
    # the default magnification makes the largest drawn translation 8 % of the structure's size
    drawn = np.linalg.norm(anim.frames.displacements[..., :3], axis=-1).max()
    assert drawn == pytest.approx(0.08 * anim.scene.length_m, rel=0.05)
    # the page plays those frames: a mass's key frames are its grid's position plus the drawn motion
    html = standalone_html(scene_commands(anim.scene, anim.frames), title="t", clips=anim.frames.clips)
    animation = [c for c in _decoded_commands(html) if c["type"] == "set_animation"][0]
    n_frames = anim.frames.times_s.size
    for body in anim.scene.masses:
        got = _track_values(animation, body.name, "position").reshape(n_frames, 3)
        grid = anim.scene.grid_ids[body.row]
        want = anim.scene.positions_m[body.row] + anim.scale * np.stack(
            [run.outputs[f"grid_{grid}_{c}"][::stride] for c in ("tx", "ty", "tz")], axis=1)
        np.testing.assert_allclose(got, want, atol=2e-7)


def test_response_needs_the_motion_of_every_drawn_grid(motion_fmu_0g, step_run_0g):
    model, _, _ = motion_fmu_0g
    run = step_run_0g
    partial = type(run)(times_s=run.times_s, inputs=run.inputs, units=run.units, descriptions=run.descriptions,
                        outputs={k: v for k, v in run.outputs.items() if not k.startswith("grid_7_")})
    with pytest.raises(MaceError, match=r"no motion outputs for grid\(s\) \[7\]"):
        animate_response(model.structure_modes, partial)
    with pytest.raises(MaceError, match="playback_speed and fps must be > 0"):
        animate_response(model.structure_modes, run, playback_speed=0.0)


def test_cli_view_response_writes_page_plot_and_fmu(motion_fmu_0g, tmp_path, capsys):
    from PIL import Image

    from mace_fmu.cli import main

    _, fmu, _ = motion_fmu_0g
    out = tmp_path / "resp.html"
    assert main(["view", "response", "0g", "--input", "rwa_z", "--signal", "impulse", "--duration", "0.4",
                 "--speed", "0.1", "--fmu", str(fmu), "--html", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "201 frames at 50 frames/s" in printed  # 0.4 s at 0.1x: every 2 ms sample is a frame
    assert f"wrote {tmp_path / 'resp_signals.png'} (rwa_z and tach_z over time)" in printed
    commands = _decoded_commands(out.read_text())
    assert sum(c["type"] == "set_object" for c in commands) > 100
    assert sum(c["type"] == "set_animation" for c in commands) == 1
    plot = np.asarray(Image.open(tmp_path / "resp_signals.png").convert("L"), dtype=float)
    assert plot.std() > 10.0  # axes and curves, not a blank image
    # the active strut's own sensor is strut 2's strain gauge pair, not the first output (an encoder)
    assert main(["view", "response", "0g", "--input", "active_strut_z", "--duration", "0.1", "--fmu", str(fmu),
                 "--html", str(out)]) == 0
    assert "(active_strut_z and strain_strut2_z over time)" in capsys.readouterr().out
    assert main(["view", "response", "1g", "--input", "rwa_z", "--fmu", str(fmu), "--html", str(out)]) == 2
    assert "is not a MACE 1g model" in capsys.readouterr().err
    assert main(["view", "response", "0g", "--input", "rwa_z", "--duration", "0.1", "--step", "0.003",
                 "--fmu", str(fmu), "--html", str(out)]) == 2
    assert "not a whole number of 0.003 s steps" in capsys.readouterr().err


def test_cli_view_response_exports_its_own_motion_fmu(tmp_path, capsys):
    """Without --fmu the command exports the model with every grid's motion next to the page."""
    import fmpy

    from mace_fmu.cli import main

    out = tmp_path / "step.html"
    assert main(["view", "response", "0g", "--input", "gimbal_primary_x", "--duration", "0.2", "--html",
                 str(out)]) == 0
    fmu = tmp_path / "MACE_0g_motion.fmu"
    assert f"wrote {fmu}" in capsys.readouterr().out and out.exists() and (tmp_path / "step_signals.png").exists()
    outputs = [v for v in fmpy.read_model_description(str(fmu)).modelVariables if v.causality == "output"]
    assert len(outputs) == 20 + 6 * 79


# --- mace-fmu view pairs: Table 5.1's 1-g and 0-g modes side by side ---

@pytest.fixture(scope="module")
def modes_1g_table():
    return compute_modes(configuration="1g", max_hz=60.0)  # Table 5.1 reaches 53 Hz in 1-g


@pytest.fixture(scope="module")
def pairs_anim(modes_1g_table, modes_0g):
    from mace_fmu.viewer import animate_pairs

    return animate_pairs(modes_1g_table, modes_0g, frames_per_cycle=8)


def test_pairs_change_from_1g_to_0g_as_table_5_1(pairs_anim):
    """Each pair's 1-g -> 0-g frequency change against the thesis's own columns of Table 5.1.

    Tolerance 1.0 percentage point: our 1-g column (large preload) is within 0.92 % and the 0-g
    one within 0.12 % of the thesis (docs/thesis/main_job.md), so the change can differ by their sum at most.
    The suspension's signature, 1st Y bending 14.7 % lower in 0-g, must show.
    """
    from mace_fmu.thesis import thesis_data

    table = thesis_data()["table_5_1"]
    assert [p.label for p in pairs_anim.pairs] == [r["label"] for r in table]
    for pair, row in zip(pairs_anim.pairs, table):
        thesis_change = 100.0 * (row["g0"] - row["g1"]) / row["g1"]
        assert pair.change_percent == pytest.approx(thesis_change, abs=1.0), pair.label
        assert pair.hz_1g == pytest.approx(row["g1"], rel=0.015) and pair.hz_0g == pytest.approx(row["g0"], rel=0.005)
        assert pair.mac >= 0.83  # docs/thesis/main_job.md: the pairing MACs are 0.84 and up (2nd Y bending: 0.8398)
    first_y = pairs_anim.pairs[1]
    assert first_y.label == "1st Y bending" and first_y.change_percent == pytest.approx(-14.72, abs=0.5)
    # the legend carries both frequencies and the change, as printed
    assert pairs_anim.frames.clips[1].title == (
        f"1st Y bending: 1-g {first_y.hz_1g:.3f} Hz (mode {first_y.index_1g}) -> 0-g {first_y.hz_0g:.3f} Hz "
        f"(mode {first_y.index_0g}), {first_y.change_percent:+.1f} %, MAC {first_y.mac:.2f}")


def test_pairs_move_in_phase(pairs_anim):
    """Turned by the mass-weighted sign, the two copies' drawn translations on their common grids point
    the same way (plain cosine of the translation fields > 0.9 at a quarter cycle of every clip)."""
    one, zero = pairs_anim.one_g, pairs_anim.zero_g
    common = [g for g in zero.scene.grid_ids if g in set(one.scene.grid_ids)]
    r1 = [one.scene.grid_ids.index(g) for g in common]
    r0 = [zero.scene.grid_ids.index(g) for g in common]
    for k, clip in enumerate(pairs_anim.frames.clips):
        frame = k * 8 + 2  # 8 frames per cycle: the quarter-cycle peak
        d1 = one.frames.displacements[frame][r1, :3].ravel()
        d0 = zero.frames.displacements[frame][r0, :3].ravel()
        assert d1 @ d0 / np.linalg.norm(d1) / np.linalg.norm(d0) > 0.9, clip.title
    # each copy's largest drawn translation is 8 % of the article's size, as on the mode pages
    for anim in (one, zero):
        peak = np.linalg.norm(anim.frames.displacements[2, :, :3], axis=1).max()
        assert peak == pytest.approx(0.08 * anim.scene.length_m, rel=1e-12)


def test_pair_page_places_both_copies_and_animates_every_body(pairs_anim):
    """Decoded page: the copies' article centres sit one above the other (deck Y), gap 0.25 article
    lengths; one set_animation moves both copies' masses by their own frames; the camera frames both."""
    from mace_fmu.viewer import pair_commands
    from mace_fmu.viewer.camera import framing_position

    html = standalone_html(pair_commands(pairs_anim), title="t", clips=pairs_anim.frames.clips)
    commands = _decoded_commands(html)
    transforms = {c["path"]: np.array(c["matrix"], dtype=float).reshape(4, 4).T
                  for c in commands if c["type"] == "set_transform"}
    from mace_fmu.viewer.meshcat_scene import Y_UP_TO_Z_UP

    np.testing.assert_array_equal(transforms["/meshcat/mace"], Y_UP_TO_Z_UP)  # no shift: the pair's box centre
    centres = {}
    for kind, anim, name in (("1g", pairs_anim.one_g, "one_g"), ("0g", pairs_anim.zero_g, "zero_g")):
        placed = transforms[f"/meshcat/mace/{name}"] @ np.append(anim.scene.centre_m, 1.0)
        centres[kind] = placed[:3]
    step = centres["1g"] - centres["0g"]
    height = max(pairs_anim.one_g.scene.extent_m[1], pairs_anim.zero_g.scene.extent_m[1])
    np.testing.assert_allclose(step, [0.0, height + 0.25 * pairs_anim.length_m, 0.0], atol=1e-12)
    np.testing.assert_allclose(centres["1g"] + centres["0g"], 0.0, atol=1e-12)
    animations = [c for c in commands if c["type"] == "set_animation"]
    assert len(animations) == 1  # meshcat's animator keeps one timeline: both copies are in it
    n_frames = pairs_anim.frames.times_s.size
    for name, anim in (("one_g", pairs_anim.one_g), ("zero_g", pairs_anim.zero_g)):
        for body in anim.scene.masses[::4]:
            got = _track_values(animations[0], f"{name}/{body.name}", "position").reshape(n_frames, 3)
            want = anim.scene.positions_m[body.row] + anim.frames.displacements[:, body.row, :3]
            np.testing.assert_allclose(got, want, atol=2e-7)
    camera = next(c for c in commands if c["type"] == "set_property" and c["path"].startswith("/Cameras"))
    np.testing.assert_allclose(camera["value"], framing_position(pairs_anim.extent_m, length_m=pairs_anim.length_m,
                                                                 view="iso"))


def test_pairs_stack_along_the_pictures_up(modes_1g_table, modes_0g):
    """Seen from above (--camera y) the copies stack along deck Z, so they do not hide each other."""
    from mace_fmu.viewer import animate_pairs

    anim = animate_pairs(modes_1g_table, modes_0g, labels=["1st Y", "torsion"], view="y", frames_per_cycle=4)
    assert [p.label for p in anim.pairs] == ["1st Y bending", "torsion, secondary end", "torsion, primary end"]
    assert anim.offsets_m["1g"][1] == 0.0 and anim.offsets_m["1g"][2] < 0.0  # picture's up is -Z from above
    with pytest.raises(MaceError, match="no Table 5.1 mode starts with 'twist'"):
        animate_pairs(modes_1g_table, modes_0g, labels=["twist"])


@needs_chromium
def test_pair_page_shows_two_articles_and_marks_the_pair(modes_1g_table, modes_0g, tmp_path):
    """In Chromium: the reaction-wheel pixels form two blobs one above the other (the two copies), and the
    legend marks the pair whose span holds the animator's time."""
    from PIL import Image

    from mace_fmu.viewer import animate_pairs

    pairs_anim = animate_pairs(modes_1g_table, modes_0g, labels=["1st Z", "1st Y", "2nd Y"], frames_per_cycle=8)
    page = tmp_path / "pairs.html"
    write_animation_html(pairs_anim, page, title="pairs")
    shot = BUILD / "viewer_pairs_600x400.png"
    dom = render_page(page, png=shot, width_px=600, height_px=400)  # picture and DOM of the same moment
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    wheels = _component_mask(pixels, _ARTICLE_HUES["reaction_wheels"])
    rows = np.nonzero(wheels)[0]
    gaps = np.diff(np.unique(rows))
    split = np.unique(rows)[np.argmax(gaps)]
    upper, lower = (rows <= split).sum(), (rows > split).sum()
    assert gaps.max() > 10 and min(upper, lower) > 75, f"wheel pixels {upper} above, {lower} below, gap {gaps.max()}"
    time_s = float(re.search(r'id="mace-legend" data-time="([0-9.e-]+)"', dom).group(1))
    playing = re.findall(r'<tr [^>]*class="playing"><td>[^<]*</td><td>([^<]*)</td>', dom)
    holding = [c.title for c in pairs_anim.frames.clips if c.start_s <= time_s < c.end_s]
    assert time_s > 0.0 and [html_text.unescape(t) for t in playing] == holding and len(holding) == 1


def test_cli_view_pairs(tmp_path, capsys):
    from mace_fmu.cli import main

    out = tmp_path / "pairs.html"
    assert main(["view", "pairs", "--mode", "1st Y", "--mode", "torsion, primary", "--preload", "linear",
                 "--html", str(out)]) == 0
    printed = capsys.readouterr().out
    assert printed_in("1st Y bending: 1-g 3.595 Hz", printed) and printed_in("-> 0-g 3.074 Hz", printed)
    assert printed_in("-14.5 %", printed)
    assert printed_in("torsion, primary end: 1-g 11.871 Hz", printed) and printed_in("+4.6 %", printed)
    commands = _decoded_commands(out.read_text())
    assert {c["path"].split("/")[3] for c in commands if c["type"] == "set_object"
            and c["path"].count("/") > 3} >= {"one_g", "zero_g"}
    assert main(["view", "pairs", "--mode", "twist", "--html", str(out)]) == 2
    assert "no Table 5.1 mode starts with 'twist'" in capsys.readouterr().err


def test_cli_view_response_takes_a_native_motion_fmu(motion_fmu_0g, tmp_path, capsys):
    """The default kind of `mace-fmu export` (native) is accepted by --fmu, and its page's frames come
    from the same motion outputs as the pythonfmu FMU's (same model, 1e-9 of the largest motion)."""
    from mace_fmu.cli import main
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.fmu.simulate import simulate_input_response

    model, python_fmu, _ = motion_fmu_0g
    native = export_fmu(model, out_dir=tmp_path, name="MACE_0g_native_motion")
    out = tmp_path / "native.html"
    assert main(["view", "response", "0g", "--input", "rwa_z", "--duration", "0.1", "--fmu", str(native),
                 "--html", str(out)]) == 0
    assert "frames at" in capsys.readouterr().out
    runs = [simulate_input_response(fmu, input_name="rwa_z", signal="impulse", duration_s=0.1)
            for fmu in (native, python_fmu)]
    motion = [k for k in runs[1].outputs if k.startswith("grid_")]
    scale = max(np.abs(runs[1].outputs[k]).max() for k in motion)
    assert scale > 0
    for k in motion:
        np.testing.assert_allclose(runs[0].outputs[k], runs[1].outputs[k], rtol=0, atol=1e-9 * scale)


def test_a_notebook_shows_an_animation_inline_as_its_standalone_page(modes_0g):
    """``_repr_html_``: the same page write_animation_html writes, in an iframe's srcdoc (no server)."""
    import html

    from mace_fmu.viewer import animation_commands, standalone_html

    anim = animate_modes(modes_0g, [14], frames_per_cycle=12)
    shown = anim._repr_html_()
    assert shown.startswith('<iframe srcdoc="') and shown.endswith("</iframe>")
    page = html.unescape(shown[len('<iframe srcdoc="'):shown.index('" style=')])
    again = standalone_html(animation_commands(anim), title="ModeAnimation", clips=anim.frames.clips)
    # the same page up to meshcat's fresh object UUIDs: same length, same viewer, same legend, same commands
    assert len(page) == len(again) and page.count('\n"') == again.count('\n"') > 100
    assert "new MeshCat.Viewer" in page and printed_in("mode 14: 2.100 Hz 1st Z bending", page)


def test_cli_view_response_of_a_modal_test_animates_floors_whose_acceleration_the_accelerometer_reads(tmp_path, capsys):
    """The three-storey frame, struck on floor 1 (an impulse of 1 N over the first 1 ms step): the page and the
    plot name the frame, not MACE, the FMU it wrote is taken back with --fmu, and the floor motion the viewer
    animates (grid 100's X displacement) has, by second differences, the acceleration the accelerometer reads."""
    from mace_fmu.cli import main
    from mace_fmu.fmu.simulate import simulate_input_response

    frame = Path(__file__).resolve().parents[2] / "examples" / "three_storey_frame"
    options = ["view", "response", "1g", "--deck", str(frame / "frame.bdf"), "--structure", str(frame / "frame.toml"),
               "--input", "force_floor_1", "--signal", "impulse", "--duration", "0.5", "--step", "0.001"]
    out = tmp_path / "frame.html"
    assert main([*options, "--html", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "(force_floor_1 and acc_floor_1 over time)" in printed
    fmu = tmp_path / "frame_1g_motion.fmu"
    assert "frame 1g: impulse response to force_floor_1" in out.read_text()
    assert main([*options, "--fmu", str(fmu), "--html", str(tmp_path / "again.html")]) == 0
    run = simulate_input_response(fmu, input_name="force_floor_1", signal="impulse", duration_s=0.5, step_s=0.001)
    assert run.units["force_floor_1"] == "N" and run.units["acc_floor_1"] == "m/s^2"
    u, a, h = run.outputs["grid_100_tx"], run.outputs["acc_floor_1"], 0.001
    second_difference = (u[2:] - 2 * u[1:-1] + u[:-2]) / h**2
    free = slice(5, None)  # after the blow: the exact ZOH's samples of a free response
    # central differences err by (w h)^2 / 12 of each mode: 2.3e-3 at the third mode (26.5 Hz)
    assert np.max(np.abs(second_difference[free] - a[1:-1][free])) < 3e-3 * np.max(np.abs(a[1:-1][free]))
