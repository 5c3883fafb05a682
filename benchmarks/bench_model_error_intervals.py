"""Intervals that stay honest when the model is not exact (issue 48, item 2): the 40-case study.

Run by hand: ``python benchmarks/bench_model_error_intervals.py [--seeds 10] [--control 20] [--records 40]
[--frame]``; the tables go into benchmarks/RESULTS.md.

Data: ``tests/support/model_error_records.py``. Four kinds of model-form error the two-mass model (k1 and k2
updated, modal damping held) lacks, ``--seeds`` cases each (40 in all at the default), the size of the error
drawn from the seed: a first-order sensor lag (0.2-0.6 s), a sensor resonance (0.45-0.7 Hz, damping
0.1-0.3), an extra mode (a 0.05-0.15 kg mass on a spring hung on mass 1, alone at 0.35-0.55 Hz), an extra
element (a spring of 0.05-0.15 N/m from mass 2 to the wall and a damper of 0.005-0.02 N s/m between the
masses). White force, 4096 samples of 0.5 s, 5 % white noise. Per case: the record's halves and two
separate records, each fitted; do their estimates agree within the combined 95 % intervals, for both
parameters, by the sandwich, by what the update reports, and by the noise's covariance (with the stated
noise; with the residual's own level)?

Also: ``--control`` cases of the exact model (the verdict should be "explained" and the reported intervals the
noise's, today's); twice as many fits of the model's own frequency response (the frequency path's sandwich
without a model error); the same study from the actual system's k1 and k2 instead of the matched start (local
minima); and the calibration of each method on one structure of each kind: ``--records`` records, the
estimates' scatter against the mean reported standard deviation. ``--frame``: the three-storey frame's FMU
updated on each of its three measured FRF files (``tests/support/frame_per_file.py``), the three estimates of
each parameter compared pairwise within their intervals.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from common import print_run_header

sys.path[:0] = [str(Path(__file__).resolve().parents[1]), str(Path(__file__).resolve().parents[1] / "tests")]

from support.model_error_records import (ACTUAL, ERRORS, METHODS, NAMES, fit, frf_control,  # noqa: E402
                                         matched_start, normalised_gaps, run_case, truth)

from mace_fmu.updating.engine.costs import TimeResponseCost  # noqa: E402


def study(kinds, seeds: int, *, start: str = "matched") -> dict:
    """kind -> its cases."""
    out = {}
    for kind in kinds:
        out[kind] = [run_case(kind, seed, start=start) for seed in range(seeds)]
    return out


def fraction(cases, test) -> str:
    hits = sum(1 for c in cases if test(c))
    return f"{hits}/{len(cases)}"


def agreement_table(cases_by_kind: dict) -> list[str]:
    columns = ["kind", "cases", "residual RMS / noise (median)", "verdict \"model error\"",
               *(f"split: {m}" for m in METHODS), *(f"tests: {m}" for m in METHODS),
               "RMS normalised gap: sandwich / noise (stated)"]
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    every = [c for cases in cases_by_kind.values() for c in cases]
    for kind, cases in [*cases_by_kind.items(), ("all", every)]:
        fits = [f for c in cases for f in c.fits()]
        rms = statistics.median(f.rms_over_noise for f in fits)
        errors = sum(f.verdict == "model error" for f in fits)
        row = [kind, str(len(cases)), f"{rms:.2f}", f"{errors}/{len(fits)}"]
        row += [fraction(cases, lambda c, m=m: c.split_agrees(m)) for m in METHODS]
        row += [fraction(cases, lambda c, m=m: c.tests_agree(m)) for m in METHODS]

        def gap_rms(method: str) -> float:
            gaps = [g for c in cases for a, b in ((c.first, c.second), (c.whole, c.other))
                    for g in normalised_gaps(a, b, method).values()]
            return float(np.sqrt(np.mean(np.square(gaps))))
        row.append(f"{gap_rms('sandwich'):.2f} / {gap_rms('noise (stated)'):.3g}")
        lines.append("| " + " | ".join(row) + " |")
    return lines


def control_table(cases) -> list[str]:
    """The exact model: the verdict, the reported width against the noise's (today's), the sandwich's, and how
    often each interval holds the actual system's values."""
    fits = [f for c in cases for f in c.fits()]
    explained = sum(f.verdict == "explained" for f in fits)
    lines = ["| quantity | k_1 | k_2 |", "|---|---|---|",
             f"| fits (verdict \"explained\") | {len(fits)} ({explained}) | |"]
    for method in ("reported", "sandwich"):
        ratios = {n: [f.sd[method][n] / f.sd["noise (stated)"][n] for f in fits] for n in NAMES}
        lines.append(f"| {method} sd / noise's sd: median (min-max) | "
                     + " | ".join(f"{statistics.median(ratios[n]):.3f} ({min(ratios[n]):.2f}-{max(ratios[n]):.2f})"
                                  for n in NAMES) + " |")
    for method in ("reported", "noise (stated)", "sandwich"):
        lines.append(f"| truth inside the {method} 95 % interval | "
                     + " | ".join(f"{sum(abs(f.values[n] - ACTUAL[n]) <= 1.96 * f.sd[method][n] for f in fits)}"
                                  f"/{len(fits)}" for n in NAMES) + " |")
    for method in ("reported", "noise (stated)", "sandwich"):
        lines.append(f"| split / tests agree ({method}) | {fraction(cases, lambda c: c.split_agrees(method))} | "
                     f"{fraction(cases, lambda c: c.tests_agree(method))} |")
    return lines


