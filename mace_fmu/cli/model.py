"""``mace-fmu model``: the volts-volts state-space model, its poles, its matrices or Modelica source."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from mace_fmu.cli.common import BUNDLED_DECK, CONFIGURATIONS, deck_option, model_options, positive_hz, volts
from mace_fmu.cli.preflight import output_option
from mace_fmu.util.atomic import atomic_path, write_text_atomic


def cmd_model(args: argparse.Namespace) -> int:
    from mace_fmu.iomodel.poles import closed_loop_poles
    from mace_fmu.thesis import format_pole_rows, table_4_7_comparison, table_5_2_comparison

    model = volts(args)
    sys_ = model.system
    poles = closed_loop_poles(model)
    if args.modelica:
        write_text_atomic(args.modelica, model.diagram.to_modelica(f"MACE_{args.configuration}_volts"))
        print(f"wrote {args.modelica}", file=sys.stderr if args.json else sys.stdout)
    if args.npz:
        # np.savez appends .npz to a file name without it; a file object keeps the temporary name
        with atomic_path(args.npz if args.npz.endswith(".npz") else f"{args.npz}.npz") as tmp, open(tmp, "wb") as f:
            np.savez(f, A=sys_.A, B=sys_.B, C=sys_.C, D=sys_.D, inputs=np.array(sys_.input_labels),
                     outputs=np.array(sys_.output_labels), states=np.array(sys_.state_labels))
        print(f"wrote {args.npz}", file=sys.stderr if args.json else sys.stdout)
    if args.json:
        json.dump({"configuration": args.configuration, "states": sys_.nstates, "inputs": list(sys_.input_labels),
                   "outputs": list(sys_.output_labels),
                   "poles": [{"frequency_hz": p.frequency_hz, "damping": p.damping, "label": p.label} for p in poles]},
                  sys.stdout, indent=1)
        print()
        return 0
    print(f"{args.configuration} volts-volts model: {sys_.nstates} states, {sys_.ninputs} inputs, "
          f"{sys_.noutputs} outputs ({model.electronics.describe(instruments=model.instruments)})")
    for state, reason in model.plant.removed_states:
        print(f"  removed: {state}: {reason}")
    if args.parameters:
        print(f"parameter set: {args.parameters}")
    if args.poles:
        # the thesis's tables are MACE's: beside another deck's poles they would be rows of "no match"
        if args.configuration in ("1g", "0g") and Path(args.deck).resolve() == Path(BUNDLED_DECK).resolve():
            one_g = args.configuration == "1g"
            rows = table_4_7_comparison(poles) if one_g else table_5_2_comparison(poles, column="g0")
            title = "Table 4.7, FE columns (closed loop)" if one_g else "Table 5.2, 0-g column (closed loop)"
            print(format_pole_rows(rows, title=title))
            print()
        print(f"all closed-loop poles up to {args.list_max_hz} Hz")
        for p in poles:
            if p.frequency_hz <= args.list_max_hz:
                print(f"  {p.frequency_hz:9.3f} Hz  zeta {p.damping:6.3f}  {p.label}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("model", help="volts-volts state-space model of the 1-g or 0-g structure")
    p.add_argument("configuration", choices=CONFIGURATIONS,
                   help="the deck's 1-g or 0-g structure, or 'modes': NASTRAN's modes, named by --structure FILE's "
                        "[modes] table")
    deck_option(p)
    p.add_argument("--poles", action="store_true", help="closed-loop poles (the bundled deck's next to Table 4.7 "
                   "(1g) or 5.2 (0g)); with --parameters, an update's")
    p.add_argument("--list-max-hz", type=positive_hz, default=60.0, help="with --poles: list all poles up to this [Hz]")
    p.add_argument("--json", action="store_true", help="states, signal names and poles as JSON")
    output_option(p, "--npz", kind="file", metavar="FILE", help="write A, B, C, D and the signal names to FILE (.npz)")
    output_option(p, "--modelica", kind="file", metavar="FILE", help="write the model as Modelica source (.mo)")
    model_options(p)
    p.set_defaults(func=cmd_model)
