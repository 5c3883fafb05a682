"""``mace-fmu modes``: natural frequencies and labels of the 1-g or 0-g structure."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING

import numpy as np

from mace_fmu.cli.common import deck_option, positive_hz, progress_bar
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
    deck = read_deck(args.deck)
    with progress_bar() as bar:
        result = compute_modes(deck, configuration=args.configuration, preload=args.preload, mass=args.mass,
                               max_hz=args.max_hz, progress=bar, structure_file=args.structure_file)
    if args.json:
        json.dump(_modes_json(result), sys.stdout, indent=1)
        print()
    else:
        _print_modes(result)
    return 0


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
    p.set_defaults(func=cmd_modes)
