"""Named model parameters as one frozen object that every stage takes; TOML in and out, with provenance.

A parameter set maps names to values in SI units. The names are the FMUs' own:

- ``E_<material>`` Young's modulus [Pa] of a MAT1 card, ``k_<spring>`` stiffness [N/m] of a
  CELAS2 card (material and spring names from the ``[parameters]`` table of the structure data
  file, e.g. ``E_lexan_center``, ``k_suspension_device_1``): FE overrides, so they act on the
  modes (and, through the 1-g preload, on gravity's stiffening);
- ``m_<mass>`` [kg] mass of a CONM2 card named in the ``[parameters]`` table's ``masses`` (e.g.
  ``m_floor_1``): a scaled body, its inertias I11..I33 scaled by the same factor about its unchanged
  centre of gravity; an FE override like the moduli (and in 1-g it changes the weight the preload carries);
- ``delay_<channel>`` [s]: an actuator's computational delay (Table 4.5) or a rate gyro's extra
  delay (Table 4.6), e.g. ``delay_gimbal_primary_x``, ``delay_gyro_bus_y``;
- ``K_a`` [V/deg], ``K_r`` [V/(deg/s)] gimbal servo gains, ``K_f``, ``K_b`` wheel speed loop gains;
- ``damping:<mode label>`` open-loop modal damping ratio of the modes with that label, e.g.
  ``damping:1st Z bending``;
- ``frequency_scale:<mode label>`` [-] factor on the open-loop natural frequency of the modes with
  that label, after the FE analysis (the updated nominal 0-g model of thesis 5.3 is made of these
  and damping ratios, see mace_fmu.zero_g.nominal);
- ``damping_mode_<k>``, ``frequency_scale_mode_<k>``: the same of mode k alone, 1-based in the model's
  retained-mode order, as an FMU names them (an FMU update writes these). Both spellings are taken
  wherever a set is applied to a model (mace_fmu.parameters.per_mode resolves them against its modes).

Names not given keep the deck's and the data file's values.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import hashlib
import math
import os
import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from mace_fmu.errors import MaceError
from mace_fmu.parameters.kinds import (DAMPING, FREQUENCY_SCALE, MASS, MODULUS, SERVO_GAINS, SPRING, KindName,
                                       kind_of_name, kind_of_set_name, unit_of)
from mace_fmu.util.atomic import write_text_atomic
from mace_fmu.util.textfile import read_text

if TYPE_CHECKING:
    from mace_fmu.deck.cards import Deck
    from mace_fmu.structure.file import StructureFile


def parameter_kind(name: str) -> KindName:
    """What a parameter-set name refers to (:mod:`mace_fmu.parameters.kinds`); a MaceError for a name of no
    known kind."""
    kind = kind_of_name(name)
    if kind is None:
        raise MaceError(f"parameter {name!r}: unknown kind of name; expected E_<material>, k_<spring>, m_<mass>, "
                        f"delay_<channel>, {', '.join(SERVO_GAINS)}, {DAMPING.set_prefix}<mode label>, "
                        f"{DAMPING.fmu_prefix}<k>, {FREQUENCY_SCALE.set_prefix}<mode label> or "
                        f"{FREQUENCY_SCALE.fmu_prefix}<k>")
    return kind.name


def parameter_unit(name: str) -> str:
    """SI unit of a parameter, as the FMUs declare it."""
    kind = kind_of_name(name)
    return "1" if kind is None else unit_of(kind, name)


@dataclass(frozen=True)
class Provenance:
    """Where a parameter set comes from: which data, which cost, how far it got, when."""

    created: str  #: ISO 8601 date and time (UTC)
    tool: str  #: e.g. "mace-fmu 0.1.0"
    deck: str = ""  #: file name of the deck the values belong to
    deck_sha256: str = ""  #: its content hash: a set made for another deck is refused
    configuration: str = ""  #: "1g" or "0g", the model that was fitted
    data: str = ""  #: what was measured
    cost: str = ""  #: which cost was minimised
    method: str = ""  #: how the parameters entered the model, outer iterations, penalty
    initial_cost: float | None = None  #: j^T j at the start
    final_cost: float | None = None  #: j^T j at the end
    notes: str = ""  #: free text written with the set
    fitted_to: str = ""  #: the model file the values were fitted to (an FMU), "" for the engine's own models


def deck_fingerprint(path: str | Path) -> str:
    """SHA-256 of a deck file's bytes."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError as exc:
        raise MaceError(f"{path}: cannot read the deck to fingerprint it: {exc}") from None


def tool_version() -> str:
    from importlib import metadata

    try:
        return f"mace-fmu {metadata.version('mace-fmu')}"
    except metadata.PackageNotFoundError:  # running from a source tree
        return "mace-fmu (source tree)"


