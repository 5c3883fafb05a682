"""Progress of long computations, reported to a callback (the library never prints)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Step:
    """``done`` of ``total`` steps of ``task`` are finished, e.g. 3 of 20 gravity-preload increments."""

    task: str  #: what is being done
    done: int  #: steps done
    total: int  #: steps in all
    detail: str = ""  #: e.g. "2 iterations, work ratio 3.5e-07"


#: What long computations call after each step (``compute_modes(..., progress=...)``).
ProgressCallback = Callable[[Step], None]


def begin_stage(progress: ProgressCallback | None, task: str, *, number: int, stages: int) -> None:
    """Report that stage ``number`` (1-based) of ``stages`` begins: one Step whose task names the stage, e.g.
    ``begin_stage(progress, "0-g closed-loop model", number=2, stages=4)``. Long stages report their own steps
    under their own task after it."""
    if progress is not None:
        progress(Step(task=task, done=number - 1, total=stages))
