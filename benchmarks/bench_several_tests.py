"""Several tests, sensor gains and the whole-record runtime call, on a truth we know (issue: updating you can trust).

Run by hand: ``python benchmarks/bench_several_tests.py [--seconds 20] [--workers 2] [--out DIR]``; results go
into benchmarks/RESULTS.md.

Truth: the 1-g native FMU of the bundled deck with its 8 kept moduli moved by a few percent (OFFSETS);
start: the pre-update moduli (Table 4.4 back-computed). Tests, written as a lab would (CSV and a channel
map), 2 % white output noise, band-limited 0.5-60 Hz excitation, ``--seconds`` each at 2 ms:
- gimbal: the four gimbals -> the five rate gyros and strut 2's strain gauges;
- strut: both active-strut piezos -> strut 2's strain gauges and the payload x gyro;
- wheel: the three reaction-wheel inputs -> the five rate gyros (for the scaling with the number of tests).

Cases (each an update of the 8 moduli through ``mace-fmu update fmu``'s own functions, ``--workers`` Dask
workers, timed end to end): the gimbal test with the time cost and with the log-FRF cost; gimbal + strut
with both costs; gimbal + strut + wheel (time); the gimbal test with the gauges' gains off by +0.9 % and
-0.7 % and known to 1 % (estimated as nuisance parameters). Also: the uncertainty report's time against
the update's, and one 20 s simulation through FMI call by call against the runtime's whole-record call.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from common import machine_line

OFFSETS = {"E_lexan_end": 0.02, "E_lexan_center": -0.03, "E_cable_1": 0.04, "E_cable_2": -0.02, "E_cable_3": 0.03,
           "E_active_strut_end": -0.02, "E_active_strut_piezo": 0.03, "E_active_strut_center": 0.02}
GIMBALS = ("gimbal_primary_x", "gimbal_primary_z", "gimbal_secondary_x", "gimbal_secondary_z")
GYROS = ("gyro_payload_x", "gyro_payload_z", "gyro_bus_x", "gyro_bus_y", "gyro_bus_z")
GAUGES = ("strain_strut2_y", "strain_strut2_z")
TESTS = {"gimbal": (GIMBALS, GYROS + GAUGES), "strut": (("active_strut_y", "active_strut_z"), GAUGES + GYROS[:1]),
         "wheel": (("rwa_x", "rwa_y", "rwa_z"), GYROS)}
GAIN_ERRORS = {"strain_strut2_y": 1.009, "strain_strut2_z": 0.993}


def measure(family, truth, name, *, seconds, out, seed, gains=None):
    """Write test ``name`` of the truth as CSV (labels in:/out:) and return its path."""
    from mace_fmu.updating.engine.measured import TimeHistory
    from mace_fmu.updating.files import write_time_history
    from mace_fmu.updating.fmu.truth import band_limited_noise

    inputs, outputs = TESTS[name]
    n = int(round(seconds / 0.002)) + 1
    t = np.arange(n) * 0.002
    u = {i: band_limited_noise(samples=n, step_s=0.002, band_hz=(0.5, 60.0), seed=seed + j)
         for j, i in enumerate(inputs)}  # the inputs a test does not drive are not recorded: held at 0 V
    y = family.full(truth).time_response(t, u, outputs=list(outputs))
    y = y * np.array([(gains or {}).get(o, 1.0) for o in outputs])
    y = y + 0.02 * np.sqrt(np.mean(y**2, axis=0)) * np.random.default_rng(seed + 50).standard_normal(y.shape)
    return write_time_history(TimeHistory(t, u, {o: y[:, k] for k, o in enumerate(outputs)}, source=name),
                              out / f"{name}{'_gain_errors' if gains else ''}.csv")


def run_case(fmu, files, *, cost, start, workers, gains=None):
    """One update as ``mace-fmu update fmu`` makes it; (result, uncertainty, report, seconds, uncertainty seconds)."""
    from mace_fmu.updating.engine.convergence import convergence_report, noise_floor
    from mace_fmu.updating.engine.uncertainty import stage_uncertainty
    from mace_fmu.updating.fmu.model import read_fmu_interface
    from mace_fmu.updating.fmu.problem import fmu_problem
    from mace_fmu.updating.fmu.update import update_fmu
    from mace_fmu.util.runner import DaskRunner

    t0 = time.perf_counter()
    problem = fmu_problem(fmu=fmu, data=files, names=list(OFFSETS), cost=cost, start=start,
                          held_inputs=read_fmu_interface(fmu).inputs, gain_uncertainty=gains)
    with DaskRunner(workers=workers) as runner:
        result = update_fmu(family=problem.family, cost=problem.cost, start=problem.start, stages=[problem.names],
                            runner=runner)
    floor = noise_floor(problem.cost)
    report = convergence_report(result, noise_floor=floor)
    t1 = time.perf_counter()
    uncertainty = stage_uncertainty(result, noise_variance=floor.expected_cost / result.final_residual.size
                                    if floor is not None else None)
    t2 = time.perf_counter()
    return result, uncertainty[0], report, t2 - t0, t2 - t1


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--seconds", type=float, default=20.0, help="record length of each test [s] (default 20)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", default=None)
    p.add_argument("--cases", default="all", help="comma-separated case numbers (default: all)")
    args = p.parse_args()

    import dask
    import fmpy

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.updating.fmu.model import _LoadedFmu, fmu_family
    from mace_fmu.updating.mace.update import pre_update_parameters

    out = Path(args.out or tempfile.mkdtemp(prefix="bench_several_tests_"))
    out.mkdir(parents=True, exist_ok=True)
    fmu = export_fmu(volts_model(compute_modes(configuration="1g")), out_dir=out, name="MACE_1g_native")
    family = fmu_family(fmu)
    truth = {n: family.interface.parameters[n] * (1 + d) for n, d in OFFSETS.items()}
    pre = pre_update_parameters()
    start = {n: pre[n] for n in OFFSETS}
    files = {name: measure(family, truth, name, seconds=args.seconds, out=out, seed=10 * k)
             for k, name in enumerate(TESTS)}
    gain_file = measure(family, truth, "gimbal", seconds=args.seconds, out=out, seed=0, gains=GAIN_ERRORS)

    lines = [machine_line(fmpy=fmpy.__version__, dask=dask.__version__),
             f"- date: {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC, load average before: "
             f"{os.getloadavg()[0]:.1f}; {args.seconds:g} s per test at 2 ms, {args.workers} workers", ""]

    # one simulation: FMI call by call against the runtime's whole-record call
    interface = family.interface
    t = np.arange(int(round(args.seconds / 0.002)) + 1) * 0.002
    u = np.random.default_rng(0).standard_normal((t.size, len(interface.inputs)))
    values = {"E_cable_1": truth["E_cable_1"]}
    timing = {}
    for label, loaded in (("FMI call by call", _LoadedFmu(interface, whole_record=False)),
                          ("whole-record call", _LoadedFmu(interface))):
        loaded.run(values, t, u, interface.inputs, interface.outputs)
        ts = []
        for _ in range(5):
            t0 = time.perf_counter()
            y = loaded.run(values, t, u, interface.inputs, interface.outputs)
            ts.append(time.perf_counter() - t0)
        timing[label] = (float(np.median(ts)), y)
    same = np.array_equal(timing["FMI call by call"][1], timing["whole-record call"][1])
    lines += ["| one 1-g simulation (12 inputs, 20 outputs, parameters set, initialised) | median [s] | "
              "per step [us] |",
              "|---|---|---|"]
    lines += [f"| {label} | {s:.4f} | {1e6 * s / t.size:.2f} |" for label, (s, _) in timing.items()]
    lines += ["", f"- outputs of the two routes equal to the last bit: {same}", ""]

    cases = {1: ("gimbal, time", [files["gimbal"]], "time", None),
             2: ("gimbal, log-FRF", [files["gimbal"]], "log-frf", None),
             3: ("gimbal + strut, time", [files["gimbal"], files["strut"]], "time", None),
             4: ("gimbal + strut, log-FRF", [files["gimbal"], files["strut"]], "log-frf", None),
             5: ("gimbal + strut + wheel, time", [files["gimbal"], files["strut"], files["wheel"]], "time", None),
             6: ("gimbal, gauges off by +0.9/-0.7 %, known to 1 %, time", [gain_file], "time",
                 {o: 0.01 for o in GAUGES})}
    chosen = list(cases) if args.cases == "all" else [int(c) for c in args.cases.split(",")]
    lines += ["| case | converged | sigmas above floor | largest error [%] (cables) | errors outside 95 % | "
              "update [s] | uncertainty report [s] |", "|---|---|---|---|---|---|---|"]
    details = []
    for k in chosen:
        label, data, cost, gains = cases[k]
        result, unc, report, seconds, t_unc = run_case(fmu, data, cost=cost, start=start, workers=args.workers,
                                                       gains=gains)
        errors = {n: 100 * (result.values[n] / truth[n] - 1) for n in OFFSETS}
        outside = [n for n in OFFSETS if abs(errors[n]) > 1.96 * unc.standard_deviation_percent[n]]
        sigmas = report.noise_floor.sigmas_above(result.final_cost) if report.noise_floor else float("nan")
        cables = max(abs(errors[n]) for n in OFFSETS if "cable" in n)
        others = max(abs(errors[n]) for n in OFFSETS if "cable" not in n)
        lines.append(f"| {label} | {report.converged} | {sigmas:+.1f} | {others:.2f} ({cables:.2f}) | "
                     f"{', '.join(outside) or 'none'} | {seconds:.1f} | {t_unc:.3f} |")
        details.append(f"{label}: " + ", ".join(f"{n} {errors[n]:+.2f} % (sd {unc.standard_deviation_percent[n]:.2f})"
                                               for n in OFFSETS)
                       + "".join(f"; {g} {100 * (result.values[g] - 1):+.2f} % (sd "
                                 f"{unc.standard_deviation_percent[g]:.2f})"
                                 for g in unc.names if g.startswith("gain:"))
                       + ("; weak: " + "; ".join(w.text() for w in unc.weak_directions) if unc.weak_directions else ""))
        print(lines[-1], flush=True)
    lines += [""] + [f"- {d}" for d in details]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
