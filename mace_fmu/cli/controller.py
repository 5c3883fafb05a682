"""``mace-fmu export-controller``: a sampled-data controller as a native FMU (FMI 2.0 or 3.0 co-simulation)."""

from __future__ import annotations

import argparse

from mace_fmu.cli.common import positive_number, progress, step_lines
from mace_fmu.cli.export import platforms_option, toolchain_warnings_as_lines
from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError


def lqg_controller(*, step_s: float):
    """The Appendix A LQG compensator of the 0-g loop (robust.design), sampled by zero-order hold at ``step_s``.

    The zero-order hold keeps the continuous compensator's lack of feedthrough (D = 0), so hosts
    that exchange values once per step (fmpy's and ecos's SSP loops) close the same discrete loop
    as the state-space model, whatever order they step the FMUs in.
    """
    import control as ct

    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.fmu.controller import DiscreteController
    from mace_fmu.iomodel.volts import volts_model
    from mace_fmu.zero_g.robust.design import design_compensator
    from mace_fmu.zero_g.robust.loop import LoopSpec

    loop = LoopSpec(step_s=step_s)
    design = design_compensator(volts_model(compute_modes(configuration="0g")).system, loop=loop)
    sampled = ct.sample_system(design.lqg.compensator, step_s, method="zoh")
    return DiscreteController(a=sampled.A, b=sampled.B, c=sampled.C, d=sampled.D, sample_time_s=step_s,
                              inputs=(loop.measurement,), outputs=(loop.control_input,))


def cmd_export_controller(args: argparse.Namespace) -> int:
    from mace_fmu.fmu.controller import DiscreteController, export_controller_fmu

    if (args.npz is None) == (not args.lqg):
        raise MaceError("give the controller: --npz FILE (A, B, C, D, sample_time_s, inputs, outputs) or --lqg")
    if args.npz:
        controller = DiscreteController.read_npz(args.npz)
    else:
        if not (args.step > 0):
            raise MaceError(f"--step must be a positive number of seconds, got {args.step}")
        progress("Appendix A LQG compensator of the 0-g loop")
        controller = lqg_controller(step_s=args.step)
    with toolchain_warnings_as_lines():
        path = export_controller_fmu(controller, out_dir=args.out, name=args.name, fmi_version=args.fmi_version,
                                     platforms=args.platforms, progress=step_lines)
    print(f"wrote {path} ({controller.a.shape[0]} states, sample time {controller.sample_time_s} s, inputs "
          f"{', '.join(controller.inputs)}, outputs {', '.join(controller.outputs)})")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export-controller", help="a discrete state-space controller as a native FMU (co-simulation)")
    p.add_argument("--npz", metavar="FILE", help="controller arrays: A, B, C, D, sample_time_s, inputs, outputs")
    p.add_argument("--lqg", action="store_true",
                   help="the Appendix A LQG compensator of the 0-g loop (payload gyro Z -> primary gimbal Z)")
    p.add_argument("--step", type=positive_number, default=0.002, help="sample time of --lqg [s] (default 0.002)")
    p.add_argument("--name", default=None, help="model identifier and file name (default: controller; with "
                   "--fmi-version 3 controller_fmi3, so that it never replaces the FMI 2 export)")
    p.add_argument("--fmi-version", type=int, choices=[2, 3], default=2, help="FMI version (default 2)")
    output_option(p, "-o", "--out", kind="folder", default=".", help="output directory")
    platforms_option(p)
    p.set_defaults(func=cmd_export_controller)
