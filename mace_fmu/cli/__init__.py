"""The ``mace-fmu`` command: one module per command; errors in the input end with one line and status 2."""

from __future__ import annotations

import argparse
import sys
from typing import Sequence

from mace_fmu.cli import build, export, model, modes, report, study, view
from mace_fmu.errors import MaceError

#: command modules in the order ``mace-fmu --help`` lists them; each has register(subparsers)
COMMANDS = (modes, model, export, report, view, build, study)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mace-fmu", description="Finite-element deck of the MACE structure to "
                                     "validated input-output models and FMUs.")
    sub = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(sub)
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
