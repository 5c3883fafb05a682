"""Measured signals against a model's: every input and output of the data must be one of the model's."""

from __future__ import annotations

import difflib
from typing import Sequence

from mace_fmu.errors import MaceError
from mace_fmu.updating.engine.measured import MeasuredFrf, TimeHistory


def check_model_signals(data: TimeHistory | MeasuredFrf, *, model_inputs: Sequence[str],
                        model_outputs: Sequence[str]) -> None:
    """Raise ``MaceError`` naming the data's source and signal when a measured input or output is not the model's.

    ``model_inputs``/``model_outputs`` are the model's signal names, e.g. a ``control.StateSpace``'s
    ``input_labels``/``output_labels`` or an FMU's input and output variables.

    Parameters
    ----------
    data : TimeHistory or MeasuredFrf
        The measured data.
    model_inputs, model_outputs : sequence of str
        The model's signal names.

    Raises
    ------
    MaceError
        A measured signal the model lacks, with the closest names.
    """
    for role, measured, model in (("input", data.inputs, model_inputs), ("output", data.outputs, model_outputs)):
        names = list(model)
        for name in measured:
            if name in names:
                continue
            other = model_outputs if role == "input" else model_inputs
            if name in other:
                raise MaceError(f"{data.source}: signal {name!r} is measured as an {role} but is a model "
                                f"{'output' if role == 'input' else 'input'}")
            close = difflib.get_close_matches(name, names, n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else f" ({len(names)} model {role}s)"
            raise MaceError(f"{data.source}: signal {name!r} is not a model {role}{hint}")
