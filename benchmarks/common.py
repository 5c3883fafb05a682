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


def timed(fn: Callable[[], Any], runs: int) -> tuple[float, float, Any]:
    """Median and minimum wall time [s] of ``runs`` calls of ``fn``, and its last result."""
    times, out = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), out