def now_utc() -> str:
    return datetime.datetime.now(datetime.UTC).replace(microsecond=0).isoformat()


@dataclass(frozen=True)
class ParameterSet:
    """Parameter values [SI] by name (see the module docstring), with where they come from."""

    #: parameter name -> value (SI: Pa, N/m, s; ratios and scales dimensionless)
    values: Mapping[str, float] = field(default_factory=dict)
    provenance: Provenance | None = None  #: what the set was made from and fitted to (None: written by hand)
    source: str = field(default="", compare=False)  #: the file it was read from ("" when made in memory)

    def __post_init__(self) -> None:
        checked = {}
        for name, value in dict(self.values).items():
            parameter_kind(name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise MaceError(f"parameter {name!r}: value must be a finite number, got {value!r}")
            checked[name] = float(value)
        object.__setattr__(self, "values", MappingProxyType(checked))

    def __getitem__(self, name: str) -> float:
        return self.values[name]

    def __contains__(self, name: object) -> bool:
        return name in self.values

    def __len__(self) -> int:
        return len(self.values)

    def describe(self) -> str:
        """One line on where the set comes from (its file, what it was fitted to, on which data, when), for
        the description of a model or FMU built from it."""
        parts = [Path(self.source).name if self.source else f"{len(self.values)} values given"]
        p = self.provenance
        if p is not None:
            parts += [f"fitted to {p.fitted_to}"] if p.fitted_to else []
            parts += [f"data {p.data}"] if p.data else []
            parts += [f"{p.cost} cost"] if p.cost else []
            parts.append(f"created {p.created} by {p.tool}")
        return ", ".join(parts)

    def digest(self) -> str:
        """SHA-256 (hex) of the values alone, name by name in sorted order and each to the bit.

        Two sets with the same values have the same digest whatever their provenance, file or order; any
        other value, or another name, gives another digest. It names the FMUs built from a set
        (:func:`mace_fmu.fmu.naming.parameter_set_variant`).

        Returns
        -------
        str
            64 hexadecimal digits.
        """
        h = hashlib.sha256()
        for name in sorted(self.values):
            h.update(f"{name}={float(self.values[name]).hex()}\n".encode())
        return h.hexdigest()

    def of_kind(self, *kinds: KindName) -> dict[str, float]:
        """The values whose names are of the given kinds.

        Parameters
        ----------
        *kinds : str
            Parameter kinds (:data:`~mace_fmu.parameters.kinds.KindName`), e.g. ``"modulus"``.

        Returns
        -------
        dict of str to float
            Name -> value of every entry of those kinds.
        """
        return {n: v for n, v in self.values.items() if parameter_kind(n) in kinds}

    def updated(self, values: Mapping[str, float], *, provenance: Provenance | None = None) -> ParameterSet:
        """A new set with ``values`` replacing or adding entries (provenance replaced when given).

        Parameters
        ----------
        values : mapping of str to float
            The entries to replace or add.
        provenance : Provenance, optional
            The new set's provenance (default: this set's).

        Returns
        -------
        ParameterSet
            The new set, read from the same source.
        """
        return ParameterSet({**self.values, **values}, provenance if provenance is not None else self.provenance,
                            source=self.source)

    # --- TOML ---------------------------------------------------------------------------------
    def to_toml(self) -> str:
        """The set as TOML: a [provenance] table and a [values] table (units in comments)."""
        lines = ["# mace-fmu parameter set: values in SI units (see mace_fmu/parameters/sets.py for the names)", ""]
        if self.provenance is not None:
            lines.append("[provenance]")
            for f in dataclasses.fields(Provenance):
                value = getattr(self.provenance, f.name)
                if value is not None and value != "":
                    lines.append(f"{f.name} = {toml_value(value)}")
            lines.append("")
        lines.append("[values]")
        for name, value in self.values.items():
            lines.append(f"{toml_key(name)} = {toml_value(value)}  # [{parameter_unit(name)}]")
        return "\n".join(lines) + "\n"

    @classmethod
    def from_toml(cls, text: str, *, source: str = "<string>") -> ParameterSet:
        """Parse :meth:`to_toml`'s format; errors name ``source`` and the offending entry.

        Parameters
        ----------
        text : str
            The TOML text.
        source : str
            Where the text came from, for messages.

        Returns
        -------
        ParameterSet
            The set.

        Raises
        ------
        MaceError
            Text that is no parameter set (not TOML, an unknown table or key, a value that is wrong), named.
        """
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise MaceError(f"{source}: not a valid TOML parameter set: {exc}") from None
        # [sensor_gains]: an FMU update's estimated sensor gains, calibration of the data, not of the model
        unknown = set(data) - {"provenance", "values", "sensor_gains"}
        if unknown:
            raise MaceError(f"{source}: unknown table(s) {sorted(unknown)}; a parameter set has [provenance] and "
                            "[values] (and, from an FMU update, [sensor_gains])")
        if not isinstance(data.get("values"), dict):
            raise MaceError(f"{source}: no [values] table")
        prov = None
        if "provenance" in data:
            allowed = {f.name for f in dataclasses.fields(Provenance)}
            extra = set(data["provenance"]) - allowed
            if extra:
                raise MaceError(f"{source}: [provenance] has unknown key(s) {sorted(extra)}; "
                                f"allowed: {sorted(allowed)}")
            if "created" not in data["provenance"] or "tool" not in data["provenance"]:
                raise MaceError(f"{source}: [provenance] needs 'created' and 'tool'")
            prov = Provenance(**data["provenance"])
        try:
            return cls(data["values"], prov, source=source if source != "<string>" else "")
        except MaceError as exc:
            raise MaceError(f"{source}: {exc}") from None

    def write(self, path: str | Path) -> Path:
        """Write the TOML atomically (a reader never sees half a file).

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write.

        Returns
        -------
        pathlib.Path
            The file written.
        """
        return write_text_atomic(path, self.to_toml())

    @classmethod
    def read(cls, path: str | Path) -> ParameterSet:
        """Read a parameter set written by :meth:`write` (or by hand).

        Parameters
        ----------
        path : str or pathlib.Path
            The TOML file.

        Returns
        -------
        ParameterSet
            The set, its messages naming ``path``.
        """
        return cls.from_toml(read_text(path, what="parameter"), source=str(path))


def toml_key(name: str) -> str:
    """``name`` as a TOML key (quoted unless bare)."""
    return name if all(c.isalnum() or c in "_-" for c in name) else '"' + name.replace('"', '\\"') + '"'


def toml_value(value: Any) -> str:
    """A string or a number as a TOML value (numbers as floats, to the last digit)."""
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    return repr(float(value))


# --- the structure's parameter names ----------------------------------------------------------
@dataclass(frozen=True)
class ParameterNames:
    """Which MAT1, CELAS2 and CONM2 cards the ``E_``, ``k_`` and ``m_`` names of a structure refer to."""

    materials: Mapping[str, int]  #: material name -> MAT1 ID
    springs: Mapping[str, int]  #: spring name -> CELAS2 ID
    masses: Mapping[str, int] = field(default_factory=dict)  #: mass name -> CONM2 ID (only those the file names)
    #: CONM2 ID -> (mass [kg], inertias I11 I21 I22 I31 I32 I33 [kg m^2]) of the deck, which an ``m_`` value scales
    mass_cards: Mapping[int, tuple[float, tuple[float, ...]]] = field(default_factory=dict)


def load_parameter_names(path: str | Path | None = None) -> ParameterNames:
    """The ``[parameters]`` table of a structure file (default: the bundled mace_em.toml).

    Parameters
    ----------
    path : path, optional
        A structure file (default: the bundled mace_em.toml).

    Returns
    -------
    ParameterNames
        Material name -> MAT1 ID and spring name -> CELAS2 ID.
    """
    from mace_fmu.structure.file import bundled_structure_path, load_structure_file

    return names_of_table(load_structure_file(path if path is not None else bundled_structure_path()).tables)


def names_of_table(tables: Mapping[str, Any]) -> ParameterNames:
    """ParameterNames of a structure file's parsed tables (its ``[parameters]``)."""
    table = tables.get("parameters", {})
    return ParameterNames(materials={name: int(mid) for mid, name in table.get("materials", {}).items()},
                          springs={name: int(sid) for sid, name in table.get("springs", {}).items()},
                          masses={name: int(eid) for eid, name in table.get("masses", {}).items()})


def parameter_names(deck: Deck, structure_file: StructureFile | str | os.PathLike[str] | None = None) -> ParameterNames:
    """The ``E_``, ``k_`` and ``m_`` names of a deck: its structure file's ``[parameters]`` names, and for every MAT1
    and CELAS2 card that table does not name (or every card, without a structure file) ``mat<ID>`` and
    ``celas<ID>`` (``E_mat2``, ``k_celas138``): a name never reaches a card of another deck. Masses are
    parameters only where the table's ``masses`` names their CONM2 cards (``masses = { "100" = "floor_1" }``):
    a deck's every CONM2 as a parameter would grow every FMU by parameters no one asked for.

    Parameters
    ----------
    deck : Deck
        The deck.
    structure_file : StructureFile or path, optional
        Its structure file, or the path of one (default: none, every MAT1 and CELAS2 card named by its ID).

    Returns
    -------
    ParameterNames
        Material name -> MAT1 ID, spring name -> CELAS2 ID, mass name -> CONM2 ID (with the deck's values).

    Raises
    ------
    MaceError
        A ``masses`` entry naming no CONM2 of the deck (the file and the key named), or a structure file that
        cannot be read.
    """
    if isinstance(structure_file, (str, os.PathLike)):
        from mace_fmu.structure.file import load_structure_file

        structure_file = load_structure_file(structure_file)
    masses = structure_file.tables.get("parameters", {}).get("masses", {}) if structure_file is not None else {}
    for key, name in masses.items():  # before names_of_table's int(key)
        assert structure_file is not None
        if not key.strip().isdigit() or int(key) not in deck.conm2s:
            raise MaceError(f"{structure_file.path}: [parameters] masses: key {key!r} ({name!r}) is no CONM2 element "
                            f"ID of {deck.path}; expected one of {sorted(deck.conm2s)[:12]}")
        if not deck.conm2s[int(key)].mass > 0.0:
            raise MaceError(f"{structure_file.path}: [parameters] masses: key {key!r} ({name!r}): CONM2 {key} has no "
                            "mass; a mass parameter scales a positive mass")
    named = names_of_table(structure_file.tables) if structure_file is not None else ParameterNames({}, {})
    materials = {**{f"mat{mid}": mid for mid in deck.mat1s if mid not in named.materials.values()},
                 **named.materials}
    springs = {**{f"celas{sid}": sid for sid in deck.celas2s if sid not in named.springs.values()}, **named.springs}
    cards = {eid: (deck.conm2s[eid].mass, tuple(deck.conm2s[eid].inertia)) for eid in named.masses.values()}
    return ParameterNames(materials=materials, springs=springs, masses=named.masses, mass_cards=cards)


def deck_values(deck: Deck, names: ParameterNames | None = None) -> dict[str, float]:
    """The ``E_``, ``k_`` and ``m_`` values [Pa, N/m, kg] a deck has for every named material, spring and mass it
    contains."""
    names = names if names is not None else load_parameter_names()
    out = {MODULUS.named(n): deck.mat1s[mid].youngs_modulus for n, mid in names.materials.items() if mid in deck.mat1s}
    out.update({SPRING.named(n): deck.celas2s[sid].k for n, sid in names.springs.items() if sid in deck.celas2s})
    out.update({MASS.named(n): deck.conm2s[eid].mass for n, eid in names.masses.items() if eid in deck.conm2s})
    return out


@contextlib.contextmanager
def naming_the_file(parameters: ParameterSet | None) -> Iterator[None]:
    """Errors raised while a parameter set is applied name the file it was read from (when it was)."""
    try:
        yield
    except MaceError as exc:
        source = parameters.source if parameters is not None else ""
        if source and not str(exc).startswith(source):
            raise MaceError(f"{source}: {exc}") from None
        raise


def fe_overrides(parameters: ParameterSet | None, names: ParameterNames | None = None
                 ) -> dict[tuple[str, int], dict[str, float]]:
    """The ``E_``, ``k_`` and ``m_`` entries as deck overrides ({("MAT1", 2): {"e": 2.3e9}, ("CELAS2", 138): {"k": ...},
    ("CONM2", 100): {"mass": 6.0, "inertia": (...)}}).

    A mass is a scaled body: ``m_<name>`` = f x the deck's mass scales the CONM2's inertias I11..I33 (about its
    centre of gravity, whose offset stays) by the same f, so that the floor or payload it models is the same
    shape of a different density. ``names`` must come from :func:`parameter_names` (which carries the deck's
    CONM2 values) for a set with masses.
    """
    if parameters is None:
        return {}
    names = names if names is not None else load_parameter_names()
    out: dict[tuple[str, int], dict[str, Any]] = {}
    what = {"MAT1": "material", "CELAS2": "spring", "CONM2": "mass"}
    for name, value in parameters.of_kind("modulus", "spring", "mass").items():
        kind = kind_of_set_name(name)
        assert kind is not None  # of_kind returns names of those kinds only
        table, card, key = {MODULUS.name: (names.materials, "MAT1", "e"), SPRING.name: (names.springs, "CELAS2", "k"),
                            MASS.name: (names.masses, "CONM2", "mass")}[kind.name]
        short = name.removeprefix(kind.set_prefix)
        if short not in table:
            known = ", ".join(kind.set_prefix + n for n in table) or "none (name one in the structure file)"
            raise MaceError(f"parameter {name!r}: no such {what[card]}; known: {known}")
        if value <= 0.0:
            raise MaceError(f"parameter {name!r} must be > 0, got {value}")
        if kind is MASS:
            if table[short] not in names.mass_cards:
                raise MaceError(f"parameter {name!r}: the deck's CONM2 {table[short]} is unknown here (names made "
                                "without the deck: use parameter_names(deck, structure_file))")
            mass, inertia = names.mass_cards[table[short]]
            out[(card, table[short])] = {"mass": value, "inertia": tuple(value / mass * i for i in inertia)}
            continue
        out[(card, table[short])] = {key: value}
    return out
