"""Deck -> structure -> (gravity preload) -> modes with labels and mass properties: one route."""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from mace_fmu.deck.cards import Deck, Eigr, Eigrl
from mace_fmu.deck.geometry import coordinate_frames
from mace_fmu.deck.reader import read_deck
from mace_fmu.errors import MaceError
from mace_fmu.fe.assembly import FEModel, assemble
from mace_fmu.fe.autospc import autospc_enabled, constrain_singular_dofs
from mace_fmu.fe.bar_strain import bar_strain_weights
from mace_fmu.fe.beam import MassKind
from mace_fmu.fe.constraints import Constraints, build_constraints
from mace_fmu.fe.drawing import deck_drawing
from mace_fmu.fe.labels import label_modes, rigid_body_vectors
from mace_fmu.fe.modal import Modes, ModesView, solve_modes
from mace_fmu.fe.pairing import continue_modes
from mace_fmu.fe.preload import Preload, PreloadKind, large_displacement_preload, linear_preload
from mace_fmu.parameters.kinds import MASS, MODULUS, SPRING, declared_range
from mace_fmu.parameters.sets import (ParameterNames, ParameterSet, deck_fingerprint, deck_values, fe_overrides,
                                      naming_the_file, parameter_names, parameter_unit)
from mace_fmu.structure.build import Structure, build_structure
from mace_fmu.structure.drawing import Drawing
from mace_fmu.structure.file import (Configuration, StructureFile, bundled_deck_path, structure_file_for,
                                     structure_label)
from mace_fmu.util.collector import collector_paused
from mace_fmu.util.frequency import DEFAULT_MAX_HZ, ZERO_HZ
from mace_fmu.util.progress import ProgressCallback
from mace_fmu.util.threads import single_blas_thread



#: the parameter kinds that need the FE (moduli, springs, masses): a deck's modes offer them, NASTRAN's cannot
FE_PARAMETER_KINDS = tuple(kind.name for kind in (MODULUS, SPRING, MASS))

#: a re-solve that continues other modes looks this much further (in frequency and in count) for them
_CONTINUATION_REACH = 1.5


@dataclass(frozen=True)
class MassProperties:
    """Rigid-body mass properties of a structure (NASTRAN's grid point weight generator)."""

    mass_kg: float  #: total mass [kg]
    center_of_mass_m: np.ndarray  #: (3,) in basic
    inertia_about_reference_kgm2: np.ndarray  #: (3, 3) about ``reference_point_m``, basic axes
    reference_grid: int | None  #: PARAM,GRDPNT grid (None: basic origin)
    reference_point_m: np.ndarray  #: point the inertia is about [m], basic


