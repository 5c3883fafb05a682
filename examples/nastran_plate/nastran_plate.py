"""From NASTRAN's modes: a shell model's OP2 to a volts-volts model, an FMU and an animation of its modes.
=========================================================================================================

    python examples/nastran_plate/nastran_plate.py [OUT_DIR]

The structure is a free steel plate of 200 CQUAD4 shells (pyNastran's public ``plate_py`` run, NX
Nastran SOL 103, in inch, lbf and second). This tool does not solve shells: it takes the modes NASTRAN
computed, from the run's OP2 file, which ``plate.toml`` names in its ``[modes]`` table with the run's
deck as the geometry to draw. The structure file places a shaker and two accelerometers on grids of
the OP2, with their gains, a computational delay on the shaker and the modal damping.

Steps: NASTRAN's modes (six rigid-body modes, the plate being free, then four flexible ones); the
volts-volts model, its frequency response checked against the modal superposition written out from
the eigenvectors; the native FMU, checked against the exact zero-order hold of the model's state
space, and a changed frequency scale set through the FMU; an animation of the flexible modes drawn
on the deck's shell edges (standalone HTML). The model's parameters are its modal ones (damping
ratios and frequency scales per mode) with the delay: NASTRAN's modes carry no FE, so no modulus.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

# the folder of this script (sphinx-gallery runs it there, without __file__, when the site is built)
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
STRUCTURE = HERE / "plate.toml"
STEP_S = 1.0e-5  #: FMU communication step [s]: a tenth of the highest mode's period (17 kHz)


def superposition_error(model, structure, frequencies_hz: np.ndarray) -> float:
    """Largest difference between the model's accelerance, middle over shaker, and the sum over NASTRAN's modes
    of -w^2 phi_middle phi_corner / (w_k^2 - w^2 + 2 i zeta_k w_k w), as a fraction of its peak (the delay
    divided out; rigid-body modes, below 0.01 Hz, as w_k = 0)."""
    from mace_fmu.iomodel.frf import frequency_response
    from modelica_like import PadeDelay

    modes = structure.modes
    w = 2 * np.pi * frequencies_hz
    omega = np.where(np.abs(modes.frequencies_hz) < 0.01, 0.0, 2 * np.pi * modes.frequencies_hz)
    zeta = model.plant.damping
    terms = modes.shape(116, 3, system="cd") * modes.shape(231, 3, system="cd")
    expected = np.array([-x**2 * np.sum(terms / (omega**2 - x**2 + 2j * zeta * omega * x)) for x in w])
    expected *= 0.001 * 1.0  # sensitivity [V per in/s^2] x gain [lbf per V]
    response = model.frequency_response(frequencies_hz)
    outs = list(model.system.output_labels)
    got = response[:, outs.index("acc_middle"), 0]
    delay = PadeDelay("d", model.instruments.electronics.actuator_delays_s["shaker"], model.electronics.pade_order)
    got = got / frequency_response(delay.lti(), frequencies_hz)[:, 0, 0]
    return float(np.max(np.abs(got - expected)) / np.max(np.abs(expected)))


def fmu_error(model, fmu: Path, *, start: dict[str, float], steps: int = 2000) -> float:
    """Largest difference between the FMU (through fmpy, ``start`` parameters set) and the exact ZOH of the
    model's state space, as a fraction of each output's range, for a step on the shaker."""
    import fmpy
    import scipy.linalg

    t = np.arange(steps + 1) * STEP_S
    u = (t >= 10 * STEP_S).astype(float)[None, :]
    a, b, c, d = (np.asarray(getattr(model.system, m)) for m in "ABCD")
    n = a.shape[0]
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n], aug[:n, n:] = a, b
    e = scipy.linalg.expm(aug * STEP_S)
    x, ref = np.zeros(n), [np.zeros(c.shape[0])]
    for k in range(steps):  # the output after a step reads the input held over it
        x = e[:n, :n] @ x + e[:n, n:] @ u[:, k]
        ref.append(c @ x + d @ u[:, k])
    ref = np.array(ref).T
    signals = np.zeros(t.size, dtype=[("time", float), ("shaker", float)])
    signals["time"], signals["shaker"] = t, u[0]
    outs = list(model.system.output_labels)
    run = fmpy.simulate_fmu(str(fmu), input=signals, output=outs, step_size=STEP_S, output_interval=STEP_S,
                            stop_time=t[-1], start_values=start)
    y = np.stack([run[o] for o in outs])[:, :t.size]
    span = np.ptp(ref, axis=1, keepdims=True)
    return float(np.max(np.abs(y - ref[:, :y.shape[1]]) / span))


def main(out: Path) -> dict:
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.modal_source import modal_structure
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.viewer import animate_modes, write_animation_html

    out.mkdir(parents=True, exist_ok=True)
    structure = modal_structure(STRUCTURE)
    print(f"NASTRAN's modes of {structure.source.name}:")
    for f, label in zip(structure.frequencies_hz, structure.labels):
        print(f"  {f:12.4f} Hz  {label}")
    model = volts_model(structure)
    print(f"volts-volts model: {model.system.nstates} states, inputs {', '.join(model.system.input_labels)}, "
          f"outputs {', '.join(model.system.output_labels)}")
    f = np.geomspace(2000.0, 20000.0, 200)
    summary = {"frequencies_hz": [float(x) for x in structure.frequencies_hz],
               "superposition_error": superposition_error(model, structure, f)}
    print(f"  its FRF against the modal superposition of NASTRAN's eigenvectors: {summary['superposition_error']:.1e} "
          "of the peak")
    fmu = export_fmu(model, out_dir=out, name="plate_modes_native")
    print(f"wrote {fmu}")
    summary["fmu_error"] = fmu_error(model, fmu, start={})
    scaled = volts_model(structure, parameters=ParameterSet({"frequency_scale:mode 7": 1.05}))
    summary["fmu_error_scaled"] = fmu_error(scaled, fmu, start={"frequency_scale_mode_7": 1.05})
    print(f"  FMU against the exact ZOH of the state space: {summary['fmu_error']:.1e} of the range; with "
          f"frequency_scale_mode_7 = 1.05 set in the FMU: {summary['fmu_error_scaled']:.1e}")
    animation = animate_modes(structure, [label for f, label in zip(structure.frequencies_hz, structure.labels)
                                          if abs(f) > 1.0])
    page = out / "plate_modes.html"
    write_animation_html(animation, page, title="plate_py: NASTRAN's flexible modes")
    summary["edges"] = len(animation.scene.segments)
    print(f"wrote {page} ({summary['edges']} shell edges)")
    return summary


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "nastran_plate"))
