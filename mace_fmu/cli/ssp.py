"""``mace-fmu export --ssp``: the plant FMU and its parameter set as one SSP 1.0 package."""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from mace_fmu.cli.common import parameters, progress, step_lines, volts
from mace_fmu.errors import MaceError


def export_ssp(args: argparse.Namespace) -> int:
    """Build the plant FMU (FE part of --parameters built in) and write it with the rest of the set as an SSV."""
    from mace_fmu.fmu.naming import model_fmu_name
    from mace_fmu.ssp import SspComponent, write_ssp
    from mace_fmu.ssp.binding import fmu_start_values, split_parameters
    from mace_fmu.ssp.package import wiring_by_name

    if args.fmi_version != 2:
        raise MaceError("--ssp: SSP 1.0 importers (fmpy, ecos) take FMI 2.0 FMUs: leave out --fmi-version 3")
    if not str(args.ssp).endswith(".ssp"):
        raise MaceError(f"--ssp {args.ssp}: the package's name must end in .ssp")
    if args.controller and not Path(args.controller).is_file():
        raise MaceError(f"--controller {args.controller}: no such file")
    split = split_parameters(parameters(args))
    progress(f"{args.configuration} volts-volts model")
    model = volts(args, parameter_set=split.built_in)
    bounds = None
    if args.frequency_bounds:
        from mace_fmu.zero_g.table import read_frequency_bounds

        bounds = read_frequency_bounds(args.frequency_bounds, mode_labels=model.plant.labels)
    from mace_fmu.cli.export import model_variant

    name = model_fmu_name(model, runtime=args.runtime, variant=model_variant(args))
    with tempfile.TemporaryDirectory(prefix="mace_ssp_") as tmp:
        progress(f"{args.runtime} FMU {name}.fmu")
        from mace_fmu.fmu.export import export_fmu
        from mace_fmu.fmu.parametric import parametric_model

        parametric = parametric_model(model, frequency_bounds=bounds)
        fmu = export_fmu(model, runtime=args.runtime, fmi_version=2, out_dir=tmp, name=name, parametric=parametric,
                         platforms=args.platforms, progress=step_lines)
        tunable = [p.name for p in parametric.parameters]
        start = fmu_start_values(split.start_values, mode_labels=model.plant.labels, fmu_parameters=tunable)
        plant = SspComponent(name="plant", fmu=Path(fmu), start_values=start)
        components, wires = [plant], []
        if args.controller:
            controller = SspComponent(name="controller", fmu=Path(args.controller))
            wires = wiring_by_name(plant=plant, controller=controller)
            components.append(controller)
        path = write_ssp(args.ssp, components=components, connections=wires,
                         system_name=model_fmu_name(model, variant=model_variant(args)))
    loop = f", closed by {Path(args.controller).name} through {len(wires)} connections" if args.controller else ""
    print(f"wrote {path} (plant {name}.fmu, {len(start)} start values bound{loop})")
    return 0
