"""The MACE volts-volts model as a parametrised family: full re-solves, reanalysis, modal coordinates.

Parameter names are those of :mod:`mace_fmu.parameters.sets`. The FE solve depends only on the
moduli and springs, so it is cached by their values; damping ratios, delays and servo gains
then enter exactly through the blocks of a :class:`~mace_fmu.iomodel.parametric.ParametricSystem`
(the FMUs' own rebuild), so a change of damping costs a block rebuild, not an FE solve. Every
solve after the first carries the first one's mode labels by MAC, so damping ratios keyed by
label stay with their modes (a recomputed label can jump to another mode: the cost would jump).
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Mapping, Sequence

import numpy as np

from mace_fmu.deck.cards import Deck
from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.modes import DEFAULT_MAX_HZ, StructureModes, compute_modes
from mace_fmu.fe.preload import PreloadKind
from mace_fmu.iomodel.parametric import ParametricSystem
from mace_fmu.iomodel.parametric_data import parametric_arrays, with_physical
from mace_fmu.iomodel.stiffness_route import StiffnessSensitivity, physical_route, stiffness_sensitivities
from mace_fmu.iomodel.volts import VoltsModel, volts_model
from mace_fmu.parameters.kinds import DAMPING, mode_reference
from mace_fmu.parameters.per_mode import label_mode_names, resolve_mode_names
from mace_fmu.parameters.sets import ParameterSet, deck_values, parameter_kind
from mace_fmu.structure.file import Configuration, bundled_deck_path
from mace_fmu.updating.engine.linear_model import LinearModel

Values = Mapping[str, float]
_CACHE_SIZE = 4  # base point, perturbed points of a modal-sensitivity step come and go


class MaceSolution:
    """One FE solve and what was built from it; reanalysis data per parameter, only when asked for."""

    def __init__(self, volts: VoltsModel, physical: Mapping[str, float]):
        self.volts = volts
        self.physical = dict(physical)  #: moduli and springs [Pa, N/m] of this solve
        self._arrays = parametric_arrays(volts, physical=False)
        self.system = ParametricSystem(self._arrays)  #: rebuilds for damping ratios, delays and gains
        self._sensitivities: dict[str, StiffnessSensitivity] = {}
        self._systems: dict[tuple[str, ...], ParametricSystem] = {}

    def reanalysis(self, names: Sequence[str]) -> ParametricSystem:
        """The system that also re-analyses the moduli and springs ``names`` (stiffness sensitivities
        computed once per name: each costs a tangent of that material's bars; the static corrections
        once per set of names)."""
        key = tuple(sorted(names))
        if key not in self._systems:
            missing = [n for n in key if n not in self._sensitivities]
            if missing:
                self._sensitivities.update({s.name: s for s in stiffness_sensitivities(self.volts, only=missing)})
            keep = self.volts.structure_modes.frequencies_hz <= np.max(self.volts.plant.frequencies_hz)
            shapes = self.volts.structure_modes.modes.shapes[:, keep]
            route = physical_route(self.volts, shapes, [self._sensitivities[n] for n in key])
            self._systems[key] = ParametricSystem(with_physical(self._arrays, route))
        return self._systems[key]


def linear_model(system: ParametricSystem, vector: np.ndarray, **modes) -> LinearModel:
    """The LinearModel of ``system`` at parameter vector ``vector`` (FMU order); ``modes`` as in build()."""
    a, b, c, d = system.build(vector, **modes)
    return LinearModel(a=a, b=b, c=c, d=d, inputs=tuple(system.inputs), outputs=tuple(system.outputs),
                       state_names=tuple(system.state_names), mode_labels=tuple(system.state_mode_labels))


class MaceFamily:
    """The 1-g or 0-g volts-volts model (servos closed) at any parameter values."""

    def __init__(self, *, configuration: Configuration = "1g", base: ParameterSet | None = None,
                 deck: Deck | str | None = None, preload: PreloadKind = "large", max_hz: float = DEFAULT_MAX_HZ):
        self.configuration = configuration
        self.base = base if base is not None else ParameterSet()
        self.deck = deck if isinstance(deck, Deck) else read_deck(deck if deck is not None else bundled_deck_path())
        self.preload = preload
        self.max_hz = max_hz
        self._cache: OrderedDict[tuple, MaceSolution] = OrderedDict()
        self._deck_values = deck_values(self.deck)  # the cache keys on every modulus and spring, given or not
        self._reference: MaceSolution | None = None  # the base point's solution
        self.solves = 0  #: FE solves done (for benchmarks)
        #: the deck's own modes, which every solve continues (mode k of a solve is the physical mode of its k)
        self._deck_modes = compute_modes(self.deck, configuration=configuration, preload=preload, max_hz=max_hz)
        nominal = self.solution(self.base.values)
        self._reference = nominal
        # the update's values name modes by label; a base set by number (an FMU update's) is put in the same
        # spelling once, so that an updated value replaces the base's rather than meeting it as a second name
        self.base = ParameterSet(label_mode_names(self.base.values, mode_labels=nominal.system.mode_labels,
                                                  model=f"{configuration} model", source=self.base.source),
                                 self.base.provenance, source=self.base.source)
        # moduli and springs of the analysed structure (0-g has no suspension springs)
        self.physical = tuple(deck_values(nominal.volts.structure_modes.structure.deck))

    # --- solving --------------------------------------------------------------------------------
    def parameter_set(self, values: Values) -> ParameterSet:
        """The base set with ``values`` replacing its entries."""
        return self.base.updated(values)

    def solution(self, values: Values) -> MaceSolution:
        """The FE solve at the moduli and springs of ``values`` (cached)."""
        params = self.parameter_set(values)
        physical = {**self._deck_values, **params.of_kind("modulus", "spring", "mass")}
        key = tuple(sorted(physical.items()))
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        # every solve continues the deck's own modes, as mace-fmu model and export --parameters do: labels (and
        # the damping ratios keyed by them) follow the physical mode, and the update's model is theirs
        modes = compute_modes(self.deck, configuration=self.configuration, preload=self.preload, max_hz=self.max_hz,
                              parameters=params, continue_from=self._deck_modes)
        volts = volts_model(modes, parameters=self._non_modal(params), max_hz=self.max_hz)
        solution = MaceSolution(volts, physical)
        self.solves += 1
        self._cache[key] = solution
        if len(self._cache) > _CACHE_SIZE:
            self._cache.popitem(last=False)
        return solution

    def _non_modal(self, params: ParameterSet) -> ParameterSet:
        """The base set's damping, delays and gains (the arrays' nominal block values)."""
        return ParameterSet(params.of_kind("delay", "gain", "damping"))

    def vector(self, system: ParametricSystem, values: Values) -> np.ndarray:
        """The FMU-ordered parameter vector of ``system`` with ``values`` (and the base set) written in."""
        vec = system.nominal.copy()
        params = self.parameter_set(values)
        for name, value in resolve_mode_names(params.values, mode_labels=system.mode_labels,
                                              model=f"{self.configuration} model", source=params.source,
                                              available=set(system.parameter_names)).items():
            kind = parameter_kind(name)
            if kind in ("modulus", "spring", "mass"):
                if name in system.parameter_names:  # the reanalysis system; the others were solved with them
                    vec[system.index(name)] = value
            else:
                try:
                    vec[system.index(name)] = value
                except KeyError:
                    raise MaceError(f"parameter {name!r} is not a parameter of the {self.configuration} "
                                    "model") from None
        return vec

    # --- the ModelFamily interface ---------------------------------------------------------------
    def full(self, values: Values) -> LinearModel:
        """Complete re-solve at ``values`` (the FE part cached by moduli and springs)."""
        sol = self.solution(values)
        return linear_model(sol.system, self.vector(sol.system, values))

    def basis(self, values: Values) -> MaceBasis:
        return MaceBasis(family=self, solution=self.solution(values))

    def current_values(self, names: Sequence[str]) -> dict[str, float]:
        """Values [SI] of ``names`` at the base point: the base set's, else the deck's and the data file's."""
        sol = self.solution(self.base.values)
        out = {}
        for n in names:
            if n in self.base:
                out[n] = self.base[n]
            elif n in self._deck_values:
                out[n] = self._deck_values[n]
            elif mode_reference(n) is not None:  # the first of its modes (a label may name several)
                first, *_ = resolve_mode_names({n: 0.0}, mode_labels=sol.system.mode_labels,
                                               model=f"{self.configuration} model",
                                               available=set(sol.system.parameter_names))
                out[n] = float(sol.system.nominal[sol.system.index(first)])
            elif n in sol.system.parameter_names:
                out[n] = float(sol.system.nominal[sol.system.index(n)])
            else:
                raise MaceError(f"parameter {n!r} is not a parameter of the {self.configuration} model")
        return out

    def values_for_rebuild(self, values: Values) -> dict[str, float]:
        """``values`` plus the damping ratios a model built afresh from them needs to be this model.

        A re-solve here continues the deck's own modes, and so does ``volts_model`` with a parameter
        set (``compute_modes``'s default): the damping ratios keyed by label land on the same modes.
        Checked by rebuilding; a mode whose damping would still differ gets its ratio under the
        rebuild's label.
        """
        system = self.solution(values).system
        vector = self.vector(system, values)
        carried = np.array([vector[system.index(DAMPING.fmu_name(k + 1))] for k in range(len(system.mode_labels))])
        out = dict(values)
        for _ in range(3):
            fresh = volts_model(compute_modes(self.deck, configuration=self.configuration, preload=self.preload,
                                              max_hz=self.max_hz, parameters=self.parameter_set(out),
                                              continue_from=self._deck_modes)).plant
            differ = np.flatnonzero(fresh.damping != carried)
            if not differ.size:
                return out
            out.update({DAMPING.set_name(fresh.labels[k]): float(carried[k]) for k in differ})
        raise MaceError("the updated damping ratios cannot be keyed by the labels of a fresh solve "
                        f"(modes {', '.join(fresh.labels[k] for k in differ)})")

    def volts_model(self, values: Values) -> VoltsModel:
        """The full volts-volts model (python-control, exact FRF) at ``values``."""
        params = self.parameter_set(values)
        return volts_model(self.solution(values).volts.structure_modes, parameters=params, max_hz=self.max_hz)


