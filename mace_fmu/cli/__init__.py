"""The ``mace-fmu`` command: one module per command; errors in the input end with one line and status 2."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from typing import Sequence

from mace_fmu.cli import (build, controller, correlate, data, ema, export, model, modes, params, plan, predict, report,
                          study, update, view)
from mace_fmu.cli.preflight import run_checks
from mace_fmu.cli.renamed import removed_spelling
from mace_fmu.errors import MaceError

__all__ = ["build_parser", "main", "package_version"]

#: command modules in the order ``mace-fmu --help`` lists them; each has register(subparsers)
COMMANDS = (modes, model, export, controller, report, view, build, ema, correlate, update, plan, predict, study, data,
            params)


def build_parser() -> argparse.ArgumentParser:
    """The ``mace-fmu`` argument parser, one subcommand per command module.

    Returns
    -------
    argparse.ArgumentParser
        Every ``mace-fmu`` command (the CLI reference is generated from it).
    """
    parser = argparse.ArgumentParser(prog="mace-fmu", description="Finite-element deck of the MACE structure to "
                                     "validated input-output models and FMUs.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {package_version()}",
                        help="print the package's version and exit")
    parser.add_argument("--verbose", action="store_true", help="with an error whose message had to be short (a "
                        "deck's unknown cards), the whole list")
    sub = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.register(sub)
    return parser


def package_version() -> str:
    """The installed package's version (its metadata: the version pyproject.toml gave the build).

    Returns
    -------
    str
        E.g. "0.1.0", or "(source tree, not installed)" when the package runs from a folder without metadata.
    """
    from importlib import metadata

    try:
        return metadata.version("mace-fmu")
    except metadata.PackageNotFoundError:
        return "(source tree, not installed)"


def _refuse_removed_spellings(parser: argparse.ArgumentParser, argv: Sequence[str]) -> None:
    """An earlier spelling (``--kind``, ``update --fmu``) is refused by name, as argparse refuses: usage, one
    line, status 2 (not "unrecognized arguments", nor read as something else)."""
    found = removed_spelling(argv)
    if found is None:
        return
    command, message = found
    sub = next(action for action in parser._actions if isinstance(action, argparse._SubParsersAction))
    sub.choices[command].error(message)


def _terminated(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)  # unwinds like Ctrl-C: unfinished atomic writes remove their temporary files


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script; errors in the input end with one message and status 2.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments after ``mace-fmu`` (default: the process's command line).

    Returns
    -------
    int
        The exit status: 0 done, 2 bad input (one line on stderr, nothing written; an output that cannot be
        written and a ``--scheduler`` where no Dask scheduler answers are found before any work), 3 an update
        that did not converge (its results written), 130 interrupted, 141 stdout closed early (``mace-fmu params
        list FMU | head``: the rest of the output is dropped, quietly, as ``head`` asked).
    """
    try:
        parser = build_parser()
        _refuse_removed_spellings(parser, sys.argv[1:] if argv is None else argv)
        args = parser.parse_args(argv)
        status = _run(args)
        sys.stdout.flush()  # a reader that left shows here, not as the interpreter's "Exception ignored" at exit
        return status
    except BrokenPipeError:
        _drop_stdout()
        return PIPE_CLOSED


#: the exit status of a command whose reader closed stdout early: a shell's for a process ended by SIGPIPE
PIPE_CLOSED = 128 + 13


def _drop_stdout() -> None:
    """stdout to /dev/null: what is left in its buffer (flushed again at exit) goes nowhere, without a traceback
    (Python's recipe for SIGPIPE, docs.python.org/3/library/signal.html#note-on-sigpipe)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (AttributeError, OSError, ValueError):  # a stdout without a file descriptor (captured in a test)
        pass


def _run(args: argparse.Namespace) -> int:
    """The parsed command, run: its status, errors in the input as one line, an interruption as one line."""
    in_main_thread = threading.current_thread() is threading.main_thread()  # signal handlers live there only
    previous = signal.signal(signal.SIGTERM, _terminated) if in_main_thread else None
    try:
        run_checks(args)  # every output writable, a scheduler answering: before any work, not after it
        return args.func(args)
    except MaceError as exc:
        print(f"mace-fmu: error: {exc}", file=sys.stderr)
        details = getattr(exc, "details", ())
        if details and args.verbose:
            print("\n".join(f"  {line}" for line in details), file=sys.stderr)
        elif details:
            lines = "1 line" if len(details) == 1 else f"{len(details)} lines"
            print(f"  ({lines} more with mace-fmu --verbose ...)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("mace-fmu: interrupted", file=sys.stderr)
        return 130
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


if __name__ == "__main__":
    sys.exit(main())
