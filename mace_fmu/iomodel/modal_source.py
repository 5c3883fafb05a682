"""A structure known by NASTRAN's normal modes alone: the modal source of a volts-volts model without a deck.

The deck route (:func:`~mace_fmu.fe.modes.compute_modes`) gives a
:class:`~mace_fmu.fe.modes.StructureModes`: the FE model, its preload, constraints and modes. A structure
file whose ``[modes]`` table points at NASTRAN's own SOL 103 output gives a :class:`ModalStructure`: the
modes NASTRAN computed, the structure file, and (for drawing) the grids' positions and the elements'
edges. Both are the modal source of the same pipeline (:func:`~mace_fmu.iomodel.volts.volts_model`,
the FMUs, SSP, the viewer); what needs the FE (moduli, springs and masses as parameters, bar strain
gauges) is refused for a ModalStructure with the reason. Its modal parameters, damping ratios and
frequency scales, are there as for a deck.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from mace_fmu.deck.connectivity import Connectivity, read_connectivity
from mace_fmu.errors import DeckError, MaceError
from mace_fmu.fe.dofs import COMPONENT_NAMES
from mace_fmu.fe.modal import Modes, ModesView
from mace_fmu.fe.modes import FE_PARAMETER_KINDS
from mace_fmu.iomodel.instruments import Instruments
from mace_fmu.nastran_modes.reading import NastranModes
from mace_fmu.parameters.sets import ParameterSet
from mace_fmu.structure.drawing import Drawing, DrawnLine, DrawnPoint
from mace_fmu.structure.file import StructureFile, instrument_grids, load_structure_file
from mace_fmu.structure.modes_table import ModesTable, modes_table
from mace_fmu.util.textfile import read_text

#: the columns of a residual flexibility file
RESIDUAL_COLUMNS = ("grid_a", "component_a", "grid_b", "component_b", "flexibility")

Dof = tuple[int, int]  #: (grid, component 1-6 in the grid's CD system)
#: edge radius and grid-sphere radius drawn, as fractions of the structure's largest extent
EDGE_RADIUS_FRACTION = 0.002
GRID_RADIUS_FRACTION = 0.006


@dataclass(frozen=True)
class ResidualFlexibility:
    """Static flexibility of the modes not in the modes file, between pairs of DOFs (symmetric).

    Entries are in the grids' displacement (CD) systems, as NASTRAN prints them, in the model's units
    (m/N, m/(N m), rad/(N m) for a model in SI).
    """

    entries: Mapping[tuple[Dof, Dof], float]  #: ((grid, component), (grid, component)) -> flexibility
    path: Path  #: the CSV file

    def between(self, a: Dof, b: Dof) -> float | None:
        """The flexibility between ``a`` and ``b`` in either order, None when the file does not give it."""
        value = self.entries.get((a, b))
        return self.entries.get((b, a)) if value is None else value


def read_residual_flexibility(path: str | os.PathLike) -> ResidualFlexibility:
    """A residual flexibility file: CSV with the header ``grid_a,component_a,grid_b,component_b,flexibility``.

    Each row is the static displacement of (grid_a, component_a) under a unit force on (grid_b,
    component_b) carried by the modes the modes file does not hold; by Maxwell's reciprocity one of the
    two orders suffices. Lines starting with ``#`` are comments.

    Parameters
    ----------
    path : str or path-like
        The CSV file.

    Returns
    -------
    ResidualFlexibility
        Its entries by DOF pair.

    Raises
    ------
    MaceError
        One line naming the file, the line and what was expected.
    """
    file = Path(path)
    text = read_text(file, what="residual flexibility")
    rows = [(n, row) for n, row in enumerate(csv.reader(text.splitlines()), start=1)
            if row and not row[0].lstrip().startswith("#")]
    if not rows or [c.strip() for c in rows[0][1]] != list(RESIDUAL_COLUMNS):
        found = ",".join(rows[0][1]) if rows else "nothing"
        raise MaceError(f"{file}:{rows[0][0] if rows else 1}: expected the header {','.join(RESIDUAL_COLUMNS)}, "
                        f"got {found}")
    entries: dict[tuple[Dof, Dof], float] = {}
    for n, row in rows[1:]:
        where = f"{file}:{n}"
        if len(row) != len(RESIDUAL_COLUMNS):
            raise MaceError(f"{where}: expected {len(RESIDUAL_COLUMNS)} columns ({','.join(RESIDUAL_COLUMNS)}), "
                            f"got {len(row)}")
        try:
            ga, ca, gb, cb = (int(x) for x in row[:4])
            value = float(row[4])
        except ValueError:
            raise MaceError(f"{where}: expected grid and component integers and a number, got {','.join(row)}") \
                from None
        if not (1 <= ca <= 6 and 1 <= cb <= 6) or ga <= 0 or gb <= 0 or not math.isfinite(value):
            raise MaceError(f"{where}: expected positive grid IDs, components 1-6 and a finite flexibility, got "
                            f"{','.join(row)}")
        pair = ((ga, ca), (gb, cb))
        if pair in entries or pair[::-1] in entries:
            raise MaceError(f"{where}: grid {ga} {COMPONENT_NAMES[ca - 1]} to grid {gb} {COMPONENT_NAMES[cb - 1]} "
                            "is given twice (one order suffices: the flexibility is symmetric)")
        entries[pair] = value
    return ResidualFlexibility(entries=entries, path=file)


@dataclass(frozen=True)
class ModalStructure(ModesView):
    """A structure known by NASTRAN's normal modes: the modal source of a model without FE.

    It offers what the pipeline reads of :class:`~mace_fmu.fe.modes.StructureModes` that needs no FE:
    ``modes``, ``frequencies_hz``, ``labels``, ``configuration`` and ``parameters``.
    """

    #: NASTRAN's modes: frequencies [Hz], mass-normalised shapes in basic, labels "mode <NASTRAN's number>"
    modes: Modes
    file: StructureFile  #: the structure file (instruments, electronics, damping)
    table: ModesTable  #: its [modes] table: the modes file, subcase, geometry, residual flexibility
    #: grid ID -> position in basic [the model's length unit], where the modes file or the geometry gives it
    positions: Mapping[int, np.ndarray] | None = None
    connectivity: Connectivity | None = None  #: element edges of the geometry deck (None: no geometry given)
    residual: ResidualFlexibility | None = None  #: static correction of the modes not in the file
    units: str = ""  #: the units the modes file states (NASTRAN's are the deck's own)
    parameters: ParameterSet | None = None  #: damping ratios and frequency scales the model takes by default

    @property
    def configuration(self) -> Literal["modes"]:
        """"modes": NASTRAN's modes are of the structure as its SOL 103 run constrained it (no 1-g/0-g choice)."""
        return "modes"

    @property
    def name(self) -> str:
        """The modes file's stem, which names the model's FMUs."""
        return self.table.file.stem

    @property
    def source(self) -> Path:
        """NASTRAN's modes file."""
        return self.table.file

    @property
    def grid_ids(self) -> tuple[int, ...]:
        """The grids whose eigenvectors the modes file holds (the ones whose motion can be an output)."""
        return tuple(self.modes.dofs.grid_ids)

    @property
    def physical_kinds(self) -> tuple[str, ...]:
        """None: NASTRAN's modes carry no FE whose moduli, springs or masses could change them."""
        return ()

    @property
    def mass(self) -> None:
        """None: NASTRAN's modes come without a mass matrix (they are mass-normalised)."""
        return None

    @property
    def constraint_transform(self) -> None:
        """None: the modes file's DOFs are the vectors' own."""
        return None

    @property
    def solved_structure(self) -> None:
        """None: NASTRAN's modes, no FE model to solve again."""
        return None

    def title(self, what: str) -> str:
        """"<stem> modes <what> (NASTRAN's modes of <file>; modal parameters only)", for model summaries.

        Parameters
        ----------
        what : str
            The model the title names, e.g. "volts-volts model".
        """
        return f"{self.name} modes {what} (NASTRAN's modes of {self.source.name}; modal parameters only)"

    def instrument_file(self) -> StructureFile:
        """The structure file, when it declares actuators and sensors; a MaceError saying to declare them."""
        if not self.file.has("actuators") or not self.file.has("sensors"):
            raise MaceError(f"{self.file.path}: a volts-volts model needs actuators and sensors; declare them "
                            "([[actuators]] and [[sensors]] on grids of the modes file)")
        return self.file

    def bar_strain_weights(self, *, bar_id: int, position: float, fiber_y_m: float,
                           fiber_z_m: float) -> tuple[tuple[int, int, float], ...]:
        """Always a MaceError: a bar strain gauge needs the deck's bar, and NASTRAN's modes hold none.

        Parameters
        ----------
        bar_id : int
            The CBAR the gauge was declared on.
        position, fiber_y_m, fiber_z_m : float
            Where on it (unused: there is no bar).
        """
        raise MaceError(f"a bar strain gauge (bar {bar_id}) needs the deck's bar; {self.source.name} holds NASTRAN's "
                        "modes only (give the gauge's DOF weights as a displacement sensor)")

    def check_parameters(self, parameters: ParameterSet | None) -> None:
        """A MaceError when ``parameters`` hold moduli, springs or masses (:func:`check_modal_parameters`).

        Parameters
        ----------
        parameters : ParameterSet or None
            The set a model is built with (None: nothing to check).
        """
        check_modal_parameters(self, parameters)

    def check_computed_with(self, parameters: ParameterSet) -> None:
        """Nothing to check: NASTRAN's modes do not depend on a parameter set.

        Parameters
        ----------
        parameters : ParameterSet
            The set a model of these modes is asked to be built with.
        """

    def check_physical(self, names: Sequence[str]) -> None:
        """A MaceError when ``names`` ask an FMU for physical parameters, which NASTRAN's modes cannot give.

        Parameters
        ----------
        names : sequence of str
            The physical parameters an FMU is asked for.
        """
        if len(names):
            raise MaceError(f"physical parameters {list(names)}: {self.source.name} holds NASTRAN's modes, not an FE "
                            "model, so its FMUs have modal parameters only (damping_mode_<k>, "
                            "frequency_scale_mode_<k>)")

    def static_correction(self, instruments: Instruments) -> np.ndarray | None:
        """The residual flexibility's feedthrough onto the displacement sensors (:func:`static_correction`).

        Parameters
        ----------
        instruments : Instruments
            The model's actuators and sensors.
        """
        return static_correction(self, instruments)

    def drawing(self) -> Drawing:
        """The grids and the geometry deck's element edges (:func:`outline_drawing`)."""
        return outline_drawing(self)


