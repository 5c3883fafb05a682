"""Wall time of deck -> 0-g modes and deck -> 1-g modes (median of several runs).

Run by hand: ``python benchmarks/bench_modes.py [--runs 7]``; paste the printed table into
benchmarks/RESULTS.md together with the machine and the date.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy
from common import machine_line, timed

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.structure.file import bundled_deck_path

CASES = {
    "deck -> 0-g modes": dict(configuration="0g"),
    "deck -> 1-g modes, large-displacement preload (20 increments)": dict(configuration="1g", preload="large"),
    "deck -> 1-g modes, linear preload": dict(configuration="1g", preload="linear"),
}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=7)
    args = parser.parse_args()
    print(machine_line(numpy=np.__version__, scipy=scipy.__version__))
    print(f"date: {time.strftime('%Y-%m-%d')}, runs per case: {args.runs} (median; first run included)")
    print("| case | median [s] | min [s] | modes <= 250 Hz |")
    print("|---|---|---|---|")
    for name, kwargs in CASES.items():
        median, fastest, result = timed(lambda: compute_modes(read_deck(bundled_deck_path()), **kwargs), args.runs)
        print(f"| {name} | {median:.3f} | {fastest:.3f} | {len(result.modes)} |")


if __name__ == "__main__":
    main()