class MaceBasis:
    """Modes of one base point: reanalysis and modal coordinates about it."""

    def __init__(self, *, family: MaceFamily, solution: MaceSolution):
        self.family = family
        self.solution = solution
        self.physical = family.physical
        modes: StructureModes = solution.volts.structure_modes
        keep = modes.frequencies_hz <= family.max_hz
        self._phi0 = modes.modes.shapes[:, keep]
        self._mass = modes.model.mass

    def model(self, values: Values, *, frequencies_hz: np.ndarray | None = None,
              phi_r: np.ndarray | None = None) -> LinearModel:
        if frequencies_hz is not None:  # modes given: nothing to re-analyse
            system, extra = self.solution.system, {"frequencies_hz": frequencies_hz, "phi_r": phi_r}
        else:
            at = self.family.parameter_set(values).values
            changed = [n for n in self.physical if n in at and at[n] != self.solution.physical[n]]
            system, extra = (self.solution.reanalysis(changed) if changed else self.solution.system), {}
        return linear_model(system, self.family.vector(system, values), **extra)

    def modes_of(self, values: Values) -> tuple[np.ndarray, np.ndarray]:
        fam = self.family
        modes = compute_modes(fam.deck, configuration=fam.configuration, preload=fam.preload, max_hz=1.1 * fam.max_hz,
                              parameters=fam.parameter_set(values), continue_from=None)
        return modes.frequencies_hz, self._phi0.T @ self._mass @ modes.modes.shapes
