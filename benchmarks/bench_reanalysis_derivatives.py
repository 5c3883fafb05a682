"""Does the FMU's reanalysis move the 1-g model as a full FE re-solve would? Output derivatives per modulus.

For each Young's modulus q of the 1-g model: the derivative of every frequency response
G_oi(f) [V/V] (all 13 inputs x 20 outputs, 300 frequencies from 0.5 to 60 Hz) with respect to
ln q, by central differences (q (1 +- 1e-3)), through
- the reanalysis the FMUs use (`ParametricSystem`: Ritz reanalysis on the nominal modes, the
  gravity preload's bar forces held), and
- a full re-solve (`volts_model` with the modulus changed: new preload, new modes).
Printed per modulus: the relative difference || dG_reanalysis - dG_full || / || dG_full || over all
channels and frequencies, and the worst single output's. Servo loops, filters and delays are
left out of both (they do not depend on the moduli); the volts model is otherwise the FMU's.

Run by hand: ``python benchmarks/bench_reanalysis_derivatives.py``; results in RESULTS.md.
"""

from __future__ import annotations

import time

import control as ct
import numpy as np

from mace_fmu.fe.modes import compute_modes
from mace_fmu.iomodel.frf import frequency_response
from mace_fmu.iomodel.model_options import ModelledElectronics
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays
from mace_fmu.iomodel.volts import volts_model
from mace_fmu.parameters.kinds import MODULUS, kind_of_fmu_name
from mace_fmu.parameters.sets import ParameterSet

STEP = 1e-2  # 1e-3 left the full re-solve's derivatives of the suspension modes in round-off (eigen-solver and preload)
FREQUENCIES_HZ = np.geomspace(0.5, 60.0, 300)
OPTIONS = dict(electronics=ModelledElectronics(servos=False, bessel="none", delays=False))


def response_full(name: str, value: float) -> np.ndarray:
    model = volts_model(compute_modes(configuration="1g", parameters=ParameterSet({name: value})), **OPTIONS)
    return frequency_response(model.system, FREQUENCIES_HZ)


def main() -> None:
    t0 = time.perf_counter()
    nominal = volts_model(compute_modes(configuration="1g"), **OPTIONS)
    system = ParametricSystem(parametric_arrays(nominal))
    names = [n for n in system.parameter_names if kind_of_fmu_name(n) is MODULUS]
    print(f"1-g model, {len(names)} moduli, {nominal.system.ninputs} inputs x {nominal.system.noutputs} outputs, "
          f"{len(FREQUENCIES_HZ)} frequencies 0.5-60 Hz, step {STEP:g}")
    print("| modulus | relative difference, all channels | worst output | its difference |")
    print("|---|---|---|---|")
    for name in names:
        k = system.index(name)
        q0 = system.nominal[k]
        responses = []
        for sign in (1.0, -1.0):
            p = system.nominal.copy()
            p[k] = q0 * (1.0 + sign * STEP)
            a, b, c, d = system.build(p)
            responses.append(frequency_response(ct.ss(a, b, c, d), FREQUENCIES_HZ))
        d_re = (responses[0] - responses[1]) / (2 * STEP)
        d_full = (response_full(name, q0 * (1 + STEP)) - response_full(name, q0 * (1 - STEP))) / (2 * STEP)
        total = np.linalg.norm(d_re - d_full) / np.linalg.norm(d_full)
        per_output = np.linalg.norm(d_re - d_full, axis=(0, 2)) / np.maximum(np.linalg.norm(d_full, axis=(0, 2)), 1e-300)
        # outputs the modulus hardly moves would dominate a max: weigh by their share of the change
        share = np.linalg.norm(d_full, axis=(0, 2)) / np.linalg.norm(d_full)
        worst = int(np.argmax(np.where(share > 0.05, per_output, 0.0)))
        print(f"| {name} | {100 * total:.2f} % | {nominal.system.output_labels[worst]} | {100 * per_output[worst]:.2f} % |",
              flush=True)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
