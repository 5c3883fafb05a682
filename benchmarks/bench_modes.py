"""Wall time of deck -> 0-g modes and deck -> 1-g modes (median of several runs).

Run by hand: ``python benchmarks/bench_modes.py [--runs 7]``; paste the printed table into
benchmarks/RESULTS.md together with the machine and the date.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np
import scipy

from mace_fmu.deck.reader import read_deck
from mace_fmu.pipeline import compute_modes
from mace_fmu.structure import bundled_deck_path

CASES = {
    "deck -> 0-g modes": dict(structure="0g"),
    "deck -> 1-g modes, large-displacement preload (20 increments)": dict(structure="1g", preload="large"),
    "deck -> 1-g modes, linear preload": dict(structure="1g", preload="linear"),
}


def cpu_name() -> str:
    """CPU model from /proc/cpuinfo (Linux), else platform's guess."""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=7)
    args = parser.parse_args()
    print(f"machine: {cpu_name()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}")
    print(f"date: {time.strftime('%Y-%m-%d')}, runs per case: {args.runs} (median; first run included)")
    print("| case | median [s] | min [s] | modes <= 250 Hz |")
    print("|---|---|---|---|")
    for name, kwargs in CASES.items():
        times, count = [], 0
        for _ in range(args.runs):
            t0 = time.perf_counter()
            result = compute_modes(read_deck(bundled_deck_path()), **kwargs)
            times.append(time.perf_counter() - t0)
            count = len(result.modes)
        print(f"| {name} | {statistics.median(times):.3f} | {min(times):.3f} | {count} |")


if __name__ == "__main__":
    main()