def mode_labels(count: int) -> tuple[str, ...]:
    """Labels of NASTRAN's modes in file order: "mode 1", "mode 2", ..."""
    return tuple(f"mode {k + 1}" for k in range(count))


def check_instrument_grids(file: StructureFile, modes: Modes, *, source: Path) -> None:
    """A MaceError naming the instrument and the grid when an instrument sits on a grid whose eigenvectors
    are not in the modes file, and the output request that puts them there."""
    have = set(modes.dofs.grid_ids)
    for what, name, grids in instrument_grids(file):
        for grid in (g for g in grids if g not in have):
            raise MaceError(f"{file.path}: {what} {name!r} sits on grid {grid}, whose eigenvectors are not in "
                            f"{source}: request them in the SOL 103 case control (DISPLACEMENT(PLOT) = ALL, or "
                            f"SET n = ..., {grid} with DISPLACEMENT(PLOT) = n) and run NASTRAN again")


def check_modal_parameters(structure: ModalStructure, parameters: ParameterSet | None) -> None:
    """A MaceError when ``parameters`` hold moduli, springs or masses: NASTRAN's modes carry no FE to change."""
    if parameters is None:
        return
    physical = sorted(parameters.of_kind(*FE_PARAMETER_KINDS))
    if physical:
        raise MaceError(f"parameter {physical[0]!r}: {structure.source.name} holds NASTRAN's modes, not an FE model, "
                        "so moduli, springs and masses cannot change them; its parameters are the modal ones "
                        "(damping_mode_<k>, frequency_scale_mode_<k>), besides delays and servo gains")


