"""Your own structure, from its NASTRAN deck and a structure file to modes, volts-volts models and FMUs.
=====================================================================================================

    python examples/own_structure/own_structure.py [OUT_DIR]

The structure is a small spacecraft the project wrote for this example (``spacecraft.bdf``): a
rigid bus with a reaction wheel and a rate gyro, a 2 m aluminium boom on a gimbal hinge, a tip
instrument with its own gyro. On the ground it sits on a test stand under gravity (the 1-g
configuration, the deck's subcase 1); in orbit the stand is gone (0-g: ``spacecraft.toml`` lists
the stand as the suspension). ``spacecraft.toml`` also declares the actuators (wheel and gimbal
torques) and sensors (two gyros, the gimbal encoder) with their gains; it has no filters, delays
or local loops, and gives every flexible mode 0.5 % damping.

Steps: the modes of both configurations, labelled by their motion; the 0-g volts-volts model; its
native FMUs (FMI 2.0 and 3.0 co-simulation), checked against the exact zero-order hold of the
model's own state space; an animation of the 0-g modes (standalone HTML). The same from the
command line::

    mace-fmu modes 0g --deck spacecraft.bdf --structure spacecraft.toml
    mace-fmu export 0g --deck spacecraft.bdf --structure spacecraft.toml -o fmus   # fmus/spacecraft_0g_native.fmu
    mace-fmu view modes 0g --deck spacecraft.bdf --structure spacecraft.toml --html modes.html

What the updating engine and ``predict-0g`` need from this structure: its modal test's FRFs
give its modes (``ema``), and ``update modal`` with this deck and structure file updates its moduli, springs
and masses against them (``update mace`` is the same route on MACE's deck with Table 4.7's data);
``predict-0g`` takes this structure with its own 1-g measurement model (``--measured FILE``);
``mace-fmu update fmu spacecraft_0g_native.fmu --data ...`` updates this structure's FMU from its own test data.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

# the folder of this script (sphinx-gallery runs it there, without __file__, when the site is built)
HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
DECK, STRUCTURE = HERE / "spacecraft.bdf", HERE / "spacecraft.toml"


def exact_zoh_error(model, fmu: Path, *, seconds: float = 2.0, step_s: float = 2e-3) -> float:
    """Largest difference between the FMU (through fmpy) and the exact ZOH of the model's state space,
    as a fraction of each output's range, for random steps on every input."""
    import control as ct
    import fmpy

    t = np.arange(int(round(seconds / step_s)) + 1) * step_s
    rng = np.random.default_rng(1)
    names = list(model.system.input_labels)
    u = np.repeat(rng.standard_normal((len(names), t.size // 50 + 1)), 50, axis=1)[:, :t.size]
    ref = ct.forced_response(ct.sample_system(model.system, step_s, "zoh"), T=t, U=u).outputs
    signals = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in names])
    signals["time"] = t
    for k, n in enumerate(names):
        signals[n] = u[k]
    outs = list(model.system.output_labels)
    run = fmpy.simulate_fmu(str(fmu), input=signals, output=outs, step_size=step_s, output_interval=step_s,
                            stop_time=t[-1])
    y = np.stack([run[o] for o in outs])[:, :t.size]
    span = np.ptp(ref, axis=1, keepdims=True)
    return float(np.max(np.abs(y - ref[:, :y.shape[1]]) / span))


def main(out: Path) -> dict:
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.export import export_fmu
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.viewer import animate_modes, write_animation_html

    out.mkdir(parents=True, exist_ok=True)
    deck = read_deck(DECK)
    summary: dict = {}
    for kind in ("1g", "0g"):
        result = compute_modes(deck, configuration=kind, structure_file=STRUCTURE)
        print(f"{kind} modes ({'on the test stand, gravity preload' if kind == '1g' else 'in orbit, free'}):")
        for f, label in zip(result.frequencies_hz, result.labels):
            print(f"  {f:9.3f} Hz  {label}")
        summary[f"modes_{kind}"] = [(float(f), label) for f, label in zip(result.frequencies_hz,
                                                                         result.labels)]
        if kind == "0g":
            animation = animate_modes(result, list(range(7, len(result.modes) + 1)))
            page = out / "spacecraft_0g_modes.html"
            write_animation_html(animation, page, title="spacecraft in orbit: flexible modes")
            print(f"wrote {page}")
    model = volts_model(compute_modes(deck, configuration="0g", structure_file=STRUCTURE))
    print(f"0g volts-volts model: {model.system.nstates} states, inputs {', '.join(model.system.input_labels)}, "
          f"outputs {', '.join(model.system.output_labels)}")
    summary["zoh_error"] = {}
    for version in (2, 3):
        fmu = export_fmu(model, out_dir=out, name=f"spacecraft_0g_native{'_fmi3' if version == 3 else ''}",
                                fmi_version=version)
        print(f"wrote {fmu}")
        error = exact_zoh_error(model, fmu)
        summary["zoh_error"][version] = error
        print(f"  FMI {version}.0 FMU against the exact ZOH of the state space: largest difference {error:.1e} of the "
              "range")
    return summary


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "own_structure"))