@dataclass(frozen=True)
class StructureModes(ModesView):
    """Everything one modal analysis produces, for tables, state-space models and the viewer."""

    structure: Structure  #: the 1-g or 0-g structure (deck, subcases, structure file) the modes are of
    model: FEModel  #: the FE matrices [N/m, kg] on the basic DOFs
    modes: Modes  #: frequencies [Hz], mass-normalised shapes and labels
    mass_properties: MassProperties  #: mass [kg], centre of mass [m] and inertia [kg m^2]
    preload: Preload | None  #: the gravity preload (1-g; None for 0-g)
    #: (grid, component) DOFs constrained automatically (PARAM,AUTOSPC): neither stiffness nor mass
    auto_constrained: tuple[tuple[int, int], ...] = ()
    #: the modal subcase's constraints (SPC, MPC, rigid elements, AUTOSPC): the shapes are T @ phi_independent
    constraints: Constraints | None = None
    #: the parameter set the modes were computed with (its moduli and springs are in ``structure.deck``)
    parameters: ParameterSet | None = None
    #: the frequencies [Hz] of the modes these continue (a parameter set's re-solve: mode k is the physical mode
    #: the nominal structure's mode k became, :func:`~mace_fmu.fe.pairing.continue_modes`); data keyed by a
    #: mode's rank (a violin family's damping ratios) follow it by these. None: modes of their own
    reference_frequencies_hz: np.ndarray | None = None

    @property
    def rank_frequencies_hz(self) -> np.ndarray:
        """The frequencies [Hz] per-mode data are ranked by: the continued modes' where these continue others."""
        return self.reference_frequencies_hz if self.reference_frequencies_hz is not None else self.frequencies_hz

    @property
    def configuration(self) -> Configuration:
        """"1g" or "0g": the structure the modes are of."""
        return self.structure.configuration

    @property
    def deck(self) -> Deck:
        """The deck the modes are of (0-g: without the suspension; with the parameter set's moduli)."""
        return self.structure.deck

    @property
    def stiffness(self):
        """The stiffness the modes are of [N/m, N m/rad], basic DOFs: the preload's tangent (1-g) or K."""
        return self.preload.tangent_stiffness if self.preload is not None else self.model.stiffness

    # the modal source a volts-volts model asks (mace_fmu.iomodel.source.ModalSource)

    @property
    def name(self) -> str:
        """"MACE" for the bundled deck's modes, else the deck file's stem: their models and FMUs are named after it."""
        return structure_label(self.deck)

    @property
    def source(self) -> Path:
        """The deck the modes are of."""
        return Path(self.deck.path)

    @property
    def grid_ids(self) -> tuple[int, ...]:
        """Every grid of the structure (the ones whose motion can be an output)."""
        return tuple(self.modes.dofs.grid_ids)

    @property
    def physical_kinds(self) -> tuple[str, ...]:
        """The physical parameter kinds a deck's modes give sensitivities to: moduli, springs and masses."""
        return FE_PARAMETER_KINDS

    @property
    def mass(self):
        """The mass matrix on the basic DOFs [kg, kg m^2]."""
        return self.model.mass

    @property
    def constraint_transform(self):
        """The modal subcase's constraints' T (basic = T @ independent); None: every DOF independent."""
        return None if self.constraints is None else self.constraints.transform

    @property
    def solved_structure(self) -> StructureModes:
        """This FE solution: the modes' structure can be solved again for new physical parameters."""
        return self

    def title(self, what: str) -> str:
        """"<structure> <configuration> <what>", e.g. "MACE 0g volts-volts model": hosts and ``view response
        --fmu`` read which structure and configuration an FMU's model is.

        Parameters
        ----------
        what : str
            What of the modes is titled ("volts-volts model").
        """
        return f"{self.name} {self.configuration} {what}"

    def instrument_file(self) -> StructureFile:
        """The structure file declaring the deck's actuators and sensors; a MaceError when there is none."""
        file = self.structure.file
        if file is None or not file.has("actuators") or not file.has("sensors"):
            raise MaceError(f"{self.deck.path}: a volts-volts model needs actuators and sensors, and this "
                            "deck has no structure file declaring them (give one: "
                            "compute_modes(..., structure_file=...), CLI --structure FILE; the bundled mace_em.toml "
                            "belongs to the bundled MACE deck only)")
        return file

    def bar_strain_weights(self, *, bar_id: int, position: float, fiber_y_m: float,
                           fiber_z_m: float) -> tuple[tuple[int, int, float], ...]:
        """A bar strain gauge's DOF weights on the deck's bar (:func:`mace_fmu.fe.bar_strain.bar_strain_weights`).

        Parameters
        ----------
        bar_id : int
            The CBAR the gauge is on.
        position : float
            Where along it, 0 at GA to 1 at GB.
        fiber_y_m, fiber_z_m : float
            The gauge's offsets from the neutral axis [m], element y and z.
        """
        return bar_strain_weights(self.model, self.deck, bar_id=bar_id, position=position, fiber_y_m=fiber_y_m,
                                  fiber_z_m=fiber_z_m)

    def check_parameters(self, parameters: ParameterSet | None) -> None:
        """A MaceError when the set's moduli, springs or masses name no card of the deck.

        Parameters
        ----------
        parameters : ParameterSet or None
            The set a model is built with (None: nothing to check).
        """
        fe_overrides(parameters, parameter_names(self.deck, self.structure.file))

    def check_computed_with(self, parameters: ParameterSet) -> None:
        """A MaceError when the set's moduli, springs or masses differ from those the modes were computed with
        (they would be ignored).

        Parameters
        ----------
        parameters : ParameterSet
            The set a model of these modes is asked to be built with.
        """
        deck = self.deck
        for (card, cid), fields in fe_overrides(parameters, parameter_names(deck, self.structure.file)).items():
            entry = {"MAT1": deck.mat1s, "CELAS2": deck.celas2s, "CONM2": deck.conm2s}[card][cid]
            for key, value in fields.items():
                if key == "inertia":  # a mass's inertias follow its mass
                    continue
                computed = float(getattr(entry, key))
                if abs(computed - value) > 1e-12 * abs(value):
                    raise MaceError(f"parameters set {card} {cid} {key} = {value:.6g} but the modes were computed "
                                    f"with {computed:.6g}; compute the modes with the same parameters "
                                    "(compute_modes(..., parameters=...)), whose set the model then takes by default")

    def check_physical(self, names: Sequence[str]) -> None:
        """Nothing to refuse: a deck's moduli, springs and masses are checked where their sensitivities are taken.

        Parameters
        ----------
        names : sequence of str
            The physical parameters an FMU is asked for.
        """

    def static_correction(self, instruments: object) -> None:
        """None: a deck's modes have no static correction (every mode up to the model's is computed).

        Parameters
        ----------
        instruments : Instruments
            The model's actuators and sensors (not needed here).
        """

    def drawing(self) -> Drawing:
        """Each CBAR a tube, each CONM2 a sphere, framed on the test article
        (:func:`mace_fmu.fe.drawing.deck_drawing`)."""
        return deck_drawing(self)


