"""From the updated model to an SSP package a colleague opens in another tool, and the proof it runs there.
========================================================================================================

    python examples/closed_loop_ssp.py [OUT_DIR] [--quick]

1. The updated nominal 0-g model (``mace-fmu predict-0g``: Table 5.3's frequencies, damping ratios and
   bounds, about a minute; ``--quick`` takes the unaltered 0-g model instead).
2. The Appendix A LQG compensator of the 0-g loop (payload gyro Z -> primary gimbal Z), sampled at
   2 ms, as a controller FMU (``mace-fmu export-controller --lqg``).
3. One SSP 1.0 package: the plant FMU with the set's moduli built in, its damping ratios and frequency
   scales bound as an SSV file (with Table 5.3's bounds as the parameters' min/max), and the
   controller wired to it by signal names (``mace-fmu export 0g --ssp ... --controller ...``).
4. The package run in ecos (ecospy) and in fmpy's SSP simulator with a 0.5 V step on the secondary
   gimbal's servo command, against the same loop computed from the state-space models.

Open ``OUT_DIR/closed_loop.ssp`` in any SSP 1.0 tool (ecos, OMSimulator, fmpy); in ecos name the
parameter set "plant parameters" at initialisation, in fmpy pass it as ``parameter_set=``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import control as ct
import numpy as np

from mace_fmu.cli import main as mace_fmu


def state_space_loop(*, parameters: Path | None, steps: int, step_s: float, disturbance_v: float,
                     closed: bool = True) -> np.ndarray:
    """gyro_payload_z [V] at t_0..t_steps of the sampled loop (``closed=False``: the controller's output
    left out), from the state-space models alone."""
    from mace_fmu.cli.controller import lqg_controller
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.parameters.sets import ParameterSet

    plant = volts_model(compute_modes(configuration="0g",
                                      parameters=ParameterSet.read(parameters) if parameters else None)).system
    sampled = ct.sample_system(plant, step_s, "zoh")
    k = lqg_controller(step_s=step_s)
    ins, outs = list(plant.input_labels), list(plant.output_labels)
    iu, iw, iy = ins.index("gimbal_primary_z"), ins.index("gimbal_secondary_z"), outs.index("gyro_payload_z")
    xp, xc, out = np.zeros(plant.nstates), np.zeros(k.a.shape[0]), []
    for _ in range(steps + 1):
        y = sampled.C[iy] @ xp
        out.append(y)
        u = np.zeros(len(ins))
        u[iu], u[iw] = (k.c[0] @ xc + k.d[0, 0] * y) if closed else 0.0, disturbance_v
        xp = sampled.A @ xp + sampled.B @ u
        xc = k.a @ xc + k.b[:, 0] * y
    return np.array(out)


def run_in_ecos(ssp: Path, *, steps: int, step_s: float, disturbance_v: float, parameter_set: str | None) -> np.ndarray:
    """gyro_payload_z [V] at t_0..t_steps of the package run by ecos."""
    import ecospy

    y = []
    with ecospy.EcosSimulation(ssp_path=str(ssp), step_size=step_s) as sim:
        sim.init(parameter_set=parameter_set)
        sim.set_real("plant::gimbal_secondary_z", disturbance_v)
        for k in range(steps + 1):
            if k:
                sim.step()
            y.append(sim.get_real("plant::gyro_payload_z"))
    return np.array(y)


def run_in_fmpy(ssp: Path, *, steps: int, step_s: float, disturbance_v: float) -> np.ndarray:
    """gyro_payload_z [V] at t_1..t_steps of the package run by fmpy (its rows are recorded after each step).

    fmpy ignores an SSP's parameter bindings: the bound SSV's values are passed as its parameter set.
    """
    import zipfile

    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import Parameter, ParameterSet

    from mace_fmu.ssp.ssv import read_ssv_values

    with zipfile.ZipFile(ssp) as z:
        bound = (read_ssv_values(z.read("resources/plant.ssv").decode(), source=f"{ssp}:resources/plant.ssv")[0]
                 if "resources/plant.ssv" in z.namelist() else {})
    values = [Parameter(name=f"plant.{k}", value=v) for k, v in bound.items()]
    values.append(Parameter(name="plant.gimbal_secondary_z", value=disturbance_v))
    rows = simulate_ssp(str(ssp), stop_time=steps * step_s, step_size=step_s, parameter_set=ParameterSet(parameters=values))
    return np.asarray(rows["plant.gyro_payload_z"])[:steps]  # its clock adds steps: one row too many at times


def ecos_available() -> str:
    """"" when ecospy loads, else one line saying what to install (checked before any work: its library
    links against Intel TBB, a system package, and failed after 27 s of building without it)."""
    try:
        import ecospy  # noqa: F401
    except (ImportError, OSError) as exc:
        return (f"ecospy cannot load ({exc}): install the libtbb12 system library (Debian/Ubuntu: sudo apt-get "
                "install libtbb12) and pip install ecospy")
    return ""


def main(out: Path, *, quick: bool) -> dict[str, float]:
    """Build the package in ``out`` and return the largest differences [fraction of the response's range]."""
    missing = ecos_available()
    if missing:
        raise SystemExit(f"closed_loop_ssp.py: {missing}")
    out.mkdir(parents=True, exist_ok=True)
    step_s, steps, w = 0.002, 1500, 0.5
    parameters, export_options = None, []
    if not quick:
        assert mace_fmu(["predict-0g", "-o", str(out)]) == 0
        parameters = out / "zero_g_nominal.toml"
        export_options = ["--parameters", str(parameters), "--frequency-bounds", str(out / "table_5_3.toml")]
    assert mace_fmu(["export-controller", "--lqg", "--step", repr(step_s), "-o", str(out)]) == 0
    ssp = out / "closed_loop.ssp"
    assert mace_fmu(["export", "0g", *export_options, "--ssp", str(ssp), "--controller",
                     str(out / "controller.fmu")]) == 0
    ref = state_space_loop(parameters=parameters, steps=steps, step_s=step_s, disturbance_v=w)
    span = float(np.ptp(ref))
    ecos = run_in_ecos(ssp, steps=steps, step_s=step_s, disturbance_v=w,
                       parameter_set="plant parameters" if parameters else None)
    fmpy_y = run_in_fmpy(ssp, steps=steps, step_s=step_s, disturbance_v=w)
    errors = {"ecos": float(np.max(np.abs(ecos - ref))) / span,
              "fmpy": float(np.max(np.abs(fmpy_y - ref[1:len(fmpy_y) + 1]))) / span}
    print(f"payload gyro Z over {steps * step_s:g} s: range {span:.4f} V")
    for host, err in errors.items():
        print(f"  {host:5s} against the state-space loop: largest difference {err:.1e} of the range")
    return errors


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(Path(args[0] if args else "closed_loop_ssp"), quick="--quick" in sys.argv)
