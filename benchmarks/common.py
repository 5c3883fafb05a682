"""What every benchmark shares: the machine line for RESULTS.md, a repeat-and-time loop, and two measures of the
machine's state during a run (the CPU time the host took, and the speed of a fixed Python loop)."""

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


def stolen_cpu_s() -> float | None:
    """CPU time the hypervisor has taken from this virtual machine since boot [s], summed over its cores
    (/proc/stat's "steal"); None where the system does not count it. The difference over a run says how
    much of its wall time the host's other guests took."""
    try:
        with open("/proc/stat") as stat:
            fields = stat.readline().split()
    except OSError:
        return None
    if len(fields) < 9 or fields[0] != "cpu":
        return None
    return int(fields[8]) / os.sysconf("SC_CLK_TCK")


def python_loop_s() -> float:
    """The fastest of three runs of 3 million additions in a Python loop [s]: the machine's speed for
    interpreted work at the moment, taken before a run (on the 2-core machine 0.107-0.195 s in one hour)."""
    def once() -> float:
        start, total = time.perf_counter(), 0
        for i in range(3_000_000):
            total += i
        return time.perf_counter() - start
    return min(once() for _ in range(3))
