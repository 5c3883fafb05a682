"""What several commands share: the progress line, the deck and model options, the model build."""

from __future__ import annotations

import argparse
import sys

from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.structure import bundled_deck_path


def progress(message: str) -> None:
    """One progress line on stderr (stdout stays the command's result)."""
    print(f"  {message}", file=sys.stderr, flush=True)


def deck_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--deck", default=str(bundled_deck_path()), help="NASTRAN bulk deck (default: bundled MACE deck)")


def model_options(p: argparse.ArgumentParser, *, motion: bool = True) -> None:
    """Options of the volts-volts model (shared by model, export and view response)."""
    p.add_argument("--max-hz", type=float, default=250.0, help="highest retained mode [Hz] (default 250)")
    p.add_argument("--bessel", choices=["full", "delay", "none"], default="full",
                   help="Bessel filters as 8-pole filters, as their 2.44 ms Pade delay, or left out")
    p.add_argument("--no-servos", action="store_true", help="leave the wheel speed loops and gimbal servos open")
    p.add_argument("--no-delays", action="store_true", help="leave out the actuator and gyro time delays")
    p.add_argument("--pade-order", type=int, default=3, help="order of the Pade delay approximations (default 3)")
    p.add_argument("--preload", choices=["large", "linear"], default="large", help="1-g gravity preload")
    if motion:
        p.add_argument("--motion-grids", default=None, metavar="all|ID,ID,...",
                       help="also output these grids' translations [m] and rotations [rad] (for animation)")


def motion_grids(text: str | None):
    """--motion-grids: None, "all" or comma-separated grid IDs."""
    if text is None or text == "all":
        return () if text is None else "all"
    try:
        return [int(g) for g in text.split(",") if g.strip()]
    except ValueError:
        raise MaceError(f"--motion-grids takes 'all' or comma-separated grid IDs, got {text!r}") from None


def volts(args: argparse.Namespace, **overrides):
    """The volts-volts model the command line asks for (model_options), errors as one message."""
    from mace_fmu.iomodel.volts import volts_model

    options = dict(servos=not args.no_servos, bessel=args.bessel, delays=not args.no_delays,
                   pade_order=args.pade_order, max_hz=args.max_hz, preload=args.preload, deck=read_deck(args.deck),
                   motion_grids=motion_grids(getattr(args, "motion_grids", None)))
    try:
        return volts_model(args.structure, **{**options, **overrides})
    except ValueError as exc:  # a bad option value: one message, not a traceback
        raise MaceError(str(exc)) from None


def fmu_name(structure: str, *, kind: str, fmi_version: int = 2) -> str:
    """File stem and model identifier of an exported FMU, saying which kind it is: MACE_1g_native,
    MACE_1g_native_fmi3, MACE_1g_pythonfmu."""
    return f"MACE_{structure}_{kind}" + ("_fmi3" if fmi_version == 3 else "")