def mass_properties(model: FEModel, deck: Deck) -> MassProperties:
    """Mass, centre of mass and inertia about PARAM,GRDPNT (basic origin when absent)."""
    grdpnt = deck.params.get("GRDPNT")
    ref_grid = int(grdpnt.values[0]) if grdpnt is not None and int(grdpnt.values[0]) > 0 else None
    ref = model.positions[model.dofs.grid_index(ref_grid)] if ref_grid is not None else np.zeros(3)
    d = rigid_body_vectors(model, ref)
    m6 = d.T @ model.mass @ d
    mass = m6[0, 0]
    # m6[0:3, 3:6] = -m skew(c - ref): read the centre of mass off its off-diagonal terms
    offset = np.array([m6[1, 5], m6[2, 3], m6[0, 4]]) / mass if mass > 0 else np.zeros(3)
    return MassProperties(mass_kg=float(mass), center_of_mass_m=ref + offset, inertia_about_reference_kgm2=m6[3:, 3:],
                          reference_grid=ref_grid, reference_point_m=ref)


def gravity_load(deck: Deck, model: FEModel, load_id: int) -> np.ndarray:
    """Load vector [N, N m] of a LOAD (or a GRAV) set: M times the uniform acceleration field."""
    return model.mass @ gravity_field(deck, model, load_id)


def gravity_field(deck: Deck, model: FEModel, load_id: int) -> np.ndarray:
    """The uniform acceleration of a LOAD (or a GRAV) set on every grid's translations, zero on the rotations.

    A mass matrix times it is the set's load (:func:`gravity_load`), so a mass change dM changes the load
    by dM times it (a mass parameter's weight, mace_fmu.iomodel.stiffness_route).

    Parameters
    ----------
    deck : Deck
        The deck with the GRAV and LOAD cards.
    model : FEModel
        Its FE model (the DOFs of the result).
    load_id : int
        The LOAD or GRAV set ID.

    Returns
    -------
    numpy.ndarray
        (n_dof,) acceleration [m/s^2] in basic axes on the translations, 0 on the rotations.
    """
    if load_id in deck.loads:
        card = deck.loads[load_id]
        terms = [(card.scale * s, sid) for s, sid in card.terms]
    else:
        terms = [(1.0, load_id)]
    frames = coordinate_frames(deck)
    accel = np.zeros(3)
    for scale, sid in terms:
        if sid not in deck.gravs:
            what = f"a {' and '.join(deck.static_loads[sid])} set" if sid in deck.static_loads else "not a GRAV card"
            raise MaceError(f"{deck.path}: load set {load_id}: set {sid} is {what}; the 1-g preload takes gravity "
                            "loads only (GRAV), "
                            "and the 0-g modes take no load")
        grav = deck.gravs[sid]
        accel += scale * grav.scale * (frames[grav.cid][1] @ np.array(grav.direction))
    field = np.zeros((len(model.positions), 6))
    field[:, :3] = accel
    return field.ravel()


