"""The FMUs' parameter route against full re-solves, and what it costs (issue 32: FMU parameters exact on every channel).

Run by hand: ``python benchmarks/bench_parameter_route.py [--runs 21] [--skip-accuracy] [--random [--resolved-only]
[--native]]``; results go
into benchmarks/RESULTS.md.

``--random`` (issue 50): the error as a user meets it, every physical parameter changed at once: 20 seeded
points, each parameter uniform in +-w of nominal (w = 5, 10, 15, 20 %) and over its declared range, every
input driven by 0.5-60 Hz noise for 10 s at 2 ms; each output's RMS difference from the full re-solve (which
continues the nominal modes, as ``export --parameters`` does) over its RMS, the worst output's per point;
the worst, median and 90th percentile of the 20, for the 1-g model with the large and the linear preload
and the 0-g model.

Accuracy, per physical parameter of both MACE models (the reference: tests/support/resolves.py, the deck with
the parameter built in and solved again, each mode keeping its nominal damping): 10 s at 2 ms of band-limited
(below 20 Hz) commands on the gimbals, and separately on the piezo patches; d y / d ln p by central
differences of 2 %, the worst output among those it moves by 2 % at least (norm of the difference over the
norm of the re-solve's change); and the worst output's largest difference at the ends of the declared range
(0.7 and 1.5 x nominal) and at +-20 %, in % of the output's range.

Cost, on the native FMUs (in process, fmpy's FMU2Slave): instantiate + initialise with the nominal
parameters and with one modulus changed (the reanalysis runs); one instance reset and initialised again with
another value each time (as an update runs its FMU: the instance keeps its work arrays); and one doStep of 2 ms,
each the median of ``--runs``; the export's parametric arrays (stiffness sensitivities and static corrections).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from common import machine_line, timed

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from support.resolves import band_limited_inputs, resolved_system, zoh_response  # noqa: E402

DRIVEN = (("gimbal",), ("active_strut",))


def accuracy(configuration: str) -> list[str]:
    """One table row per physical parameter of ``configuration``'s model."""
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.parametric_data import parametric_arrays
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import deck_values
    from mace_fmu.structure.file import bundled_deck_path

    model = volts_model(compute_modes(configuration=configuration))
    system = ParametricSystem(parametric_arrays(model))
    values = deck_values(read_deck(bundled_deck_path()))
    u_sets = [band_limited_inputs(system.inputs, d) for d in DRIVEN]
    y0 = [zoh_response(system.build(system.nominal), u) for u in u_sets]
    rows = []
    for name in (str(n) for n in system.data["physical_names"]):
        def route(factor):
            params = system.nominal.copy()
            params[system.index(name)] *= factor
            built = system.build(params)
            return [zoh_response(built, u) for u in u_sets]

        def resolve(factor):
            built = resolved_system(configuration, {**values, name: values[name] * factor}, model)
            return [zoh_response(built, u) for u in u_sets]

        worst_d, moved = (0.0, ""), 0
        for k, (rp, rm, ep, em) in enumerate(zip(route(1.02), route(0.98), resolve(1.02), resolve(0.98))):
            dr, de = (rp - rm) / 0.04, (ep - em) / 0.04
            for j, output in enumerate(system.outputs):
                change = np.linalg.norm(de[:, j])
                if change < 0.02 * np.linalg.norm(y0[k][:, j]):
                    continue
                moved += 1
                error = np.linalg.norm(dr[:, j] - de[:, j]) / change
                worst_d = max(worst_d, (error, f"{output} ({DRIVEN[k][0]})"))
        ends = []
        for factor in (0.7, 0.8, 1.2, 1.5):
            worst = 0.0
            for k, (yr, ye) in enumerate(zip(route(factor), resolve(factor))):
                worst = max(worst, float(np.max(np.max(np.abs(yr - ye), axis=0) / np.ptp(y0[k], axis=0))))
            ends.append(worst)
        rows.append(f"| {configuration} | {name} | {moved} | {100 * worst_d[0]:.2f} % {worst_d[1]} | "
                    + " | ".join(f"{100 * e:.3f}" for e in ends) + " |")
        print(rows[-1], flush=True)
    return rows


