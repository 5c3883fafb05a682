"""Plan a test, run it, update: which experiment fixes which moduli, and does the update agree?
===============================================================================================

1. ``plan-test``: before any test, the uncertainty each candidate experiment would leave on the
   lexan, cable and active-strut moduli of the 1-g FMU (from the model alone).
2. A "lab" runs the best candidate on a truth we know (the FMU with its moduli moved a few
   percent), with strut 2's strain gauges off by +0.8 / -0.6 % and known only to 1 %.
3. The FMU update on those files, the gauge gains estimated with the moduli; its reported standard
   deviations beside the plan's, and the truth inside every 95 % interval.

Run: ``python examples/plan_then_update.py [--out DIR] [--seconds 8] [--workers 2]``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

GIMBALS = ("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z")
GYROS = ("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z")
GAUGES = ("strain_strut2_y", "strain_strut2_z")
STRUT_INPUTS = ("active_strut_y", "active_strut_z")
MODULI = ("E_lexan_end", "E_cable_1", "E_cable_2", "E_active_strut_end", "E_active_strut_piezo")
OFFSETS = (0.02, -0.03, 0.02, -0.02, 0.03)  #: the truth, relative to the FMU's start values
GAIN_ERRORS = {"strain_strut2_y": 1.008, "strain_strut2_z": 0.994}


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=None, help="folder for the FMU and the data (default: temporary)")
    p.add_argument("--seconds", type=float, default=8.0, help="length of each test [s]")
    p.add_argument("--workers", type=int, default=2, help="Dask workers for the FMU runs")
    args = p.parse_args(argv)

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.engine.convergence import convergence_report, noise_floor
    from mace_fmu.updating.engine.measured import TimeHistory
    from mace_fmu.updating.engine.uncertainty import format_uncertainty, stage_uncertainty
    from mace_fmu.updating.files import write_time_history
    from mace_fmu.updating.fmu.model import fmu_family
    from mace_fmu.updating.fmu.planning import Candidate, TestDesign, format_plan, plan_tests
    from mace_fmu.updating.fmu.problem import fmu_problem
    from mace_fmu.updating.fmu.truth import band_limited_noise
    from mace_fmu.updating.fmu.update import update_fmu
    from mace_fmu.util.runner import DaskRunner

    out = Path(args.out or tempfile.mkdtemp(prefix="plan_then_update_"))
    out.mkdir(parents=True, exist_ok=True)
    fmu = export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=out, name="MACE_1g_native")

    # 1. the plan: three candidates, before any test
    gimbal = TestDesign(name="gimbal", inputs=GIMBALS, outputs=GYROS, seconds=args.seconds)
    strut = TestDesign(name="strut, gauges to 1 %", inputs=STRUT_INPUTS, outputs=GAUGES + GYROS[:1],
                       seconds=args.seconds, gain_uncertainty_percent={g: 1.0 for g in GAUGES})
    candidates = [Candidate("gimbal", (gimbal,)), Candidate("strut", (strut,)),
                  Candidate("gimbal + strut", (gimbal, strut))]
    with DaskRunner(workers=args.workers) as runner:
        planned = plan_tests(fmu=fmu, parameters=MODULI, candidates=candidates, runner=runner)
    print(format_plan(planned))
    best = planned[0]

    # 2. the lab runs the best candidate on the truth
    family = fmu_family(fmu)
    truth = {n: family.interface.parameters[n] * (1 + d) for n, d in zip(MODULI, OFFSETS)}
    files = []
    for k, test in enumerate(best.candidate.tests):
        n = int(round(test.seconds / test.sample_time_s)) + 1
        t = np.arange(n) * test.sample_time_s
        u = {i: band_limited_noise(samples=n, step_s=test.sample_time_s, band_hz=test.band_hz, seed=100 + 10 * k + j)
             for j, i in enumerate(test.inputs)}
        y = family.full(truth).time_response(t, u, outputs=list(test.outputs))
        y = y * np.array([GAIN_ERRORS.get(o, 1.0) for o in test.outputs])
        y = y + 0.02 * np.sqrt(np.mean(y**2, axis=0)) * np.random.default_rng(7 + k).standard_normal(y.shape)
        files.append(write_time_history(TimeHistory(t, u, {o: y[:, j] for j, o in enumerate(test.outputs)},
                                                    source=test.name), out / f"test_{k}.csv"))
    print(f"\nthe lab ran '{best.candidate.name}': " + ", ".join(str(f) for f in files))

    # 3. the update, the gauges' gains estimated with the moduli
    gains = {o: p / 100 for test in best.candidate.tests for o, p in test.gain_uncertainty_percent.items()}
    problem = fmu_problem(fmu=fmu, data=files, names=MODULI, cost="time", held_inputs=family.interface.inputs,
                          gain_uncertainty=gains)
    with DaskRunner(workers=args.workers) as runner:
        result = update_fmu(family=problem.family, cost=problem.cost, start=problem.start, stages=[problem.names],
                            runner=runner)
    floor = noise_floor(problem.cost)
    report = convergence_report(result, noise_floor=floor)
    (stage,) = stage_uncertainty(result, noise_variance=floor.expected_cost / result.final_residual.size
                                 if floor is not None else None)
    print(format_uncertainty((stage,)))
    print(report.summary())
    print(f"\n{'modulus':<24} {'error %':>8} {'reported sd %':>14} {'planned sd %':>13}  truth in 95 %")
    rows = {}
    for name in MODULI:
        error = 100 * (result.values[name] / truth[name] - 1)
        sd, planned_sd = stage.standard_deviation_percent[name], best.uncertainty.standard_deviation_percent[name]
        rows[name] = (error, sd, planned_sd)
        print(f"{name:<24} {error:>+8.3f} {sd:>14.3f} {planned_sd:>13.3f}  {'yes' if abs(error) <= 1.96 * sd else 'NO'}")
    print("\nThe plan linearised about the FMU's start values, the update about the truth (moduli 2-3 % away):\n"
          "where modes nearly coincide (the cables' 7 Hz violins) the standard deviations move with the point;\n"
          "plan again about the updated values (plan-test --at parameters.toml) before the next test.")
    return {"best": best.candidate.name, "converged": report.converged, "rows": rows}


if __name__ == "__main__":
    main()
