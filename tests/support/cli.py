"""Run the console script in-process as a shell would see it: exit status, stdout, stderr."""

from __future__ import annotations


def run_cli(capsys, argv: list[str]) -> tuple[int, str, str]:
    """``mace-fmu *argv`` in this process; argparse's own refusals (SystemExit 2) count as the exit status they
    give the shell, as do the statuses ``main`` returns."""
    from mace_fmu.cli import main

    try:
        code = main(argv)
    except SystemExit as stopped:
        code = stopped.code if isinstance(stopped.code, int) else (0 if stopped.code is None else 1)
    out, err = capsys.readouterr()
    return code, out, err
