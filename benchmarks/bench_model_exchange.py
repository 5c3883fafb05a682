"""Where a model-exchange run of the native 1-g FMU spends its time in fmpy (CVode), against co-simulation.

Run by hand: ``python benchmarks/bench_model_exchange.py [--seconds 10] [--cases held,steps,random]``;
results in RESULTS.md. Every run is compared with the exact zero-order-hold response of the
state-space model (``control.forced_response`` of the ZOH discretisation at the 2 ms output step),
as the largest error relative to each output's range.

Cases (all with outputs every 2 ms):
- ``held``: every input stepped to a constant at t = 0 (the test's case), fmpy's default tolerance
  (1e-5) and the tolerances that reach 1e-6 of each output's range; one run with the FMU's exact
  Jacobian (``fmi2GetDirectionalDerivative``, column by column) given to fmpy's CVode;
- ``steps``: random input levels switched every 0.5 s, each switch an input event (fmpy stops
  CVode there and restarts it);
- ``random``: the first benchmark's inputs, a random level on every input every 2 ms (0.1 V rms,
  seed 0), once as fmpy reads that table (interpolated linearly, which its model exchange applies only
  at the output points) and once as steps (an input event every 2 ms); shorter runs, see --random-seconds.

CVode's counters (steps, right-hand sides, difference-quotient right-hand sides for the Jacobian,
Jacobians, LU factorisations) come from SUNDIALS through fmpy's own library handle, accumulated over
the restarts; the solver class is wrapped only to count and time (``fmi2GetDerivatives`` calls).
"""

from __future__ import annotations

import argparse
import ctypes
import os
import tempfile
import time
from pathlib import Path

import control as ct
import numpy as np
import fmpy.sundials as sundials
from fmpy import read_model_description, simulate_fmu
from fmpy.sundials.libraries import sundials_cvode, sundials_sunmatrixdense

from mace_fmu.fe.modes import compute_modes
from mace_fmu.fmu.export import export_fmu
from mace_fmu.iomodel.volts import volts_model

COUNTERS = ("Steps", "RhsEvals", "LinRhsEvals", "JacEvals", "LinSolvSetups", "ErrTestFails")
DT = 0.002


class Probe:
    """Counts and times what fmpy's CVode asks of the FMU; optionally gives CVode the FMU's Jacobian."""

    def __init__(self):
        self.calls, self.seconds, self.counts, self.jacobian = 0, 0.0, dict.fromkeys(COUNTERS, 0), False
        self.fmu = None
        probe, init, reset = self, sundials.CVodeSolver.__init__, sundials.CVodeSolver.reset

        def counted_init(solver, *args, **kwargs):
            get_dx = kwargs["get_dx"]

            def timed(pointer, n):
                t0 = time.perf_counter()
                get_dx(pointer, n)
                probe.seconds += time.perf_counter() - t0
                probe.calls += 1

            kwargs["get_dx"] = timed
            init(solver, *args, **kwargs)
            probe.solver = solver
            if probe.jacobian:
                probe.give_jacobian(solver)

        def counted_reset(solver, t):
            probe.collect(solver)
            reset(solver, t)

        sundials.CVodeSolver.__init__, sundials.CVodeSolver.reset = counted_init, counted_reset
        from fmpy import fmi2
        instantiate = fmi2.FMU2Model.instantiate

        def remember(fmu, *args, **kwargs):
            probe.fmu = fmu
            return instantiate(fmu, *args, **kwargs)

        fmi2.FMU2Model.instantiate = remember

    def start(self, jacobian: bool) -> None:
        self.calls, self.seconds, self.counts, self.jacobian = 0, 0.0, dict.fromkeys(COUNTERS, 0), jacobian

    def collect(self, solver) -> None:
        for name in COUNTERS:
            value = ctypes.c_long()
            getattr(sundials_cvode, f"CVodeGetNum{name}")(ctypes.c_void_p(solver.cvode_mem), ctypes.byref(value))
            self.counts[name] += value.value

    def give_jacobian(self, solver) -> None:
        """CVodeSetJacFn: the Jacobian column by column from fmi2GetDirectionalDerivative (what a host that
        uses the FMU's directional derivatives does; fmpy's simulate_fmu has no option for it)."""
        fmu, n = self.fmu, solver.nx
        ders = [u.variable.valueReference for u in self.md.derivatives]
        states = [u.variable.derivative.valueReference for u in self.md.derivatives]
        unknown, known = (ctypes.c_uint * n)(*ders), (ctypes.c_uint * n)(*states)
        seed = (ctypes.c_double * n)()
        sundials_sunmatrixdense.SUNDenseMatrix_Data.restype = ctypes.c_void_p
        sundials_sunmatrixdense.SUNDenseMatrix_Data.argtypes = [ctypes.c_void_p]
        directional = fmu.dll.fmi2GetDirectionalDerivative
        column = ctypes.POINTER(ctypes.c_double)

        def jac(t, y, fy, matrix, user_data, tmp1, tmp2, tmp3):
            data = sundials_sunmatrixdense.SUNDenseMatrix_Data(matrix)  # column-major
            for j in range(n):
                seed[j] = 1.0
                status = directional(fmu.component, unknown, n, known, n, seed, ctypes.cast(data + 8 * n * j, column))
                seed[j] = 0.0
                if status != 0:
                    return -1
            return 0

        jac_type = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                                    ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
        solver.jac_ = jac_type(jac)
        sundials_cvode.CVodeSetJacFn.argtypes = [ctypes.c_void_p, jac_type]
        if sundials_cvode.CVodeSetJacFn(ctypes.c_void_p(solver.cvode_mem), solver.jac_) != 0:
            raise RuntimeError("CVodeSetJacFn failed")


