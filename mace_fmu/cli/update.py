"""``mace-fmu update``: model updating (thesis chapter 4): the sample problem or the MACE update."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

from mace_fmu.cli.common import (deck_option, non_negative_hz, non_negative_number, parameters_option,
                                 positive_integer, positive_number, progress, progress_bar)
from mace_fmu.cli.correlate import structure_options
from mace_fmu.cli.preflight import output_option, scheduler_options
from mace_fmu.errors import MaceError
from mace_fmu.util.atomic import output_folder, write_text_atomic
from mace_fmu.util.textfile import read_toml

#: exit status of an update that wrote its results but did not converge (see ``mace-fmu update --help``)
NOT_CONVERGED = 3


def cmd_sample(args: argparse.Namespace) -> int:
    from mace_fmu.updating.sample.problem import as_json, format_tables, run_sample_problem

    if not args.json:
        progress("sample problem: 'experiment', measurement model, 7 updates")
    problem = run_sample_problem()
    if args.json:
        json.dump(as_json(problem), sys.stdout, indent=1)
        print()
    else:
        print(format_tables(problem))
    return 0


def _read_start(path: str, fmu: str) -> tuple[dict[str, float], dict[str, tuple[float | None, float | None]]]:
    """Start values from a parameter TOML file ([values] table) by the FMU's names, and the bounds of its optional
    [bounds] table (name = [LOW, HIGH], either side "" for its default): a set of ``update mace`` names its damping
    ratios and frequency scales by mode label, which the FMU's parameters say."""
    from mace_fmu.updating.fmu.model import read_fmu_interface

    table = read_toml(path, what="start-value")
    values = table.get("values")
    if not isinstance(values, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                               for v in values.values()):
        raise MaceError(f"{path}: expected a [values] table of numbers (name = value)")
    interface = read_fmu_interface(fmu)
    bounds = table.get("bounds", {})
    if not isinstance(bounds, dict):
        raise MaceError(f"{path}: [bounds] must be a table of name = [LOW, HIGH]")
    given: dict[str, tuple[float | None, float | None]] = {}
    for name, pair in bounds.items():
        sides = pair if isinstance(pair, list) and len(pair) == 2 else None
        if sides is None or not all(side == "" or (isinstance(side, (int, float)) and not isinstance(side, bool))
                                    for side in sides):
            raise MaceError(f"{path}: [bounds] {name} = {pair!r}: expected [LOW, HIGH], numbers in the "
                            "parameter's unit (\"\" keeps that side's default), e.g. [0.001, 0.05]")
        given[name] = tuple(None if side == "" else float(side) for side in sides)  # type: ignore[assignment]
    by_fmu_name = _bounds_by_fmu_name(interface, given, source=f"{path}: [bounds]")
    return interface.values_by_fmu_name({k: float(v) for k, v in values.items()}, source=path), by_fmu_name


def _bounds_by_fmu_name(interface, given: dict[str, tuple[float | None, float | None]], *,
                        source: str) -> dict[str, tuple[float | None, float | None]]:
    """``given`` (name -> (low, high)) by the FMU's names: a per-mode name by label becomes every such mode's."""
    out: dict[str, tuple[float | None, float | None]] = {}
    for name, (low, high) in given.items():
        for fmu_name in interface.values_by_fmu_name({name: 0.0}, source=source):
            out[fmu_name] = (low, high)
    return out


def _bound(text: str) -> tuple[str, float | None, float | None]:
    """argparse type of ``--bounds NAME=LOW:HIGH``: (name, low, high) [the parameter's unit]; an empty side keeps
    its default."""
    name, eq, sides = text.partition("=")
    low_text, colon, high_text = sides.partition(":")
    expected = (f"{text!r}: expected NAME=LOW:HIGH in the parameter's unit, either side empty for its default "
                "(e.g. damping_mode_2=0.001:0.05, E_cable_1=:2.2e11)")
    if not name.strip() or not eq or not colon or (not low_text.strip() and not high_text.strip()):
        raise argparse.ArgumentTypeError(expected)
    try:
        low = float(low_text) if low_text.strip() else None
        high = float(high_text) if high_text.strip() else None
    except ValueError:
        raise argparse.ArgumentTypeError(expected) from None
    if any(v is not None and not math.isfinite(v) for v in (low, high)) or \
            (low is not None and high is not None and not low < high):
        raise argparse.ArgumentTypeError(f"{text!r}: expected finite LOW < HIGH")
    return name.strip(), low, high


