"""Volts-volts models: build time, and all-channel frequency responses against python-control.

Run by hand: ``python benchmarks/bench_volts.py [--runs 5]``; results go into benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import time

import control as ct
import numpy as np
from common import machine_line, timed

from mace_fmu.deck.reader import read_deck
from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.structure.file import bundled_deck_path


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    print(machine_line(control=ct.__version__, numpy=np.__version__))
    print(f"- date: {time.strftime('%Y-%m-%d')}, runs: {args.runs} (median, min)\n")
    print("| case | median [s] | min [s] | notes |")
    print("|---|---|---|---|")
    for kind in ("1g", "0g"):
        med, mn, model = timed(lambda: volts_model(compute_modes(read_deck(bundled_deck_path()), configuration=kind)),
                               args.runs)
        print(f"| deck -> {kind} volts-volts model (servos, full Bessel, delays) | {med:.3f} | {mn:.3f} | "
              f"{model.system.nstates} states |")
    model = volts_model(compute_modes(configuration="1g"))
    f = np.logspace(np.log10(0.5), np.log10(250.0), 1000)
    t0 = time.perf_counter()
    model.frequency_response(f)
    cold = time.perf_counter() - t0
    med_ours, mn_ours, ours = timed(lambda: model.frequency_response(f), args.runs)
    med_ct, mn_ct, ref = timed(lambda: ct.frequency_response(model.system, 2 * np.pi * f), max(1, args.runs // 2))
    theirs = np.moveaxis(np.asarray(ref.frdata), -1, 0)
    err = np.max(np.abs(ours - theirs) / np.abs(theirs).max(axis=0, keepdims=True))
    channels = model.system.ninputs * model.system.noutputs
    pointwise = np.median(np.abs(ours - theirs) / np.abs(theirs))
    print(f"| FRF, 1-g model, 1000 frequencies x {channels} channels: VoltsModel.frequency_response | {med_ours:.3f} | "
          f"{mn_ours:.3f} | first call {cold:.3f} s (builds the filter-free core once); max error vs control "
          f"{err:.1e} relative to each channel's peak, median pointwise {pointwise:.1e} |")
    print(f"| same with control.frequency_response | {med_ct:.3f} | {mn_ct:.3f} | speed-up "
          f"{med_ct / med_ours:.1f}x (medians) |")


if __name__ == "__main__":
    main()