def variant_sd(f, *, bins: int | None, real: bool) -> np.ndarray:
    """The sandwich's standard deviations [SI] of fit ``f`` by a variant of its meat: the Bartlett half-width
    ``bins`` (None: the width Andrews's rule gives the scores, as a frequency response's lines have it), and
    (``real``) the scores' real parts alone (the part of each bin a time score sums)."""
    from mace_fmu.updating.engine.residual_covariance import _bartlett, _groups, _runs, _time_scores, bandwidth

    jac = f.jacobian
    m, n = jac.shape
    (group,) = _groups(f.blocks)
    scores = _time_scores(group, jac, f.residual)
    runs = _runs(group[0])
    if real:
        scores = np.sqrt(2.0) * scores.real  # 2 Re(s) per one-sided bin: its variance is what the score's is
    width = bandwidth(scores, runs) if bins is None else bins + 1.0
    bread = np.linalg.inv(jac.T @ jac)
    cov = bread @ _bartlett(scores, width, runs) @ bread * m / (m - n)
    return np.sqrt(np.diag(cov)) * np.array([f.values[n] for n in NAMES])


VARIANTS = {"sandwich (bins 2, as shipped)": dict(bins=2, real=False), "bins 0": dict(bins=0, real=False),
            "bins 5": dict(bins=5, real=False), "width by Andrews's rule": dict(bins=None, real=False),
            "real parts, bins 2": dict(bins=2, real=True)}


def calibration_table(records: int) -> list[str]:
    """One structure of each kind (seed 0), ``records`` records of it, each fitted from the matched start: the
    scatter of the estimates over the mean standard deviation each method reports (1: calibrated; below 1 the
    intervals are wider than the scatter), for the noise's covariance and the sandwich with variants of its
    meat."""
    columns = ["noise (stated)", "noise (residual level)", *VARIANTS]
    lines = ["| kind | structure | estimates' sd k_1, k_2 [%] | " + " | ".join(f"{c}: scatter / mean sd"
                                                                            for c in columns) + " |",
             "|---|---|---|" + "---|" * len(columns)]
    for kind in (*ERRORS, "none"):
        system = truth(kind, 0)
        matched = matched_start(system)
        start = {"k_1": 0.99 * matched["k_1"], "k_2": 1.01 * matched["k_2"]}
        fits = []
        for r in range(records):
            record, sd = system.record(samples=4096, seed=5000 + r)
            fits.append(fit(TimeResponseCost(record), noise_sd=sd, start=start))
        values = np.array([[f.values[n] for n in NAMES] for f in fits])
        scatter = values.std(axis=0, ddof=1)
        row = [kind, system.what, ", ".join(f"{100 * s / v:.3g}" for s, v in zip(scatter, values.mean(axis=0)))]
        for column in columns:
            if column in VARIANTS:
                mean_sd = np.mean([variant_sd(f, **VARIANTS[column]) for f in fits], axis=0)
            else:
                mean_sd = np.array([np.mean([f.sd[column][n] for f in fits]) for n in NAMES])
            row.append(", ".join(f"{x:.2f}" for x in scatter / mean_sd))
        lines.append("| " + " | ".join(row) + " |")
    return lines


def frf_control_table(seeds: int) -> list[str]:
    """The frequency path without a model error: the model's own response, 2 % log noise, lines unweighted (the
    sandwich is what an FRF file without coherence gets); each width over the noise's, how often each interval
    holds the truth, and the shipped width over the two-line one it replaces."""
    fits = [frf_control(seed) for seed in range(seeds)]
    lines = ["| quantity | k_1 | k_2 |", "|---|---|---|"]
    for method in ("sandwich", "sandwich, two lines"):
        lines.append(f"| {method} sd / noise's sd: median (min-max) | " + " | ".join(
            f"{statistics.median(r):.3f} ({min(r):.2f}-{max(r):.2f})" for r in
            ([f.sd[method][n] / f.sd["noise"][n] for f in fits] for n in NAMES)) + " |")
    lines.append("| sandwich sd / two-line sandwich's sd: median (min-max) | " + " | ".join(
        f"{statistics.median(r):.3f} ({min(r):.2f}-{max(r):.2f})" for r in
        ([f.sd["sandwich"][n] / f.sd["sandwich, two lines"][n] for f in fits] for n in NAMES)) + " |")
    for method in ("noise", "sandwich", "sandwich, two lines"):
        lines.append(f"| truth inside the {method} 95 % interval | " + " | ".join(
            f"{sum(abs(f.values[n] - ACTUAL[n]) <= 1.96 * f.sd[method][n] for f in fits)}/{len(fits)}"
            for n in NAMES) + " |")
    return lines


