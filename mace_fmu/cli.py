"""The ``mace-fmu`` command: modes of the bundled (or any) deck and the thesis comparison."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Sequence

import numpy as np

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.pipeline import StructureModes, compute_modes
from mace_fmu.structure import bundled_deck_path


def _progress(message: str) -> None:
    print(f"  {message}", file=sys.stderr, flush=True)


def _modes_json(result: StructureModes) -> dict:
    props = result.mass_properties
    return {
        "structure": result.structure.kind,
        "deck": result.structure.deck.path,
        "preload": result.preload.kind if result.preload else None,
        "modes": [{"index": i + 1, "frequency_hz": float(f), "label": lab}
                  for i, (f, lab) in enumerate(zip(result.modes.frequencies_hz, result.modes.labels))],
        "mass_properties": {
            "mass_kg": props.mass_kg,
            "center_of_mass_m": [float(x) for x in props.center_of_mass_m],
            "reference_grid": props.reference_grid,
            "inertia_about_center_node_kgm2": [[float(x) for x in row] for row in props.inertia_about_reference_kgm2],
        },
    }


def _print_modes(result: StructureModes) -> None:
    pre = f", {result.preload.kind} preload" if result.preload else ""
    print(f"{result.structure.kind} modes of {result.structure.deck.path}{pre}")
    print(f"{'mode':>4s} {'frequency Hz':>13s}  label")
    for i, (f, lab) in enumerate(zip(result.modes.frequencies_hz, result.modes.labels)):
        print(f"{i + 1:4d} {f:13.4f}  {lab}")
    p = result.mass_properties
    j = np.diag(p.inertia_about_reference_kgm2)
    print(f"mass {p.mass_kg:.4f} kg, centre of mass {np.round(p.center_of_mass_m, 5).tolist()} m, inertia about "
          f"grid {p.reference_grid}: Jxx {j[0]:.4f}, Jyy {j[1]:.4f}, Jzz {j[2]:.4f} kg m^2")


def cmd_modes(args: argparse.Namespace) -> int:
    deck = read_deck(args.deck)
    result = compute_modes(deck, structure=args.structure, preload=args.preload, mass=args.mass, max_hz=args.max_hz,
                           progress=None if args.json else _progress)
    if args.json:
        json.dump(_modes_json(result), sys.stdout, indent=1)
        print()
    else:
        _print_modes(result)
    return 0


def cmd_build(args: argparse.Namespace) -> int:
    # imported here, as in the other commands, so that `mace-fmu modes` starts without control/pythonfmu
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import DEFAULT_MAX_HZ, volts_model
    from mace_fmu.thesis import (format_mass_rows, format_rows, format_side_by_side, table_3_15_comparison,
                                 table_5_1_0g, table_5_1_1g)

    deck = read_deck(args.deck)
    _progress("0-g modes (suspension removed, linear)")
    # the modes the FMUs are built from: the same cut-off as `mace-fmu export`, whatever the deck's EIGRL says
    m0 = compute_modes(deck, structure="0g", max_hz=DEFAULT_MAX_HZ)
    results = {}
    for kind in ("large", "linear"):
        _progress(f"1-g modes ({kind} gravity preload)")
        results[kind] = compute_modes(deck, structure="1g", preload=kind, max_hz=DEFAULT_MAX_HZ,
                                      progress=_progress if kind == "large" else None)
    print(format_rows(table_5_1_0g(m0), title="Table 5.1, 0-g column (flexible modes)"))
    print()
    print(format_side_by_side({kind: table_5_1_1g(m1, m0) for kind, m1 in results.items()},
                              title="Table 5.1, 1-g column (structural modes paired with the 0-g ones by MAC)"))
    print()
    print(format_mass_rows(table_3_15_comparison(m0), title="Table 3.15, free-free mass properties about the centre node"))
    print()
    for kind, modes in (("1g", results["large"]), ("0g", m0)):
        _progress(f"{kind} volts-volts model and FMU")
        path = export_fmu(volts_model(kind, modes=modes), out_dir=args.out)
        print(f"wrote {path}")
    print()
    print("1-g modes below 25 Hz (large-displacement preload | linear preload)")
    large, linear = results["large"].modes, results["linear"].modes
    for i in range(min(len(large), len(linear))):  # side by side by index: the two preloads keep the mode order
        if large.frequencies_hz[i] > 25.0:
            break
        print(f"{i + 1:3d} {large.frequencies_hz[i]:9.3f}  {large.labels[i]:40s} | "
              f"{linear.frequencies_hz[i]:9.3f}  {linear.labels[i]}")
    return 0


def _motion_grids(text: str | None):
    """--motion-grids: None, "all" or comma-separated grid IDs."""
    if text is None or text == "all":
        return () if text is None else "all"
    try:
        return [int(g) for g in text.split(",") if g.strip()]
    except ValueError:
        raise MaceError(f"--motion-grids takes 'all' or comma-separated grid IDs, got {text!r}") from None


def _volts(args: argparse.Namespace, **overrides):
    from mace_fmu.iomodel.volts import volts_model

    options = dict(servos=not args.no_servos, bessel=args.bessel, delays=not args.no_delays,
                   pade_order=args.pade_order, max_hz=args.max_hz, preload=args.preload, deck=read_deck(args.deck),
                   motion_grids=_motion_grids(getattr(args, "motion_grids", None)))
    try:
        return volts_model(args.structure, **{**options, **overrides})
    except ValueError as exc:  # a bad option value: one message, not a traceback
        raise MaceError(str(exc)) from None


def cmd_model(args: argparse.Namespace) -> int:
    from mace_fmu.iomodel.poles import closed_loop_poles
    from mace_fmu.thesis import format_pole_rows, table_4_7_comparison, table_5_2_comparison

    model = _volts(args)
    sys_ = model.system
    poles = closed_loop_poles(model)
    if args.modelica:
        model.diagram.write_modelica(args.modelica, model_name=f"MACE_{args.structure}_volts")
    if args.npz:
        np.savez(args.npz, A=sys_.A, B=sys_.B, C=sys_.C, D=sys_.D, inputs=np.array(sys_.input_labels),
                 outputs=np.array(sys_.output_labels), states=np.array(sys_.state_labels))
    if args.json:
        json.dump({"structure": args.structure, "states": sys_.nstates, "inputs": list(sys_.input_labels),
                   "outputs": list(sys_.output_labels),
                   "poles": [{"frequency_hz": p.frequency_hz, "damping": p.damping, "label": p.label} for p in poles]},
                  sys.stdout, indent=1)
        print()
        return 0
    print(f"{args.structure} volts-volts model: {sys_.nstates} states, {sys_.ninputs} inputs, {sys_.noutputs} outputs "
          f"(servos {'on' if model.servos else 'off'}, Bessel {model.bessel}, delays {'on' if model.delays else 'off'})")
    for state, reason in model.plant.removed_states:
        print(f"  removed: {state}: {reason}")
    if args.poles:
        rows = table_4_7_comparison(poles) if args.structure == "1g" else table_5_2_comparison(poles, column="g0")
        title = "Table 4.7, FE columns (closed loop)" if args.structure == "1g" else "Table 5.2, 0-g column (closed loop)"
        print(format_pole_rows(rows, title=title))
        print()
        print(f"all closed-loop poles up to {args.list_max_hz} Hz")
        for p in poles:
            if p.frequency_hz <= args.list_max_hz:
                print(f"  {p.frequency_hz:9.3f} Hz  zeta {p.damping:6.3f}  {p.label}")
    return 0


def cmd_export(args: argparse.Namespace) -> int:
    from mace_fmu.fmu.export import export_fmu

    _progress(f"{args.structure} volts-volts model")
    path = export_fmu(_volts(args), out_dir=args.out)
    print(path)
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    from mace_fmu.report import bode_report

    for path in bode_report(read_deck(args.deck), out_dir=args.out, progress=_progress):
        print(path)
    return 0


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
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.fmu.simulate import simulate_input_response
    from viewer import animate_response, plot_response

    _need_target(args)
    out_dir = Path(args.html).parent if args.html else Path(".")
    if args.fmu:
        import fmpy

        fmu = Path(args.fmu)
        if not fmu.exists():
            raise MaceError(f"--fmu {fmu}: no such file")
        described = fmpy.read_model_description(str(fmu)).description or ""
        if not described.startswith(f"MACE {args.structure} "):
            raise MaceError(f"--fmu {fmu} is not a MACE {args.structure} model (its description: {described!r})")
        # only the scene is needed from the FE model: its lowest modes are enough
        modes = compute_modes(read_deck(args.deck), structure=args.structure, preload=args.preload, max_hz=1.0,
                              progress=_progress)
    else:
        _progress(f"{args.structure} volts-volts model with the motion of every grid")
        model = _volts(args, motion_grids="all")
        modes = model.structure_modes
        fmu = export_fmu(model, out_dir=out_dir, name=f"MACE_{args.structure}_motion")
        print(f"wrote {fmu} (reuse it with --fmu)")
    _progress(f"simulating {args.duration} s of {args.signal} on {args.input} through fmpy")
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
    result = compute_modes(deck, structure=args.structure, max_hz=max_hz, progress=_progress)
    modes = args.mode or list(range(1, result.modes.frequencies_hz.size + 1))
    animation = animate_modes(result, modes, scale=args.scale, cycles=args.cycles,
                              seconds_per_cycle=args.seconds_per_cycle)
    for clip in animation.frames.clips:
        print(f"  {clip.start_s:6.1f}-{clip.end_s:6.1f} s  {clip.title}")
    _show(animation, args, title=f"MACE {args.structure} modes")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mace-fmu", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    def deck_option(p: argparse.ArgumentParser) -> None:
        p.add_argument("--deck", default=str(bundled_deck_path()), help="NASTRAN bulk deck (default: bundled MACE deck)")

    def model_options(p: argparse.ArgumentParser, *, motion: bool = True) -> None:
        p.add_argument("--max-hz", type=float, default=250.0, help="highest retained mode [Hz] (default 250)")
        p.add_argument("--bessel", choices=["full", "delay", "none"], default="full",
                       help="Bessel filters as 8-pole filters, as their 2.44 ms Pade delay, or left out")
        p.add_argument("--no-servos", action="store_true", help="leave the wheel speed loops and gimbal servos open")
        p.add_argument("--no-delays", action="store_true", help="leave out the actuator and gyro time delays")
        p.add_argument("--pade-order", type=int, default=3, help="order of the Pade delay approximations (default 3)")
        p.add_argument("--preload", choices=["large", "linear"], default="large", help="1-g gravity preload")
        if motion:
            p.add_argument("--motion-grids", default=None, metavar="all|ID,ID,...",
                           help="also output these grids' translations [m] and rotations [rad] (for animation)")

    p = sub.add_parser("modes", help="natural frequencies [Hz] and labels of the 1-g or 0-g structure")
    p.add_argument("structure", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("--max-hz", type=float, default=None, help="upper frequency [Hz] (default: the deck's EIGRL)")
    p.add_argument("--preload", choices=["large", "linear"], default="large",
                   help="1-g gravity preload: large displacement (SOL 106, default) or linear")
    p.add_argument("--mass", choices=["lumped", "consistent"], default="lumped", help="bar mass matrix")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_modes)

    p = sub.add_parser("model", help="volts-volts state-space model of the 1-g or 0-g structure")
    p.add_argument("structure", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("--poles", action="store_true", help="closed-loop poles next to Table 4.7 (1g) or 5.2 (0g)")
    p.add_argument("--list-max-hz", type=float, default=60.0, help="with --poles: list all poles up to this [Hz]")
    p.add_argument("--json", action="store_true", help="states, signal names and poles as JSON")
    p.add_argument("--npz", metavar="FILE", help="write A, B, C, D and the signal names to FILE (.npz)")
    p.add_argument("--modelica", metavar="FILE", help="write the model as Modelica source (.mo)")
    model_options(p)
    p.set_defaults(func=cmd_model)

    p = sub.add_parser("export", help="FMI 2.0 co-simulation FMU of the 1-g or 0-g volts-volts model")
    p.add_argument("structure", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("-o", "--out", default=".", help="output directory (writes MACE_1g.fmu / MACE_0g.fmu)")
    model_options(p)
    p.set_defaults(func=cmd_export)

    p = sub.add_parser("report", help="Bode plots of the 1-g and 0-g models (PNG; thesis Figs. 4.15, 4.16, 5.1, 5.2)")
    deck_option(p)
    p.add_argument("--out", default="report", help="output directory (default ./report)")
    p.set_defaults(func=cmd_report)

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

    p = sub.add_parser("build", help="the main job: modes next to the thesis tables, and both FMUs")
    deck_option(p)
    p.add_argument("-o", "--out", default="fmus", help="where to write MACE_1g.fmu and MACE_0g.fmu (default ./fmus)")
    p.set_defaults(func=cmd_build)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; errors in the input end with one message and status 2."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except MaceError as exc:
        print(f"mace-fmu: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
