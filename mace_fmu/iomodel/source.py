"""The modal source of a volts-volts model: what the model, the FMU writers and the viewer ask of the modes.

Two sources implement it: a deck's modes (:class:`~mace_fmu.fe.modes.StructureModes`, from
:func:`~mace_fmu.fe.modes.compute_modes`) and NASTRAN's own (:class:`~mace_fmu.iomodel.modal_source.ModalStructure`,
from :func:`~mace_fmu.iomodel.modal_source.modal_structure`). The pipeline never asks which one it holds: it asks
the source (its name, its instruments' file, a strain gauge's weights, its mass, its static correction, the
physical parameters it offers, what it draws), and each answers for itself, refusing with the reason what it
cannot give (a bar strain gauge or a modulus of NASTRAN's modes).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from mace_fmu.fe.modal import Modes
from mace_fmu.parameters.sets import ParameterSet
from mace_fmu.structure.drawing import Drawing
from mace_fmu.structure.file import SourceConfiguration, StructureFile

if TYPE_CHECKING:
    from mace_fmu.fe.modes import StructureModes
    from mace_fmu.iomodel.instruments import Instruments

Dof = tuple[int, int, float]  #: (grid, component 1-6 in the grid's CD system, weight)


class ModalSource(Protocol):
    """The modes a volts-volts model is built from, and what they offer besides (module docstring)."""

    @property
    def modes(self) -> Modes:
        """Frequencies [Hz], mass-normalised shapes on the basic DOFs, and labels."""

    @property
    def parameters(self) -> ParameterSet | None:
        """The parameter set the modes were computed or read with, which models take by default."""

    @property
    def name(self) -> str:
        """What the source's models and FMUs are named after: "MACE", a deck's or a modes file's stem."""

    @property
    def source(self) -> Path:
        """The file the modes come from: the deck, or NASTRAN's modes file."""

    @property
    def configuration(self) -> SourceConfiguration:
        """What the modes are of: the deck's "1g" or "0g" structure, or NASTRAN's "modes"."""

    @property
    def frequencies_hz(self) -> np.ndarray:
        """Natural frequencies [Hz] of the modes."""

    @property
    def labels(self) -> tuple[str, ...]:
        """One label per mode."""

    @property
    def rank_frequencies_hz(self) -> np.ndarray:
        """The frequencies [Hz] per-mode data keyed by rank are ranked by."""

    @property
    def grid_ids(self) -> tuple[int, ...]:
        """Every grid the modes move (the ones whose motion can be an output)."""

    @property
    def physical_kinds(self) -> tuple[str, ...]:
        """The physical parameter kinds ("modulus", "spring", "mass") whose sensitivities the source gives."""

    @property
    def mass(self) -> Any | None:
        """The mass matrix on the basic DOFs [kg, kg m^2] (None: the source has none to check against)."""

    @property
    def constraint_transform(self) -> Any | None:
        """The constraints' T (basic = T @ independent); None: every DOF independent."""

    @property
    def solved_structure(self) -> StructureModes | None:
        """The FE solution behind the modes, which an FMU solves again for new physical parameters
        (:mod:`mace_fmu.iomodel.resolve`); None: modes read from a file, nothing to solve."""

    def title(self, what: str) -> str:
        """``what`` of this source as model summaries say it, e.g. "MACE 0g volts-volts model"."""

    def instrument_file(self) -> StructureFile:
        """The structure file declaring the actuators and sensors; a MaceError saying where to declare them."""

    def bar_strain_weights(self, *, bar_id: int, position: float, fiber_y_m: float,
                           fiber_z_m: float) -> tuple[Dof, ...]:
        """A bar strain gauge's DOF weights; a MaceError when the source has no such bar."""

    def check_parameters(self, parameters: ParameterSet | None) -> None:
        """A MaceError when the set names a physical parameter the source cannot have."""

    def check_computed_with(self, parameters: ParameterSet) -> None:
        """A MaceError when the set's physical values differ from those the modes were computed with."""

    def check_physical(self, names: Sequence[str]) -> None:
        """A MaceError when an FMU is asked for physical parameters ``names`` the source cannot give."""

    def static_correction(self, instruments: Instruments) -> np.ndarray | None:
        """(n_sensors, n_actuators) static feedthrough of the modes the source lacks (None: none)."""

    def drawing(self) -> Drawing:
        """What the viewer draws: lines and points on the grids, and the box the camera frames."""