def _native_responses(model, folder: Path):
    """``response(point, u)``: outputs (samples, n_outputs) of ``model``'s native FMU (its C runtime, through FMI 2)
    initialised with ``point`` (name -> value), u[k] held over each 2 ms step."""
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    from mace_fmu.fmu.export import export_fmu

    unzipped = fmpy.extract(str(export_fmu(model, out_dir=folder, name="MACE_native")), unzipdir=str(folder / "x"))
    md = fmpy.read_model_description(unzipped)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    ins = [vr[n] for n in model.system.input_labels]
    outs = [vr[n] for n in model.system.output_labels]

    def response(point: dict[str, float], u: np.ndarray) -> np.ndarray:
        slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName="bench")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setReal([vr[k] for k in point], list(point.values()))
        slave.exitInitializationMode()
        y = []
        for k, uk in enumerate(u):
            slave.setReal(ins, list(uk))
            y.append(slave.getReal(outs))
            slave.doStep(currentCommunicationPoint=2e-3 * k, communicationStepSize=2e-3)
        slave.terminate()
        slave.freeInstance()
        return np.array(y)

    return response


def random_points(configuration: str, preload: str, width: float | None, *, seed: int = 50, resolve: bool = False,
                  native_folder: Path | None = None) -> str:
    """One table row: the worst output's RMS difference over its RMS at 20 seeded points (module docstring);
    ``resolve``: the structure solved again at each point (mace_fmu.iomodel.resolve, the pythonfmu FMU's way), the
    median time of that build [ms] in the row's model column; ``native_folder``: the native FMU (its C re-solve)
    exported there and run through FMI at the same points instead."""
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.parametric import ParametricSystem
    from mace_fmu.iomodel.parametric_data import parametric_arrays
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.updating.fmu.truth import band_limited_noise

    model = volts_model(compute_modes(configuration=configuration, preload=preload))
    system = ParametricSystem(parametric_arrays(model, resolve=resolve))
    builds = []
    u = np.column_stack([band_limited_noise(samples=5000, step_s=2e-3, band_hz=(0.5, 60.0), seed=1 + k)
                         for k in range(len(system.inputs))])
    native = _native_responses(model, native_folder) if native_folder is not None else None
    rng = np.random.default_rng(seed)
    worst = []
    for _ in range(20):
        params, point = system.nominal.copy(), {}
        for name in (str(n) for n in system.data["physical_names"]):
            k = system.index(name)
            low, high = system.minimum[k], system.maximum[k]
            if width is not None:
                low, high = max(low, system.nominal[k] * (1 - width)), min(high, system.nominal[k] * (1 + width))
            params[k] = point[name] = float(rng.uniform(low, high))
        resolved = volts_model(compute_modes(configuration=configuration, preload=preload,
                                             parameters=ParameterSet(point), continue_from=model.structure_modes))
        reference = ParametricSystem(parametric_arrays(resolved, physical=False))
        started = time.perf_counter()
        built = system.build(params)
        builds.append(time.perf_counter() - started)
        y = zoh_response(built, u) if native is None else native(point, u)
        y_ref = zoh_response(reference.build(reference.nominal), u)
        rms = np.sqrt(np.mean(y_ref**2, axis=0))
        errors = np.sqrt(np.mean((y - y_ref) ** 2, axis=0)) / np.where(rms > 0, rms, 1.0)
        worst.append((float(errors.max()), system.outputs[int(errors.argmax())]))
    values = 100 * np.array([w for w, _ in worst])
    box = "declared range" if width is None else f"+-{100 * width:g} %"
    model_name = configuration if not resolve else f"{configuration}, solved again ({1e3 * np.median(builds):.0f} ms)"
    if native is not None:
        model_name = f"{configuration}, the native FMU solving again"
    return (f"| {model_name} | {preload if configuration == '1g' else '-'} | {box} | {values.max():.3g} "
            f"({max(worst)[1]}) | {np.median(values):.3g} | {np.percentile(values, 90):.3g} |")


