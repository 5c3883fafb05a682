"""What several commands share: the progress line, the deck and model options, the model build."""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from pathlib import Path
from typing import Iterator

from mace_fmu.errors import MaceError
from mace_fmu.util.frequency import DEFAULT_MAX_HZ
from mace_fmu.util.progress import ProgressCallback, Step

#: the bundled deck (mace_fmu/data/mace_em.bdf): the --deck default, named without importing the reader, so
#: that ``mace-fmu --help`` and a refused argument answer at once
BUNDLED_DECK = str(Path(__file__).resolve().parents[1] / "data" / "mace_em.bdf")


def model_variant(args: argparse.Namespace) -> str:
    """What sets this FMU's model apart from the plain one, for its name: the parameter set (its file's
    stem, its folder's name for an update's ``parameters.toml``, and a digest of its values:
    :func:`~mace_fmu.fmu.naming.parameter_set_variant`) and "bounded" with frequency bounds ("" for the plain
    model, which keeps the plain name)."""
    from mace_fmu.fmu.naming import parameter_set_variant
    from mace_fmu.parameters.sets import ParameterSet

    path = getattr(args, "parameters", None)
    parts = [parameter_set_variant(ParameterSet.read(path), path=path)] if path else []
    if getattr(args, "frequency_bounds", None):
        parts.append("bounded")
    return "_".join(parts)


def progress(message: str) -> None:
    """One progress line on stderr (stdout stays the command's result)."""
    print(f"  {message}", file=sys.stderr, flush=True)


def step_lines(step: Step) -> None:
    """A progress callback that writes every step as one line on stderr, ``task: detail``: for steps of seconds
    to minutes each (the native runtime's compilation), where a log needs each one and a bar would say less."""
    progress(f"{step.task}: {step.detail}" if step.detail else f"{step.task} ({step.done} of {step.total})")


@contextlib.contextmanager
def progress_bar(*, task_lines: bool = False) -> Iterator[ProgressCallback]:
    """A progress callback that draws one tqdm bar on stderr (none when stderr is not a terminal).

    With ``task_lines``, each new task (a stage of a multi-stage computation, see
    :func:`mace_fmu.util.progress.begin_stage`) is also written as one line, terminal or not, so that a log
    shows where a long run is.
    """
    from tqdm import tqdm

    bars: list[tqdm] = []
    tasks: list[str] = []

    def update(step: Step) -> None:
        if task_lines and (not tasks or tasks[-1] != step.task):
            tqdm.write(f"  {step.task}", file=sys.stderr)
        tasks[:] = [step.task]
        if not bars:  # created at the first step: a computation without steps draws nothing
            bars.append(tqdm(total=step.total, desc=step.task, unit="step", leave=False, file=sys.stderr,
                             disable=None))
        bar = bars[0]
        bar.total, bar.n = step.total, step.done
        bar.set_description(step.task, refresh=False)
        bar.set_postfix_str(step.detail)

    try:
        yield update
    finally:
        for bar in bars:
            bar.close()


def _checked(text: str, *, convert, valid, expected: str):
    """``convert(text)`` when it is ``valid``, else the ArgumentTypeError argparse turns into one line, exit 2."""
    try:
        value = convert(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
    if not valid(value):
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return value


def positive_number(text: str) -> float:
    """argparse type of an option that is a finite number > 0 (a segment length, a noise level)."""
    return _checked(text, convert=float, valid=lambda v: math.isfinite(v) and v > 0, expected="a finite number > 0")


def positive_integer(text: str) -> int:
    """argparse type of a count option (workers, rounds): an integer >= 1."""
    return _checked(text, convert=int, valid=lambda v: v >= 1, expected="an integer >= 1")


def positive_hz(text: str) -> float:
    """argparse type of a frequency option: a finite number > 0 [Hz] (-5 or nan would give an empty table)."""
    return _checked(text, convert=float, valid=lambda v: math.isfinite(v) and v > 0,
                    expected="a finite frequency > 0 Hz")


def non_negative_number(text: str) -> float:
    """argparse type of an option that may be 0 (a weight): a finite number >= 0."""
    return _checked(text, convert=float, valid=lambda v: math.isfinite(v) and v >= 0, expected="a finite number >= 0")


def finite_number(text: str) -> float:
    """argparse type of a signed option (an amplitude): a finite number (nan or inf would reach the solver)."""
    return _checked(text, convert=float, valid=math.isfinite, expected="a finite number")


def non_negative_hz(text: str) -> float:
    """argparse type of a frequency that may be 0 (a band's or a chirp's lower end): a finite number >= 0 [Hz]."""
    return _checked(text, convert=float, valid=lambda v: math.isfinite(v) and v >= 0,
                    expected="a finite frequency >= 0 Hz")


def fraction(text: str) -> float:
    """argparse type of a fraction (an overlap, a damping ratio): a number in [0, 1)."""
    return _checked(text, convert=float, valid=lambda v: 0 <= v < 1, expected="a fraction in [0, 1)")


def percent(text: str) -> float:
    """argparse type of a percentage (a bound): a number in [0, 100)."""
    return _checked(text, convert=float, valid=lambda v: 0 <= v < 100, expected="a percentage in [0, 100)")


def non_negative_integer(text: str) -> int:
    """argparse type of a seed or a count that may be 0: an integer >= 0."""
    return _checked(text, convert=int, valid=lambda v: v >= 0, expected="an integer >= 0")


def deck_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--deck", default=BUNDLED_DECK, help="NASTRAN bulk deck (default: bundled MACE deck)")
    p.add_argument("--structure", metavar="FILE", default=None, dest="structure_file",
                   help="structure file of the deck (TOML: suspension removed for 0-g, components, mechanisms, "
                        "instruments; schema in mace_fmu/data/README.md). Default: the bundled mace_em.toml for the "
                        "bundled deck, none for any other deck (its modes as NASTRAN defines them, nothing removed)")


def model_options(p: argparse.ArgumentParser, *, motion: bool = True) -> None:
    """Options of the volts-volts model (shared by model, export and view response)."""
    p.add_argument("--max-hz", type=positive_hz, default=None,
                   help=f"highest retained mode [Hz] (default: the deck's EIGRL, else {DEFAULT_MAX_HZ:g})")
    p.add_argument("--bessel", choices=["full", "delay", "none"], default="full",
                   help="Bessel filters as 8-pole filters, as their 2.44 ms Pade delay, or left out")
    p.add_argument("--no-servos", action="store_true", help="leave the wheel speed loops and gimbal servos open")
    p.add_argument("--no-delays", action="store_true", help="leave out the actuator and gyro time delays")
    p.add_argument("--pade-order", type=positive_integer, default=3,
                   help="order of the Pade delay approximations (default 3)")
    p.add_argument("--preload", choices=["large", "linear"], default="large", help="1-g gravity preload")
    parameters_option(p)
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


def parameters_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--parameters", metavar="FILE",
                   help="parameter set (TOML, e.g. from mace-fmu update) replacing the deck's and data file's values")


