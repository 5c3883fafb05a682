"""What a cost calls on a model: the protocols the engine's models satisfy.

A :class:`SimulatedModel` is driven by inputs and read at its outputs: the state-space
:class:`~mace_fmu.updating.engine.linear_model.LinearModel` and an FMU
(:class:`~mace_fmu.updating.fmu.model.FmuModel`) both are, so the time-domain and simulated frequency-response
costs take either. A :class:`PoleModel` gives labelled poles: the linear model and the modal model
(:class:`~mace_fmu.updating.engine.modal_model.ModalModel`) do, an FMU does not.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol, runtime_checkable

import numpy as np

from mace_fmu.iomodel.poles import ClosedLoopPole


@runtime_checkable
class SimulatedModel(Protocol):
    """A model known by simulation: named inputs and outputs, a response to sampled inputs from rest."""

    @property
    def inputs(self) -> tuple[str, ...]:
        """The input signals' names."""
        ...

    @property
    def outputs(self) -> tuple[str, ...]:
        """The output signals' names."""
        ...

    def time_response(self, times_s: np.ndarray, inputs: Mapping[str, np.ndarray], *,
                      outputs: Sequence[str] | None = None) -> np.ndarray:
        """Outputs y[k, output] at uniformly spaced ``times_s`` [s] from rest, each input held over a sample
        (zero-order hold); inputs not given are zero.

        Parameters
        ----------
        times_s : numpy.ndarray
            Increasing, uniformly spaced sample times [s].
        inputs : mapping of str to numpy.ndarray
            Input name -> its samples, one per time.
        outputs : sequence of str, optional
            The outputs wanted, in this order (default: every output).

        Returns
        -------
        numpy.ndarray
            y[k, output] in the model's units.
        """
        ...


@runtime_checkable
class PoleModel(Protocol):
    """A model with labelled poles (what the modal costs pair measured modes with)."""

    def poles(self, *, max_hz: float | None = None) -> list[ClosedLoopPole]:
        """Poles with Im >= 0 up to ``max_hz`` [Hz] (default: all), labelled by the modes they live in.

        Parameters
        ----------
        max_hz : float, optional
            The highest pole frequency kept [Hz]; None keeps every pole.
        """
        ...
