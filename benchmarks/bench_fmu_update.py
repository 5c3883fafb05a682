"""Updating through FMU simulation: one cost-sensitivity recomputation serial and on a 2-worker LocalCluster,
Dask's per-task overhead, and the end-to-end synthetic update (examples/update_from_test_data.py).

Run by hand: ``python benchmarks/bench_fmu_update.py [--runs 5] [--out DIR] [--no-example]``; results go into
benchmarks/RESULTS.md.

1. One cost-sensitivity recomputation of the time-domain cost about the pre-update moduli: 9 FMU
   simulations of 20 s at 2 ms (the base point and the 8 moduli the thesis kept, each 1 % up),
   serially in this process and through a DaskRunner on a LocalCluster of 2 single-threaded
   workers (each worker has loaded the FMU at an untimed warm-up call: the load is paid once per
   worker, as in an update). Timed: ``runner(residual, points)`` for the 9 points, residuals included.
2. Dask's own cost per task: a map of 200 trivial tasks on the same cluster.
3. The whole synthetic update of the example (export, measure, 2 x 8 moduli, 2 x 9 delays, export of
   the updated FMU, plot), 2 workers, timed end to end.

``--identifiability`` instead: the time cost's sensitivities at the truth (noise-free 20 s record;
forward and central differences at steps 1e-3 and 1e-4, the central 1e-3 ones reported), their singular values, the weakest direction and the linearised standard deviation
of each modulus for 2 % output noise (sigma^2 (S^T S)^-1, the residual normalised by each
output's RMS so that its noise is 0.02 per sample).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from common import machine_line, timed


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--out", default=None, help="directory for the FMU and the example's output (default: temporary)")
    p.add_argument("--no-example", action="store_true", help="skip the end-to-end example run")
    p.add_argument("--identifiability", action="store_true", help="only the sensitivity analysis at the truth")
    args = p.parse_args()
    if args.identifiability:
        identifiability(Path(args.out or tempfile.mkdtemp(prefix="bench_fmu_update_")))
        return

    import cloudpickle
    import dask
    import fmpy

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.truth import measure_test_article
    from mace_fmu.updating.fmu.update import fmu_cost
    from mace_fmu.updating.mace.update import THESIS_KEPT, pre_update_parameters
    from mace_fmu.util.runner import DaskRunner
    from mace_fmu.util.threads import single_blas_thread

    out = Path(args.out or tempfile.mkdtemp(prefix="bench_fmu_update_"))
    fmu = export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=out, name="MACE_1g_native")
    family = fmu_family(fmu)
    article = measure_test_article(family, out_dir=out / "data", seconds=20.0)
    cost = fmu_cost("time", history=article.history)
    pre = pre_update_parameters()
    base = {n: pre[n] for n in THESIS_KEPT}
    points = [base] + [{**base, n: base[n] * 1.01} for n in THESIS_KEPT]

    def residual(values):
        return cost.residual(family.full(values))

    load = os.getloadavg()[0]
    serial_run = single_blas_thread(lambda: list(map(residual, points)))
    serial_run()  # this process loads the FMU once, as the workers do at their warm-up
    t_serial, t_serial_min, j_serial = timed(serial_run, args.runs)
    one_sim, _, _ = timed(lambda: family.full({**base, "E_cable_1": base["E_cable_1"] * 1.02}).time_response(
        article.history.times_s, article.history.inputs, outputs=list(article.history.outputs)), args.runs)
    with DaskRunner(workers=2) as runner:
        t0 = time.perf_counter()
        runner(residual, points)  # warm-up: each worker loads the FMU
        t_first = time.perf_counter() - t0
        t_dask, t_dask_min, j_dask = timed(lambda: runner(residual, points), args.runs)
        identical = all(np.array_equal(a, b) for a, b in zip(j_serial, j_dask))
        n_tasks = 200
        runner(lambda k: k, range(20))
        t_trivial, _, _ = timed(lambda: runner(lambda k: k, range(n_tasks)), args.runs)
    task_bytes = len(cloudpickle.dumps(residual))
    overhead = t_trivial / n_tasks

    lines = [machine_line(fmpy=fmpy.__version__, dask=dask.__version__),
             f"- date: {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC, runs: {args.runs} (median), "
             f"load average before: {load:.1f}", "",
             "| case | median [s] | min [s] | notes |", "|---|---|---|---|",
             f"| one FMU simulation, 20 s at 2 ms (10 001 steps, 4 inputs, 5 outputs), in process | {one_sim:.3f} | | "
             f"{1e6 * one_sim / 10001:.1f} us per step |",
             f"| cost-sensitivity recomputation, 9 simulations, serial | {t_serial:.3f} | {t_serial_min:.3f} | |",
             f"| same, LocalCluster 2 workers | {t_dask:.3f} | {t_dask_min:.3f} | speed-up {t_serial / t_dask:.2f} "
             f"(min {t_serial_min / t_dask_min:.2f}); bit-identical to serial: {identical}; first call incl. FMU "
             f"load per worker {t_first:.3f} s |",
             f"| Dask per-task overhead (map of {n_tasks} trivial tasks) | {overhead * 1e3:.2f} ms per task | | |",
             "", f"- serialised task function (cost with the 20 s record, FMU family): {task_bytes / 1e3:.0f} kB"]
    per_sim = t_serial / len(points)
    lines.append(f"- per simulation inside the sensitivity map (residual included): {per_sim:.3f} s")

    if not args.no_example:
        example = Path(__file__).resolve().parents[1] / "examples" / "update_from_test_data.py"
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        done = subprocess.run([sys.executable, str(example), "--out", str(out / "example"), "--workers", "2"],
                              capture_output=True, text=True)
        t_example = time.perf_counter() - t0
        if done.returncode != 0:
            raise SystemExit(done.stderr[-3000:])
        lines += ["", f"- end-to-end example (load average before {load:.1f}): {t_example:.1f} s wall, "
                      "`python examples/update_from_test_data.py --workers 2`", "", "```", done.stdout.strip(), "```"]
    print("\n".join(lines))


def identifiability(out: Path) -> None:
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.engine.sensitivity import cost_sensitivities
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.truth import measure_test_article
    from mace_fmu.updating.fmu.update import fmu_cost
    from mace_fmu.updating.mace.update import THESIS_KEPT, table_4_4_moduli

    family = fmu_family(export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=out,
                                          name="MACE_1g_native"))
    article = measure_test_article(family, out_dir=out / "noise_free", seconds=20.0, noise_fraction=0.0)
    cost = fmu_cost("time", history=article.history)
    truth = {n: table_4_4_moduli()[n] for n in THESIS_KEPT}

    def sensitivities(difference: str, step: float) -> np.ndarray:
        return cost_sensitivities(cost, base_model=family.full(truth), perturbed=family.full, base=truth,
                                  names=THESIS_KEPT, relative_step=step, difference=difference).matrix

    # a step study: the Jacobian must not depend on how it is taken
    study = {(d, h): sensitivities(d, h) for d in ("forward", "central") for h in (1e-3, 1e-4)}
    s = study[("central", 1e-3)]
    for (d, h), m in study.items():
        change = np.linalg.norm(m - s, axis=0) / np.linalg.norm(s, axis=0)
        sd = 100 * 0.02 * np.sqrt(np.diag(np.linalg.inv(m.T @ m)))
        print(f"{d:>8} step {h:g}: smallest singular value {np.linalg.svd(m, compute_uv=False)[-1]:.4g}; largest "
              f"column change from central 1e-3 {change.max():.2e}; sd % " + ", ".join(f"{x:.3g}" for x in sd))
    _, sv, vt = np.linalg.svd(s, full_matrices=False)
    std = 100 * 0.02 * np.sqrt(np.diag(np.linalg.inv(s.T @ s)))
    print("central differences, step 1e-3:")
    print("| modulus | column norm | std for 2 % noise [%] | weakest direction |\n|---|---|---|---|")
    for k, n in enumerate(THESIS_KEPT):
        print(f"| {n} | {np.linalg.norm(s[:, k]):.1f} | {std[k]:.3f} | {vt[-1, k]:+.3f} |")
    print("singular values: " + ", ".join(f"{v:.3g}" for v in sv))

if __name__ == "__main__":
    main()