def _window(text: str) -> float:
    """argparse type of each number of ``--window START END`` [s]."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a time [s], got {text!r}")
    return value


def _gain_priors(text: str) -> list[tuple[str, float]]:
    """argparse type of ``--gain-uncertainty OUTPUT=P%[,...]``: (output, standard deviation [fraction]) pairs."""
    out = []
    for item in (x.strip() for x in text.split(",") if x.strip()):
        name, _, value = item.partition("=")
        try:
            percent = float(value.strip().rstrip("%"))
        except ValueError:
            percent = float("nan")
        if not name.strip() or not (0 < percent < float("inf")):
            raise argparse.ArgumentTypeError(f"{item!r}: expected OUTPUT=P% with P > 0 (e.g. strain_strut2_y=1%)")
        out.append((name.strip(), percent / 100.0))
    return out


def _held_inputs(text: str) -> list[str]:
    """argparse type of ``--hold-input NAME=0[,...]``: the names of inputs the data lack, held at 0 V."""
    names = []
    for item in (x.strip() for x in text.split(",") if x.strip()):
        name, _, value = item.partition("=")
        try:
            zero = float(value) == 0.0
        except ValueError:
            zero = False
        if not name.strip() or not zero:
            raise argparse.ArgumentTypeError(f"{item!r}: expected NAME=0 (an input the data lack, held at 0 V)")
        names.append(name.strip())
    return names


def _gain_uncertainty(groups: list[list[tuple[str, float]]]) -> dict[str, float]:
    """The ``--gain-uncertainty`` options together: output -> standard deviation [fraction], each output once."""
    out: dict[str, float] = {}
    for name, fraction in (pair for group in groups for pair in group):
        if name in out:
            raise MaceError(f"--gain-uncertainty: {name!r} given twice")
        out[name] = fraction
    return out


def local_workers(workers: int | None) -> str:
    """Where the FMU runs go without a scheduler, in words: "2 local worker processes (one per core)".

    Parameters
    ----------
    workers : int or None
        ``--workers`` (None: as many as the machine has cores, as :class:`~mace_fmu.util.runner.DaskRunner`
        starts).

    Returns
    -------
    str
        The count and what it is, e.g. "3 local worker processes", "1 local worker process (one per core)".
    """
    count = workers or os.cpu_count() or 1
    text = f"{count} local worker process" + ("es" if count != 1 else "")
    return text if workers else f"{text} (one per core)"


def cmd_fmu_update(args: argparse.Namespace) -> int:
    """``update fmu FILE``: update FMU parameters against measured-data files. argparse checks each option,
    ``fmu_problem`` the files and names together: all before any run."""
    from mace_fmu.updating.fmu.problem import fmu_problem
    from mace_fmu.updating.fmu.update import update_fmu
    from mace_fmu.util.runner import DaskRunner

    from mace_fmu.updating.fmu.model import read_fmu_interface

    noise_fraction = None if args.noise_rms_percent is None else args.noise_rms_percent / 100.0
    start, bounds = _read_start(args.start, args.fmu) if args.start else (None, {})
    source = {name: f"{args.start}: [bounds]" for name in bounds}
    given = _bounds_by_fmu_name(read_fmu_interface(args.fmu), {name: (low, high) for name, low, high in args.bounds},
                                source="--bounds") if args.bounds else {}
    twice = [name for name, _, _ in args.bounds if [n for n, _, _ in args.bounds].count(name) > 1]
    if twice:
        raise MaceError(f"--bounds: {twice[0]!r} given twice (state each parameter's bounds once)")
    bounds.update(given)  # the command line over the start file
    source.update({name: "--bounds" for name in given})
    problem = fmu_problem(fmu=args.fmu, data=args.data,
                          names=[n.strip() for part in args.update for n in part.split(",") if n.strip()],
                          cost=args.cost, start=start,
                          channel_map=args.map, segment_s=args.segment_s, weighting=args.weighting,
                          held_inputs=[name for group in args.hold_input for name in group],
                          noise_rms_fraction=noise_fraction, gain_uncertainty=_gain_uncertainty(args.gain_uncertainty),
                          bands_hz=[tuple(band) for band in args.band_hz], averages=args.averages,
                          frf_floor=None if args.frf_floor_percent is None else args.frf_floor_percent / 100.0,
                          window_s=tuple(args.window) if args.window else None, bounds=bounds,
                          bounds_source=source)
    for note in problem.notes:
        progress(note)
    where = f"the Dask cluster at {args.scheduler}" if args.scheduler else local_workers(args.workers)
    gains = len(problem.family.gain_outputs)
    progress(f"updating {len(problem.names) - gains} parameter(s)" + (f" and {gains} sensor gain(s)" if gains else "")
         + f" of {Path(args.fmu).name} on the {args.cost} cost; FMU runs on {where}")
    with progress_bar() as bar:
        with DaskRunner(scheduler=args.scheduler, workers=args.workers, progress=bar, task="FMU runs",
                        connect_timeout_s=args.scheduler_timeout) as runner:
            result = update_fmu(family=problem.family, cost=problem.cost, start=problem.start, stages=[problem.names],
                                runner=runner, progress=bar, bounds=problem.bounds)
    report = _write_fmu_update(problem, result, out=Path(args.out), noise_fraction=noise_fraction, strict=args.strict)
    progress(report.summary())
    for line in report.misfit_lines()[:8]:
        progress(f"  {line}")
    return NOT_CONVERGED if report.failed else 0


def _write_fmu_update(problem, result, *, out: Path, noise_fraction: float | None, strict: bool):
    """parameters.toml, convergence.toml, uncertainty.toml, summary.json and the residual figure of an FMU update
    into ``out``, and its table on stdout; returns the convergence report."""
    from mace_fmu.updating.engine.convergence import (blocks_with_noise, convergence_report, missing_noise_floor,
                                                      noise_floor)
    from mace_fmu.updating.engine.residuals import residual_figure
    from mace_fmu.updating.engine.uncertainty import (format_uncertainty, one_sided_at_bounds, stage_uncertainty,
                                                      uncertainty_toml)
    from mace_fmu.updating.fmu.update import fmu_parameters

    floor = noise_floor(problem.cost, noise_rms_fraction=noise_fraction)
    report = convergence_report(result, noise_floor=floor, strict=strict, cost=problem.cost,
                                missing_floor=missing_noise_floor(problem.cost, noise_rms_fraction=noise_fraction))
    params = fmu_parameters(result, family=problem.family, data=", ".join(problem.data_files), cost=problem.cost,
                            convergence=report)
    output_folder(out)  # checked before the update; should it have gone since, a line that says so
    # the residual is the noise when the model explains the data: the covariance from the noise's level (the
    # floor's, not what the fit left over); otherwise from the residuals themselves, their correlations included
    sigma2 = floor.expected_cost / result.final_residual.size if floor is not None else None
    from_residuals = report.verdict != "explained" or (report.residuals is not None and not report.residuals.white)
    blocks = blocks_with_noise(problem.cost, floor) if from_residuals else None
    uncertainty = stage_uncertainty(result, noise_variance=sigma2, residual_blocks=blocks,
                                    noise_source=f"from the noise floor ({floor.source})" if floor else "")
    uncertainty = one_sided_at_bounds(uncertainty, result.at_bounds,  # as the verdict says: one-sided there
                                      ranges=problem.family.interface.ranges)
    figure = residual_figure(report.residuals, out / "residuals.png") if report.residuals is not None else None
    summary = {"fmu": str(problem.family.interface.path), "data": list(problem.data_files), "cost": problem.cost.name,
               "start": dict(problem.start), "values": dict(result.values), "initial_cost": result.initial_cost,
               "seconds": result.seconds, **report.to_json(),
               "uncertainty": [{"stage": st.stage, "method": st.method, "method_text": st.method_text,
                                "standard_deviation_percent": st.standard_deviation_percent,
                                "interval_95": {n: list(v) for n, v in st.interval_95.items()},
                                "interval_95_at_bound": dict(st.at_bound)} for st in uncertainty]}
    written = [params.write(out / "parameters.toml"), write_text_atomic(out / "convergence.toml", report.to_toml()),
               write_text_atomic(out / "uncertainty.toml", uncertainty_toml(uncertainty)),
               write_text_atomic(out / "summary.json", json.dumps(summary, indent=1, default=float) + "\n")]
    if figure is not None:
        written.append(figure)
    units = problem.family.interface.units
    print(f"{'parameter':<28} {'start':>14} {'updated':>14}  change")
    for n in problem.names:
        v0, v = problem.start[n], result.values[n]
        print(f"{n:<28} {v0:>14.6g} {v:>14.6g}  {100 * (v / v0 - 1):+.2f} %  [{units.get(n, '')}]")
    print(f"cost {result.initial_cost:.5g} -> {result.final_cost:.5g} ({100 * result.reduction:.1f} % lower) in "
          f"{result.seconds:.1f} s, {len(result.history)} outer iterations")
    print(format_uncertainty(uncertainty))
    for path in written:
        print(f"wrote {path}")
    return report


def cmd_mace_update(args: argparse.Namespace) -> int:
    """``update mace``: the thesis's modal update of the bundled MACE deck's moduli."""
    from mace_fmu.deck.reader import read_deck
    if args.structure_file is not None:
        raise MaceError(f"--structure {args.structure_file}: update mace is the thesis's MACE update (its "
                        "candidate moduli, Table 4.4 start and Table 4.7 data) and reads MACE's structure file; to "
                        "update your own structure against its measured modes: mace-fmu update modal --deck D "
                        "--structure S --modes modes.toml --update NAMES -o DIR (or its FMU against the test data: "
                        "mace-fmu update fmu FILE --data ...)")
    if args.out is None:
        raise MaceError("say where to write the updated parameter set and the report: -o DIR "
                        "(or run: mace-fmu update sample-problem)")
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.engine.measured import read_measured_modes
    from mace_fmu.updating.engine.solve import UpdateSettings
    from mace_fmu.updating.mace.report import write_report
    from mace_fmu.updating.mace.update import format_mode_rows, mode_rows, run_mace_update, scores

    out = Path(args.out)  # checked with every output before the command
    deck = read_deck(args.deck)
    start = ParameterSet.read(args.start) if args.start else None
    measured = read_measured_modes(args.measured) if args.measured else None
    settings = UpdateSettings(method=args.method, perturbation=args.perturbation, rounds=args.rounds)
    with progress_bar(task_lines=True) as bar:
        outcome = run_mace_update(start=start, measured=measured, preload=args.preload, settings=settings, deck=deck,
                                  progress=bar)
    progress(f"writing the report to {out}/")
    paths = write_report(outcome, out)
    s = scores(mode_rows(outcome))
    res = outcome.result
    print(format_mode_rows(mode_rows(outcome)))
    print()
    print(f"kept {len(outcome.selection.keep)} of {len(outcome.selection.names)} candidates: "
          f"{', '.join(outcome.selection.keep)}")
    print(f"cost {res.initial_cost:.5g} -> {res.final_cost:.5g} ({100 * res.reduction:.1f} % lower) in "
          f"{res.seconds:.1f} s; RMS frequency error (zeta < 10 %) {s.rms_light_before:.2f} -> {s.rms_light_after:.2f} % "
          f"(thesis {s.rms_light_thesis:.2f} %)")
    from mace_fmu.updating.engine.convergence import convergence_report
    from mace_fmu.updating.engine.uncertainty import (format_uncertainty, one_sided_at_bounds, stage_uncertainty,
                                                      uncertainty_toml)

    report = convergence_report(res, strict=args.strict)
    uncertainty = one_sided_at_bounds(stage_uncertainty(res), res.at_bounds)
    print(format_uncertainty(uncertainty))
    paths += [write_text_atomic(out / "convergence.toml", report.to_toml()),
              write_text_atomic(out / "uncertainty.toml", uncertainty_toml(uncertainty))]
    for path in paths:
        print(f"wrote {path}")
    progress(report.summary())
    return NOT_CONVERGED if report.failed else 0


def cmd_modal_update(args: argparse.Namespace) -> int:
    """``update modal``: a deck's structure-file parameters against measured modes (modes.toml)."""
    from mace_fmu.cli.common import parameters
    from mace_fmu.cli.correlate import family_of
    from mace_fmu.updating.engine.convergence import convergence_report
    from mace_fmu.updating.engine.selection import plot_selection
    from mace_fmu.updating.engine.solve import UpdateSettings
    from mace_fmu.updating.engine.uncertainty import format_uncertainty, stage_uncertainty, uncertainty_toml
    from mace_fmu.updating.modal.correlation import DEFAULT_MIN_MAC
    from mace_fmu.updating.modal.figures import plot_mac
    from mace_fmu.updating.modal.update import MODAL_SETTINGS, mode_table, run_modal_update, summary

    names = [n.strip() for part in args.update for n in part.split(",") if n.strip()]
    measured, family = family_of(args, base=parameters(args))
    family.check_names(names)
    settings = UpdateSettings(method=args.method, perturbation="full", penalty=args.penalty, rounds=args.rounds,
                              max_outer=MODAL_SETTINGS.max_outer)
    scaled = {"auto": None, "mass-normalised": True, "mac": False}[args.shapes]
    progress(f"updating {len(names)} candidate parameter(s) of {family.where} against {len(measured.modes)} measured "
         f"mode(s) of {args.modes}")
    with progress_bar(task_lines=True) as bar:
        outcome = run_modal_update(family=family, measured=measured, names=names, settings=settings,
                                   keep_all=args.keep_all, shape_weight=args.shape_weight, scaled=scaled,
                                   min_mac=args.min_mac or DEFAULT_MIN_MAC, progress=bar)
    res = outcome.result
    report = convergence_report(res, strict=args.strict, cost=outcome.cost)
    uncertainty = stage_uncertainty(res)
    out = output_folder(Path(args.out))
    text = [f"Modal update of {family.where} ({family.configuration}) against {args.modes}", "",
            "Parameter selection (orthogonality and strength tests, eq. 4.15-4.16):", outcome.selection.table(), "",
            "Measured modes against the model (paired by MAC):", mode_table(outcome), "",
            f"Cost j^T j: {res.initial_cost:.6g} -> {res.final_cost:.6g} ({100 * res.reduction:.1f} % lower)", "",
            format_uncertainty(uncertainty), "", report.summary()]
    labels = lambda c: [f"{lab} {f:.2f} Hz" for lab, f in zip(c.model_labels, c.model_hz)]  # noqa: E731
    measured_labels = [f"{m.label} {m.frequency_hz:.2f} Hz" for m in measured.modes]
    paths = [outcome.parameters.write(out / "parameters.toml"),
             write_text_atomic(out / "convergence.toml", report.to_toml()),
             write_text_atomic(out / "uncertainty.toml", uncertainty_toml(uncertainty)),
             write_text_atomic(out / "report.txt", "\n".join(text) + "\n"),
             write_text_atomic(out / "summary.json", json.dumps({**summary(outcome), **report.to_json()}, indent=1,
                                                                default=float) + "\n"),
             plot_mac(outcome.before.mac, measured=measured_labels, model=labels(outcome.before),
                      path=out / "mac_before.png", title="MAC before the update"),
             plot_mac(outcome.after.mac, measured=measured_labels, model=labels(outcome.after),
                      path=out / "mac_after.png", title="MAC after the update"),
             *plot_selection(outcome.selection, orthogonality_png=out / "orthogonality.png",
                             strength_png=out / "strength.png", title="modal cost")]
    print(mode_table(outcome))
    print()
    print(f"kept {len(outcome.selection.keep)} of {len(outcome.selection.names)} candidates: "
          f"{', '.join(outcome.selection.keep)}")
    print(f"{'parameter':<28} {'start':>14} {'updated':>14}  change")
    for n in outcome.selection.keep:
        v0, v = res.start[n], res.values[n]
        print(f"{n:<28} {v0:>14.6g} {v:>14.6g}  {100 * (v / v0 - 1):+.2f} %")
    for n, z in outcome.damping.items():
        print(f"{n:<28} {'(measured)':>14} {z:>14.6g}")
    print(f"cost {res.initial_cost:.5g} -> {res.final_cost:.5g} ({100 * res.reduction:.1f} % lower) in "
          f"{res.seconds:.1f} s, {len(res.history)} outer iterations, {family.solves} FE solves")
    print(format_uncertainty(uncertainty))
    for path in paths:
        print(f"wrote {path}")
    progress(report.summary())
    return NOT_CONVERGED if report.failed else 0


