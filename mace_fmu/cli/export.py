"""``mace-fmu export``: the FMU of the 1-g or 0-g volts-volts model, native (C runtime) or pythonfmu."""

from __future__ import annotations

import argparse
import contextlib
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

from mace_fmu.cli.common import (CONFIGURATIONS, deck_option, model_options, model_variant, progress, step_lines,
                                 volts)
from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError


def platforms_argument(text: str) -> list[str]:
    """argparse ``type`` of ``--platforms``: comma-separated FMI 3 platform tuples, or ``all``; an unknown name is
    refused at once (one line, exit 2) with the known ones."""
    from mace_fmu.fmu.native.platforms import BY_NAME, select_platforms

    if text.strip() == "all":
        return list(BY_NAME)
    try:
        return [p.name for p in select_platforms(text)]
    except MaceError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("platforms: ")) from None


def platforms_option(p: argparse.ArgumentParser) -> None:
    """``--platforms``: which binaries a native FMU carries (shared by export and export-controller)."""
    from mace_fmu.fmu.native.platforms import BY_NAME

    p.add_argument("--platforms", type=platforms_argument, default=None, metavar="LIST",
                   help=f"native FMU: the platforms to carry binaries for, comma-separated, from {', '.join(BY_NAME)} "
                        "(default: all; every FMU also carries sources/); a named platform that cannot be built is "
                        "an error")


@contextlib.contextmanager
def toolchain_warnings_as_lines() -> Iterator[None]:
    """Print a platform left out for want of a toolchain as one line on stderr; other warnings pass as Python
    shows them."""
    from mace_fmu.fmu.native.compile import MissingToolchainWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", MissingToolchainWarning)
        try:
            yield
        finally:
            for warning in caught:
                if issubclass(warning.category, MissingToolchainWarning):
                    print(f"mace-fmu: warning: {warning.message}", file=sys.stderr)
                else:
                    warnings.showwarning(warning.message, warning.category, warning.filename, warning.lineno)


def cmd_export(args: argparse.Namespace) -> int:
    from mace_fmu.fmu.naming import model_fmu_name
    if args.runtime == "pythonfmu" and args.fmi_version != 2:
        raise MaceError("--fmi-version 3 needs --runtime native (pythonfmu FMUs are FMI 2.0)")
    if args.frequency_bounds and not Path(args.frequency_bounds).is_file():
        raise MaceError(f"--frequency-bounds {args.frequency_bounds}: no such file")
    if args.platforms is not None and args.runtime != "native":
        raise MaceError("--platforms needs --runtime native (a pythonfmu FMU has no binaries of its own)")
    if args.controller and not args.ssp:
        raise MaceError("--controller needs --ssp FILE.ssp (the controller is wired to the plant inside a package)")
    if args.ssp:
        from mace_fmu.cli.ssp import export_ssp

        with toolchain_warnings_as_lines():
            return export_ssp(args)
    progress(f"{args.configuration} volts-volts model")
    model = volts(args)
    bounds = None
    if args.frequency_bounds:
        from mace_fmu.zero_g.table import read_frequency_bounds

        bounds = read_frequency_bounds(args.frequency_bounds, mode_labels=model.plant.labels)
    name = model_fmu_name(model, runtime=args.runtime, fmi_version=args.fmi_version, variant=model_variant(args))
    progress(f"{args.runtime} FMU {name}.fmu")
    from mace_fmu.fmu.export import export_fmu

    with toolchain_warnings_as_lines():
        path = export_fmu(model, runtime=args.runtime, fmi_version=args.fmi_version, out_dir=args.out, name=name,
                          frequency_bounds=bounds, platforms=args.platforms, progress=step_lines)
    print(f"wrote {path}")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="FMU of the 1-g or 0-g volts-volts model (native C runtime or pythonfmu)")
    p.add_argument("configuration", choices=CONFIGURATIONS,
                   help="the deck's 1-g or 0-g structure, or 'modes': NASTRAN's modes, named by --structure FILE's "
                        "[modes] table")
    deck_option(p)
    output_option(p, "-o", "--out", kind="folder", default=".", used=lambda args: not args.ssp,
                  help="output directory (writes e.g. MACE_1g_native.fmu; with --motion-grids "
                  "MACE_1g_native_motion.fmu; with --parameters P.toml MACE_1g_native_P_<digest>.fmu, the first "
                  "6 hex digits of the set's values (an update's DIR/parameters.toml: "
                  "MACE_1g_native_DIR_parameters_<digest>.fmu), with --frequency-bounds too "
                  "MACE_0g_native_P_<digest>_bounded.fmu: never the plain model's name, nor another set's)")
    p.add_argument("--runtime", choices=["native", "pythonfmu"], default="native",
                   help="native: C runtime, no Python needed in the host, FMI 2.0 co-simulation and model exchange "
                        "(default); pythonfmu: FMI 2.0 co-simulation through Python")
    p.add_argument("--fmi-version", type=int, choices=[2, 3], default=2,
                   help="FMI version of a native FMU: 2 (co-simulation and model exchange) or 3 (co-simulation)")
    p.add_argument("--frequency-bounds", metavar="FILE",
                   help="table_5_3.toml of mace-fmu predict-0g: its bounds become the min/max of the modes' "
                        "frequency_scale_mode_<k> (with --parameters zero_g_nominal.toml: the updated nominal 0-g FMU)")
    output_option(p, "--ssp", kind="file", metavar="FILE.ssp",
                  help="write an SSP 1.0 package instead of a bare FMU: the plant FMU (FMI 2.0) with the moduli, "
                       "springs and frequency scales of --parameters built in, and the set's damping ratios, delays "
                       "and gains as an SSV file bound to it")
    p.add_argument("--controller", metavar="FILE.fmu",
                   help="with --ssp: a controller FMU (mace-fmu export-controller) wired to the plant by signal names "
                        "(its inputs read the plant outputs of those names, its outputs drive the plant inputs)")
    platforms_option(p)
    model_options(p)
    p.set_defaults(func=cmd_export)
