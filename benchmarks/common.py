"""What every benchmark shares: the machine line for RESULTS.md and a repeat-and-time loop."""

from __future__ import annotations

import os
import platform
import statistics
import time
from collections.abc import Callable
from typing import Any


def cpu_name() -> str:
    """CPU model from /proc/cpuinfo (Linux), else platform's guess."""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine_line(**versions: str) -> str:
    """'- machine: CPU, N cores, Python x, lib v, ...' for RESULTS.md."""
    libs = "".join(f", {name} {version}" for name, version in versions.items())
    return f"- machine: {cpu_name()}, {os.cpu_count()} cores, Python {platform.python_version()}{libs}"


def print_run_header(**context: str) -> None:
    """Print what heads a benchmark's table in RESULTS.md: the machine line (numpy and scipy versions) and
    the date, the load before the run and ``context`` ("ordering: chosen")."""
    import numpy
    import scipy

    print(machine_line(numpy=numpy.__version__, scipy=scipy.__version__))
    extra = "".join(f", {key}: {value}" for key, value in context.items())
    print(f"date: {time.strftime('%Y-%m-%d %H:%M')}, load: {os.getloadavg()[0]:.2f}{extra}")


def timed(fn: Callable[[], Any], runs: int) -> tuple[float, float, Any]:
    """Median and minimum wall time [s] of ``runs`` calls of ``fn``, and its last result."""
    times, out = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), out