def frame_table() -> list[str]:
    """The frame's three per-file updates: each parameter's three estimates, their reported standard deviations
    (and the noise's), and the pairwise normalised gaps."""
    import tempfile

    from support.frame_per_file import pairwise_gaps, per_file_fits

    with tempfile.TemporaryDirectory() as folder:
        fits = per_file_fits(Path(folder))
    files = list(fits)
    print("; ".join(f"{f}: verdict {fit.verdict}, covariance {fit.method}, update {fit.seconds:.0f} s"
                    for f, fit in fits.items()))
    gaps = {m: pairwise_gaps(fits, m) for m in ("reported", "noise")}
    pairs = [f"{a.split('.')[0]}-{b.split('.')[0]}" for a, b in
             [(files[0], files[1]), (files[0], files[2]), (files[1], files[2])]]
    lines = ["| parameter | " + " | ".join(files) + " | reported sd [%] | noise's sd [%] | gaps, reported ("
             + ", ".join(pairs) + ") | gaps, noise's |", "|---|---|---|---|---|---|---|---|"]
    for n in fits[files[0]].values:
        lines.append(f"| {n} | " + " | ".join(f"{fits[f].values[n]:.5g}" for f in files) + " | "
                     + ", ".join(f"{fits[f].sd_percent['reported'][n]:.2f}" for f in files) + " | "
                     + ", ".join(f"{fits[f].sd_percent['noise'][n]:.2f}" for f in files) + " | "
                     + ", ".join(f"{g:.2f}" for g in gaps["reported"][n]) + " | "
                     + ", ".join(f"{g:.1f}" for g in gaps["noise"][n]) + " |")
    for m in ("reported", "noise"):
        agree = sum(g <= 1.96 for v in gaps[m].values() for g in v)
        every = sum(all(g <= 1.96 for g in v) for v in gaps[m].values())
        lines.append(f"\n{m}: {agree}/{3 * len(gaps[m])} pairs agree; {every}/{len(gaps[m])} parameters agree in all "
                     "three pairs")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="cases per kind of model error (default 10: 40 in all)")
    parser.add_argument("--control", type=int, default=20, help="cases of the exact model (default 20)")
    parser.add_argument("--records", type=int, default=40, help="records per structure for the calibration")
    parser.add_argument("--frame", action="store_true", help="the three-storey frame's per-file updates alone")
    args = parser.parse_args()
    print_run_header()
    if args.frame:
        t0 = time.perf_counter()
        lines = frame_table()
        print(f"\n### The three-storey frame, one update per file ({time.perf_counter() - t0:.0f} s)\n")
        print("\n".join(lines))
        return
    t0 = time.perf_counter()
    cases = study(ERRORS, args.seeds)
    for kind, found in cases.items():
        for c in found:
            print(f"{kind} {c.seed}: {c.what}; split {normalised_gaps(c.first, c.second, 'sandwich')}, tests "
                  f"{normalised_gaps(c.whole, c.other, 'sandwich')}")
    print(f"\n### Split-record and separate-test consistency, matched start ({time.perf_counter() - t0:.0f} s)\n")
    print("\n".join(agreement_table(cases)))
    t0 = time.perf_counter()
    control = study(("none",), args.control)["none"]
    print(f"\n### The exact model ({time.perf_counter() - t0:.0f} s)\n")
    print("\n".join(control_table(control)))
    t0 = time.perf_counter()
    lines = frf_control_table(2 * args.control)
    print(f"\n### The frequency path without a model error ({time.perf_counter() - t0:.0f} s)\n")
    print("\n".join(lines))
    t0 = time.perf_counter()
    actual = study(ERRORS, args.seeds, start="actual")
    print(f"\n### The same cases started from the actual two-mass system's k1, k2 ({time.perf_counter() - t0:.0f} s)\n")
    print("\n".join(agreement_table(actual)))
    t0 = time.perf_counter()
    lines = calibration_table(args.records)
    print(f"\n### Calibration, {args.records} records of one structure per kind ({time.perf_counter() - t0:.0f} s)\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
