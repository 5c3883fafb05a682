"""``mace-fmu update``: model updating (thesis chapter 4): the sample problem or the MACE update."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mace_fmu.cli.common import deck_option, progress_bar
from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError


def _say(message: str) -> None:
    print(f"  {message}", file=sys.stderr, flush=True)


def cmd_sample(args: argparse.Namespace) -> int:
    from mace_fmu.updating.sample import as_json, format_tables, run_sample_problem

    if not args.json:
        _say("sample problem: 'experiment', measurement model, 7 updates")
    problem = run_sample_problem()
    if args.json:
        json.dump(as_json(problem), sys.stdout, indent=1)
        print()
    else:
        print(format_tables(problem))
    return 0


def cmd_update(args: argparse.Namespace) -> int:
    if args.sample_problem:
        return cmd_sample(args)
    if args.out is None:
        raise MaceError("say where to write the updated parameter set and the report: -o DIR "
                        "(or run --sample-problem)")
    from mace_fmu.parameters import ParameterSet
    from mace_fmu.updating.data import read_measured_modes
    from mace_fmu.updating.mace_update import run_mace_update, format_mode_rows, mode_rows, scores
    from mace_fmu.updating.report import write_report
    from mace_fmu.updating.solve import UpdateSettings

    out = Path(args.out)
    if args.rounds < 1:
        raise MaceError(f"--rounds must be >= 1, got {args.rounds}")
    if out.exists() and not out.is_dir():
        raise MaceError(f"-o {out}: exists and is not a directory")
    deck = read_deck(args.deck)
    start = ParameterSet.read(args.start) if args.start else None
    measured = read_measured_modes(args.measured) if args.measured else None
    settings = UpdateSettings(method=args.method, perturbation=args.perturbation, rounds=args.rounds)
    with progress_bar() as bar:
        outcome = run_mace_update(start=start, measured=measured, preload=args.preload, settings=settings, deck=deck,
                                  progress=bar, message=_say)
    _say(f"writing the report to {out}/")
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
    for path in paths:
        print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("update", help="model updating (thesis ch. 4): the MACE 1-g update or the sample problem")
    deck_option(p)
    p.add_argument("-o", "--out", help="directory for parameters.toml, report.txt, summary.json and figures")
    p.add_argument("--sample-problem", action="store_true",
                   help="run the two-mass sample problem (thesis 4.3) and print Tables 4.2 and 4.3 beside the thesis")
    p.add_argument("--json", action="store_true", help="with --sample-problem: the tables as JSON")
    p.add_argument("--start", metavar="FILE", help="parameter set to start from (default: the pre-update moduli, "
                   "Table 4.4 back-computed)")
    p.add_argument("--measured", metavar="FILE", help="measured modes (CSV: label, pattern, frequency_hz, damping "
                   "[, weight]; pattern: which model pole labels a row can be, e.g. '* Y bending'); default: Table "
                   "4.7's measurement model")
    p.add_argument("--method", choices=["cost-sensitivity", "full", "reanalysis", "modal-sensitivity"],
                   default="cost-sensitivity", help="how the parameters enter the cost (default: cost-sensitivity)")
    p.add_argument("--perturbation", choices=["reanalysis", "full"], default="reanalysis",
                   help="how the cost-sensitivity method makes its perturbed models (default: reanalysis)")
    p.add_argument("--rounds", type=int, default=2, help="repeats of physical, delays, damping (default 2)")
    p.add_argument("--preload", choices=["large", "linear"], default="large", help="1-g gravity preload")
    p.set_defaults(func=cmd_update)