_EXIT_STATUS = (f"exit status: 0 converged, whether the model explains the data to their noise or not (a model "
                f"error: residuals above the noise or correlated with the inputs, said on the terminal and in "
                f"convergence.toml; a parameter that ends at a bound is named; --strict makes either {NOT_CONVERGED}); "
                f"2 bad input (nothing written); {NOT_CONVERGED} the update stopped without converging (at its "
                "iteration cap): the results are written all the same, with converged = false and the reasons in "
                "convergence.toml")


def _out_option(p: argparse.ArgumentParser, *, required: bool = False) -> None:
    output_option(p, "-o", "--out", kind="folder", required=required, help="directory for parameters.toml, "
                  "convergence.toml, uncertainty.toml, report.txt, summary.json and figures")
    p.add_argument("--strict", action="store_true", help=f"a parameter that ends at a bound counts as not converged, "
                   f"and a model the data show wrong (residuals above the noise or correlated with the inputs) as a "
                   f"failure (exit {NOT_CONVERGED}); by default both are named and the exit status is 0")


def _sample_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true",
                   help="print the tables as JSON")


def _mace_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--start", metavar="FILE", help=("parameter set to start from (default: the pre-update moduli, "
                   "Table 4.4 back-computed; for an FMU update: the FMU's own start values)"))
    p.add_argument("--measured", metavar="FILE", help=("measured modes (CSV: label, pattern, frequency_hz, damping "
                   "[, weight]; pattern: which model pole labels a row can be, e.g. '* Y bending'); default: Table "
                   "4.7's measurement model"))
    p.add_argument("--method", choices=["cost-sensitivity", "full", "reanalysis", "modal-sensitivity"],
                   default="cost-sensitivity", help=("how the parameters enter the cost (default: "
                                                         "cost-sensitivity)"))
    p.add_argument("--perturbation", choices=["reanalysis", "full"], default="reanalysis",
                   help=("how the cost-sensitivity method makes its perturbed models (default: reanalysis)"))
    p.add_argument("--rounds", type=positive_integer, default=2, help=("repeats of physical, delays, damping (default 2)"))
    p.add_argument("--preload", choices=["large", "linear"], default="large", help=("1-g gravity preload"))


