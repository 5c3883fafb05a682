"""``mace-fmu params``: parameter sets between TOML and SSP 1.0 parameter value files (SSV)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError

#: the first line of the bounds ``params from-ssv`` writes
FROM_SSV = "frequency bounds of the open-loop modes (from an SSV file; mace-fmu params from-ssv)"


def cmd_to_ssv(args: argparse.Namespace) -> int:
    from mace_fmu.parameters.frequency_bounds import read_bounds
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.ssp import SsvContent, write_parameter_ssv

    parameters = ParameterSet.read(args.parameters)
    bounds = read_bounds(args.frequency_bounds) if args.frequency_bounds else ()
    out = Path(args.out) if args.out else Path(args.parameters).with_suffix(".ssv")
    path = write_parameter_ssv(SsvContent(parameters=parameters, frequency_bounds=bounds), out)
    print(f"wrote {path} ({len(parameters)} parameters{f', {len(bounds)} frequency bounds' if bounds else ''})")
    return 0


def cmd_from_ssv(args: argparse.Namespace) -> int:
    from mace_fmu.parameters.frequency_bounds import bounds_toml
    from mace_fmu.ssp import read_parameter_ssv
    from mace_fmu.util.atomic import write_text_atomic

    content = read_parameter_ssv(args.ssv)
    out = Path(args.out) if args.out else Path(args.ssv).with_suffix(".toml")
    if content.frequency_bounds and not args.frequency_bounds_out:
        raise MaceError(f"{args.ssv} holds {len(content.frequency_bounds)} frequency bounds: give "
                        "--frequency-bounds-out FILE.toml to keep them (nothing written)")
    path = content.parameters.write(out)
    print(f"wrote {path} ({len(content.parameters)} parameters)")
    if content.frequency_bounds:
        text = bounds_toml(content.frequency_bounds, comment=FROM_SSV)
        print(f"wrote {write_text_atomic(args.frequency_bounds_out, text)} "
              f"({len(content.frequency_bounds)} frequency bounds)")
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    """Every Real parameter of an FMU: name, start value, declared range, unit and description."""
    from mace_fmu.updating.fmu.model import read_fmu_interface

    interface = read_fmu_interface(args.fmu)
    names = sorted(interface.parameters) if args.sort else list(interface.parameters)
    width = max([9, *(len(n) for n in names)])
    print(f"{len(names)} parameters of {args.fmu} (set through FMI before initialisation; a parameter set names "
          "per-mode ones as here or by label: damping:<label>)")
    print(f"{'parameter':<{width}} {'start':>14} {'min':>12} {'max':>12}  unit  description")
    for n in names:
        low, high = interface.ranges.get(n, (float("-inf"), float("inf")))
        print(f"{n:<{width}} {interface.parameters[n]:>14.7g} {low:>12.5g} {high:>12.5g}  "
              f"{interface.units.get(n, '') or '-':<4}  {interface.descriptions.get(n, '')}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("params", help="an FMU's parameters; parameter sets as SSP 1.0 parameter value files (SSV) "
                       "and back")
    psub = p.add_subparsers(dest="params_command", required=True)
    ls = psub.add_parser("list", help="every parameter of an FMU: start value, declared range, unit, description")
    ls.add_argument("fmu", metavar="FILE", help="an FMI 2.0 co-simulation FMU")
    ls.add_argument("--sort", action="store_true", help="by name (default: the FMU's order)")
    ls.set_defaults(func=cmd_list)
    to = psub.add_parser("to-ssv", help="a parameter set (TOML) as an SSV file, losslessly")
    to.add_argument("parameters", help="parameter set TOML (mace-fmu update mace, update fmu or predict-0g)")
    to.add_argument("--frequency-bounds", metavar="FILE",
                    help="table_5_3.toml of mace-fmu predict-0g: its bounds travel in the SSV too")
    output_option(to, "-o", "--out", kind="file", derived=lambda args: Path(args.parameters).with_suffix(".ssv"),
                  help="SSV file to write (default: the TOML's name with .ssv)")
    to.set_defaults(func=cmd_to_ssv)
    back = psub.add_parser("from-ssv", help="an SSV file of to-ssv (or with our parameter names) as a TOML set")
    back.add_argument("ssv", help="SSV file")
    output_option(back, "-o", "--out", kind="file", derived=lambda args: Path(args.ssv).with_suffix(".toml"),
                  help="TOML parameter set to write (default: the SSV's name with .toml)")
    output_option(back, "--frequency-bounds-out", kind="file", metavar="FILE",
                  help="where to write the SSV's frequency bounds ([[mode]] rows that export "
                       "--frequency-bounds reads)")
    back.set_defaults(func=cmd_from_ssv)
