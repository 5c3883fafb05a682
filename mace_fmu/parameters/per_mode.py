"""Per-mode parameter names resolved against a model's modes: the one place a set's modal names meet a model.

A damping ratio or a frequency scale is named by its mode's label (``damping:1st Z bending``: what the
engine's update and the 0-g prediction write) or by the mode's 1-based number in the model's
retained-mode order (``damping_mode_14``: an FMU's variable, what an FMU update writes). Every flow that
applies a set to a model (``volts_model``, hence ``export --parameters`` and the SSP package's FMU; the
package's start values; an FMU's start values in ``update fmu --start`` and ``plan-test --at``; the MACE
update's family) resolves the names here, so that each flow takes what every other writes and both
spellings of a mode's value give the same model.

:func:`resolve_mode_names` gives the FMU's spelling (a label names every mode that carries it);
:func:`label_mode_names` gives the labels, for a set that goes on to a structure whose modes are
numbered otherwise (a 1-g set in the 0-g prediction).
"""

from __future__ import annotations

import difflib
from collections.abc import Collection, Mapping, Sequence

from mace_fmu.errors import MaceError
from mace_fmu.parameters.kinds import ModeReference, mode_reference


def _where(source: str) -> str:
    """A message's opening that names the file, when there is one."""
    return f"{source}: " if source else ""


def _expected(ref: ModeReference, count: int, model: str) -> str:
    """What a name of ``ref``'s kind may say in a model of ``count`` modes."""
    kind = ref.kind
    if count == 0:
        return f"the {model} has no modes with per-mode parameters"
    return (f"the {model} has modes 1 to {count}; expected {kind.fmu_prefix}<k> with k from 1 to {count}, or "
            f"{kind.set_prefix}<mode label>")


def _unknown_label(name: str, ref: ModeReference, labels: Sequence[str], model: str) -> str:
    """Why a label no mode has is refused: the closest labels the model has (or the first of them)."""
    known = [x for x in dict.fromkeys(labels) if x]
    close = difflib.get_close_matches(ref.label or "", known, n=3)
    if close:
        hint = "closest: " + ", ".join(ref.kind.set_name(x) for x in close)
    else:
        hint = "labels: " + (", ".join(known[:12]) + (", ..." if len(known) > 12 else "") if known else "none")
    return f"parameter {name!r}: no mode labelled {ref.label!r} in the {model}; {hint}"


def _modes_of(name: str, ref: ModeReference, *, mode_labels: Sequence[str], model: str,
              available: Collection[str] | None) -> list[int]:
    """The 1-based numbers of the modes ``name`` addresses; a MaceError message (without the file) when none."""
    count = len(mode_labels)
    if ref.number is not None:
        if not 1 <= ref.number <= count:
            raise MaceError(f"parameter {name!r}: no mode {ref.number}: {_expected(ref, count, model)}")
        if available is not None and name not in available:
            label = mode_labels[ref.number - 1]
            raise MaceError(f"parameter {name!r}: mode {ref.number}{f' ({label})' if label else ''} of the {model} has "
                            f"no {ref.kind.name.replace('_', ' ')} parameter (a rigid-body or mechanism mode has no "
                            "frequency to scale)")
        return [ref.number]
    modes = [k + 1 for k, label in enumerate(mode_labels) if label == ref.label
             and (available is None or ref.kind.fmu_name(k + 1) in available)]
    if not modes and ref.label in mode_labels:  # the label is there, its modes lack the parameter
        raise MaceError(f"parameter {name!r}: the modes labelled {ref.label!r} in the {model} have no "
                        f"{ref.kind.name.replace('_', ' ')} parameter (a rigid-body or mechanism mode has no "
                        "frequency to scale)")
    if not modes:
        raise MaceError(_unknown_label(name, ref, mode_labels, model))
    return modes