def static_correction(structure: ModalStructure, instruments: Instruments) -> np.ndarray | None:
    """(n_sensors, n_actuators) feedthrough of the residual flexibility onto the displacement sensors, in
    the instruments' physical units [m/N, ...] (None without a residual flexibility file).

    Rate and acceleration sensors get none: the truncated modes' static response enters them as s R and
    s^2 R, no feedthrough. A pair a displacement sensor and an actuator need and the file lacks is a
    MaceError naming both DOFs.
    """
    residual = structure.residual
    if residual is None:
        return None
    d = np.zeros((len(instruments.sensors), len(instruments.actuators)))
    for i, sensor in enumerate(instruments.sensors):
        if sensor.kind != "displacement":
            continue
        for j, actuator in enumerate(instruments.actuators):
            for gs, cs, ws in sensor.dofs:
                for ga, ca, wa in actuator.dofs:
                    value = residual.between((gs, cs), (ga, ca))
                    if value is None:
                        raise MaceError(
                            f"{residual.path}: no flexibility between grid {gs} {COMPONENT_NAMES[cs - 1]} (sensor "
                            f"{sensor.name!r}) and grid {ga} {COMPONENT_NAMES[ca - 1]} (actuator {actuator.name!r}); "
                            f"add the row {gs},{cs},{ga},{ca},<flexibility> (0 where it is negligible)")
                    d[i, j] += ws * wa * value
    return d