def _eigrl(deck: Deck, structure: Structure):
    """The EIGRL (or EIGR) card the modal subcase's METHOD selects (None without one)."""
    method = structure.modal.method
    if method is None:
        return None
    return deck.eigrls.get(method) or deck.eigrs.get(method)


#: EIGR methods that reduce to a tridiagonal matrix and find every root: NASTRAN prints them all, and ND, when
#: given, is the number of lowest roots whose vectors it computes whatever F1 and F2 say (QRG, EIGR remarks;
#: MSC's pt145 run, tests/data/nastran/pt145: F2 = 0.1 Hz and ND = 6 gave the six lowest modes, up to 1153 Hz)
_TRIDIAGONAL = ("GIV", "MGIV", "HOU", "MHOU", "AHOU")


def _eigen_request(card: Eigrl | Eigr | None) -> tuple[str, float | None, float | None, int | None]:
    """(name, V1 [Hz], V2 [Hz], ND) of the deck's eigenvalue request card, in NASTRAN's meaning."""
    if card is None:
        return "", None, None, None
    if isinstance(card, Eigr):  # EIGR: F1, F2, ND
        name, v1, v2, nd = f"EIGR {card.sid} {card.method}", card.f1, card.f2, card.nd
        if card.method in _TRIDIAGONAL and nd:
            v1 = v2 = None
        return name, v1, v2, nd
    return f"EIGRL {card.sid}", card.v1, card.v2, card.nd


def _modes_to_find(deck: Deck, structure: Structure, max_hz: float | None) -> tuple[float | None, int | None]:
    """(frequency [Hz], count) the eigen-solution must reach for :func:`_requested_modes` to pick from."""
    if max_hz is not None:
        return max_hz, None
    _, _, v2, nd = _eigen_request(_eigrl(deck, structure))
    if v2 is not None or nd:
        # with V1 too, the sparse route finds the lowest ND and V1 then drops some: NASTRAN would shift
        # to V1 instead; a large model with V1 and ND but no V2 may get fewer than ND modes
        return v2, nd or None
    return DEFAULT_MAX_HZ, None


def _requested_modes(modes: Modes, deck: Deck, structure: Structure, max_hz: float | None) -> Modes:
    """The modes the analysis asks for: up to ``max_hz`` when given, else as the deck's EIGRL asks
    (NASTRAN's meaning: frequencies in [V1, V2], the lowest ND of them), else up to 250 Hz.

    A MaceError when that leaves no mode, saying what was asked and where the modes are.
    """
    card = _eigrl(deck, structure)
    f = modes.frequencies_hz
    name, v1, v2, nd = _eigen_request(card)
    if max_hz is not None:
        keep, asked = f <= max_hz, f"up to {max_hz:g} Hz"
    elif card is not None and (v1 is not None or v2 is not None or nd):
        keep = np.ones(len(f), dtype=bool)
        if v1 is not None:
            keep &= f >= v1
        if v2 is not None:
            keep &= f <= v2
        if nd:
            keep &= np.cumsum(keep) <= nd
        asked = f"{name} (V1 = {v1}, V2 = {v2}, ND = {nd}; {card.source.file}:{card.source.line})"
    else:
        keep, asked = f <= DEFAULT_MAX_HZ, f"up to {DEFAULT_MAX_HZ:g} Hz (no EIGRL in the deck)"
    if not keep.any():
        lowest = f"; its lowest mode is at {f.min():.6g} Hz" if len(f) else ""
        raise MaceError(f"{deck.path}: no modes in the range asked for, {asked}{lowest} (set the range with "
                        "max_hz / --max-hz, or the deck's EIGRL)")
    return replace(modes, frequencies_hz=f[keep], shapes=modes.shapes[:, keep])


