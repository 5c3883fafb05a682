"""``mace-fmu study``: the modelling-for-control studies of thesis Appendix A (figures and a table)."""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path

import numpy as np

from mace_fmu.cli.common import non_negative_integer, positive_integer, positive_number, progress
from mace_fmu.cli.preflight import output_option, scheduler_options
from mace_fmu.errors import MaceError

FIGURE_OF_AUTHORITY = {"low": "A2", "moderate": "A3", "high": "A4"}


def _grid(text: str, what: str) -> np.ndarray:
    """'start:stop:step' [N/m] to the inclusive grid."""
    try:
        start, stop, step = (float(x) for x in text.split(":"))
    except ValueError:
        raise MaceError(f"{what} takes START:STOP:STEP in N/m, got {text!r}") from None
    if not (0.0 < start < stop and step > 0.0):
        raise MaceError(f"{what}: expected 0 < START < STOP and STEP > 0, got {text!r}")
    return np.round(np.arange(start, stop + 0.5 * step, step), 10)


def cmd_lqg_sensitivity(args: argparse.Namespace) -> int:
    from mace_fmu.control_studies.figures import sensitivity_contour
    from mace_fmu.control_studies.lqg import LqgWeights
    from mace_fmu.control_studies.stiffness_sensitivity import AUTHORITIES, format_studies, study_authority
    from mace_fmu.updating.sample.two_mass import TwoMassSystem
    from mace_fmu.util.atomic import write_text_atomic

    k1, k2 = _grid(args.k1, "--k1"), _grid(args.k2, "--k2")
    out = Path(args.out)
    studies = []
    for name, weights in AUTHORITIES.items():
        if args.theta is not None:
            weights = LqgWeights(rho=weights.rho, theta=args.theta)
        progress(f"{name} authority: {k1.size * k2.size} LQG designs")
        study = study_authority(name=name, actual=TwoMassSystem(), weights=weights, k1_values=k1, k2_values=k2)
        studies.append(study)
        fig = FIGURE_OF_AUTHORITY[name]
        title = f"Fig. {fig[0]}.{fig[1:]}: LQG sensitivity to stiffness errors, {name} authority"
        figure = sensitivity_contour(study.cost_map, minima=study.minima, title=title,
                                     path=out / f"figure_{fig}_{name}_authority.png")
        print(f"wrote {figure}")
    print(f"wrote {write_text_atomic(out / 'lqg_sensitivity.txt', format_studies(studies))}")
    if not args.quiet:
        print(format_studies(studies))
    return 0


def cmd_reduced_order(args: argparse.Namespace) -> int:
    from mace_fmu.control_studies.cantilever import cantilever_model
    from mace_fmu.control_studies.figures import bode_overlay
    from mace_fmu.control_studies.loop_shapes import dereverberated_crossover_hz, format_table, loop_shapes
    from mace_fmu.control_studies.lqg import LqgWeights
    from mace_fmu.control_studies.reduced_order import THESIS_COSTS, reduced_order_study, weights_for_full_cost
    from mace_fmu.util.atomic import write_text_atomic

    if args.max_iterations < 0:
        raise MaceError(f"--max-iterations must be 0 or more, got {args.max_iterations}")
    beam = cantilever_model()
    progress(f"cantilever: {beam.length:.4f} m, modes " + ", ".join(f"{f:.1f}" for f in beam.frequencies_hz) + " Hz")
    if args.rho is None:
        weights = weights_for_full_cost(beam.system, target_cost=THESIS_COSTS["full"])
    else:
        weights = LqgWeights(rho=args.rho, theta=args.rho)
    progress(f"rho = theta = {weights.rho:.4g}; updating the balanced 4-mode model (BFGS, at most "
             f"{args.max_iterations} iterations)")

    def every_tenth(iteration: int, ratio: float) -> None:
        if iteration % 10 == 0:
            progress(f"  iteration {iteration}: J/J_full = {ratio:.5f}")

    study = reduced_order_study(full=beam.system, weights=weights, max_iterations=args.max_iterations,
                                progress=every_tenth)
    f = np.logspace(0.0, 4.0, 4001)
    shapes = loop_shapes(study, frequencies_hz=f)
    out = Path(args.out)
    labels = {"full": "full order (5 modes)", "balanced": "balanced (4 modes)", "updated": "updated (4 modes)"}
    for name, data, title, ylabel, unit in (
            ("figure_A6_open_loop.png", shapes.plants, "Fig. A.6: open-loop tip force -> tip displacement",
             "|G| [m/N]", False),
            ("figure_A7_loop.png", shapes.loops, "Fig. A.7: loop G_full K of each model's compensator",
             "|G K|", True),
            ("figure_A8_compensators.png", shapes.compensators, "Fig. A.8: LQG compensators",
             "|K| [N/m]", False)):
        figure = bode_overlay({labels[k]: v for k, v in data.items()}, frequencies_hz=f, title=title, ylabel=ylabel,
                              path=out / name, unit_line=unit)
        print(f"wrote {figure}")
    table = format_table(study, crossover_hz=dereverberated_crossover_hz(shapes.loops["full"], f),
                         mode_frequencies_hz=beam.frequencies_hz, length_m=beam.length)
    print(f"wrote {write_text_atomic(out / 'table_A1.txt', table)}")
    if not args.quiet:
        print(table)
    return 0


