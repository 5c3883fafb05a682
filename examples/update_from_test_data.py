"""Updating an FMU from test data files: the whole story, on a test article whose truth is known.
==============================================================================================

1. Export the 1-g FMU of the bundled deck (native, FMI 2.0 co-simulation). The deck holds the
   updated moduli of Table 4.4 and the FMU the updated delays of Tables 4.5 and 4.6: it is the
   "test article".
2. "Measure" it once: band-limited white noise (0.5-60 Hz) on the four gimbals, the five rate
   gyros recorded with 2 % white noise, written to a CSV time history and a UFF 58 frequency
   response, as a lab's data would arrive.
3. Update the FMU exported at the pre-update moduli (Table 4.4 back-computed; a full re-solve, so
   the truth is not the model's own parameter route: the route must reach it), from its own values,
   on the 8 moduli the thesis kept: once on the time-domain cost, once on the log-FRF cost, each
   through FMU simulations run side by side on a 2-worker Dask LocalCluster.
4. Update the servo and gyro delays from a perturbed start (moduli at the truth).
5. Write parameters.toml, export the updated FMU from it, and plot its gimbal-to-gyro FRFs over
   the truth's and the start's (PNG).

Run: ``python examples/update_from_test_data.py [--out DIR] [--seconds 20] [--workers 2]``; prints
the recovery per parameter, the cost reductions, the FRF errors in dB and the delays' errors.
``--quick`` (used by the test) runs an 8 s record (1 s H1 segments), the two lexan moduli and two delays.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="update_from_test_data", help="output directory")
    p.add_argument("--seconds", type=float, default=20.0, help="record length [s] (2 ms samples)")
    p.add_argument("--workers", type=int, default=2, help="local Dask workers (0: run serially in this process)")
    p.add_argument("--quick", action="store_true", help="8 s record, 2 moduli, 2 delays (for the test)")
    p.add_argument("--model-exported-at", choices=["pre-update", "truth"], default="pre-update",
                   help="the FMU being updated: exported from the pre-update moduli (default: the route must reach "
                        "the truth) or the test article's own file started at them (its reanalysis basis is the "
                        "truth's modes: the truth is then the route's own nominal, exact by construction)")
    args = p.parse_args(argv)

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.problem import fmu_problem
    from mace_fmu.updating.fmu.truth import GYRO_DELAYS, SERVO_DELAYS, compare_frfs, default_estimator, measure_test_article
    from mace_fmu.updating.fmu.update import fmu_parameters, update_fmu
    from mace_fmu.updating.mace.update import THESIS_KEPT, pre_update_parameters, table_4_4_moduli
    from mace_fmu.util.runner import DaskRunner

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    seconds = 8.0 if args.quick else args.seconds
    segment_s = 1.0 if args.quick else 2.0  # H1 segments: at least 4 inputs' worth of averages in a short record
    moduli = ("E_lexan_end", "E_lexan_center") if args.quick else THESIS_KEPT
    delays = ("delay_gimbal_primary_x", "delay_gyro_payload_x") if args.quick else SERVO_DELAYS + GYRO_DELAYS
    timings: dict[str, float] = {}

    t0 = time.perf_counter()
    fmu = export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=out,
                            name="MACE_1g_native")  # 1. the test article
    timings["export the FMU"] = time.perf_counter() - t0
    family = fmu_family(fmu)  # the truth
    nominal = family.interface.parameters
    truth = {**{n: nominal[n] for n in delays}, **{n: table_4_4_moduli()[n] for n in moduli}}
    if any(abs(nominal[n] / truth[n] - 1.0) > 1e-12 for n in moduli):
        raise SystemExit("the FMU's moduli are not Table 4.4's: the bundled deck changed")

    t0 = time.perf_counter()
    estimator = default_estimator(step_s=0.002, segment_s=segment_s)
    article = measure_test_article(family, out_dir=out / "data", seconds=seconds, estimator=estimator)  # 2. the measured data
    timings["measure (simulate, write files)"] = time.perf_counter() - t0
    time_file, uff_file = article.files[0], article.files[1]
    # the test drives the gimbals only: the wheels and the active strut stay at 0 V, which the update is told
    unrecorded = tuple(i for i in family.interface.inputs if i not in article.history.inputs)
    model_fmu = fmu
    if args.model_exported_at == "pre-update":  # a Ritz basis that is not the truth's: what reanalysis costs
        t0 = time.perf_counter()
        # the moduli this run updates at their pre-update values, the others at the truth's (a quick run updates two)
        pre_update = compute_modes(configuration="1g", parameters=ParameterSet(
            {n: pre_update_parameters()[n] for n in moduli}))
        model_fmu = export_fmu(volts_model(pre_update), out_dir=out / "pre_update", name="MACE_1g_native")
        timings["export the pre-update FMU"] = time.perf_counter() - t0

    runner_cm = DaskRunner(workers=args.workers, task="FMU runs") if args.workers > 0 else None
    runner = runner_cm if runner_cm is not None else map
    summary: dict = {"seconds_of_record": seconds, "workers": args.workers, "model": args.model_exported_at, "files": [str(f) for f in article.files],
                     "updates": {}}
    try:
        pre = pre_update_parameters()
        for cost, data in (("time", [time_file]), ("log-frf", [time_file, uff_file])):  # 3. the moduli
            start = {n: pre[n] for n in moduli}
            t0 = time.perf_counter()
            problem = fmu_problem(fmu=model_fmu, data=data, names=moduli, cost=cost, start=start, segment_s=segment_s,
                                  held_inputs=unrecorded)
            result = update_fmu(family=problem.family, cost=problem.cost, start=problem.start,
                                stages=[problem.names], runner=runner)
            timings[f"moduli, {cost} cost"] = time.perf_counter() - t0
            frfs = compare_frfs(family, truth={}, updated=problem.family.full(result.values), history=article.history,
                                estimator=estimator)
            summary["updates"][f"moduli, {cost}"] = {
                "start_error_percent": {n: 100 * (start[n] / truth[n] - 1) for n in moduli},
                "final_error_percent": {n: 100 * (result.values[n] / truth[n] - 1) for n in moduli},
                "initial_cost": result.initial_cost, "final_cost": result.final_cost,
                "reduction_percent": 100 * result.reduction, "outer_iterations": len(result.history),
                "fmu_runs": sum(1 + (len(moduli) * (2 if result.settings.difference == "central" else 1)
                                     if it.sensitivities is not None else 0) for it in result.history),
                **_verdict(result, problem.cost),
                "frf_max_db": {f"{i} -> {o}": d for (i, o), d in frfs.max_db.items()},
                "frf_bins_used": {f"{i} -> {o}": k for (i, o), k in frfs.bins_used.items()},
                "seconds": result.seconds}
            if cost == "log-frf":
                best = result
                params = fmu_parameters(result, family=problem.family, data=", ".join(map(str, data)),
                                        cost=problem.cost)
        for cost in ("log-frf", "time"):  # 4. the delays, from 20 % long (servo) and 15 % short (gyro)
            start = {n: truth[n] * (1.2 if "gimbal" in n else 0.85) for n in delays}
            fixed = {n: truth[n] for n in moduli}
            t0 = time.perf_counter()
            problem = fmu_problem(fmu=model_fmu, data=[time_file], names=delays, cost=cost, start={**fixed, **start},
                                  segment_s=segment_s, held_inputs=unrecorded)
            result = update_fmu(family=problem.family, cost=problem.cost, start=problem.start,
                                stages=[problem.names], runner=runner)
            timings[f"delays, {cost} cost"] = time.perf_counter() - t0
            summary["updates"][f"delays, {cost}"] = {
                "start_error_ms": {n: 1e3 * (start[n] - truth[n]) for n in delays},
                "final_error_ms": {n: 1e3 * (result.values[n] - truth[n]) for n in delays},
                "initial_cost": result.initial_cost, "final_cost": result.final_cost,
                "reduction_percent": 100 * result.reduction, "outer_iterations": len(result.history),
                "seconds": result.seconds, **_verdict(result, problem.cost)}
    finally:
        if runner_cm is not None:
            runner_cm.close()

    t0 = time.perf_counter()  # 5. the updated FMU and the overlay plot
    toml = params.write(out / "parameters.toml")
    updated_fmu = export_fmu(volts_model(compute_modes(configuration="1g", parameters=ParameterSet.read(toml))),
                                    out_dir=out / "updated",
                                    name="MACE_1g_native")
    timings["export the updated FMU"] = time.perf_counter() - t0
    png = overlay_plot(truth_fmu=fmu, updated_fmu=updated_fmu, start={n: pre[n] for n in moduli},
                       history=article.history, estimator=estimator, path=out / "overlay.png")
    summary.update(parameters=str(toml), updated_fmu=str(updated_fmu), overlay=str(png), timings_s=timings,
                   log_frf_reduction_percent=100 * best.reduction)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(format_summary(summary))
    return summary


def _verdict(result, cost) -> dict:
    """Converged or not, and why (the noise-floor test for the time cost): what a user signs off on."""
    from mace_fmu.updating.engine.convergence import convergence_report, time_noise_floor
    from mace_fmu.updating.engine.costs import TimeResponseCost

    floor = time_noise_floor(cost) if isinstance(cost, TimeResponseCost) else None
    report = convergence_report(result, noise_floor=floor)
    return {"converged": report.converged, "convergence": report.summary()}


def overlay_plot(*, truth_fmu: Path, updated_fmu: Path, start: dict, history, estimator, path: Path) -> Path:
    """|H| and phase of the four checked gimbal-to-gyro FRFs: truth, start (pre-update moduli), updated FMU."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mace_fmu.updating.engine.measured import TimeHistory
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.truth import CHECKED_FRFS
    from mace_fmu.util.atomic import save_figure_atomic

    outs = sorted({o for _, o in CHECKED_FRFS})
    curves = {}
    for label, path_, values in (("truth", truth_fmu, {}), ("start", truth_fmu, start), ("updated FMU", updated_fmu, {})):
        y = fmu_family(path_).full(values).time_response(history.times_s, history.inputs, outputs=outs)
        curves[label] = estimator(TimeHistory(history.times_s, history.inputs, {o: y[:, k] for k, o in enumerate(outs)}))
    fig, axes = plt.subplots(2, 4, figsize=(16, 6), sharex=True)
    for col, (i, o) in enumerate(CHECKED_FRFS):
        for label, style in (("truth", "k-"), ("start", "C1--"), ("updated FMU", "C0:")):
            frd = curves[label]
            h = frd.response[:, frd.outputs.index(o), frd.inputs.index(i)]
            axes[0, col].semilogx(frd.frequencies_hz, 20 * np.log10(np.abs(h)), style, label=label)
            axes[1, col].semilogx(frd.frequencies_hz, np.degrees(np.angle(h)), style)
        axes[0, col].set_title(f"{i} -> {o}", fontsize=9)
        axes[1, col].set_xlabel("frequency [Hz]")
    axes[0, 0].set_ylabel("|H| [dB V/V]")
    axes[1, 0].set_ylabel("phase [deg]")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    save_figure_atomic(fig, path, dpi=90)
    plt.close(fig)
    return path