def inputs(kind: str, seconds: float, names: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(output times, inputs held over each 2 ms step (n_in x n_t), fmpy's input table) of a case:
    held, steps (every 0.5 s), random (every 2 ms, one sample each), random_events (every 2 ms, as steps)."""
    t = np.arange(0.0, seconds + DT / 2, DT)
    rng = np.random.default_rng(0)
    if kind == "held":
        u = np.repeat((0.1 + 0.05 * np.arange(len(names)))[:, None], len(t), axis=1)
        at, values = np.array([0, len(t) - 1]), u[:, [0, -1]]
    else:
        period = 250 if kind == "steps" else 1  # output steps per input level
        levels = 0.1 * rng.standard_normal((len(names), len(t) // period + 1))
        u = np.repeat(levels, period, axis=1)[:, :len(t)]
        if kind == "random":  # the table as the first benchmark gave it: one sample every 2 ms
            at, values = np.arange(len(t)), u
        else:  # each change twice, left and right value, at the same time: fmpy's input events
            change = np.arange(period, len(t), period)
            rows = np.concatenate([[0], np.ravel([(k - 1, k) for k in change]), [len(t) - 1]]).astype(int)
            at, values = np.concatenate([[0], np.repeat(change, 2), [len(t) - 1]]), u[:, rows]
    table = np.zeros(len(at), dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = t[at]
    for i, name in enumerate(names):
        table[name] = values[i]
    return t, u, table


def error(result, t: np.ndarray, reference: np.ndarray, outputs: list[str]) -> float:
    """Largest error relative to each output's range, at the output times (after an event there)."""
    rows = np.searchsorted(result["time"], t + 1e-12, side="right") - 1
    if not np.allclose(result["time"][rows], t, atol=1e-9):
        return float("nan")
    y = np.array([result[n][rows] for n in outputs])
    return float(np.max(np.max(np.abs(y - reference), axis=1) / np.ptp(reference, axis=1)))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated time of the held/steps runs [s]")
    parser.add_argument("--random-seconds", type=float, default=0.2, help="simulated time of the random runs [s]")
    parser.add_argument("--cases", default="held,steps,random")
    parser.add_argument("--no-jacobian", action="store_true", help="skip the run with the exact Jacobian (for "
                        "FMUs without directional derivatives)")
    args = parser.parse_args()
    probe = Probe()
    model = volts_model(compute_modes(configuration="1g"))
    names, outputs = list(model.system.input_labels), list(model.system.output_labels)
    zoh = ct.sample_system(model.system, DT, "zoh")
    with tempfile.TemporaryDirectory() as tmp:
        fmu = str(export_fmu(model, runtime="native", out_dir=Path(tmp), name="MACE_1g_native"))
        probe.md = read_model_description(fmu)
        print(f"{len(probe.md.derivatives)} states; load {os.getloadavg()}")
        print("| case | simulated | rtol | wall [s] | x CS | error / range | CVode steps | RHS (+ DQ Jacobian) | "
              "Jacobians | LU | derivative calls (us each) |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        long, short = args.seconds, args.random_seconds
        runs = {"held": [("held", long, 1e-5, False), ("held", long, 1e-9, False), ("held", long, 3e-9, False),
                         ("held", long, 3e-9, True)],
                "steps": [("steps", long, 1e-5, False), ("steps", long, 3e-9, False)],
                "random": [("random", short, 1e-5, False), ("random", short, 3e-9, False),
                           ("random_events", short, 1e-5, False), ("random_events", short, 3e-9, False)]}
        labels = {"held": "held from t = 0", "steps": "steps every 0.5 s (events)",
                  "random": "random every 2 ms, interpolated", "random_events": "random every 2 ms, as events"}
        for case in args.cases.split(","):
            for kind, seconds, rtol, jacobian in runs[case]:
                if jacobian and args.no_jacobian:
                    continue
                t, u, table = inputs(kind, seconds, names)
                reference = ct.forced_response(zoh, T=t, U=u).outputs
                run = dict(stop_time=seconds, output_interval=DT, input=table, output=outputs)
                t0 = time.perf_counter()
                cs = simulate_fmu(fmu, fmi_type="CoSimulation", **run)
                cs_time = time.perf_counter() - t0
                probe.start(jacobian)
                t0 = time.perf_counter()
                try:
                    me, err = simulate_fmu(fmu, fmi_type="ModelExchange", relative_tolerance=rtol, **run), ""
                except RuntimeError as e:  # CVode gives up
                    me, err = None, "CVode failed: " + str(e).split(":")[-1].strip()[:70]
                me_time = time.perf_counter() - t0
                probe.collect(probe.solver)
                c = probe.counts
                err = err or f"{error(me, t, reference, outputs):.1e}"
                print(f"| {labels[kind]}{' + exact Jacobian' if jacobian else ''} | {seconds:g} s | {rtol:g} | "
                      f"{me_time:.2f} | {me_time / cs_time:.0f} | {err} (CS {error(cs, t, reference, outputs):.0e}, "
                      f"{cs_time:.2f} s) | {c['Steps']} | {c['RhsEvals']} + {c['LinRhsEvals']} | {c['JacEvals']} | "
                      f"{c['LinSolvSetups']} | {probe.calls} ({1e6 * probe.seconds / max(probe.calls, 1):.1f}) |",
                      flush=True)
        print(f"load at the end {os.getloadavg()}")


if __name__ == "__main__":
    main()