def costs(configuration: str, runs: int, folder: Path) -> str:
    """Export, initialisation and step times of ``configuration``'s native FMU."""
    import fmpy
    from fmpy.fmi2 import FMU2Slave

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.parametric_data import parametric_arrays
    from mace_fmu.iomodel.volts import volts_model

    model = volts_model(compute_modes(configuration=configuration))
    t0 = time.perf_counter()
    arrays = parametric_arrays(model)
    arrays_s = time.perf_counter() - t0
    fmu = export_fmu(model, out_dir=folder, name=f"MACE_{configuration}_native")
    unzipped = fmpy.extract(str(fmu), unzipdir=str(folder / configuration))
    md = fmpy.read_model_description(unzipped)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    modulus = "E_active_strut_center"
    start = next(float(v.start) for v in md.modelVariables if v.name == modulus)

    def instance(values):
        slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName="bench")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        if values:
            slave.setReal([vr[k] for k in values], list(values.values()))
        slave.exitInitializationMode()
        return slave

    def init(values):
        slave = instance(values)
        slave.terminate()
        slave.freeInstance()

    nominal_s, _, _ = timed(lambda: init({}), runs)
    changed_s, _, _ = timed(lambda: init({modulus: 1.1 * start}), runs)
    kept = instance({modulus: 1.1 * start})
    calls = [0]

    def again():  # as an update runs its FMU: the instance reset and initialised at another point each time
        calls[0] += 1
        kept.reset()
        kept.setupExperiment(startTime=0.0)
        kept.enterInitializationMode()
        kept.setReal([vr[modulus]], [(1.1 + 1e-3 * calls[0]) * start])
        kept.exitInitializationMode()

    again_s, _, _ = timed(again, runs)
    kept.terminate()
    kept.freeInstance()
    steps = {}
    for label, values in (("nominal", {}), ("changed", {modulus: 1.1 * start})):
        slave = instance(values)
        t = [0.0]

        def step(slave=slave, t=t):
            for _ in range(500):
                slave.doStep(currentCommunicationPoint=t[0], communicationStepSize=0.002)
                t[0] += 0.002

        steps[label], _, _ = timed(step, max(3, runs // 5))
        slave.terminate()
        slave.freeInstance()
    n_w = arrays["correction_stiffness"].shape[0]
    return (f"| {configuration} | {len(arrays['physical_names'])} | {n_w} ({int(arrays['correction_massive'])} with "
            f"mass) | {arrays_s:.2f} | {1e3 * nominal_s:.1f} | {1e3 * changed_s:.1f} | {1e3 * again_s:.1f} | "
            f"{1e6 * steps['nominal'] / 500:.2f} | {1e6 * steps['changed'] / 500:.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=21)
    parser.add_argument("--skip-accuracy", action="store_true")
    parser.add_argument("--random", action="store_true", help="only the all-at-once random points")
    parser.add_argument("--resolved-only", action="store_true", help="with --random: only the models solved again")
    parser.add_argument("--native", action="store_true", help="with --random: the native FMUs' own re-solve too")
    args = parser.parse_args()
    import os

    import fmpy

    print(machine_line(fmpy=fmpy.__version__))
    print(f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average before: "
          f"{os.getloadavg()[0]:.1f}")
    if args.random:
        print("\n| model | preload | box | worst [% of RMS] (output) | median | 90th percentile |")
        print("|---|---|---|---|---|---|")
        for configuration, preload in () if args.resolved_only else (("1g", "large"), ("1g", "linear"), ("0g", "large")):
            for width in (0.05, 0.10, 0.15, 0.20, None):
                print(random_points(configuration, preload, width), flush=True)
        for configuration in ("1g", "0g"):
            print(random_points(configuration, "large", None, resolve=True), flush=True)
            if args.native:
                with tempfile.TemporaryDirectory() as folder:
                    print(random_points(configuration, "large", None, resolve=True, native_folder=Path(folder)),
                          flush=True)
        print(f"- load average after: {os.getloadavg()[0]:.1f}")
        return
    print("\n| model | physical parameters | static corrections | arrays at export [s] | initialise, nominal [ms] "
          "| initialise, a modulus changed [ms] | reset and initialise again, another value [ms] "
          "| doStep 2 ms, nominal [us] | doStep, changed [us] |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for configuration in ("1g", "0g"):
            print(costs(configuration, args.runs, Path(folder)), flush=True)
    if args.skip_accuracy:
        return
    print("\n| model | parameter | outputs moved >= 2 % | worst d y / d ln p off the re-solve | 0.7 x [% of range] "
          "| 0.8 x | 1.2 x | 1.5 x |")
    print("|---|---|---|---|---|---|---|---|")
    for configuration in ("1g", "0g"):
        accuracy(configuration)
    print(f"- load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
