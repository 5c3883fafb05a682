"""``mace-fmu modes``: natural frequencies and labels of the 1-g or 0-g structure."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING

import numpy as np

from mace_fmu.cli.common import deck_option, parameters, parameters_option, positive_hz, progress_bar
from mace_fmu.util.frequency import DEFAULT_MAX_HZ, ZERO_HZ, hz_text

if TYPE_CHECKING:
    from mace_fmu.fe.modes import StructureModes


def _modes_json(result: StructureModes) -> dict:
    props = result.mass_properties
    return {
        "configuration": result.structure.configuration,
        "deck": result.structure.deck.path,
        "structure_file": str(result.structure.file.path) if result.structure.file is not None else None,
        "auto_constrained": [[int(g), int(c)] for g, c in result.auto_constrained],
        "skipped_cards": [{"card": n, "count": k, "first": where} for n, k, where in result.structure.deck.skipped],
        "preload": result.preload.kind if result.preload else None,
        # a rigid-body or mechanism mode reads 0 Hz; its eigenvalue (round-off, either sign) is kept apart
        "modes": [{"index": i + 1, "frequency_hz": 0.0 if abs(f) < ZERO_HZ else float(f), "label": lab,
                   "eigenvalue_rad2_per_s2": float(np.sign(f) * (2 * np.pi * f) ** 2)}
                  for i, (f, lab) in enumerate(zip(result.frequencies_hz, result.labels))],
        "mass_properties": {
            "mass_kg": props.mass_kg,
            "center_of_mass_m": [float(x) for x in props.center_of_mass_m],
            "reference_grid": props.reference_grid,
            "inertia_about_center_node_kgm2": [[float(x) for x in row] for row in props.inertia_about_reference_kgm2],
        },
    }


def _print_modes(result: StructureModes) -> None:
    from mace_fmu.structure.file import deck_units

    pre = f", {result.preload.kind} preload" if result.preload else ""
    print(f"{result.structure.configuration} modes of {result.structure.deck.path}{pre}")
    file = result.structure.file
    print(f"structure file: {file.path}" if file is not None else
          "structure file: none (the deck's own SPC, MPC and EIGRL or EIGR; nothing removed; labels by motion)")
    if result.structure.deck.skipped:
        print("read past (no mass or stiffness): " + ", ".join(f"{n} ({k}x, first at {where})"
                                                             for n, k, where in result.structure.deck.skipped))
    if result.auto_constrained:
        from mace_fmu.fe.autospc import describe_dofs

        print(f"AUTOSPC: constrained {len(result.auto_constrained)} DOFs with neither stiffness nor mass: "
              f"{describe_dofs(result.auto_constrained)}")
    print(f"{'mode':>4s} {'frequency Hz':>13s}  label")
    for i, (f, lab) in enumerate(zip(result.frequencies_hz, result.labels)):
        print(f"{i + 1:4d} {hz_text(f, decimals=4):>13s}  {lab}")
    p = result.mass_properties
    j = np.diag(p.inertia_about_reference_kgm2)
    about = f"grid {p.reference_grid}" if p.reference_grid is not None else "the basic origin"
    units = deck_units(result.structure.deck, result.structure.file)
    mass, length = units or ("(the deck's mass unit)", "(the deck's length unit)")
    inertia = f"{mass} {length}^2" if units else "(mass x length^2 in the deck's units)"
    print(f"mass {p.mass_kg:.4f} {mass}, centre of mass {np.round(p.center_of_mass_m, 5).tolist()} {length}, inertia "
          f"about {about}: Jxx {j[0]:.4f}, Jyy {j[1]:.4f}, Jzz {j[2]:.4f} {inertia}")


def cmd_modes(args: argparse.Namespace) -> int:
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.volts import scale_frequencies

    deck = read_deck(args.deck)
    parameter_set = parameters(args)  # a set made for the other structure, or for another deck: refused here
    with progress_bar() as bar:
        result = compute_modes(deck, configuration=args.configuration, preload=args.preload, mass=args.mass,
                               max_hz=args.max_hz, progress=bar, structure_file=args.structure_file,
                               parameters=parameter_set)
    # an update's frequency scales move the modes the FMU has: the same frequencies here
    result = scale_frequencies(result, parameter_set, configuration=args.configuration)
    if args.json:
        payload = _modes_json(result)
        payload["parameters"] = _parameters_json(args.parameters, parameter_set)
        json.dump(payload, sys.stdout, indent=1)
        print()
    else:
        _print_modes(result)
        if parameter_set is not None:
            print(_parameters_line(args.parameters, parameter_set))
    return 0


def _what_the_set_moves(parameter_set) -> dict[str, list[str]]:
    """The set's names by what they do to the modes: re-solved (moduli, springs, masses), scaled (frequency
    scales), and the rest (damping, delays, gains: the input-output model's, not the modes')."""
    kinds = {"re-solved": ("modulus", "spring", "mass"), "scaled": ("frequency_scale",)}
    out = {what: list(parameter_set.of_kind(*names)) for what, names in kinds.items()}
    moved = {n for names in out.values() for n in names}
    out["not in the modes"] = [n for n in parameter_set.values if n not in moved]
    return out


def _parameters_json(path: str | None, parameter_set) -> dict | None:
    if parameter_set is None:
        return None
    return {"file": path, **{what.replace(" ", "_").replace("-", "_"): names
                             for what, names in _what_the_set_moves(parameter_set).items()}}


def _parameters_line(path: str, parameter_set) -> str:
    parts = _what_the_set_moves(parameter_set)
    said = [f"{len(parts['re-solved'])} moduli, springs and masses re-solved"]
    if parts["scaled"]:
        said.append(f"{len(parts['scaled'])} frequency scales applied")
    if parts["not in the modes"]:
        said.append(f"{len(parts['not in the modes'])} others (damping ratios, delays, gains) are the input-output "
                    "model's: mace-fmu model --poles")
    return f"parameter set: {path} ({'; '.join(said)})"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("modes", help="natural frequencies [Hz] and labels of the 1-g or 0-g structure")
    p.add_argument("configuration", choices=["1g", "0g"])
    deck_option(p)
    p.add_argument("--max-hz", type=positive_hz, default=None,
                   help=f"upper frequency [Hz] (default: the deck's EIGRL, else {DEFAULT_MAX_HZ:g})")
    p.add_argument("--preload", choices=["large", "linear"], default="large",
                   help="1-g gravity preload: large displacement (SOL 106, default) or linear")
    p.add_argument("--mass", choices=["lumped", "consistent"], default="lumped", help="bar mass matrix")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    parameters_option(p)
    p.set_defaults(func=cmd_modes)
