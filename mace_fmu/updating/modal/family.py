"""Any deck and structure file as a parametrised family of modal models: full FE re-solves at the moduli, springs
and masses the structure file names, the modes seen at a test's measured DOFs.

Every solve after the first carries the first one's mode labels by MAC (as the MACE family does), so a measured
mode paired with a model mode by label stays with that mode while the parameters move.
"""

from __future__ import annotations

import dataclasses
import os
from collections import OrderedDict
from typing import Mapping, Sequence

import numpy as np

from mace_fmu.deck.cards import Deck
from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import StructureModes, compute_modes
from mace_fmu.fe.pairing import carry_labels
from mace_fmu.fe.preload import PreloadKind
from mace_fmu.iomodel.damping import modal_damping
from mace_fmu.iomodel.instruments import influence_vector, load_instruments
from mace_fmu.parameters.sets import ParameterSet, deck_values, parameter_kind, parameter_names
from mace_fmu.structure.file import Configuration, StructureFile, structure_file_for
from mace_fmu.updating.engine.modal_model import ModalModel
from mace_fmu.updating.modal.modes_file import Dof

Values = Mapping[str, float]
_CACHE_SIZE = 16  # a cost-sensitivity step: the base point and one perturbed point per parameter
#: what a full re-solve takes from a parameter set: the rest (damping ratios, delays, gains) is no FE parameter
PHYSICAL_KINDS = ("modulus", "spring", "mass")


def shapes_at(modes: StructureModes, dofs: Sequence[tuple[Dof, ...]]) -> np.ndarray:
    """(DOF, mode) mass-normalised shapes at the measured DOFs: each a weighted sum of (grid, component in the grid's
    displacement system), as a structure file's sensors read."""
    m = modes.modes
    rows = np.array([influence_vector(tuple(d), m.dofs, m.cd_frames) for d in dofs])
    return rows @ m.shapes


class StructureFamily:
    """The modes of a deck's 1-g or 0-g structure at any values of the parameters its structure file names.

    Parameters
    ----------
    deck : Deck or path
        The NASTRAN deck.
    structure_file : StructureFile or path, optional
        Its structure file (default: the bundled one for the bundled deck, else none).
    dofs : sequence of str
        The measured DOFs' names (the shapes' rows).
    dof_places : sequence of tuple of Dof
        Where each measured DOF is: (grid, component, weight) triples.
    configuration : {"1g", "0g"}
        The structure solved.
    base : ParameterSet, optional
        Values every solve starts from (e.g. an earlier update's).
    max_hz : float, optional
        Highest mode [Hz] (default: the deck's EIGRL).
    preload : {"large", "linear"}
        The 1-g preload.
    """

    def __init__(self, *, deck: Deck | str | os.PathLike, structure_file: StructureFile | str | os.PathLike | None,
                 dofs: Sequence[str], dof_places: Sequence[tuple[Dof, ...]], configuration: Configuration = "1g",
                 base: ParameterSet | None = None, max_hz: float | None = None, preload: PreloadKind = "large"):
        self.deck = deck if isinstance(deck, Deck) else read_deck(deck)
        self.structure_file = structure_file_for(self.deck, structure_file)
        self.dofs = tuple(dofs)
        self.dof_places = tuple(tuple(p) for p in dof_places)
        self.configuration = configuration
        self.base = base if base is not None else ParameterSet()
        self.max_hz = max_hz
        self.preload = preload
        self.names = parameter_names(self.deck, self.structure_file)
        self._deck_values = deck_values(self.deck, self.names)
        self.physical = tuple(self._deck_values)  #: every modulus, spring and mass a value can be given for
        unknown = [n for n in self.base.values if parameter_kind(n) in PHYSICAL_KINDS and n not in self._deck_values]
        if unknown:
            raise MaceError(f"{self.base.source or 'parameter set'}: {', '.join(unknown)}: no such parameter of "
                            f"{self.where}; it has {', '.join(self.physical) or 'none'}")
        self._damping = load_instruments(self.structure_file).damping if self.structure_file is not None else None
        self._cache: OrderedDict[tuple, tuple[StructureModes, ModalModel]] = OrderedDict()
        self._reference: StructureModes | None = None
        self.solves = 0  #: FE solves done
        self._reference = self.solve(self.base.values)[0]

    @property
    def where(self) -> str:
        """The deck and structure file, for messages."""
        deck = str(self.deck.path).rsplit("/", 1)[-1] if self.deck.path else "the deck"
        file = f" with {self.structure_file.path.name}" if self.structure_file is not None else ""
        return f"{deck}{file}"

    def physical_values(self, values: Values) -> dict[str, float]:
        """Every modulus, spring and mass at ``values`` (the base set's, then the deck's where not given)."""
        params = self.base.updated(values)
        return {**self._deck_values, **params.of_kind(*PHYSICAL_KINDS)}

    def check_names(self, names: Sequence[str]) -> None:
        """Every name is a modulus, spring or mass of the structure file's ``[parameters]``."""
        bad = [n for n in names if n not in self._deck_values]
        if bad:
            raise MaceError(f"--update {', '.join(bad)}: not a parameter of {self.where}; its moduli, springs and "
                            f"masses (the structure file's [parameters]) are {', '.join(self.physical) or 'none'}")

    def solve(self, values: Values) -> tuple[StructureModes, ModalModel]:
        """The FE solve at ``values`` and its modal model at the measured DOFs (cached)."""
        physical = self.physical_values(values)
        key = tuple(sorted(physical.items()))
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        modes = compute_modes(self.deck, configuration=self.configuration, preload=self.preload, max_hz=self.max_hz,
                              parameters=ParameterSet(physical), structure_file=self.structure_file)
        if self._reference is not None:  # labels follow the modes, not the solve's own labelling
            ref = self._reference
            modes = dataclasses.replace(modes, modes=carry_labels(ref.modes, ref.model, modes.modes))
        f = np.asarray(modes.frequencies_hz, dtype=float)
        labels = tuple(modes.labels)
        zeta = modal_damping(labels, f, self._damping) if self._damping is not None else np.zeros(len(labels))
        model = ModalModel(frequencies_hz=f, damping=zeta, labels=labels, dofs=self.dofs,
                           shapes=shapes_at(modes, self.dof_places), parameter_values=physical)
        self.solves += 1
        self._cache[key] = (modes, model)
        if len(self._cache) > _CACHE_SIZE:
            self._cache.popitem(last=False)
        return modes, model

    # --- the ModelFamily interface -------------------------------------------------------------
    def full(self, values: Values) -> ModalModel:
        """The modal model at ``values`` by a complete FE re-solve (cached by the physical values).

        The family has no modal basis (no ``basis``): the perturbed models of the cost-sensitivity method are
        full re-solves (thesis 4.2.1: "this method uses the perturbed finite element models")."""
        return self.solve(values)[1]

    def current_values(self, names: Sequence[str]) -> dict[str, float]:
        """Values [SI] of ``names`` at the base point."""
        self.check_names(names)
        physical = self.physical_values({})
        return {n: physical[n] for n in names}

    def fresh_labels(self, values: Values) -> dict[str, str]:
        """Carried label -> the label a fresh solve at ``values`` gives the same mode (what an export sees)."""
        carried, _ = self.solve(values)
        fresh = compute_modes(self.deck, configuration=self.configuration, preload=self.preload, max_hz=self.max_hz,
                              parameters=ParameterSet(self.physical_values(values)), structure_file=self.structure_file)
        relabelled = carry_labels(fresh.modes, fresh.model, carried.modes)
        return dict(zip(carried.labels, relabelled.labels))

