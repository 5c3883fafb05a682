"""File names of exported FMUs: the name says which outputs the FMU has, so variants never overwrite each other."""

from __future__ import annotations

from collections.abc import Sequence

#: Up to this many motion grids are spelled out in the name; more are counted.
LISTED_GRIDS = 6


def fmu_model_name(configuration: str, *, runtime: str | None = None, fmi_version: int = 2,
                   motion_grids: Sequence[int] = (), all_grids: Sequence[int] = (), variant: str = "",
                   prefix: str = "MACE") -> str:
    """Model name (and .fmu file stem) of a MACE FMU, e.g. MACE_1g_native, MACE_1g_native_fmi3,
    MACE_1g_pythonfmu, MACE_0g_native_motion_1_7 (MACE_1g, MACE_1g_motion without ``runtime``).

    The runtime ("native", "pythonfmu") and FMI 3 come first; then no motion outputs: nothing; the
    motion of every grid in ``all_grids``: ``_motion``; a few grids: their IDs; more than
    ``LISTED_GRIDS``: ``_motion_<count>_grids``. ``variant`` (e.g. the stem of the parameter set the model
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
        Names a changed model, e.g. the parameter set's file stem.
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
        Names a changed model, e.g. the parameter set's file stem.

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
    from pathlib import Path

    from mace_fmu.iomodel.modal_source import ModalStructure
    from mace_fmu.structure.file import is_bundled_deck

    if isinstance(model.structure_modes, ModalStructure):  # NASTRAN's modes: named by their file
        return model.structure_modes.name
    deck = model.structure_modes.deck
    return "MACE" if is_bundled_deck(deck) else Path(deck.path).stem


def variant_identifier(text: str) -> str:
    """``text`` as a C-identifier fragment: letters, digits and underscores ("zero-g nominal" -> "zero_g_nominal")."""
    out = "".join(c if c.isalnum() and c.isascii() else "_" for c in text).strip("_")
    while "__" in out:
        out = out.replace("__", "_")
    return out or "variant"
