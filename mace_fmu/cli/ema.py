"""``mace-fmu ema``: modes identified from measured FRF files (LSCF and LSFD, a stabilisation diagram, modes.toml)."""

from __future__ import annotations

import argparse

from mace_fmu.cli.common import positive_hz, progress
from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError


def _even_order(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 4 or value > 400 or value % 2:
        raise argparse.ArgumentTypeError(f"expected an even model order from 4 to 400, got {text!r}")
    return value


def _frequencies(text: str) -> list[float]:
    try:
        values = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        values = []
    if not values or not all(v > 0 for v in values):
        raise argparse.ArgumentTypeError(f"expected frequencies [Hz] > 0 separated by commas, got {text!r}")
    return values


def structure_instruments(path: str | None):
    """(sensors, actuators) of a structure file by name -> their DOFs; ({}, {}) without one."""
    if path is None:
        return {}, {}
    from mace_fmu.iomodel.instruments import load_instruments

    instruments = load_instruments(path)
    return ({s.name: s.dofs for s in instruments.sensors if s.dofs},
            {a.name: a.dofs for a in instruments.actuators if a.dofs})


def cmd_ema(args: argparse.Namespace) -> int:
    from mace_fmu.updating.files import read_channel_map, read_frequency_response
    from mace_fmu.updating.modal.dofs import driving_points, dofs_of_name
    from mace_fmu.updating.modal.figures import plot_stabilisation
    from mace_fmu.updating.modal.identify import identify_modes
    from mace_fmu.updating.modal.modes_file import MeasuredDof, write_modes_file
    from mace_fmu.util.atomic import output_folder

    channel_map = read_channel_map(args.map) if args.map else None
    frfs = [read_frequency_response(path, channel_map=channel_map) for path in args.files]
    if args.band_hz is not None and not args.band_hz[0] < args.band_hz[1]:
        raise MaceError(f"--band-hz {args.band_hz[0]:g} {args.band_hz[1]:g}: expected LOW < HIGH [Hz]")
    sensors, actuators = structure_instruments(args.structure_file)
    outputs = frfs[0].outputs
    inputs = [name for frd in frfs for name in frd.inputs]
    driving = driving_points(inputs, outputs, actuators=actuators, sensors=sensors)
    progress(f"identifying modes in {len(frfs)} file(s): {len(outputs)} output(s), {len(inputs)} input(s)"
             + (f", driving points {', '.join(f'{o}/{i}' for i, o in driving.items())}" if driving else ""))
    found = identify_modes(frfs, band_hz=tuple(args.band_hz) if args.band_hz else None, max_order=args.order,
                           frf_form=args.frf_form, driving_points=driving, near_hz=args.near_hz)
    dofs = [MeasuredDof(n, found.units.get(n, ""), tuple(sensors.get(n) or dofs_of_name(n) or ())) for n in outputs]
    out = output_folder(args.out)
    paths = [write_modes_file(found, out / "modes.toml", dofs=dofs),
             plot_stabilisation(found, out / "stabilisation.png")]
    lo, hi = found.band_hz
    print(f"{len(found.modes)} mode(s) in {lo:g}-{hi:g} Hz ({found.frf_form}; {found.method})")
    width = max(12, *(len(n) for n in outputs))
    print(f"{'mode':>4} {'f [Hz]':>10} {'zeta [%]':>9} {'order':>5} {'MPC':>6}  real-normalised shape "
          f"({', '.join(outputs)})")
    for k, m in enumerate(found.modes, start=1):
        shape = ", ".join(f"{v:+.3f}" for v in m.shape_real)
        print(f"{k:>4} {m.frequency_hz:>10.4f} {100 * m.damping:>9.3f} {m.order:>5} {m.mpc:>6.3f}  {shape}")
    scaled = [m.shape_mass_normalised for m in found.modes if m.shape_mass_normalised is not None]
    if scaled:
        print(f"mass-normalised shapes [1/sqrt(kg)] (driving points {', '.join(found.driving_points.values())}):")
        for k, m in enumerate(found.modes, start=1):
            if m.shape_mass_normalised is not None:
                print(f"{k:>4} " + ", ".join(f"{n:>{width}s} {v:+.4f}" for n, v in zip(outputs, m.shape_mass_normalised)))
    print(f"fit error ||H - H_modal|| / ||H|| over the band: {100 * found.fit_error:.2f} %")
    for note in found.notes:
        progress(note)
    for path in paths:
        print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("ema", help="modes from measured FRF files (experimental modal analysis): poles, damping "
                       "ratios and shapes at the measured DOFs, a stabilisation diagram, modes.toml",
                       description="Identify modes from FRF files (UFF 58, CSV of complex values; one file per "
                                   "driving point, the same outputs in each): poles by the least-squares complex "
                                   "frequency method (sdypy-EMA's LSCF) over model orders 2 to --order, the modes "
                                   "that stay stable over a third of the orders, refined by nonlinear least squares; "
                                   "shapes by LSFD residues, mass-normalised where an input's DOF is also measured. "
                                   "Writes modes.toml (for mace-fmu correlate and update modal) and "
                                   "stabilisation.png.")
    p.add_argument("files", nargs="+", metavar="FRF_FILE", help="measured frequency responses (.uff, .unv, .csv)")
    p.add_argument("--band-hz", type=positive_hz, nargs=2, metavar=("LOW", "HIGH"),
                   help="the band fitted [Hz] (default: every line above 0 Hz)")
    p.add_argument("--order", type=_even_order, default=40, metavar="MAX",
                   help="highest model order of the stabilisation diagram (even; default 40)")
    p.add_argument("--frf-form", choices=["accelerance", "mobility", "receptance"], default=None,
                   help="what the FRFs are (default: from their units: m/s^2, m/s or m per N)")
    p.add_argument("--near-hz", type=_frequencies, default=None, metavar="F[,F...]",
                   help="take the stable poles nearest these frequencies [Hz] instead of every stable mode")
    p.add_argument("--structure", metavar="FILE", default=None, dest="structure_file",
                   help="structure file whose sensors and actuators the FRFs' signals are: it places the measured "
                        "DOFs on the model (written into modes.toml) and finds the driving points (an actuator and "
                        "a sensor on the same DOFs)")
    p.add_argument("--map", metavar="CSV", help="channel map: the files' channel names to signals")
    output_option(p, "-o", "--out", kind="folder", default=".", metavar="DIR",
                  help="folder for modes.toml and stabilisation.png (default: the current folder)")
    p.set_defaults(func=cmd_ema)