def _read_modes(table: ModesTable) -> NastranModes:
    """NASTRAN's modes through :func:`mace_fmu.nastran_modes.read_nastran_modes`, with the geometry deck's GRID and
    CORD cards where one is given (its CD systems turn the vectors to basic; shells and solids are passed over)."""
    from mace_fmu.nastran_modes import read_nastran_modes

    return read_nastran_modes(table.file, subcase=table.subcase, geometry=table.geometry,
                              normalisation=table.normalisation)


def _check_output_systems(table: ModesTable, connectivity: Connectivity, modes: Modes) -> None:
    """A MaceError when the modes file gave no geometry (so its vectors were taken as basic) and the deck puts
    a grid of the modes in a CD system other than basic."""
    for grid in modes.dofs.grid_ids:
        point = connectivity.grids.get(grid)
        if point is not None and point.cd != 0:
            raise MaceError(f"{table.source}: [modes] {table.file.name} has no geometry tables and grid {grid} of "
                            f"{connectivity.path} writes its motion in system {point.cd} (CD), which cannot be "
                            "resolved to basic here: run NASTRAN with PARAM,OGEOM,YES (the OP2's GEOM1 tables)")


def _positions(read: NastranModes, connectivity: Connectivity | None) -> dict[int, np.ndarray] | None:
    """Grid positions in basic: the modes file's where it gives them, else the geometry deck's GRIDs in CP 0."""
    given = read.grid_positions
    if given:
        return {int(g): np.asarray(x, dtype=float) for g, x in given.items()}
    if connectivity is None:
        return None
    return {g: np.array(p.xyz, dtype=float) for g, p in connectivity.grids.items() if p.cp == 0}