def parameters(args: argparse.Namespace):
    """The --parameters file as a ParameterSet (None without the option)."""
    from mace_fmu.parameters.sets import ParameterSet

    path = getattr(args, "parameters", None)
    if not path:
        return None
    parameters = ParameterSet.read(path)
    prov, configuration = parameters.provenance, getattr(args, "configuration", None)
    # a fit to one structure's FMU absorbed that structure's errors: it is not carried to the other
    # (the engine's 1-g sets are, on purpose: predict-0g); the provenance says which kind a set is
    if prov is not None and prov.fitted_to and prov.configuration and configuration in ("1g", "0g") \
            and prov.configuration != configuration:
        raise MaceError(f"{path}: fitted to the {prov.configuration} FMU {prov.fitted_to}, not to the "
                        f"{configuration} model; refit it, or remove 'configuration' from its [provenance] to use "
                        "it anyway")
    return parameters


_FROM_ARGS = object()

#: the configuration argument's choices: a deck's 1-g and 0-g structures, or NASTRAN's modes ([modes] table)
CONFIGURATIONS = ("1g", "0g", "modes")


def modal_structure_of(args: argparse.Namespace, *, parameter_set=None):
    """The structure of configuration ``modes``: NASTRAN's modes, which --structure FILE's [modes] table names."""
    from mace_fmu.iomodel.modal_source import modal_structure

    if not getattr(args, "structure_file", None):
        raise MaceError("configuration 'modes' needs --structure FILE, a structure file whose [modes] table names "
                        "NASTRAN's modes (OP2 or punch)")
    return modal_structure(args.structure_file, parameters=parameter_set)


def volts(args: argparse.Namespace, *, parameter_set=_FROM_ARGS, every_grid_moves: bool = False):
    """The volts-volts model the command line asks for (model_options), errors as one message.

    ``parameter_set`` replaces the set ``--parameters`` names (SSP: only its built-in part);
    ``every_grid_moves`` adds every grid's motion as outputs whatever ``--motion-grids`` says.
    """
    from mace_fmu.deck.reader import read_deck
    from mace_fmu.fe.modes import compute_modes
    from mace_fmu.iomodel.model_options import ModelledElectronics, SignalSelection
    from mace_fmu.iomodel.volts import volts_model

    # a bad option value: a MaceError from the record that refuses it
    electronics = ModelledElectronics(servos=not args.no_servos, bessel=args.bessel, delays=not args.no_delays,
                                      pade_order=args.pade_order)
    grids = "all" if every_grid_moves else motion_grids(getattr(args, "motion_grids", None))
    if args.configuration == "modes":  # NASTRAN's modes: the structure file's [modes] table, no deck solved
        modes = modal_structure_of(args, parameter_set=parameters(args) if parameter_set is _FROM_ARGS
                                   else parameter_set)
        return volts_model(modes, electronics=electronics, signals=SignalSelection(motion_grids=grids),
                           max_hz=args.max_hz)
    modes = compute_modes(read_deck(args.deck), configuration=args.configuration, preload=args.preload,
                          max_hz=args.max_hz, structure_file=getattr(args, "structure_file", None),
                          parameters=parameters(args) if parameter_set is _FROM_ARGS else parameter_set)
    return volts_model(modes, electronics=electronics, signals=SignalSelection(motion_grids=grids))