def _bounds(args: argparse.Namespace) -> tuple[object, dict[int, float], str]:
    """(nominal 0-g volts model, 1-based mode -> relative bound, where the bounds come from)."""
    from mace_fmu.cli.common import parameters
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.volts import volts_model

    if args.bound and args.frequency_bounds:
        raise MaceError("give the bounds either with --bound or with --frequency-bounds, not both")
    if args.frequency_bounds and not Path(args.frequency_bounds).is_file():
        raise MaceError(f"--frequency-bounds {args.frequency_bounds}: no such file")
    if args.bound or args.frequency_bounds:
        params = parameters(args)
        progress("0-g volts model" + (f" with {args.parameters}" if params is not None else " (nominal, not updated)"))
        model = volts_model(compute_modes(configuration="0g", parameters=params))
    if args.frequency_bounds:
        from mace_fmu.zero_g.table import read_frequency_bounds

        return model, read_frequency_bounds(args.frequency_bounds, mode_labels=model.plant.labels), args.frequency_bounds
    if args.bound:
        from mace_fmu.parameters.frequency_bounds import relative_bound

        bounds = {}
        for text in args.bound:
            try:
                mode, percent = text.split("=")
                mode, percent = int(mode), float(percent)
            except ValueError:
                raise MaceError(f"--bound takes MODE=PERCENT (e.g. 17=2.5 for mode 17 within +-2.5 %), got {text!r}") from None
            bounds[mode] = relative_bound(percent / 100.0, what=f"--bound {text}")
        return model, bounds, "--bound"
    if args.parameters:
        raise MaceError("--parameters needs its bounds: --frequency-bounds table_5_3.toml or --bound MODE=PERCENT")
    from mace_fmu.zero_g.nominal import predict_zero_g
    from mace_fmu.zero_g.robust.study import prediction_bounds

    progress("updated nominal 0-g model and Table 5.3 bounds (about a minute; mace-fmu predict-0g -o DIR writes "
             "them once for --parameters and --frequency-bounds)")
    prediction = predict_zero_g()
    return prediction.model, prediction_bounds(prediction), "Table 5.3 (updated nominal 0-g model)"


