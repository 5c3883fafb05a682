"""``mace-fmu correlate``: measured modes (modes.toml) paired with a deck's modes by MAC at the measured DOFs."""

from __future__ import annotations

import argparse

from mace_fmu.cli.common import parameters_option, progress
from mace_fmu.cli.preflight import output_option
from mace_fmu.errors import MaceError


def structure_options(p: argparse.ArgumentParser) -> None:
    """--deck, --structure, --modes, --dof-map, --configuration, --min-mac: a deck's modes against measured ones."""
    p.add_argument("--deck", required=True, help="NASTRAN bulk deck of the structure tested")
    p.add_argument("--structure", metavar="FILE", default=None, dest="structure_file",
                   help="its structure file: the sensors that place the measured DOFs, the [parameters] an update "
                        "may change (default: the bundled one for the bundled deck, else none)")
    p.add_argument("--modes", metavar="FILE", required=True, help="measured modes (modes.toml, as mace-fmu ema "
                   "writes it)")
    p.add_argument("--dof-map", metavar="FILE", default=None,
                   help="where measured DOFs are on the model (TOML: \"<channel>\" = [[grid, component, weight]]), "
                        "for channels that are neither a sensor of the structure file nor named by node and "
                        "direction ('101+Z')")
    p.add_argument("--configuration", choices=["1g", "0g"], default="1g",
                   help="the structure the test saw (default 1g: the deck's gravity preload)")
    p.add_argument("--min-mac", type=_fraction, default=None, metavar="M",
                   help="a measured mode whose best model partner has a MAC below M is unpaired (default 0.6)")


def _fraction(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a number between 0 and 1, got {text!r}")
    return value


def family_of(args: argparse.Namespace, *, base=None):
    """(modes file, family) from the structure options: the measured DOFs placed on the model."""
    from mace_fmu.cli.ema import structure_instruments
    from mace_fmu.updating.modal.dofs import read_dof_map, resolve_dofs
    from mace_fmu.updating.modal.family import StructureFamily
    from mace_fmu.updating.modal.modes_file import read_modes_file

    from mace_fmu.deck.reader import read_deck
    from mace_fmu.structure.build import build_structure

    # the structure file against the deck first (cheap, no FE): a file of another structure is the cause to name,
    # before its sensors are asked where the measured DOFs are
    build_structure(read_deck(args.deck), configuration=args.configuration, structure_file=args.structure_file)
    measured = read_modes_file(args.modes)
    sensors, _ = structure_instruments(args.structure_file)
    dof_map = read_dof_map(args.dof_map) if args.dof_map else None
    places = resolve_dofs(measured.dofs, sensors=sensors, dof_map=dof_map, source=args.modes)
    family = StructureFamily(deck=args.deck, structure_file=args.structure_file, dofs=measured.dof_names,
                             dof_places=places, configuration=args.configuration, base=base)
    return measured, family


def cmd_correlate(args: argparse.Namespace) -> int:
    from mace_fmu.cli.common import parameters
    from mace_fmu.updating.modal.correlation import DEFAULT_MIN_MAC, correlate, format_correlation
    from mace_fmu.updating.modal.figures import plot_mac
    from mace_fmu.util.atomic import output_folder

    measured, family = family_of(args, base=parameters(args))
    model = family.full({})
    found = correlate(measured, model, min_mac=args.min_mac or DEFAULT_MIN_MAC)
    print(format_correlation(found, model, title=[
        f"{len(measured.modes)} measured mode(s) ({args.modes}) against the {args.configuration} modes of "
        f"{family.where}" + (f" with {args.parameters}" if args.parameters else "") + ", at "
        f"{', '.join(measured.dof_names)}", ""]))
    if not found.pairs:
        raise MaceError(f"no measured mode pairs with a model mode (MAC >= {found.min_mac:g}): are the measured DOFs "
                        "placed right (--dof-map) and is it the structure tested?")
    out = output_folder(args.out)
    path = plot_mac(found.mac, measured=[f"{lab} {f:.2f} Hz" for lab, f in zip(found.measured_labels,
                                                                                 found.measured_hz)],
                    model=[f"{lab} {f:.2f} Hz" for lab, f in zip(found.model_labels, found.model_hz)],
                    path=out / "mac.png")
    print(f"wrote {path}")
    if found.unpaired_measured:
        progress(f"{len(found.unpaired_measured)} measured mode(s) unpaired")
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("correlate", help="measured modes (modes.toml) against a deck's modes: pairs by MAC, "
                       "frequency differences, the MAC matrix, unpaired modes",
                       description="The model's mass-normalised shapes at the measured DOFs (the structure file's "
                                   "sensors, node-and-direction names or a DOF map), paired one-to-one with the "
                                   "measured modes by the largest total MAC; a pair needs MAC >= --min-mac. Prints the "
                                   "paired table and the unpaired modes, draws the MAC matrix (mac.png).")
    structure_options(p)
    parameters_option(p)
    output_option(p, "-o", "--out", kind="folder", default=".", metavar="DIR",
                  help="folder for mac.png (default: the current folder)")
    p.set_defaults(func=cmd_correlate)
