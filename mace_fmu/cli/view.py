"""``mace-fmu view``: meshcat animations of mode shapes and of FMU time responses (standalone HTML)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mace_fmu.cli.common import deck_option, model_options, progress, volts
from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.pipeline import compute_modes


def _show(animation, args: argparse.Namespace, *, title: str) -> None:
    """Write the animation to --html and/or serve it on a live meshcat server until Ctrl-C."""
    from viewer import scene_commands, send_to_visualizer, write_animation_html  # meshcat only here

    if args.html:
        size = write_animation_html(animation, args.html, title=title)
        print(f"wrote {args.html} ({size / 1e6:.1f} MB, {animation.frames.times_s.size} frames)")
    if args.live:
        import time

        import meshcat

        visualizer = meshcat.Visualizer()
        send_to_visualizer(visualizer, scene_commands(animation.scene, animation.frames))
        print(f"meshcat server at {visualizer.url()} - Ctrl-C to stop", flush=True)
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass


def _need_target(args: argparse.Namespace) -> None:
    if not args.html and not args.live:
        raise MaceError("say where to show the animation: --html OUT.html, --live, or both")


def cmd_view_response(args: argparse.Namespace) -> int:
    from mace_fmu.fmu.archive import check_fmu
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.fmu.simulate import simulate_input_response
    from viewer import animate_response, plot_response

    _need_target(args)
    out_dir = Path(args.html).parent if args.html else Path(".")
    if args.fmu:
        import fmpy

        fmu = check_fmu(args.fmu)  # a foreign, damaged or malicious archive is refused before fmpy opens it
        described = fmpy.read_model_description(str(fmu)).description or ""
        if not described.startswith(f"MACE {args.structure} "):
            raise MaceError(f"--fmu {fmu} is not a MACE {args.structure} model (its description: {described!r})")
        # only the scene is needed from the FE model: its lowest modes are enough
        modes = compute_modes(read_deck(args.deck), structure=args.structure, preload=args.preload, max_hz=1.0,
                              progress=progress)
    else:
        progress(f"{args.structure} volts-volts model with the motion of every grid")
        model = volts(args, motion_grids="all")
        modes = model.structure_modes
        fmu = export_fmu(model, out_dir=out_dir, name=f"MACE_{args.structure}_motion")
        print(f"wrote {fmu} (reuse it with --fmu)")
    progress(f"simulating {args.duration} s of {args.signal} on {args.input} through fmpy")
    run = simulate_input_response(fmu, input_name=args.input, signal=args.signal, duration_s=args.duration,
                                  step_s=args.step, amplitude_v=args.amplitude, chirp_hz=tuple(args.chirp_hz))
    animation = animate_response(modes, run, scale=args.scale, playback_speed=args.speed, fps=args.fps)
    print(f"  {animation.frames.times_s.size} frames at {animation.frames.fps:.3g} frames/s of playback, "
          f"{args.speed:g} simulated s per s, motion drawn x {animation.scale:.4g}")
    output = args.output or _collocated_output(args.input, run)
    if args.html:
        png = plot_response(run, output_name=output, path=Path(args.html).with_suffix(".png"),
                            title=f"MACE {args.structure}: {args.signal} on {args.input}")
        print(f"wrote {png}")
    _show(animation, args, title=f"MACE {args.structure}: {args.signal} response to {args.input}")
    return 0


def _collocated_output(input_name: str, run) -> str:
    """The sensor that closes the input's local loop (encoder, tachometer), else the first sensor output."""
    from mace_fmu.iomodel.instruments import load_instruments
    from mace_fmu.iomodel.motion import parse_motion_output

    servos = load_instruments().servos
    partner = {**servos.gimbals, **servos.wheels}.get(input_name)
    if partner in run.outputs:
        return partner
    return next((n for n in run.outputs if parse_motion_output(n) is None), next(iter(run.outputs)))


def cmd_view(args: argparse.Namespace) -> int:
    from viewer import animate_modes

    _need_target(args)
    deck = read_deck(args.deck)
    max_hz = args.max_hz if args.max_hz is not None else (None if args.mode else 60.0)
    result = compute_modes(deck, structure=args.structure, max_hz=max_hz, progress=progress)
    modes = args.mode or list(range(1, result.modes.frequencies_hz.size + 1))
    animation = animate_modes(result, modes, scale=args.scale, cycles=args.cycles,
                              seconds_per_cycle=args.seconds_per_cycle)
    for clip in animation.frames.clips:
        print(f"  {clip.start_s:6.1f}-{clip.end_s:6.1f} s  {clip.title}")
    _show(animation, args, title=f"MACE {args.structure} modes")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("view", help="meshcat animation of mode shapes or FMU time responses (standalone HTML)")
    view = p.add_subparsers(dest="what", required=True)
    p = view.add_parser("modes", help="animate mode shapes (one clip per mode, one after the other)")
    p.add_argument("structure", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("--mode", action="append", help="1-based index or label (prefix); repeat for several "
                   "(default: every mode up to --max-hz)")
    p.add_argument("--max-hz", type=float, default=None, help="highest mode computed [Hz] (default 60 without --mode)")
    p.add_argument("--scale", type=float, default=None,
                   help="metres drawn per unit mass-normalised shape (default: largest motion 8%% of the size)")
    p.add_argument("--cycles", type=int, default=1, help="vibration cycles per mode (default 1)")
    p.add_argument("--seconds-per-cycle", type=float, default=1.0, help="playback time of one cycle [s]")
    p.add_argument("--html", help="write a standalone HTML file (opens in any browser, no server)")
    p.add_argument("--live", action="store_true", help="also serve it on a live meshcat server until Ctrl-C")
    p.set_defaults(func=cmd_view)

    p = view.add_parser("response", help="an FMU's time response to one input, played on the mesh (fmpy)")
    p.add_argument("structure", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("--input", required=True, help="the driven input, e.g. gimbal_secondary_z")
    p.add_argument("--signal", choices=["step", "chirp", "impulse"], default="step",
                   help="step from t = 0, chirp (see --chirp-hz), or a pulse over the first step (default step)")
    p.add_argument("--duration", type=float, default=2.0, help="simulated time [s] (default 2)")
    p.add_argument("--amplitude", type=float, default=1.0, help="signal amplitude [V] (default 1)")
    p.add_argument("--chirp-hz", type=float, nargs=2, default=[0.1, 10.0], metavar=("F0", "F1"),
                   help="chirp start and end frequency [Hz] (default 0.1 10)")
    p.add_argument("--step", type=float, default=0.002, help="FMU communication step [s] (default 0.002)")
    p.add_argument("--speed", type=float, default=1.0, help="playback speed: simulated s per s (default 1, real time)")
    p.add_argument("--fps", type=float, default=50.0, help="key frames per second of playback (default 50)")
    p.add_argument("--scale", type=float, default=None,
                   help="magnification of the motion (default: largest motion 8%% of the size)")
    p.add_argument("--output", help="output plotted next to the input (default: the input's encoder or tachometer)")
    p.add_argument("--fmu", help="an FMU with motion outputs to run (default: export one next to the HTML)")
    p.add_argument("--html", help="write a standalone HTML file and, next to it, a PNG plot of input and output")
    p.add_argument("--live", action="store_true", help="also serve it on a live meshcat server until Ctrl-C")
    model_options(p, motion=False)  # the exported FMU carries the motion of every grid
    p.set_defaults(func=cmd_view_response)
