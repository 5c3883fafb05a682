"""One BLAS thread for the model build: its matrices are a few hundred rows, too small to share out.

Measured on the 2-core machine with other processes running (benchmarks/RESULTS.md, model build):
with OpenBLAS's two threads the eigen-solution of both models took 1.6-8.6 s, with one 0.07-0.08 s;
the labels, the assembly and the interconnection gained 2-5x as well. Threads that wait for a
busy core cost more than they share out on matrices of this size.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable
from typing import TypeVar

from threadpoolctl import threadpool_limits

F = TypeVar("F", bound=Callable)


def single_blas_thread(function: F) -> F:
    """Decorator: run ``function`` with BLAS/LAPACK limited to one thread (restored afterwards)."""
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return function(*args, **kwargs)
    return wrapper  # type: ignore[return-value]


def usable_cores() -> int:
    """The cores this process may run on (its affinity where the system tells it, else the machine's)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1