def check_parameters_deck(parameters: ParameterSet, deck: Deck) -> None:
    """A MaceError when ``parameters`` were made for another deck (its provenance's fingerprint)."""
    prov = parameters.provenance
    if prov is None or not prov.deck_sha256 or not Path(deck.path).is_file():
        return
    if deck_fingerprint(deck.path) != prov.deck_sha256:
        raise MaceError(f"the parameter set was made for deck {prov.deck!r} (sha256 {prov.deck_sha256[:12]}...), "
                        f"not for {deck.path}; refit it for this deck or remove its deck_sha256")


def _check_preload_elements(deck: Deck) -> None:
    """The gravity preload's tangent stiffness holds CBAR (corotational) and CELAS2 terms only: a deck with
    CBEAM or rod elements would lose their stiffness there, so it is refused rather than solved wrongly."""
    others: list[tuple[str, Mapping[int, Any]]] = [(name, table) for name, table in (("CBEAM", deck.beams),
                                                                             ("CROD/CONROD", deck.rods)) if table]
    if others:
        listed = ", ".join(f"{len(table)} {name} (first {next(iter(table.values())).source})" for name, table in others)
        raise MaceError(f"{deck.path}: the 1-g gravity preload models CBAR and CELAS2 elements only, and this deck "
                        f"has {listed}; compute the 0-g modes (configuration='0g'), or model them as CBARs")


