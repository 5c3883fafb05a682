"""``mace-fmu params``: parameter sets between TOML and SSP 1.0 parameter value files (SSV)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError


def _read_bounds_table(path: str):
    """The (mode, mode label, relative bound) rows of a table_5_3.toml of ``mace-fmu predict-0g``."""
    from mace_fmu.ssp import FrequencyBound
    from mace_fmu.util.textfile import read_toml

    rows = read_toml(path, what="frequency-bounds").get("mode")
    if not isinstance(rows, list) or not rows:
        raise MaceError(f"{path}: no [[mode]] rows (expected the table_5_3.toml of mace-fmu predict-0g)")
    out = []
    for k, row in enumerate(rows, start=1):
        if "mode" not in row:
            continue  # a servo mechanism: no FMU mode, no bound to carry
        mode, label, percent = row.get("mode"), row.get("mode_label"), row.get("bound_percent")
        if isinstance(mode, bool) or not isinstance(mode, int) or mode < 1 or not isinstance(label, str) \
                or isinstance(percent, bool) or not isinstance(percent, (int, float)) or not 0.0 <= percent < 100.0:
            raise MaceError(f"{path}: [[mode]] {k}: expected mode >= 1, mode_label and bound_percent in [0, 100), "
                            f"got mode = {mode!r}, mode_label = {label!r}, bound_percent = {percent!r}")
        out.append(FrequencyBound(mode=mode, mode_label=label, bound_percent=float(percent)))
    return tuple(out)


def _bounds_toml(bounds) -> str:
    """The bounds as [[mode]] rows that ``--frequency-bounds`` of export and to-ssv read back."""
    from mace_fmu.parameters.sets import toml_value

    lines = ["# frequency bounds of the open-loop modes (from an SSV file; mace-fmu params from-ssv)", ""]
    for b in bounds:
        lines += ["[[mode]]", f"mode = {b.mode}", f"mode_label = {toml_value(b.mode_label)}",
                  f"bound_percent = {toml_value(b.bound_percent)}", ""]
    return "\n".join(lines)


def cmd_to_ssv(args: argparse.Namespace) -> int:
    from mace_fmu.parameters.sets import ParameterSet
    from mace_fmu.ssp import SsvContent, write_parameter_ssv

    parameters = ParameterSet.read(args.parameters)
    bounds = _read_bounds_table(args.frequency_bounds) if args.frequency_bounds else ()
    out = Path(args.out) if args.out else Path(args.parameters).with_suffix(".ssv")
    path = write_parameter_ssv(SsvContent(parameters=parameters, frequency_bounds=bounds), out)
    print(f"wrote {path} ({len(parameters)} parameters{f', {len(bounds)} frequency bounds' if bounds else ''})")
    return 0


def cmd_from_ssv(args: argparse.Namespace) -> int:
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
        print(f"wrote {write_text_atomic(args.frequency_bounds_out, _bounds_toml(content.frequency_bounds))} "
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