def _fmu_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", metavar="FILE", action="append", required=True,
                   help=("measured data: a time history (CSV, npz or LabVIEW's .lvm, its channels and units from "
                             "its header; its inputs drive the FMU), one per test (repeat "
                             "the option: several tests are summed, each in units of its own noise) and, with one "
                             "test and --cost log-frf, optionally a frequency response (UFF 58/CSV); or, with "
                             "--cost log-frf, measured frequency responses alone, one file per test"))
    p.add_argument("--update", metavar="NAME[,NAME...]", action="append", required=True,
                   help=("FMU parameters to update (repeatable)"))
    p.add_argument("--cost", choices=["time", "log-frf"], default="time",
                   help=("time: output errors (eq. 4.3); log-frf: log ratio of H1 estimates (eq. 4.5/4.17)"))
    where = p.add_mutually_exclusive_group()  # --workers sizes a local cluster; a scheduler's cluster has its own
    scheduler_options(p, group=where,
                      scheduler_help="run the FMU simulations on this Dask cluster (default: local worker processes)")
    where.add_argument("--workers", type=positive_integer, default=None,
                       help=("local worker processes (default: one per core)"))
    p.add_argument("--map", metavar="FILE", help=("channel map: data channel names and units to the FMU's signals"))
    p.add_argument("--band-hz", type=non_negative_hz, nargs=2, metavar=("LOW", "HIGH"), action="append", default=[],
                   help=("[Hz] time histories, --cost time: the same zero-phase band-pass on the measured and the "
                         "FMU's outputs (the FMU driven by the measured inputs as they are), the noise read outside "
                         "the band; --cost log-frf: the H1 estimate's band (default 0.5-60 Hz, or the lines of a "
                         "periodic excitation). Measured frequency responses given alone (an analyser's UFF 58 or "
                         "CSV files): a band they are compared over (repeatable, e.g. one about each resonance; "
                         "default: all their frequencies)"))
    p.add_argument("--window", type=_window, nargs=2, metavar=("START", "END"), default=None,
                   help=("time histories: compare from START to END [s, the record's time axis]; the FMU is driven "
                         "from the record's first sample, so START sees the structure's state (START past the "
                         "transient of a record that begins mid-stream); default: the whole record"))
    p.add_argument("--segment-s", type=positive_number, default=None,
                   help=("time histories: H1 segment length [s] of the log-frf cost (default 2; periodic inputs: "
                         "the shortest whole number of periods, a given length refused, with the lengths that would "
                         "do, unless every line falls on its bins)"))
    p.add_argument("--bounds", metavar="NAME=LOW:HIGH", type=_bound, action="append", default=[],
                   help=("the range a parameter may take [its unit] (repeatable; an empty side keeps its default; "
                         "also a [bounds] table of the --start file, name = [LOW, HIGH]). Default, relative to the "
                         "start value: moduli and masses x0.5-1.5, springs x0.2-5, delays x0.2-3, damping ratios "
                         "x0.1-4 (at most 0.95), others x0.2-5, within the range the FMU declares"))
    p.add_argument("--hold-input", metavar="NAME=0[,NAME=0...]", type=_held_inputs, action="append", default=[],
                   help=("FMU inputs the data have no channel for, held at 0 V (repeatable); any other missing "
                             "input is an error"))
    p.add_argument("--noise-rms-percent", type=positive_number, default=None, metavar="P",
                   help=("time cost: the measurement noise RMS as P %% of each output's RMS, for the noise-floor "
                             "test (default: estimated from the outputs' spectra above the inputs' band)"))
    p.add_argument("--gain-uncertainty", metavar="OUTPUT=P%[,...]", type=_gain_priors, action="append", default=[],
                   help=("an output sensor whose gain is known only to P %% (standard deviation; repeatable, or "
                             "the channel map's gain_uncertainty_percent column): its gain is estimated with the "
                             "parameters, with that prior, and the parameters' uncertainty includes it"))
    p.add_argument("--weighting", choices=["noise", "none"], default=None,
                   help=("log-frf: each line's log error over its noise standard deviation (default; a time "
                         "history's from the record, a frequency-response file's from its coherence and averages), "
                         "or unweighted"))
    p.add_argument("--averages", type=positive_integer, default=None, metavar="N",
                   help=("measured frequency responses given alone: the averages behind their estimates, where the "
                         "files do not state them (the analyser's setting; files of mace-fmu data h1 state it)"))
    p.add_argument("--frf-floor-percent", type=positive_number, default=None, metavar="P",
                   help=("measured frequency responses given alone: the error the coherence does not see (leakage "
                         "at lightly damped resonances, calibration), P %% of each output's whole response "
                         "(default 1)"))


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("update", help="model updating (thesis ch. 4): the MACE update, any deck against measured "
                       "modes, an FMU against test data, or the sample problem",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Four updates, one subcommand each: 'mace' (the thesis's modal update of the "
                                   "bundled deck's moduli against Table 4.7), 'modal' (any deck's structure-file "
                                   "parameters against measured modes: mace-fmu ema's modes.toml), 'fmu' (any FMI "
                                   "2.0 FMU's parameters against measured data files), 'sample-problem' (the "
                                   "two-mass problem of thesis 4.3).",
                       epilog=_EXIT_STATUS)
    modes = p.add_subparsers(dest="update_mode", metavar="{mace,modal,fmu,sample-problem}", required=True)

    m = modes.add_parser("mace", help="the thesis's modal update of the bundled MACE deck's moduli against Table 4.7 "
                         "(chapter 4; the modal route's sequence on the closed-loop model)",
                         formatter_class=argparse.RawDescriptionHelpFormatter, epilog=_EXIT_STATUS)
    deck_option(m)
    _out_option(m)
    _mace_options(m)
    m.set_defaults(func=cmd_mace_update)

    f = modes.add_parser("fmu", help="update an FMU's parameters against measured data files (any FMI 2.0 "
                         "co-simulation FMU)", formatter_class=argparse.RawDescriptionHelpFormatter,
                         epilog=_EXIT_STATUS)
    f.add_argument("fmu", metavar="FILE", help="the FMU whose parameters are updated (set through FMI)")
    _out_option(f, required=True)
    f.add_argument("--start", metavar="FILE", help="parameter values to start from (TOML [values]; default: the "
                   "FMU's own start values) and, optionally, their bounds ([bounds]: name = [LOW, HIGH])")
    _fmu_options(f)
    f.set_defaults(func=cmd_fmu_update)

    d = modes.add_parser("modal", help="the thesis's modal update of any deck: a structure file's moduli, springs "
                         "and masses against measured modes (modes.toml from mace-fmu ema)",
                         formatter_class=argparse.RawDescriptionHelpFormatter, epilog=_EXIT_STATUS,
                         description="Measured modes paired with the deck's by MAC at the measured DOFs; the cost: "
                                     "relative frequency errors (thesis eq. 4.2) and the paired shapes' differences "
                                     "(mass-normalised where the modes file has them, else 1 - MAC), shape weight "
                                     "--shape-weight; the candidates judged by the orthogonality and strength tests "
                                     "(eq. 4.15-4.16), those kept updated by the cost-sensitivity method on full "
                                     "re-solves (eq. 4.12-4.13); the damping ratios taken from the measured modes. "
                                     "Writes parameters.toml (for export --parameters and update fmu --start), "
                                     "convergence.toml, uncertainty.toml, report.txt, summary.json and figures.")
    structure_options(d)
    parameters_option(d)
    _out_option(d, required=True)
    d.add_argument("--update", metavar="NAME[,NAME...]", action="append", required=True,
                   help="candidate parameters: moduli, springs and masses the structure file's [parameters] names "
                        "(E_<material>, k_<spring>, m_<mass>; repeatable)")
    d.add_argument("--keep-all", action="store_true", help="update every candidate whatever the selection tests say "
                   "(they are still reported)")
    d.add_argument("--shapes", choices=["auto", "mass-normalised", "mac"], default="auto",
                   help="how shapes enter the cost: their mass-normalised difference (needs a driving point: it tells "
                        "masses from stiffnesses), or 1 - MAC (scale-free); default auto: mass-normalised where the "
                        "modes file has them")
    d.add_argument("--shape-weight", type=non_negative_number, default=0.1, metavar="W",
                   help="weight of the shape residuals against the relative frequency errors (default 0.1: a 10 %% "
                        "shape difference counts like a 1 %% frequency error; 0: frequencies alone, eq. 4.2)")
    d.add_argument("--method", choices=["cost-sensitivity", "full"], default="cost-sensitivity",
                   help="how the parameters enter the cost (default: the thesis's cost-sensitivity method)")
    d.add_argument("--rounds", type=positive_integer, default=2, help="repeats of the update (default 2)")
    d.add_argument("--penalty", action="store_true", help="augment the cost with the changes (thesis eq. 4.18: a "
                   "10 %% change of a modulus or mass costs 1 %% of the initial cost); default off")
    d.set_defaults(func=cmd_modal_update)

    s = modes.add_parser("sample-problem", help="the two-mass sample problem (thesis 4.3): Tables 4.2 and 4.3 "
                         "beside the thesis")
    _sample_options(s)
    s.set_defaults(func=cmd_sample)