@single_blas_thread
@collector_paused()  # a large deck's cards stay alive: the collector's passes would walk them all
def compute_modes(deck: Deck | str | os.PathLike | None = None, *, configuration: Configuration = "1g",
                  preload: PreloadKind = "large", mass: MassKind = "lumped", max_hz: float | None = None,
                  parameters: ParameterSet | None = None,
                  structure_file: StructureFile | str | os.PathLike | None = None,
                  progress: ProgressCallback | None = None,
                  continue_from: StructureModes | Literal["nominal"] | None = "nominal") -> StructureModes:
    """Modes of the 1-g or 0-g structure of a deck, labelled, with the structure's mass properties.

    Parameters
    ----------
    deck : Deck, path or None
        The NASTRAN deck (default: the bundled MACE deck).
    configuration : {"1g", "0g"}
        1-g: the deck's gravity subcase preloads the structure and the modes are those about the
        preloaded state; 0-g: the suspension the structure file names is removed, no preload.
    preload : {"large", "linear"}
        The 1-g preload: incremental Newton on the updated geometry, or linear prestress.
    mass : {"lumped", "consistent"}
        Bar mass matrices: lumped (NASTRAN's default) or consistent (NASTRAN's coupled mass, which a deck's
        PARAM,COUPMASS > 0 also selects).
    max_hz : float or None
        Highest mode [Hz]; by default the deck's EIGRL/EIGR decides (V1, V2, ND), else 250 Hz.
    parameters : ParameterSet, optional
        Moduli [Pa], spring stiffnesses [N/m] and masses [kg] by name (``E_<material>``, ``k_<spring>``,
        ``m_<mass>``); the modes keep
        the set, whose other entries (delays, gains, damping) :func:`~mace_fmu.iomodel.volts.volts_model` takes.
    structure_file : StructureFile, path or None
        What the deck does not say (see :mod:`mace_fmu.structure.file`): by default the bundled one for
        the bundled deck and none for any other deck, which then keeps NASTRAN's meaning (nothing
        removed; modes labelled by their motion, not by MACE's names).
    progress : callable, optional
        Called with a :class:`~mace_fmu.util.progress.Step` after each preload increment; nothing is
        printed (the increments are also logged at DEBUG level).
    continue_from : StructureModes, "nominal" or None
        With ``parameters`` that change moduli, springs or masses: the modes these continue. "nominal" (the
        default): the deck's own modes, solved first; mode k of the result is then the physical mode the
        nominal mode k became, with its label, as an FMU's parameter route keys them
        (:func:`~mace_fmu.fe.pairing.continue_modes`), so that an FMU exported with the set equals the
        nominal FMU with the set given through FMI. None: the re-solve's own modes, in frequency order and
        labelled afresh.

    Returns
    -------
    StructureModes
        The structure, its FE model, the modes (frequencies [Hz], mass-normalised shapes, labels), the
        mass properties [kg, m, kg m^2] and the preload (1-g).

    Raises
    ------
    MaceError
        For a deck or structure file that cannot give modes, with the file, line and card or key.

    Examples
    --------
    >>> from mace_fmu import compute_modes
    >>> modes = compute_modes(configuration="0g", max_hz=5.0)
    >>> [f"{hz:.2f} Hz {label}" for hz, label in zip(modes.frequencies_hz, modes.labels) if hz > 1]
    ['2.10 Hz 1st Z bending', '3.07 Hz 1st Y bending']
    """
    if preload not in ("large", "linear"):
        raise MaceError(f"preload must be 'large' or 'linear', got {preload!r}")
    if mass not in ("lumped", "consistent"):
        raise MaceError(f"mass must be 'lumped' or 'consistent', got {mass!r}")
    if not isinstance(deck, Deck):
        deck = read_deck(deck if deck is not None else bundled_deck_path())
    file = structure_file_for(deck, structure_file)
    overrides, names = None, None
    if parameters is not None:
        with naming_the_file(parameters):
            check_parameters_deck(parameters, deck)
            names = parameter_names(deck, file)
            overrides = fe_overrides(parameters, names)
    struct = build_structure(deck, configuration=configuration, overrides=overrides, structure_file=file)
    if struct.preload is not None:  # the deck's own limit, before a set could be blamed for it
        _check_preload_elements(struct.deck)
    reference = None
    if overrides and continue_from is not None:
        reference = continue_from if isinstance(continue_from, StructureModes) else compute_modes(
            deck, configuration=configuration, preload=preload, mass=mass, max_hz=max_hz, structure_file=file,
            continue_from=None)
    with _failure_blamed_on_the_set(parameters, deck=deck, names=names):
        return _solved_modes(struct, mass=mass, preload=preload, max_hz=max_hz, progress=progress,
                             parameters=parameters, reference=reference)


@contextlib.contextmanager
def _failure_blamed_on_the_set(parameters: ParameterSet | None, *, deck: Deck,
                               names: ParameterNames | None) -> Iterator[None]:
    """A model that cannot be solved with a set's modulus, spring or mass far outside the deck's names the set.

    The solution's own message speaks of the model (a singular stiffness, a preload beyond small strains),
    which reads as a broken deck; a set with a modulus 1e-6 x the deck's is what broke it. The values outside
    the range the FMUs take (:func:`~mace_fmu.parameters.kinds.declared_range`, 0.7-1.5 x nominal) are named
    with their file, farthest first; a set within that range leaves the message as it is.
    """
    try:
        yield
    except MaceError as exc:
        if parameters is None or names is None:
            raise
        nominal = deck_values(deck, names)
        outside = []
        for name, value in parameters.of_kind(MODULUS.name, SPRING.name, MASS.name).items():
            if nominal.get(name, 0.0) > 0.0 and value > 0.0:
                low, high = declared_range(name, nominal[name])
                if not low <= value <= high:
                    outside.append((abs(math.log(value / nominal[name])), name, value, nominal[name], low, high))
        if not outside:
            raise
        _, name, value, deck_value, low, high = max(outside)
        unit = parameter_unit(name)
        others = f" (and {len(outside) - 1} more outside theirs)" if len(outside) > 1 else ""
        raise MaceError(f"{parameters.source or 'the parameter set'}: {name} = {value:g} {unit} is "
                        f"{value / deck_value:.3g} x the deck's {deck_value:g} {unit}, outside the range the FMUs "
                        f"take ({low / deck_value:.3g}-{high / deck_value:.3g} x){others}; with it the model cannot "
                        f"be solved ({exc})") from None


