"""File names of exported FMUs: the name says which outputs the FMU has, so variants never overwrite each other."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mace_fmu.parameters.sets import ParameterSet

#: Up to this many motion grids are spelled out in the name; more are counted.
LISTED_GRIDS = 6

#: hexadecimal digits of a parameter set's digest in the name of an FMU built from it
SET_DIGEST_DIGITS = 6

#: the file name every update writes its set to: such a set is named by its folder too
UPDATE_SET_NAME = "parameters"


def fmu_model_name(configuration: str, *, runtime: str | None = None, fmi_version: int = 2,
                   motion_grids: Sequence[int] = (), all_grids: Sequence[int] = (), variant: str = "",
                   prefix: str = "MACE") -> str:
    """Model name (and .fmu file stem) of a MACE FMU, e.g. MACE_1g_native, MACE_1g_native_fmi3,
    MACE_1g_pythonfmu, MACE_0g_native_motion_1_7 (MACE_1g, MACE_1g_motion without ``runtime``).

    The runtime ("native", "pythonfmu") and FMI 3 come first; then no motion outputs: nothing; the
    motion of every grid in ``all_grids``: ``_motion``; a few grids: their IDs; more than
    ``LISTED_GRIDS``: ``_motion_<count>_grids``. ``variant`` (e.g. :func:`parameter_set_variant` of the set the model
    was built from) follows the runtime, so that an FMU of a changed model never takes the plain model's name.
    ``prefix``: "MACE" for the bundled structure, another deck's file stem for its FMUs.

    Parameters
    ----------
    configuration : str
        "1g" or "0g".
    runtime : str, optional
        "native" or "pythonfmu", what runs inside the FMU (None: neither in the name).
    fmi_version : int
        2 or 3 (3 adds ``_fmi3``).
    motion_grids : sequence of int
        The grids whose motion the FMU outputs.
    all_grids : sequence of int
        Every grid of the structure (to say "all of them" as ``_motion``).
    variant : str
        Names a changed model, e.g. :func:`parameter_set_variant` of its parameter set.
    prefix : str
        "MACE", or another deck's file stem.

    Returns
    -------
    str
        A C identifier, the FMU's model name and file stem.
    """
    base = (f"{variant_identifier(prefix)}_{configuration}" + (f"_{runtime}" if runtime else "")
            + ("_fmi3" if fmi_version == 3 else ""))
    if variant:
        base += "_" + variant_identifier(variant)
    grids = sorted(set(int(g) for g in motion_grids))
    if not grids:
        return base
    if all_grids and grids == sorted(set(int(g) for g in all_grids)):
        return f"{base}_motion"
    if len(grids) <= LISTED_GRIDS:
        return f"{base}_motion_" + "_".join(str(g) for g in grids)
    return f"{base}_motion_{len(grids)}_grids"


def model_fmu_name(model, *, runtime: str | None = None, fmi_version: int = 2, variant: str = "") -> str:
    """The FMU name of a volts-volts model (:func:`fmu_model_name` with its configuration, motion grids and prefix).

    Parameters
    ----------
    model : VoltsModel
        The model the FMU is of.
    runtime : str, optional
        "native" or "pythonfmu" (None: neither in the name).
    fmi_version : int
        2 or 3 (3 adds ``_fmi3``).
    variant : str
        Names a changed model, e.g. :func:`parameter_set_variant` of its parameter set.

    Returns
    -------
    str
        A C identifier, e.g. MACE_0g, MACE_1g_native_motion, beam_0g_pythonfmu.
    """
    return fmu_model_name(model.configuration, runtime=runtime, fmi_version=fmi_version,
                          motion_grids=model.plant.motion_grids, all_grids=model.grid_ids, variant=variant,
                          prefix=model_prefix(model))


def model_prefix(model) -> str:
    """"MACE" for the bundled deck's models, else the deck's file stem (an FMU of another structure is not MACE's)."""
    return model.structure_modes.name


def variant_identifier(text: str) -> str:
    """``text`` as a C-identifier fragment: letters, digits and underscores ("zero-g nominal" -> "zero_g_nominal")."""
    out = "".join(c if c.isalnum() and c.isascii() else "_" for c in text).strip("_")
    while "__" in out:
        out = out.replace("__", "_")
    return out or "variant"


def parameter_set_variant(parameters: ParameterSet, *, path: str | os.PathLike | None = None) -> str:
    """The part of an FMU's name that says which parameter set its model was built from.

    The set file's stem, with its folder's name before it when the stem is ``parameters`` (the name every
    ``mace-fmu update`` writes), then the first :data:`SET_DIGEST_DIGITS` hexadecimal digits of the set's
    values (:meth:`~mace_fmu.parameters.sets.ParameterSet.digest`): ``lexan.toml`` gives ``lexan_3fa2c1``,
    ``run_a/parameters.toml`` ``run_a_parameters_9e0d4b``. Two sets with different values do not give one
    name (two updates written into folders of one name, a set edited and exported again: one chance in 16
    million that two digests share their first six digits), and a set's copy of the same name gives the same
    name.

    Parameters
    ----------
    parameters : ParameterSet
        The set the model was built from.
    path : str or path-like, optional
        Its file (default: the file it was read from, ``parameters.source``; "set" for one made in memory).

    Returns
    -------
    str
        A C-identifier fragment, e.g. ``run_a_parameters_9e0d4b``.
    """
    source = Path(os.fspath(path)) if path is not None else (Path(parameters.source) if parameters.source else None)
    if source is None:
        label = "set"
    elif source.stem == UPDATE_SET_NAME:
        label = f"{source.absolute().parent.name}_{source.stem}"
    else:
        label = source.stem
    return f"{variant_identifier(label)}_{parameters.digest()[:SET_DIGEST_DIGITS]}"