def format_summary(summary: dict) -> str:
    lines = [f"record {summary['seconds_of_record']:g} s at 2 ms, {summary['workers']} workers, model FMU exported "
             f"at the {summary['model']} moduli"]
    for name, u in summary["updates"].items():
        lines.append(f"\n{name}: cost {u['initial_cost']:.4g} -> {u['final_cost']:.4g} "
                     f"({u['reduction_percent']:.1f} % lower), {u['outer_iterations']} outer iterations, "
                     f"{u['seconds']:.1f} s")
        lines.append(f"  {u['convergence']}")
        if "final_error_percent" in u:
            for n, e in u["final_error_percent"].items():
                lines.append(f"  {n:<26} start {u['start_error_percent'][n]:+7.2f} %   updated {e:+8.3f} %")
            lines.append("  FRF max |dB| (away from zeros): " +
                         ", ".join(f"{k} {v:.3f}" for k, v in u["frf_max_db"].items()))
        else:
            for n, e in u["final_error_ms"].items():
                lines.append(f"  {n:<26} start {u['start_error_ms'][n]:+7.3f} ms  updated {e:+8.4f} ms")
    lines.append("\n" + ", ".join(f"{k} {v:.1f} s" for k, v in summary["timings_s"].items()))
    lines.append(f"wrote {summary['parameters']}, {summary['updated_fmu']}, {summary['overlay']}")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
