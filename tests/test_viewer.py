"""Viewer: the scene against the deck, key frames against shape x scale x sin, and a real browser."""

from __future__ import annotations

import base64
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import umsgpack

from mace_fmu.errors import MaceError
from mace_fmu.pipeline import compute_modes
from viewer import (animate_mode, animate_modes, animate_response, build_scene, scene_commands, standalone_html,
                    write_animation_html)
from viewer.frames import body_motion
from viewer.meshcat_scene import FLOAT32_EXT
from viewer.scene import tube_outer_radius_m

BUILD = Path(__file__).resolve().parents[1] / "build"


@pytest.fixture(scope="module")
def modes_0g():
    return compute_modes(structure="0g", max_hz=60.0)


@pytest.fixture(scope="module")
def modes_1g():
    return compute_modes(structure="1g", max_hz=20.0)


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


def _chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(params=["modes", "response"])
def page_0g(request, modes_0g, motion_fmu_0g, step_run_0g, tmp_path):
    """(page, screenshot path): two 0-g mode clips, or the step response of the secondary gimbal."""
    if request.param == "modes":
        anim = animate_modes(modes_0g, [14, 15], frames_per_cycle=12)
    else:
        anim = animate_response(motion_fmu_0g[0].structure_modes, step_run_0g)
    page = tmp_path / f"{request.param}.html"
    write_animation_html(anim, page, title=f"MACE 0g {request.param}")
    return page, BUILD / f"viewer_0g_{request.param}.png"


@pytest.mark.skipif(_chromium() is None and not os.environ.get("MACE_REQUIRE_CHROMIUM"),
                    reason="Debian chromium not installed (.ci/run installs it and requires this test)")
def test_html_renders_the_structure_in_headless_chromium(page_0g, tmp_path):
    from PIL import Image

    assert _chromium(), "chromium missing: .ci/run must install Debian's chromium"
    page, shot = page_0g
    BUILD.mkdir(exist_ok=True)
    shot.unlink(missing_ok=True)
    subprocess.run([_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                    "--use-angle=swiftshader", "--disable-quic", "--no-first-run", "--disable-background-networking",
                    "--disable-component-update", "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}",
                    "--window-size=800,600", "--virtual-time-budget=3000", f"--screenshot={shot}", page.as_uri()],
                   check=True, capture_output=True, timeout=240)
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert pixels.shape == (600, 800, 3)
    assert pixels.std() > 20.0  # not blank
    r, g, b = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    # the bus is drawn in its component blue (0x4A7FC1), the secondary gimbal red, the wheels green
    bus_like = (np.abs(r - 0x4A) < 40) & (np.abs(g - 0x7F) < 40) & (b > 150) & (b - r > 60)
    red_like = (r > 150) & (g < 110) & (b < 130)
    green_like = (g > 120) & (r < 110) & (b < 120)
    assert bus_like.sum() > 200, f"bus pixels: {bus_like.sum()}"
    assert red_like.sum() > 50, f"secondary gimbal pixels: {red_like.sum()}"
    assert green_like.sum() > 50, f"wheel pixels: {green_like.sum()}"


#: hue [deg] of each component drawn in the gimbal and wheel colours (viewer.scene.COMPONENT_COLOURS)
_ARTICLE_HUES = {"primary_gimbal": 29.0, "secondary_gimbal": 351.0, "reaction_wheels": 127.0}


def _screenshot(page: Path, shot: Path, profile: Path, *, width: int, height: int) -> np.ndarray:
    """RGB pixels of ``page`` rendered by headless Chromium after 3 s of virtual time."""
    from PIL import Image

    shot.parent.mkdir(parents=True, exist_ok=True)
    shot.unlink(missing_ok=True)
    subprocess.run([_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
                    "--use-angle=swiftshader", "--disable-quic", "--no-first-run", "--disable-background-networking",
                    "--disable-component-update", "--disable-sync", f"--user-data-dir={profile}",
                    f"--window-size={width},{height}", "--virtual-time-budget=3000", f"--screenshot={shot}",
                    page.as_uri()], check=True, capture_output=True, timeout=240)
    return np.asarray(Image.open(shot).convert("RGB"), dtype=float)


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
    return page, BUILD / f"viewer_{request.param}_1200x800.png"


@pytest.mark.skipif(_chromium() is None and not os.environ.get("MACE_REQUIRE_CHROMIUM"),
                    reason="Debian chromium not installed (.ci/run installs it and requires this test)")
@pytest.mark.xfail(strict=True, reason="today's camera: 1-g modes 49/20/73 gimbal/wheel pixels at the origin, "
                   "0-g modes span 34.6 %, 0-g response 33.4 % of the width")
def test_pages_open_framed_on_the_test_article(framed_page, tmp_path):
    """At 1200 x 800 the gimbals and wheels, found by their colours, span at least 40 % of the width."""
    assert _chromium(), "chromium missing: .ci/run must install Debian's chromium"
    page, shot = framed_page
    pixels = _screenshot(page, shot, tmp_path / "profile", width=1200, height=800)
    assert pixels.shape == (800, 1200, 3)
    span, counts = _article_span(pixels)
    assert min(counts.values()) > 30, f"gimbal and wheel pixels: {counts}"
    assert span >= 0.40, f"gimbals and wheels span {100 * span:.1f} % of the width ({counts} pixels)"


def test_cli_writes_the_html_and_lists_the_clips(tmp_path, capsys):
    from mace_fmu.cli import main

    out = tmp_path / "m.html"
    assert main(["view", "modes", "0g", "--mode", "1st Z bending", "--mode", "15", "--html", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "mode 14: 2.100 Hz 1st Z bending" in printed and "mode 15:" in printed
    commands = _decoded_commands(out.read_text())
    assert sum(c["type"] == "set_object" for c in commands) > 100
    assert main(["view", "modes", "0g", "--mode", "no such", "--html", str(out)]) == 2
    assert "exactly one mode" in capsys.readouterr().err


def test_live_meshcat_server_receives_the_same_animation(modes_0g):
    """The live path (a real meshcat server) stores exactly the commands the standalone page embeds."""
    meshcat = pytest.importorskip("meshcat")
    from viewer import send_to_visualizer

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
    commands = _decoded_commands(out.read_text())
    assert sum(c["type"] == "set_object" for c in commands) > 100
    assert sum(c["type"] == "set_animation" for c in commands) == 1
    plot = np.asarray(Image.open(out.with_suffix(".png")).convert("L"), dtype=float)
    assert plot.std() > 10.0  # axes and curves, not a blank image
    assert main(["view", "response", "0g", "--input", "no_such_input", "--fmu", str(fmu), "--html", str(out)]) == 2
    assert "has no input 'no_such_input'; inputs: gimbal_primary_x" in capsys.readouterr().err
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
    assert f"wrote {fmu}" in capsys.readouterr().out and out.exists() and out.with_suffix(".png").exists()
    outputs = [v for v in fmpy.read_model_description(str(fmu)).modelVariables if v.causality == "output"]
    assert len(outputs) == 20 + 6 * 79
