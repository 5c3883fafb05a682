"""``mace-fmu report``: Bode plots of the 1-g and 0-g models."""

from __future__ import annotations

import argparse

from mace_fmu.cli.common import deck_option, progress
from mace_fmu.cli.preflight import output_option


def cmd_report(args: argparse.Namespace) -> int:
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.iomodel.bode import bode_report

    for path in bode_report(read_deck(args.deck), structure_file=args.structure_file, out_dir=args.out,
                            progress=progress):
        print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="Bode plots of the 1-g and 0-g models (PNG; thesis Figs. 4.15, 4.16, 5.1, 5.2)")
    deck_option(p)
    output_option(p, "-o", "--out", kind="folder", default="report", help="output directory (default ./report)")
    p.set_defaults(func=cmd_report)
