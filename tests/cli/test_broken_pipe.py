"""A reader that stops early (``mace-fmu params list FMU | head``) ends the command quietly:
no BrokenPipeError traceback, the shell's status of a process ended by SIGPIPE."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from support.paths import ROOT

pytestmark = pytest.mark.slow  # each test runs the command in a subprocess that solves modes (4-7 s)


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}


def test_a_closed_stdout_ends_the_command_without_a_traceback():
    """stdout's reading end closed before the command writes a line (its first write meets a closed pipe)."""
    for argv in (["modes", "0g", "--max-hz", "3"], ["modes", "0g", "--max-hz", "3", "--json"]):
        run = subprocess.Popen([sys.executable, "-m", "mace_fmu.cli", *argv], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, env=_env(), cwd=ROOT)
        run.stdout.close()
        err = run.stderr.read().decode()
        assert run.wait(timeout=120) == 141 and err == "", err


def test_piping_into_head_prints_the_first_line_and_nothing_else(tmp_path):
    """The shell pipeline a user runs, on an output (125 kB: a lattice tower's 1000 modes as JSON) larger than
    the pipe holds and head reads, so that the command is still writing when head has left; with pipefail the
    command's own status shows: SIGPIPE's 141 (the old code: 1, after a BrokenPipeError traceback)."""
    from support.decks import frame_tower

    deck = tmp_path / "tower.bdf"
    deck.write_text(frame_tower(nx=5, ny=5, levels=12, modes=1000))
    command = f"set -o pipefail; {sys.executable} -m mace_fmu.cli modes 0g --deck {deck} --json | head -1"
    run = subprocess.run(["bash", "-c", command], capture_output=True, text=True, env=_env(), cwd=ROOT, timeout=120)
    assert run.stdout == "{\n" and run.stderr == "" and run.returncode == 141, run.stderr
