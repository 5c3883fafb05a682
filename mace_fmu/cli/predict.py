"""``mace-fmu predict-0g``: the updated nominal 0-g model and its frequency bounds (thesis 5.3, Table 5.3)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mace_fmu.cli.common import (deck_option, fraction, non_negative_number, parameters, parameters_option, percent,
                                 progress, progress_bar, step_lines)
from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError


def cmd_predict(args: argparse.Namespace) -> int:
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.zero_g.nominal import BoundRule, predict_zero_g, read_zero_g_measured
    from mace_fmu.zero_g.table import format_table, rows_as_data, write_prediction

    # everything is checked before anything is computed or written
    if args.fmu and args.out is None:
        raise MaceError("--fmu writes into the output directory: give -o DIR")
    out = Path(args.out) if args.out is not None else None  # checked with every output before the command
    rule = BoundRule(heavy_damping=args.heavy_damping, minimum_bound=args.minimum_bound_percent / 100.0,
                     error_fraction=args.error_fraction, heavy_bound=args.heavy_bound_percent / 100.0,
                     correct_heavy=args.correct_heavy)
    deck = read_deck(args.deck)
    params = parameters(args)
    measured = patterns = None
    source = "Table 4.7 measurement model"
    if args.measured:
        measured, patterns = read_zero_g_measured(args.measured)
        source = f"measurement model {args.measured}"
    say = (lambda _: None) if args.json else progress
    with progress_bar(task_lines=not args.json) as bar:
        prediction = predict_zero_g(parameters=params, measured=measured, zero_g_patterns=patterns, rule=rule,
                                    deck=deck, structure_file=args.structure_file, source=source, progress=bar)
    paths = {}
    if args.fmu:  # first: an export that fails leaves no tables behind
        from mace_fmu.fmu.naming import model_fmu_name

        name = model_fmu_name(prediction.model, runtime=args.runtime, variant="nominal")
        say(f"{args.runtime} FMU {name}.fmu with the frequency bounds")
        from mace_fmu.fmu.export import export_fmu

        paths["fmu"] = export_fmu(prediction.model, runtime=args.runtime, out_dir=out, name=name,
                                  frequency_bounds=prediction.frequency_bounds, progress=step_lines)
    if out is not None:
        paths.update(write_prediction(prediction, out))
    if args.json:
        json.dump({"source": prediction.source, "rows": rows_as_data(prediction),
                   "frequency_bounds": {str(k): v for k, v in prediction.frequency_bounds.items()},
                   "files": {k: str(v) for k, v in paths.items()}}, sys.stdout, indent=1)
        print()
    else:
        print(format_table(prediction))
        for path in paths.values():
            print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("predict-0g", help="updated nominal 0-g model and frequency bounds (thesis 5.3, Table 5.3)",
                       description="Carry a parameter set to 0-g, take the residual 1-g errors (model against a "
                                   "measurement model) out of the lightly damped modes and bound every mode's "
                                   "frequency, as the thesis's Table 5.3.")
    deck_option(p)
    parameters_option(p)
    p.add_argument("--measured", metavar="FILE",
                   help="1-g measurement model (CSV: label, pattern, frequency_hz, damping, pattern_0g; pattern_0g "
                        "empty for modes the 0-g structure lacks); default: Table 4.7's measured column")
    output_option(p, "-o", "--out", kind="folder", default=None, metavar="DIR",
                  help="write table_5_3.csv/.toml/.txt and zero_g_nominal.toml (the parameter set of the nominal "
                       "model, for export/build --parameters) into DIR")
    p.add_argument("--fmu", action="store_true", help="also export the nominal 0-g FMU with the bounds as the "
                   "min/max of its frequency_scale_mode_<k> (MACE_0g_<runtime>_nominal.fmu in DIR; another deck's "
                   "FMU is named after its file)")
    p.add_argument("--runtime", choices=["native", "pythonfmu"], default="native",
                   help="what runs inside the FMU: native (C, default) or pythonfmu")
    p.add_argument("--json", action="store_true", help="print the rows as JSON (label, nominal_hz, damping, "
                   "bound_percent, ...) instead of the table")
    p.add_argument("--heavy-damping", type=fraction, default=0.10,
                   help="measured 1-g damping ratio from which a mode is heavily damped (default 0.10)")
    p.add_argument("--minimum-bound-percent", type=percent, default=1.0,
                   help="smallest bound of a lightly damped mode [%%] (default 1)")
    p.add_argument("--error-fraction", type=non_negative_number, default=0.5,
                   help="lightly damped modes: bound = this times the |residual 1-g error| when larger (default 0.5)")
    p.add_argument("--heavy-bound-percent", type=percent, default=2.5,
                   help="bound of heavily damped modes [%%] (default 2.5)")
    p.add_argument("--correct-heavy", action="store_true",
                   help="also take the residual errors out of heavily damped modes (the thesis does not)")
    p.set_defaults(func=cmd_predict)
