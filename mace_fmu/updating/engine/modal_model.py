"""A model as the modal costs read it: natural frequencies, damping ratios and mass-normalised shapes at the
measured DOFs (thesis 4.2.1's first technique compares these with a measurement model's)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.iomodel.poles import ClosedLoopPole


@dataclass(frozen=True, eq=False)
class ModalModel:
    """Modes of a structure at some parameter values, seen at the measured DOFs.

    ``poles()`` gives them as :class:`~mace_fmu.iomodel.poles.ClosedLoopPole` (one per mode, labelled, ``mode``
    its column in ``shapes``), so :class:`~mace_fmu.updating.engine.costs.ModalCost` reads this model as it reads
    a state-space one.
    """

    frequencies_hz: np.ndarray  #: natural frequencies [Hz]
    damping: np.ndarray  #: modal damping ratios
    labels: tuple[str, ...]  #: one per mode
    dofs: tuple[str, ...]  #: the measured DOFs, the rows of ``shapes``
    shapes: np.ndarray  #: (DOF, mode) mass-normalised shapes [1/sqrt(kg)] at the measured DOFs
    parameter_values: Mapping[str, float] = field(default_factory=dict)  #: the values it was solved at

    def __post_init__(self) -> None:
        n = len(self.labels)
        if self.frequencies_hz.shape != (n,) or self.damping.shape != (n,) or self.shapes.shape != (len(self.dofs), n):
            raise MaceError(f"ModalModel: {n} labels, {self.frequencies_hz.shape} frequencies, {self.damping.shape} "
                            f"damping ratios, shapes {self.shapes.shape} for {len(self.dofs)} DOFs")

    def poles(self, *, max_hz: float | None = None) -> list[ClosedLoopPole]:
        """One pole per mode, Im >= 0, in the modes' order (ascending frequency)."""
        out = []
        for k, (f, z, label) in enumerate(zip(self.frequencies_hz, self.damping, self.labels)):
            if max_hz is not None and f > max_hz:
                continue
            w = 2 * np.pi * f
            out.append(ClosedLoopPole(frequency_hz=float(f), damping=float(z), label=label, share=1.0,
                                      eigenvalue=complex(-z * w, w * np.sqrt(max(1 - z * z, 0.0))), mode=k))
        return out
