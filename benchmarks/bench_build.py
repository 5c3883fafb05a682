"""Model build time: deck -> both volts-volts models (1-g with servos, Bessel filters, delays; 0-g), by stage.

Run by hand: ``cd benchmarks && python bench_build.py [--runs 7]``; results go into benchmarks/RESULTS.md.
The goal (issue 13): under 1 s for both models together on the 2-core machine. The stages are
timed inside one build by wrapping the functions that do them, so their sum is the build.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections import defaultdict
from contextlib import contextmanager

import numpy as np
import scipy
from common import machine_line

from mace_fmu.fe import modes as pipeline  # the deck -> modes route, whose stage functions are wrapped
from mace_fmu.iomodel import volts
from mace_fmu.structure.file import bundled_deck_path

#: (module, function name, stage) wrapped to time the stages of one build
STAGES = ((pipeline, "read_deck", "read deck"), (pipeline, "assemble", "assemble K, M"),
          (pipeline, "large_displacement_preload", "1-g gravity preload"), (pipeline, "solve_modes", "eigen-solution"),
          (pipeline, "label_modes", "mode labels"), (volts, "modal_plant", "modal plant"),
          (volts, "build_diagram", "block diagram"))


@contextmanager
def stage_timers(totals: dict[str, float]):
    """Wrap the stage functions so that each call adds its wall time to ``totals``."""
    originals = [(module, name, getattr(module, name)) for module, name, _ in STAGES]

    def timed(fn, stage):
        def wrapper(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                totals[stage] += time.perf_counter() - t0
        return wrapper

    for (module, name, stage), (_, _, fn) in zip(STAGES, originals):
        setattr(module, name, timed(fn, stage))
    try:
        yield
    finally:
        for module, name, fn in originals:
            setattr(module, name, fn)


def build_both() -> None:
    deck = pipeline.read_deck(bundled_deck_path())  # through the module, so that the stage timer sees it
    volts.volts_model("1g", deck=deck)
    volts.volts_model("0g", deck=deck)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=7)
    args = parser.parse_args()
    print(machine_line(numpy=np.__version__, scipy=scipy.__version__))
    print(f"- date: {time.strftime('%Y-%m-%d %H:%M')}, runs: {args.runs} (median, min); load average before: "
          f"{os.getloadavg()[0]:.1f}\n")
    build_both()  # imports and caches warm
    totals, stages = [], defaultdict(list)
    for _ in range(args.runs):
        per_stage: dict[str, float] = defaultdict(float)
        with stage_timers(per_stage):
            t0 = time.perf_counter()
            build_both()
            totals.append(time.perf_counter() - t0)
        for stage, value in per_stage.items():
            stages[stage].append(value)
    print("| stage (both models) | median [s] | min [s] |")
    print("|---|---|---|")
    for _, _, stage in STAGES:
        print(f"| {stage} | {statistics.median(stages[stage]):.3f} | {min(stages[stage]):.3f} |")
    rest = [t - sum(stages[s][k] for s in stages) for k, t in enumerate(totals)]
    print(f"| rest (structure, compile, damping, signals) | {statistics.median(rest):.3f} | {min(rest):.3f} |")
    print(f"| **deck -> 1-g and 0-g volts-volts models** | **{statistics.median(totals):.3f}** | "
          f"**{min(totals):.3f}** |")
    print(f"\n- load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
