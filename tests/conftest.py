"""Session hooks shared by all tests."""

from __future__ import annotations

import os
import sys

import pytest

_exit_status: list[int] = []


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    _exit_status.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config: pytest.Config) -> None:
    """Leave without interpreter finalisation once pythonfmu FMUs were loaded in this process.

    pythonfmu 0.7 keeps every instance's module alive (upstream issue #229); when the interpreter
    finalises, its native wrapper has been seen to corrupt the heap ("corrupted double-linked
    list", SIGABRT) after all tests passed and the summary was printed, on one CI clone and not
    on another. The exit status is pytest's own; only the crash at teardown is skipped.
    """
    if _exit_status and any("pythonfmu" in name or "fmpy" in name for name in sys.modules):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_exit_status[-1])
