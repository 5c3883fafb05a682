"""``mace-fmu view``: meshcat animations of mode shapes and of FMU time responses (standalone HTML)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mace_fmu.cli.common import (CONFIGURATIONS, deck_option, finite_number, model_options, non_negative_hz,
                                 positive_hz, positive_integer, positive_number, progress, progress_bar, volts)
from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError

#: mace_fmu.viewer.camera.CAMERA_VIEWS, spelled out so that `mace-fmu --help` does not import meshcat
CAMERA_CHOICES = ("iso", "x", "y", "z")


def _show(animation, args: argparse.Namespace, *, title: str) -> None:
    """Write the animation to --html, a still of it to --png, and/or serve it live until Ctrl-C."""
    import tempfile

    from mace_fmu.viewer import animation_commands, send_to_visualizer, write_animation_html, write_still  # meshcat only here

    if args.html:
        size = write_animation_html(animation, args.html, title=title, camera=args.camera)
        print(f"wrote {args.html} ({size / 1e6:.1f} MB, {animation.frames.times_s.size} frames)")
    if args.png:
        with tempfile.TemporaryDirectory(prefix="mace_fmu_page_") as tmp:
            page = args.html or Path(tmp) / "page.html"
            if not args.html:
                write_animation_html(animation, page, title=title, camera=args.camera)
            write_still(page, args.png, width_px=args.png_size[0], height_px=args.png_size[1])
        print(f"wrote {args.png} (still from headless Chromium, {args.camera} view)")
    if args.live:
        import time

        import meshcat

        visualizer = meshcat.Visualizer()
        send_to_visualizer(visualizer, animation_commands(animation, camera=args.camera))
        print(f"meshcat server at {visualizer.url()} - Ctrl-C to stop", flush=True)
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass


def _need_target(args: argparse.Namespace) -> None:
    """An output is named, and a still can be taken (before any work is done)."""
    from mace_fmu.viewer import chromium_executable

    if not (args.html or args.png or args.live):
        raise MaceError("say where to show the animation: --html OUT.html, --png OUT.png, --live, or several")
    if args.png and not all(16 <= px <= 8192 for px in args.png_size):
        raise MaceError(f"--png-size {' '.join(map(str, args.png_size))}: expected WIDTH HEIGHT in pixels, each "
                        "16-8192")
    if args.png and chromium_executable() is None:
        raise MaceError("--png needs headless Chromium, which is not installed (Debian: apt-get install chromium); "
                        "use --html and open the page in a browser")


def _check_signals(args: argparse.Namespace, deck, *, modal=None) -> str:
    """Check --output (a sensor or a grid motion of this structure) and the run's times; returns the output.

    --input is checked by argparse (its choices). The default output is the sensor collocated
    with the input. All of this is known before anything is exported or simulated.
    """
    from mace_fmu.deck.geometry import grid_positions
    from mace_fmu.fmu.simulate import communication_times, input_signal
    from mace_fmu.iomodel.collocation import collocated_sensor
    from mace_fmu.iomodel.instruments import load_instruments
    from mace_fmu.iomodel.motion import MOTION_COMPONENTS, parse_motion_output
    from mace_fmu.structure.build import build_structure
    from mace_fmu.structure.file import structure_file_for

    input_signal(args.signal, communication_times(duration_s=args.duration, step_s=args.step),
                 amplitude_v=args.amplitude, chirp_hz=tuple(args.chirp_hz))
    file = modal.file if modal is not None else structure_file_for(deck, args.structure_file)
    if file is None or not file.has("actuators"):
        raise MaceError(f"{deck.path}: a time response needs the actuators and sensors of a structure file "
                        "(--structure FILE)")
    instruments = load_instruments(file)
    actuators = [a.name for a in instruments.actuators]
    if args.input not in actuators:
        raise MaceError(f"--input {args.input!r} is not an actuator of {file.path}: use one of {', '.join(actuators)}")
    if args.output is None:
        return collocated_sensor(instruments, args.input, modal.positions or {} if modal is not None
                                 else grid_positions(deck))
    sensors = [s.name for s in instruments.sensors]
    motion = parse_motion_output(args.output)
    grids = modal.modes.dofs.grid_ids if modal is not None else \
        build_structure(deck, configuration=args.configuration, structure_file=file).deck.grids
    if args.output in sensors or (motion is not None and motion[0] in grids):
        return args.output
    raise MaceError(f"--output {args.output!r} is not an output of the {args.configuration} model: use a sensor "
                    f"({', '.join(sensors)}) or grid_<id>_<{'|'.join(MOTION_COMPONENTS)}> for one of its "
                    f"{len(grids)} grids")


def _checked_fmu(path: str, configuration: str, label: str) -> Path:
    """--fmu: an existing FMU of this structure (``label``, :func:`~mace_fmu.structure.file.structure_label`) and
    configuration, with grid motion outputs."""
    import fmpy

    from mace_fmu.fmu.archive import check_fmu
    from mace_fmu.iomodel.motion import parse_motion_output

    fmu = Path(path)
    if not fmu.is_file():
        raise MaceError(f"--fmu {fmu}: no such file")
    check_fmu(fmu)  # a foreign, damaged or malicious archive is refused before fmpy opens it
    md = fmpy.read_model_description(str(fmu))
    if not (md.description or "").startswith(f"{label} {configuration} "):
        raise MaceError(f"--fmu {fmu} is not a {label} {configuration} model (its description: {md.description!r})")
    if not any(parse_motion_output(v.name) for v in md.modelVariables if v.causality == "output"):
        raise MaceError(f"--fmu {fmu} has no grid motion outputs; export one with "
                        f"mace-fmu export {configuration} --motion-grids all")
    return fmu


def cmd_view_response(args: argparse.Namespace) -> int:
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.fmu.simulate import simulate_input_response
    from mace_fmu.structure.file import structure_label
    from mace_fmu.viewer import animate_response, plot_response

    _need_target(args)
    if args.configuration == "modes":  # NASTRAN's modes: the scene from the [modes] table's geometry deck
        from mace_fmu.cli.common import modal_structure_of

        deck, modal = None, modal_structure_of(args)
        label = modal.name
    else:
        deck, modal = read_deck(args.deck), None
        label = structure_label(deck)
    output = _check_signals(args, deck, modal=modal)
    out_dir = Path(args.html or args.png).parent if (args.html or args.png) else Path(".")  # FMU next to the page
    if args.fmu:
        fmu = _checked_fmu(args.fmu, args.configuration, label)
        if modal is not None:
            modes = modal
        else:
            # only the scene is needed from the FE model; the deck's own range of modes (a fixed low one would hold
            # no mode of a stiffer structure)
            with progress_bar() as bar:
                modes = compute_modes(deck, configuration=args.configuration, preload=args.preload,
                                      progress=bar, structure_file=args.structure_file)
    else:
        progress(f"{args.configuration} volts-volts model with the motion of every grid")
        model = volts(args, every_grid_moves=True)
        modes = model.structure_modes
        # the name `mace-fmu export --motion-grids all` gives it
        fmu = export_fmu(model, out_dir=out_dir, runtime="pythonfmu")
        print(f"wrote {fmu} (reuse it with --fmu)")
    progress(f"simulating {args.duration} s of {args.signal} on {args.input} through fmpy")
    run = simulate_input_response(fmu, input_name=args.input, signal=args.signal, duration_s=args.duration,
                                  step_s=args.step, amplitude_v=args.amplitude, chirp_hz=tuple(args.chirp_hz))
    animation = animate_response(modes, run, scale=args.scale, playback_speed=args.speed, fps=args.fps)
    print(f"  {animation.frames.times_s.size} frames at {animation.frames.fps:.3g} frames/s of playback, "
          f"{args.speed:g} simulated s per s, motion drawn x {animation.scale:.4g}")
    if args.html:
        png = plot_response(run, output_name=output, path=signals_plot_path(args.html),
                            title=f"{label} {args.configuration}: {args.signal} on {args.input}")
        print(f"wrote {png} ({args.input} and {output} over time)")
    _show(animation, args, title=f"{label} {args.configuration}: {args.signal} response to {args.input}")
    return 0


def signals_plot_path(html: str | Path) -> Path:
    """Where view response puts its plot of input and output: <page name>_signals.png next to the page."""
    html = Path(html)
    return html.with_name(f"{html.stem}_signals.png")


def cmd_view(args: argparse.Namespace) -> int:
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.structure.file import structure_label
    from mace_fmu.viewer import animate_modes

    _need_target(args)
    if args.configuration == "modes":  # NASTRAN's modes: every mode of the file, drawn on the geometry deck's edges
        from mace_fmu.cli.common import modal_structure_of

        result = modal_structure_of(args)
        title = f"{result.name}: NASTRAN's modes"
    else:
        deck = read_deck(args.deck)
        max_hz = args.max_hz if args.max_hz is not None else (None if args.mode else 60.0)
        with progress_bar() as bar:
            result = compute_modes(deck, configuration=args.configuration, max_hz=max_hz, progress=bar,
                                   structure_file=args.structure_file)
        title = f"{structure_label(deck)} {args.configuration} modes"
    modes = args.mode or list(range(1, result.frequencies_hz.size + 1))
    animation = animate_modes(result, modes, scale=args.scale, cycles=args.cycles,
                              seconds_per_cycle=args.seconds_per_cycle)
    for clip in animation.frames.clips:
        print(f"  {clip.start_s:6.1f}-{clip.end_s:6.1f} s  {clip.title}")
    _show(animation, args, title=title)
    return 0


def cmd_view_pairs(args: argparse.Namespace) -> int:
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.viewer import animate_pairs

    _need_target(args)
    deck = read_deck(args.deck)
    progress("0-g modes")
    zero_g = compute_modes(deck, configuration="0g", max_hz=args.max_hz, structure_file=args.structure_file)
    progress(f"1-g modes ({args.preload} gravity preload)")
    with progress_bar() as bar:
        one_g = compute_modes(deck, configuration="1g", preload=args.preload, max_hz=args.max_hz, progress=bar,
                              structure_file=args.structure_file)
    animation = animate_pairs(one_g, zero_g, labels=args.mode, view=args.camera, cycles=args.cycles,
                              seconds_per_cycle=args.seconds_per_cycle)
    print("Table 5.1 pairs (1-g above, 0-g below; change = 0-g vs 1-g)")
    for clip in animation.frames.clips:
        print(f"  {clip.start_s:6.1f}-{clip.end_s:6.1f} s  {clip.title}")
    _show(animation, args, title=f"MACE 1-g (top, {args.preload} preload) and 0-g (bottom) modes of Table 5.1")
    return 0


def _output_options(p: argparse.ArgumentParser, *, html: str) -> None:
    """Where the animation goes and from where it is seen (both view commands)."""
    output_option(p, "--html", kind="file", help=html)
    output_option(p, "--png", kind="file", type=_png_path,
                  help="write a still of the page (a .png file) through headless Chromium, if installed")
    p.add_argument("--png-size", type=positive_integer, nargs=2, default=[1200, 800], metavar=("WIDTH", "HEIGHT"),
                   help="size of the still [px] (default 1200 800)")
    p.add_argument("--camera", choices=CAMERA_CHOICES, default="iso",
                   help="initial view: iso (3/4 view, default), or along the x, y (from above) or z axis")
    p.add_argument("--live", action="store_true", help="also serve it on a live meshcat server until Ctrl-C")


def _png_path(text: str) -> str:
    """argparse type: a .png file to write (Chromium's still is a PNG whatever the name says)."""
    if not text.lower().endswith(".png"):
        raise argparse.ArgumentTypeError(f"the still is a PNG image: give a file ending in .png, got {text!r}")
    return text


def register(sub: argparse._SubParsersAction) -> None:
    # the signal names for --help, from the bundled structure file's tables (not the instruments module, which
    # brings python-control: `mace-fmu --help` answers at once)
    from mace_fmu.structure.file import bundled_structure_path, load_structure_file

    tables = load_structure_file(bundled_structure_path()).tables
    actuator_names = [a["name"] for a in tables.get("actuators", [])]
    sensor_names = [s["name"] for s in tables.get("sensors", [])]

    p = sub.add_parser("view", help="meshcat animation of mode shapes or FMU time responses (standalone HTML)")
    view = p.add_subparsers(dest="what", required=True)
    p = view.add_parser("modes", help="animate mode shapes (one clip per mode, one after the other)")
    p.add_argument("configuration", choices=CONFIGURATIONS,
                   help="the deck's 1-g or 0-g structure, or 'modes': NASTRAN's modes, named by --structure FILE's "
                        "[modes] table (every mode of the file; drawn on its geometry deck's element edges)")
    deck_option(p)
    p.add_argument("--mode", action="append", help="1-based index or label (prefix); repeat for several "
                   "(default: every mode up to --max-hz)")
    p.add_argument("--max-hz", type=positive_hz, default=None,
                   help="highest mode computed [Hz] (default 60 without --mode)")
    p.add_argument("--scale", type=positive_number, default=None,
                   help="metres drawn per unit mass-normalised shape (default: largest motion 8%% of the size)")
    p.add_argument("--cycles", type=positive_integer, default=1, help="vibration cycles per mode (default 1)")
    p.add_argument("--seconds-per-cycle", type=positive_number, default=1.0, help="playback time of one cycle [s]")
    _output_options(p, html="write a standalone HTML file (opens in any browser, no server)")
    p.set_defaults(func=cmd_view)

    p = view.add_parser("pairs", help="Table 5.1's 1-g and 0-g modes, paired by MAC, side by side (1-g above)")
    deck_option(p)
    p.add_argument("--mode", action="append", help="a Table 5.1 mode by label prefix, e.g. '1st Y'; repeat for "
                   "several (default: all 14)")
    p.add_argument("--preload", choices=["large", "linear"], default="large",
                   help="1-g gravity preload (default large, as mace-fmu build's FMUs)")
    p.add_argument("--max-hz", type=positive_hz, default=60.0,
                   help="highest mode computed [Hz] (default 60: Table 5.1 ends at 54 Hz)")
    p.add_argument("--cycles", type=positive_integer, default=1, help="vibration cycles per mode (default 1)")
    p.add_argument("--seconds-per-cycle", type=positive_number, default=1.0, help="playback time of one cycle [s]")
    _output_options(p, html="write a standalone HTML file (opens in any browser, no server)")
    p.set_defaults(func=cmd_view_pairs)

    p = view.add_parser("response", help="an FMU's time response to one input, played on the mesh (fmpy)")
    p.add_argument("configuration", choices=CONFIGURATIONS,
                   help="the deck's 1-g or 0-g structure, or 'modes': NASTRAN's modes, named by --structure FILE's "
                        "[modes] table")
    deck_option(p)
    p.add_argument("--input", required=True, metavar="INPUT",
                   help="the driven input, an actuator of the structure file (MACE: "
                        + ", ".join(actuator_names) + ")")
    p.add_argument("--signal", choices=["step", "chirp", "impulse"], default="step",
                   help="step from t = 0, chirp (see --chirp-hz), or a pulse over the first step (default step)")
    p.add_argument("--duration", type=positive_number, default=2.0, help="simulated time [s] (default 2)")
    p.add_argument("--amplitude", type=finite_number, default=1.0,
                   help="signal amplitude in the input's unit (V, or N for a force input in newtons; default 1)")
    p.add_argument("--chirp-hz", type=non_negative_hz, nargs=2, default=[0.1, 10.0], metavar=("F0", "F1"),
                   help="chirp start and end frequency [Hz] (default 0.1 10)")
    p.add_argument("--step", type=positive_number, default=0.002, help="FMU communication step [s] (default 0.002)")
    p.add_argument("--speed", type=positive_number, default=1.0,
                   help="playback speed: simulated s per s (default 1, real time)")
    p.add_argument("--fps", type=positive_number, default=50.0, help="key frames per second of playback (default 50)")
    p.add_argument("--scale", type=positive_number, default=None,
                   help="magnification of the motion (default: largest motion 8%% of the size)")
    p.add_argument("--output", help="output plotted next to the input: a sensor (" + ", ".join(sensor_names)
                   + ") or grid_<id>_<tx|ty|tz|rx|ry|rz> (default: the sensor "
                   "collocated with the input: its encoder or tachometer, the active strut's strain gauge)")
    p.add_argument("--fmu", help="an FMU with motion outputs to run (default: export one next to the HTML)")
    _output_options(p, html="write a standalone HTML file and, next to it, <name>_signals.png: input and output "
                    "over time")
    model_options(p, motion=False)  # the exported FMU carries the motion of every grid
    p.set_defaults(func=cmd_view_response)