def resolve_mode_names(values: Mapping[str, float], *, mode_labels: Sequence[str], model: str, source: str = "",
                       available: Collection[str] | None = None, other_structure: str = "",
                       hint: str = "") -> dict[str, float]:
    """``values`` with every per-mode name in the FMU's spelling, ``damping_mode_<k>``; other names kept.

    Parameters
    ----------
    values : mapping of str to float
        Parameter values [SI] by name, per-mode ones in either spelling.
    mode_labels : sequence of str
        The model's mode labels in its retained-mode order, mode 1 first ("" where a label is unknown).
    model : str
        What the messages call the model ("0g structure", an FMU's file).
    source : str
        The file the values come from, which the messages name.
    available : collection of str, optional
        The model's per-mode parameters (an FMU's variables: a rigid-body mode has no frequency scale); a
        label then names only those of its modes that have one. None: every mode has both kinds.
    other_structure : str
        The structure the set was made for when it is not this model's ("1g" for a 0-g model): its labels
        the model lacks are passed over (a 1-g set's suspension modes), its mode numbers are refused (they
        count another structure's modes).
    hint : str
        Added to every message (e.g. the command that lists an FMU's parameters).

    Returns
    -------
    dict of str to float
        A label's value under the name of every mode that carries it; a number's under its own name.

    Raises
    ------
    MaceError
        One line naming ``source``, the parameter and what was expected: a label no mode has (with the
        closest labels), a mode number outside 1..n (with n), a mode number of a set made for another
        structure, a mode given twice with different values.
    """
    out: dict[str, float] = {}
    given_as: dict[str, str] = {}
    for name, value in values.items():
        ref = mode_reference(name)
        if ref is None:
            out[name] = value
            continue
        try:
            if other_structure and ref.number is not None:
                raise MaceError(f"parameter {name!r} names a mode of the {other_structure} structure the set was made "
                                f"for by its number, which counts other modes in the {model}: name it by label "
                                f"({ref.kind.set_prefix}<mode label>)")
            if other_structure and ref.label not in mode_labels:
                continue
            modes = _modes_of(name, ref, mode_labels=mode_labels, model=model, available=available)
        except MaceError as exc:
            raise MaceError(f"{_where(source)}{exc}{hint}") from None
        for k in modes:
            target = ref.kind.fmu_name(k)
            if target in out and out[target] != value:
                raise MaceError(f"{_where(source)}parameter {name!r} = {value!r} and {given_as[target]!r} = "
                                f"{out[target]!r} both set {target} of the {model}: give the mode one value{hint}")
            out[target], given_as[target] = value, name
    return out


def label_mode_names(values: Mapping[str, float], *, mode_labels: Sequence[str], model: str,
                     source: str = "") -> dict[str, float]:
    """``values`` with every per-mode name by number turned into its mode's label (``damping:<label>``), other
    names kept as they are: a set that goes on to a structure whose modes are numbered otherwise (a label is the
    spelling every structure shares; the model that takes the set checks it).

    Parameters
    ----------
    values : mapping of str to float
        Parameter values [SI] by name, per-mode ones in either spelling.
    mode_labels : sequence of str
        The labels of the modes the numbers count, mode 1 first.
    model : str
        What the messages call that model ("1g structure").
    source : str
        The file the values come from, which the messages name.

    Returns
    -------
    dict of str to float
        The values, per-mode ones by label.

    Raises
    ------
    MaceError
        One line naming ``source`` and the parameter: a mode number outside 1..n (with n), a mode without a
        label, or two names that become one label with different values (a label names every mode that
        carries it).
    """
    out: dict[str, float] = {}
    given_as: dict[str, str] = {}
    for name, value in values.items():
        ref, target = mode_reference(name), name
        try:
            if ref is not None and ref.number is not None:
                (number,) = _modes_of(name, ref, mode_labels=mode_labels, model=model, available=None)
                if not mode_labels[number - 1]:
                    raise MaceError(f"parameter {name!r}: mode {number} of the {model} has no label to name it by")
                target = ref.kind.set_name(mode_labels[number - 1])
            if target in out and out[target] != value:
                raise MaceError(f"parameter {name!r} = {value!r} and {given_as[target]!r} = {out[target]!r} both set "
                                f"{target!r} of the {model} (a label names every mode that carries it): give them "
                                "one value")
        except MaceError as exc:
            raise MaceError(f"{_where(source)}{exc}") from None
        out[target], given_as[target] = value, name
    return out
