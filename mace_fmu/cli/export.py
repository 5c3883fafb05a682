"""``mace-fmu export``: the FMU of the 1-g or 0-g volts-volts model."""

from __future__ import annotations

import argparse

from mace_fmu.cli.common import deck_option, model_options, progress, volts


def cmd_export(args: argparse.Namespace) -> int:
    from mace_fmu.fmu.export import export_fmu

    progress(f"{args.structure} volts-volts model")
    path = export_fmu(volts(args), out_dir=args.out)
    print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="FMI 2.0 co-simulation FMU of the 1-g or 0-g volts-volts model")
    p.add_argument("structure", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("-o", "--out", default=".", help="output directory (writes MACE_1g.fmu / MACE_0g.fmu; "
                   "with --motion-grids MACE_1g_motion.fmu, ...)")
    model_options(p)
    p.set_defaults(func=cmd_export)