def modal_structure(structure_file: StructureFile | str | os.PathLike, *, nastran_modes: NastranModes | None = None,
                    parameters: ParameterSet | None = None) -> ModalStructure:
    """The structure a structure file's ``[modes]`` table describes: NASTRAN's modes, the instruments' grids
    checked against them, the residual flexibility and the drawing geometry read.

    Parameters
    ----------
    structure_file : StructureFile or path
        A structure file with a ``[modes]`` table (:mod:`mace_fmu.structure.modes_table`).
    nastran_modes : NastranModes, optional
        The modes, already read (default: read from ``[modes] file`` with its subcase and geometry).
    parameters : ParameterSet, optional
        Damping ratios and frequency scales (by mode label, "mode <k>"), delays and gains the models take
        by default; moduli, springs and masses are refused.

    Returns
    -------
    ModalStructure
        The modes (labelled "mode 1", ...), the structure file and what is there to draw.

    Raises
    ------
    MaceError
        A structure file without ``[modes]``, an instrument on a grid whose eigenvectors the file lacks, a
        malformed residual flexibility file or geometry deck, a modulus among the parameters; one line each.
    """
    file = structure_file if isinstance(structure_file, StructureFile) else load_structure_file(structure_file)
    table = modes_table(file)
    if table is None:
        raise MaceError(f"{file.path}: has no [modes] table (expected [modes] file = \"<NASTRAN's modes>.op2\"; a "
                        "structure file of a deck goes with compute_modes(deck, structure_file=...))")
    connectivity = None
    if table.geometry is not None:
        try:
            connectivity = read_connectivity(table.geometry)
        except DeckError as exc:
            raise MaceError(f"{file.path}: [modes] geometry: {exc}") from None
    read = nastran_modes if nastran_modes is not None else _read_modes(table)
    modes = read.modes
    modes = Modes(frequencies_hz=np.asarray(modes.frequencies_hz, dtype=float), shapes=modes.shapes, dofs=modes.dofs,
                  cd_frames=modes.cd_frames, labels=tuple(modes.labels) or mode_labels(len(modes.frequencies_hz)))
    check_instrument_grids(file, modes, source=table.file)
    if connectivity is not None and not read.grid_positions:
        _check_output_systems(table, connectivity, modes)
    residual = read_residual_flexibility(table.residual_flexibility) if table.residual_flexibility else None
    structure = ModalStructure(modes=modes, file=file, table=table, positions=_positions(read, connectivity),
                               connectivity=connectivity, residual=residual, units=read.units,
                               parameters=parameters if parameters is not None and len(parameters) else None)
    check_modal_parameters(structure, parameters)
    return structure


def outline_drawing(structure: ModalStructure) -> Drawing:
    """The grids and element edges of ``structure`` (from its geometry deck) to draw.

    Shells are drawn as the edges of their faces, solids as the edges of their corners, bars and rods as
    lines (:mod:`mace_fmu.deck.connectivity`); a grid on no edge is drawn as a small sphere. Only grids
    whose eigenvectors are in the modes file can move, so an edge to any other grid is left out.

    Parameters
    ----------
    structure : ModalStructure
        NASTRAN's modes with the positions and edges read for drawing.

    Returns
    -------
    Drawing
        Edges of radius :data:`EDGE_RADIUS_FRACTION` and lone grids of radius :data:`GRID_RADIUS_FRACTION` of
        the largest extent, framed on every grid with a position.

    Raises
    ------
    MaceError
        When nothing can be drawn, naming what to add.
    """
    grids = structure.modes.dofs.grid_ids
    positions = structure.positions or {}
    known = [g for g in grids if g in positions]
    if not known:
        raise MaceError(f"{structure.file.path}: nothing to draw: {structure.source.name} gives no grid positions "
                        "and [modes] names no geometry deck (add geometry = \"<the run's deck>\")")
    row = {g: k for k, g in enumerate(grids)}
    xyz = np.array([positions[g] if g in positions else np.full(3, np.nan) for g in grids], dtype=float)
    low, high = np.nanmin(xyz, axis=0), np.nanmax(xyz, axis=0)
    xyz[np.isnan(xyz[:, 0])] = 0.5 * (low + high)  # never drawn: no edge or sphere reaches a grid without position
    length = float((high - low).max()) or 1.0
    spec = structure.file.spec
    edges = structure.connectivity.edges if structure.connectivity is not None else ()
    drawn = [(a, b) for a, b in edges if a in row and b in row and a in positions and b in positions]
    lines = tuple(DrawnLine(name=f"edges/{a}_{b}", element_id=0, row_a=row[a], row_b=row[b],
                            radius_m=EDGE_RADIUS_FRACTION * length, component=spec.component_of(a, b) or "other",
                            bends=False) for a, b in drawn)
    on_edge = {g for pair in drawn for g in pair}
    points = tuple(DrawnPoint(name=f"grids/{g}", row=row[g], radius_m=GRID_RADIUS_FRACTION * length,
                              component=spec.component_of(g) or "other") for g in known if g not in on_edge)
    return Drawing(positions_m=xyz, grid_ids=tuple(grids), lines=lines, points=points, centre_m=0.5 * (low + high),
                   extent_m=high - low, length_m=length)
