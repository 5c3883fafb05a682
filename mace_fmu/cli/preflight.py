"""What every command is checked for before it works: each output it will write can be written, and a Dask
scheduler it is sent to answers.

An option that names an output is declared with :func:`output_option` (a folder or a file), the Dask
options with :func:`scheduler_options`; either records its check on the command's parser, and
:func:`run_checks` runs the checks of the command chosen, before the command itself. A refusal is one
line naming the option, the path or address and why (exit 2, nothing written), where it was a
traceback, or the same line, after the work (an update's results lost with it).

Imports nothing heavy: the parser is built for ``mace-fmu --help``, which answers at once.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Any, Callable, Literal

from mace_fmu.cli.common import positive_number
from mace_fmu.util.runner import DEFAULT_CONNECT_TIMEOUT_S

#: the parser default (argparse ``set_defaults``) under which a command's checks are recorded
CHECKS = "preflight_checks"


@dataclass(frozen=True)
class OutputCheck:
    """An option that names an output: where its value, or the path the command derives without it, must be
    writable as a folder or a file."""

    dest: str  #: the option's attribute on the parsed arguments
    option: str  #: how messages name it, e.g. "-o"
    kind: Literal["folder", "file"]
    #: where the command writes when the option is not given and its default is None (e.g. the input's name with
    #: .ssv); None: nothing is written then
    derived: Callable[[argparse.Namespace], Any] | None = None
    #: whether the command writes there with these arguments (e.g. export's -o is not used with --ssp)
    used: Callable[[argparse.Namespace], bool] | None = None

    def path(self, args: argparse.Namespace) -> str | None:
        """The path the command will write to with ``args``, or None if it writes nothing there."""
        if self.used is not None and not self.used(args):
            return None
        value = getattr(args, self.dest, None)
        if value is None and self.derived is not None:
            value = self.derived(args)
        return None if value is None else str(value)

    def check(self, args: argparse.Namespace) -> None:
        """Raise a MaceError naming the option and the path unless the command can write there."""
        from mace_fmu.util.writable import check_output_file, check_output_folder

        path = self.path(args)
        if path is not None:
            check = check_output_folder if self.kind == "folder" else check_output_file
            check(path, name=f"{self.option} {path}")


@dataclass(frozen=True)
class SchedulerCheck:
    """``--scheduler ADDRESS``: a Dask scheduler answers there within ``--scheduler-timeout`` seconds."""

    used: Callable[[argparse.Namespace], bool] | None = None

    def check(self, args: argparse.Namespace) -> None:
        """Raise a MaceError naming the option and the address unless a Dask scheduler answers there."""
        from mace_fmu.util.runner import check_scheduler

        if args.scheduler and (self.used is None or self.used(args)):
            check_scheduler(args.scheduler, timeout_s=args.scheduler_timeout, name=f"--scheduler {args.scheduler}")


def _record(parser: argparse.ArgumentParser, check: OutputCheck | SchedulerCheck) -> None:
    parser.set_defaults(**{CHECKS: (*(parser.get_default(CHECKS) or ()), check)})


def output_option(parser: argparse.ArgumentParser, *flags: str, kind: Literal["folder", "file"],
                  derived: Callable[[argparse.Namespace], Any] | None = None,
                  used: Callable[[argparse.Namespace], bool] | None = None, **options: Any) -> argparse.Action:
    """Add an option that names an output, checked by :func:`run_checks` before the command works.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser (its defaults record the check).
    *flags : str
        The option strings, e.g. ``"-o", "--out"``; messages name the output by the first.
    kind : {"folder", "file"}
        A folder the command writes into (it must be creatable, or be a folder that takes files) or one file
        (its folder likewise, and a file already there must be a writable regular file).
    derived : callable, optional
        ``derived(args)``: where the command writes when the option's value is None.
    used : callable, optional
        ``used(args)``: False when the command writes nothing there with these arguments.
    **options
        What ``add_argument`` takes (help, default, metavar, required ...).

    Returns
    -------
    argparse.Action
        The option added.
    """
    action = parser.add_argument(*flags, **options)
    _record(parser, OutputCheck(dest=action.dest, option=flags[0], kind=kind, derived=derived, used=used))
    return action


def scheduler_options(parser: argparse.ArgumentParser, *, scheduler_help: str, group: Any = None,
                      used: Callable[[argparse.Namespace], bool] | None = None) -> None:
    """Add ``--scheduler ADDRESS`` and ``--scheduler-timeout S``; a scheduler given is asked before the work.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser.
    scheduler_help : str
        The help of ``--scheduler`` (what runs there).
    group : optional
        A group of ``parser`` for ``--scheduler`` (e.g. one that excludes ``--workers``).
    used : callable, optional
        ``used(args)``: False when the command would not use the scheduler with these arguments.
    """
    (group or parser).add_argument("--scheduler", metavar="ADDRESS", help=scheduler_help)
    parser.add_argument("--scheduler-timeout", type=positive_number, default=DEFAULT_CONNECT_TIMEOUT_S,
                        metavar="S", help=f"how long --scheduler is given to answer as a Dask scheduler [s] "
                        f"(default {DEFAULT_CONNECT_TIMEOUT_S:g}); it is asked before any work, and an address "
                        "where none answers (nothing listening, another service) ends with one line")
    _record(parser, SchedulerCheck(used=used))


def run_checks(args: argparse.Namespace) -> None:
    """Run the checks the chosen command's options recorded: the outputs first (at once), then a scheduler
    (up to its timeout). Raises the first refusal as a MaceError (one line)."""
    checks = getattr(args, CHECKS, ())
    for check in sorted(checks, key=lambda c: isinstance(c, SchedulerCheck)):
        check.check(args)