def _solved_modes(struct: Structure, *, mass: MassKind, preload: PreloadKind, max_hz: float | None,
                  progress: ProgressCallback | None, parameters: ParameterSet | None,
                  reference: StructureModes | None) -> StructureModes:
    """The rest of :func:`compute_modes`: assembly, the 1-g preload, the modal constraints and the solution;
    ``reference``: the modes the solution continues (None: its own)."""
    model = assemble(struct.deck, mass=mass)
    props = mass_properties(model, struct.deck)
    stiffness, pre = model.stiffness, None
    auto = autospc_enabled(struct.deck)
    removed: tuple[tuple[int, int], ...] = ()
    if struct.preload is not None:
        static = build_constraints(struct.deck, model.dofs, model.cd_frames, spc_set=struct.preload.spc,
                                   mpc_set=struct.preload.mpc)
        if auto:  # statics: a DOF without stiffness is singular whatever its mass
            static, removed = constrain_singular_dofs(static, model.stiffness)
        assert struct.preload.load is not None  # the preload subcase is the first with a LOAD (structure.build)
        load = gravity_load(struct.deck, model, struct.preload.load)
        if preload == "linear":
            pre = linear_preload(model, static, load)
        else:
            nl = struct.deck.nlparms.get(struct.preload.nlparm) if struct.preload.nlparm is not None else None
            pre = large_displacement_preload(model, static, load, increments=nl.ninc if nl else 10,
                                             max_iterations=nl.max_iter if nl else 25,
                                             path_tolerance=nl.eps_w if nl else 1e-3, progress=progress)
        stiffness = pre.tangent_stiffness
    if not np.any(model.mass.data):  # K phi = lambda M phi with M = 0 has no finite root: say why, not "no modes"
        removed_some = struct.spec.suspension_grids or struct.spec.suspension_elements
        what = "the 0-g structure (the deck without its suspension) has" if struct.configuration == "0g" \
            and removed_some else "the deck has"
        raise MaceError(f"{struct.deck.path}: {what} no mass: no CONM1, CONM2, CMASS1, CMASS2 or PMASS card and no density "
                        "(RHO) on its MAT1 cards nor non-structural mass (NSM) on its properties, so it has no "
                        "vibration modes (expected RHO on the MAT1 cards, or mass elements)")
    modal = build_constraints(struct.deck, model.dofs, model.cd_frames, spc_set=struct.modal.spc,
                              mpc_set=struct.modal.mpc)
    if auto:
        modal, removed_modal = constrain_singular_dofs(modal, stiffness, model.mass)
        removed = tuple(dict.fromkeys(removed + removed_modal))
    wanted_hz, wanted_count = _modes_to_find(struct.deck, struct, max_hz)
    if reference is not None:  # the continuations may have moved above the range: look further
        wanted_hz = _CONTINUATION_REACH * float(np.max(np.abs(reference.frequencies_hz)))
        wanted_count = math.ceil(_CONTINUATION_REACH * len(reference.frequencies_hz))
    modes = solve_modes(stiffness, model.mass, modal, model.dofs, model.cd_frames, wanted_hz=wanted_hz,
                        wanted_count=wanted_count)
    if reference is None:
        modes = _requested_modes(modes, struct.deck, struct, max_hz)
    modes = label_modes(model, modes, struct.spec, reference=props.reference_point_m,
                        state=pre.state if pre is not None else None,
                        bar_forces=pre.bar_forces if pre is not None else None)
    if reference is not None:
        modes = continue_modes(reference.modes, reference.model, modes, zero_hz=ZERO_HZ)
    return StructureModes(structure=struct, model=model, modes=modes, mass_properties=props, preload=pre,
                          auto_constrained=removed, constraints=modal,
                          parameters=parameters if parameters is not None and len(parameters) else None,
                          reference_frequencies_hz=None if reference is None else reference.rank_frequencies_hz)