def cmd_robust_0g(args: argparse.Namespace) -> int:
    from mace_fmu.cli.common import progress_bar
    from mace_fmu.control_studies.lqg import LqgWeights
    from mace_fmu.util.atomic import write_text_atomic
    from mace_fmu.zero_g.robust.loop import LoopSpec
    from mace_fmu.zero_g.robust.study import format_cross_checks, robust_0g_study, write_runs_csv
    from mace_fmu.zero_g.robust.summary import format_summary, sweep_figure

    if args.samples < 0 or args.critical < 0:
        raise MaceError(f"--samples and --critical must be 0 or more, got {args.samples} and {args.critical}")
    loop = LoopSpec(duration_s=args.duration)
    weights = LqgWeights(rho=args.rho, theta=args.theta)
    model, bounds, source = _bounds(args)
    out = Path(args.out)
    with contextlib.ExitStack() as stack:  # the runner closes quietly when the run is interrupted
        runner = map
        if not args.serial:
            from mace_fmu.util.runner import DaskRunner

            runner = stack.enter_context(DaskRunner(scheduler=args.scheduler, workers=args.workers,
                                                    task="closed-loop runs", connect_timeout_s=args.scheduler_timeout))
            progress(f"Dask: {runner.workers} workers" + (f" at {args.scheduler}" if args.scheduler else " (local)"))
        with progress_bar() as bar:
            if not args.serial:
                runner.progress = bar
            study = robust_0g_study(model, frequency_bounds=bounds, out_dir=out, loop=loop, weights=weights,
                                    reduced_states=args.states, samples=args.samples, seed=args.seed,
                                    critical_count=args.critical, runner=runner, progress=None)
    summary = "\n".join([f"Robustness of the LQG compensator on {study.fmu.name} (bounds: {source})",
                         format_summary(study.sweep, study.design),
                         format_cross_checks(study.cross_checks, study.sweep)])
    print(f"wrote {study.fmu}")
    print(f"wrote {write_runs_csv(study.sweep, out / 'robust_0g_runs.csv')}")
    print(f"wrote {sweep_figure(study.sweep, path=out / 'robust_0g.png')}")
    print(f"wrote {write_text_atomic(out / 'robust_0g.txt', summary + chr(10))}")
    print(summary)
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("study", help="modelling-for-control studies of thesis Appendix A (PNG figures and a table)")
    studies = p.add_subparsers(dest="study", required=True)
    s = studies.add_parser("lqg-sensitivity", help="A.1: LQG designed on mismodelled stiffnesses (Figs. A.2-A.4)")
    output_option(s, "--out", kind="folder", default="study", help="output directory (default ./study)")
    s.add_argument("--k1", default="0.1:3.0:0.05", help="design k1 grid START:STOP:STEP [N/m] (default 0.1:3.0:0.05)")
    s.add_argument("--k2", default="0.1:2.0:0.05", help="design k2 grid START:STOP:STEP [N/m] (default 0.1:2.0:0.05)")
    s.add_argument("--theta", type=positive_number, default=None,
                   help="sensor noise intensity for all authorities (default 1)")
    s.add_argument("--quiet", action="store_true", help="print only the written paths")
    s.set_defaults(func=cmd_lqg_sensitivity)
    r = studies.add_parser("reduced-order", help="A.2: LQG on balanced and updated 4-mode models of a cantilever "
                           "(Table A.1, Figs. A.6-A.8)")
    output_option(r, "--out", kind="folder", default="study", help="output directory (default ./study)")
    r.add_argument("--max-iterations", type=positive_integer, default=200,
                   help="BFGS iterations of the update (default 200)")
    r.add_argument("--rho", type=positive_number, default=None,
                   help="rho = theta (default: the value giving the thesis's J_full = 7.58e-6)")
    r.add_argument("--quiet", action="store_true", help="print only the written paths")
    r.set_defaults(func=cmd_reduced_order)
    o = studies.add_parser("robust-0g", help="LQG on the nominal 0-g model closed around the 0-g FMU over its frequency "
                           "bounds: corners and a Monte Carlo sample on Dask (PNG, CSV and a summary)")
    output_option(o, "-o", "--out", kind="folder", default="study", help="output directory (default ./study)")
    o.add_argument("--samples", type=positive_integer, default=100,
                   help="Monte Carlo samples, uniform in the bounds (default 100)")
    o.add_argument("--seed", type=non_negative_integer, default=1, help="seed of the sample (default 1)")
    o.add_argument("--critical", type=non_negative_integer, default=4,
                   help="parameters whose 2^N corners are run: the N that move the "
                        "cost most alone (default 4; all corners if there are at most N)")
    o.add_argument("--bound", action="append", metavar="MODE=PERCENT",
                   help="frequency bound of a mode, e.g. 17=2.5; repeat (default: Table 5.3's, updated nominal model)")
    o.add_argument("--frequency-bounds", metavar="FILE", help="table_5_3.toml of mace-fmu predict-0g: its bounds")
    o.add_argument("--parameters", metavar="FILE", help="parameter set of the 0-g model, e.g. zero_g_nominal.toml of "
                   "mace-fmu predict-0g (with --frequency-bounds or --bound; default with neither: predict it)")
    o.add_argument("--rho", type=positive_number, default=0.01, help="LQG control weighting (default 0.01)")
    o.add_argument("--theta", type=positive_number, default=0.1, help="LQG sensor noise intensity (default 0.1)")
    o.add_argument("--states", type=positive_integer, default=30,
                   help="states of the reduced design model (default 30)")
    o.add_argument("--duration", type=positive_number, default=4.0,
                   help="simulated time of each run [s]: 1 s of disturbance, "
                        "then settling (default 4)")
    scheduler_options(o, used=lambda args: not args.serial,
                      scheduler_help="address of a Dask scheduler, e.g. tcp://host:8786 (default: a local cluster)")
    o.add_argument("--workers", type=positive_integer, default=None, help="local cluster workers (default: the machine's cores)")
    o.add_argument("--serial", action="store_true", help="run in this process, no Dask")
    o.set_defaults(func=cmd_robust_0g)
