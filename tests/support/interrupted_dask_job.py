"""A command of the ``mace-fmu`` kind that runs long tasks on a local Dask cluster, for an interruption test.

Run as ``python interrupted_dask_job.py WORKERS``: the command is added to ``mace-fmu``'s parser and run
through ``mace_fmu.cli.main`` (its one line for an interruption, status 130), with a ``DaskRunner`` and a
progress bar, as ``mace-fmu update fmu`` runs its FMU simulations. It prints ``starting`` before the
cluster starts and ``running`` once the tasks are submitted, each on its own line of stderr, so that a
test can send Ctrl-C (SIGINT to the process group, as a terminal does) at either point; the tasks keep the
workers busy in numpy for a minute, as FMU runs do.
"""

from __future__ import annotations

import argparse
import sys
import time


def busy(item: int) -> int:
    """A minute of numerical work (an FMU run's kind: compiled code that holds a worker's thread)."""
    import numpy as np

    start = time.monotonic()
    while time.monotonic() - start < 60:
        np.linalg.eigvals(np.random.default_rng(item).random((60, 60)))
    return item


def job(args: argparse.Namespace) -> int:
    from mace_fmu.cli.common import progress_bar
    from mace_fmu.util.runner import DaskRunner

    print("starting", file=sys.stderr, flush=True)
    with progress_bar() as bar:
        with DaskRunner(workers=args.workers, progress=bar, task="FMU runs") as runner:
            print("running", file=sys.stderr, flush=True)
            runner(busy, range(4 * args.workers))
    return 0


def _with_the_job(build_parser):
    """``build_parser`` with one command more, ``interruptible-job --workers N``."""
    def parser() -> argparse.ArgumentParser:
        made = build_parser()
        commands = next(a for a in made._actions if isinstance(a, argparse._SubParsersAction))
        job_parser = commands.add_parser("interruptible-job")
        job_parser.add_argument("--workers", type=int, required=True)
        job_parser.set_defaults(func=job)
        return made
    return parser


if __name__ == "__main__":  # the workers import this file as their __mp_main__: nothing runs there
    import signal

    # Ctrl-C as a terminal's foreground job receives it: a test process started with SIGINT ignored (a shell's
    # background job) passes that on, and Python then installs no KeyboardInterrupt handler of its own
    signal.signal(signal.SIGINT, signal.default_int_handler)

    from mace_fmu import cli

    cli.build_parser = _with_the_job(cli.build_parser)  # main() builds its parser through this name
    sys.exit(cli.main(["interruptible-job", "--workers", sys.argv[1]]))
