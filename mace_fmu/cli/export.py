"""``mace-fmu export``: the FMU of the 1-g or 0-g volts-volts model, native (C runtime) or pythonfmu."""

from __future__ import annotations

import argparse

from mace_fmu.cli.common import deck_option, model_options, progress, volts
from mace_fmu.errors import MaceError
from mace_fmu.fmu.naming import fmu_name


def cmd_export(args: argparse.Namespace) -> int:
    if args.kind == "pythonfmu" and args.fmi_version != 2:
        raise MaceError("--fmi-version 3 needs --kind native (pythonfmu FMUs are FMI 2.0)")
    progress(f"{args.structure} volts-volts model")
    model = volts(args)
    name = fmu_name(args.structure, kind=args.kind, fmi_version=args.fmi_version,
                    motion_grids=model.plant.motion_grids, all_grids=model.structure_modes.modes.dofs.grid_ids)
    progress(f"{args.kind} FMU {name}.fmu")
    if args.kind == "native":
        from mace_fmu.fmu.native.export import export_native_fmu

        path = export_native_fmu(model, out_dir=args.out, name=name, fmi_version=args.fmi_version)
    else:
        from mace_fmu.fmu.export import export_fmu

        path = export_fmu(model, out_dir=args.out, name=name)
    print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="FMU of the 1-g or 0-g volts-volts model (native C runtime or pythonfmu)")
    p.add_argument("structure", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("-o", "--out", default=".", help="output directory (writes e.g. MACE_1g_native.fmu; with "
                   "--motion-grids MACE_1g_native_motion.fmu, ...)")
    p.add_argument("--kind", choices=["native", "pythonfmu"], default="native",
                   help="native: C runtime, no Python needed in the host, FMI 2.0 co-simulation and model exchange "
                        "(default); pythonfmu: FMI 2.0 co-simulation through Python")
    p.add_argument("--fmi-version", type=int, choices=[2, 3], default=2,
                   help="FMI version of a native FMU: 2 (co-simulation and model exchange) or 3 (co-simulation)")
    model_options(p)
    p.set_defaults(func=cmd_export)
