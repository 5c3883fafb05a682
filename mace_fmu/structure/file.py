"""The structure file: what a deck does not say about its structure, read and checked against the deck.

A deck says what NASTRAN needs; a structure file (TOML) says what it does not: which cards form a
suspension removed for the 0-g structure, which grids form named components (mode labels,
viewer colours), which coincident grid pairs are mechanisms, and (for the later stages) the
instruments, electronics, damping and parameter names. The bundled ``mace_em.toml`` belongs to
the bundled MACE deck only: it applies when the deck's content is the bundled deck's, or when it
is named (``structure_file=``, CLI ``--structure``). Any other deck without a structure file keeps
NASTRAN's meaning: its modes as its own SPC, MPC and EIGRL define them, nothing removed.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

from mace_fmu.deck.card_tables import ELEMENT_TABLES
from mace_fmu.deck.cards import Deck
from mace_fmu.errors import MaceError
from mace_fmu.structure.values import PARAMETER_KEYS, check_values, key_line
from mace_fmu.util.textfile import read_text

Configuration = Literal["1g", "0g"]  #: the structures a deck is built as: suspended and preloaded, or free
#: what a modal source's modes are of: a deck's 1-g or 0-g structure, or NASTRAN's modes as its run constrained it
SourceConfiguration = Literal["1g", "0g", "modes"]

#: the tables a structure file may hold, and what each is for (the schema, checked on loading)
STRUCTURE_FILE_TABLES = {
    "suspension": "grids and elements removed for the 0-g structure",
    "components": "named groups of grids (mode labels, viewer colours)",
    "mechanisms": "hinges: [dependent grid, independent grid, released component]",
    "actuators": "actuators as weighted sums of grid DOFs",
    "sensors": "sensors as weighted sums of grid DOFs",
    "electronics": "filters and delays",
    "servos": "wheel speed loops and gimbal servos",
    "damping": "modal damping table",
    "parameters": "names of the MAT1, CELAS2 and CONM2 cards an update may change",
    "labels": "rules = \"generic\" (default: by strain-energy family) or \"mace\" (MACE's bus, cable and gimbal names)",
    "units": "mass = \"kg\", length = \"m\": the units the deck is written in, for printed labels (nothing is "
             "converted)",
    "modes": "file = NASTRAN's normal modes (OP2 or punch) instead of a deck; subcase, geometry (a deck, for drawing), "
             "residual_flexibility (a CSV), normalisation = \"mass\" (stated, for a file without generalized masses)",
}


def bundled_deck_path() -> Path:
    """Path of the bundled MACE deck (Appendix B of the thesis).

    Returns
    -------
    Path
        ``mace_fmu/data/mace_em.bdf`` of the installed package.
    """
    return Path(str(resources.files("mace_fmu") / "data" / "mace_em.bdf"))


def bundled_structure_path() -> Path:
    """Path of the bundled MACE structure file, ``mace_em.toml`` (it belongs to the bundled deck only).

    Returns
    -------
    Path
        ``mace_fmu/data/mace_em.toml`` of the installed package.
    """
    return Path(str(resources.files("mace_fmu") / "data" / "mace_em.toml"))


@dataclass(frozen=True)
class Mechanism:
    """A hinge: two coincident grids whose relative motion is free in one CD component."""

    name: str
    dependent: int
    independent: int
    component: int


@dataclass(frozen=True)
class StructureSpec:
    """Non-deck data about the structure: suspension membership, components, mechanisms."""

    suspension_grids: frozenset[int]  #: grids removed for the 0-g structure
    suspension_elements: frozenset[int]  #: CBAR, CONM2 and CELAS2 IDs (one NASTRAN namespace)
    components: Mapping[str, frozenset[int]]  #: name -> grid IDs
    mechanisms: tuple[Mechanism, ...]  #: mechanisms named for the labels
    source: str  #: the file they come from
    label_rules: str = "generic"  #: "generic" (strain-energy families) or "mace" (MACE's component conventions)

    @classmethod
    def empty(cls, source: str = "no structure file") -> StructureSpec:
        """Nothing beyond the deck: no suspension, no components, no mechanisms (NASTRAN's meaning).

        Parameters
        ----------
        source : str
            What messages name as the spec's source.

        Returns
        -------
        StructureSpec
            The empty spec.
        """
        return cls(suspension_grids=frozenset(), suspension_elements=frozenset(), components={}, mechanisms=(),
                   source=source)

    def component_of(self, *grids: int) -> str | None:
        """Name of the component that contains every one of ``grids`` (None when none does).

        Parameters
        ----------
        *grids : int
            Grid IDs.

        Returns
        -------
        str or None
            The first component (in the file's order) that holds them all.
        """
        for name, members in self.components.items():
            if all(g in members for g in grids):
                return name
        return None


@dataclass(frozen=True)
class StructureFile:
    """A structure file read once: its path, its parsed tables and the structure part of them.

    The later stages read their tables (``actuators``, ``sensors``, ``electronics``, ``servos``,
    ``damping``, ``parameters``) from ``tables``, never from the file again.
    """

    path: Path  #: the file
    tables: Mapping[str, Any]  #: the parsed TOML (read-only)
    spec: StructureSpec  #: its suspension, components and mechanisms

    def has(self, table: str) -> bool:
        """Whether the file holds ``table`` (e.g. "actuators").

        Parameters
        ----------
        table : str
            A table's name.

        Returns
        -------
        bool
            True when the file has that table.
        """
        return table in self.tables


def _line_of(text: str, key: str) -> int:
    """1-based line where ``key`` is defined in a TOML text (a table header or a key), 0 if not found."""
    for n, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped.startswith(("[" + key + "]", "[[" + key + "]]", key + " ", key + "=", f'"{key}"')):
            return n
    return 0


def _where(path: Path, text: str, key: str) -> str:
    line = _line_of(text, key.split(".")[-1].strip('"'))
    return f"{path}:{line}: [{key}]" if line else f"{path}: [{key}]"


def _id_set(values: Any, where: str) -> frozenset[int]:
    """IDs from a list of ints and "first-last" ranges."""
    if not isinstance(values, list):
        raise MaceError(f"{where}: expected a list of IDs and 'first-last' ranges, got {values!r}")
    ids: set[int] = set()
    for v in values:
        if isinstance(v, int) and not isinstance(v, bool) and v > 0:
            ids.add(v)
        elif isinstance(v, str) and v.count("-") == 1 and all(p.strip().isdigit() for p in v.split("-")):
            lo, hi = (int(p) for p in v.split("-"))
            if hi < lo:
                raise MaceError(f"{where}: range {v!r} runs backwards (expected 'first-last' with first <= last)")
            ids.update(range(lo, hi + 1))
        else:
            raise MaceError(f"{where}: expected a positive ID or a 'first-last' range, got {v!r}")
    return frozenset(ids)


def _spec_of(path: Path, text: str, data: Mapping[str, Any]) -> StructureSpec:
    susp = data.get("suspension", {})
    if not isinstance(susp, dict) or set(susp) - {"grids", "elements"}:
        raise MaceError(f"{_where(path, text, 'suspension')}: expected the keys 'grids' and 'elements', got "
                        f"{sorted(susp) if isinstance(susp, dict) else susp!r}")
    components = data.get("components", {})
    mechanisms = data.get("mechanisms", {})
    if not isinstance(components, dict) or not isinstance(mechanisms, dict):
        raise MaceError(f"{path}: [components] and [mechanisms] must be tables")
    labels = data.get("labels", {})
    rules = labels.get("rules", "generic") if isinstance(labels, dict) else labels
    if rules not in ("generic", "mace") or (isinstance(labels, dict) and set(labels) - {"rules"}):
        raise MaceError(f"{_where(path, text, 'labels')}: expected rules = \"generic\" or \"mace\", got {labels!r}")
    mechs = []
    for name, v in mechanisms.items():
        if not (isinstance(v, list) and len(v) == 3 and all(isinstance(x, int) and not isinstance(x, bool) for x in v)
                and 1 <= v[2] <= 6):
            raise MaceError(f"{_where(path, text, 'mechanisms.' + name)}: expected [dependent grid, independent grid, "
                            f"component 1-6], got {v!r}")
        mechs.append(Mechanism(name=name, dependent=v[0], independent=v[1], component=v[2]))
    return StructureSpec(
        suspension_grids=_id_set(susp.get("grids", []), _where(path, text, "suspension") + " grids"),
        suspension_elements=_id_set(susp.get("elements", []), _where(path, text, "suspension") + " elements"),
        components={name: _id_set(v, _where(path, text, "components") + f" {name}") for name, v in components.items()},
        mechanisms=tuple(mechs), source=str(path), label_rules=rules)


@functools.lru_cache(maxsize=16)
def _load_structure_file(path: str, resolved: str, mtime_ns: int, size: int) -> StructureFile:
    del resolved, mtime_ns, size  # cache keys: another file under the same name, or a changed one, is read again
    file = Path(path)  # as the user gave it: messages and the model's provenance name it so
    text = read_text(file, what="structure")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MaceError(f"{file}: not a valid structure file (TOML): {exc}") from None
    unknown = sorted(set(data) - set(STRUCTURE_FILE_TABLES))
    if unknown:
        raise MaceError(f"{_where(file, text, unknown[0])}: unknown table {unknown[0]!r}; a structure file has "
                        + "; ".join(f"[{k}] ({v})" for k, v in STRUCTURE_FILE_TABLES.items()))
    check_values(file, text, data)  # damping ratios, delays, parameter names ...: each value, once, at reading
    return StructureFile(path=file, tables=MappingProxyType(data), spec=_spec_of(file, text, data))


def load_structure_file(path: str | os.PathLike[str]) -> StructureFile:
    """Read and check a structure file: what a deck does not say (suspension, components, instruments).

    Parameters
    ----------
    path : str or path-like
        The structure file (TOML; schema in ``mace_fmu/data/README.md``).

    Returns
    -------
    StructureFile
        Its tables, read once (later calls with an unchanged file return the same object).

    Raises
    ------
    MaceError
        Naming the file, the line and the table or key that is wrong, and what was expected.
    """
    file = Path(path)
    try:
        st = file.stat()
    except OSError:
        raise MaceError(f"{file}: no such structure file") from None
    return _load_structure_file(str(file), str(file.resolve()), st.st_mtime_ns, st.st_size)


def load_spec(path: str | os.PathLike[str] | None = None) -> StructureSpec:
    """The structure part of a structure file (default: the bundled ``mace_em.toml``)."""
    return load_structure_file(path if path is not None else bundled_structure_path()).spec


@functools.lru_cache(maxsize=1)
def _bundled_deck_sha256() -> str:
    return hashlib.sha256(bundled_deck_path().read_bytes()).hexdigest()


@functools.lru_cache(maxsize=64)
def _file_sha256(path: str, mtime_ns: int, size: int) -> str:
    del mtime_ns, size
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def deck_units(deck: Deck, file: StructureFile | None) -> tuple[str, str] | None:
    """(mass, length) unit labels of a deck: its structure file's ``[units]``, kg and m for the bundled deck, else
    None: a deck states no units (NASTRAN takes whatever it is written in), so they are the deck's own."""
    if file is None:
        return ("kg", "m") if is_bundled_deck(deck) else None
    units = dict(file.tables.get("units", {}))
    unknown = sorted(set(units) - {"mass", "length"})
    if unknown:
        raise MaceError(f"{file.path}: [units] has unknown key(s) {unknown} (expected mass and length)")
    if not units:
        return ("kg", "m") if is_bundled_deck(deck) else None
    return str(units.get("mass", "(the deck's mass unit)")), str(units.get("length", "(the deck's length unit)"))


def is_bundled_deck(deck: Deck) -> bool:
    """Whether ``deck`` was read from a file whose content is the bundled MACE deck's."""
    path = Path(deck.path)
    try:
        st = path.stat()
    except OSError:
        return False
    return st.st_size == bundled_deck_path().stat().st_size and \
        _file_sha256(str(path.resolve()), st.st_mtime_ns, st.st_size) == _bundled_deck_sha256()


def structure_label(deck: Deck) -> str:
    """What a model of ``deck`` is called in titles and FMU descriptions: "MACE" for the bundled deck, else the
    deck file's name without its extension (``frame`` for frame.bdf)."""
    return "MACE" if is_bundled_deck(deck) else Path(deck.path).stem


def structure_file_for(deck: Deck, structure_file: StructureFile | str | os.PathLike[str] | None = None
                       ) -> StructureFile | None:
    """The structure file that goes with ``deck``: the one given, else the bundled one for the bundled
    deck, else None (the deck's own meaning, nothing added or removed).

    Parameters
    ----------
    deck : Deck
        The deck.
    structure_file : StructureFile or path, optional
        The structure file given by the user.

    Returns
    -------
    StructureFile or None
        The file that applies, read.
    """
    if isinstance(structure_file, StructureFile):
        return structure_file
    if structure_file is not None:
        return load_structure_file(structure_file)
    return load_structure_file(bundled_structure_path()) if is_bundled_deck(deck) else None


def _ids_text(ids: list[int]) -> str:
    """'1-31, 35, 93-112': IDs as compact ranges for error messages."""
    ids, parts, start = sorted(ids), [], None
    for i, k in enumerate(ids):
        start = k if start is None else start
        if i + 1 == len(ids) or ids[i + 1] != k + 1:
            parts.append(str(k) if k == start else f"{start}-{k}")
            start = None
    return ", ".join(parts)


def instrument_grids(file: StructureFile) -> list[tuple[str, str, list[int]]]:
    """The grids each actuator and sensor of ``file`` names, as written (before the instruments are read).

    Parameters
    ----------
    file : StructureFile
        A structure file.

    Returns
    -------
    list of (str, str, list of int)
        ("actuator" or "sensor", its name, the grids of its ``dofs`` rows and ``wheels`` pairs) per entry,
        in file order; entries and grids that are not well formed are passed over (they are refused where
        the instruments are read, :func:`mace_fmu.iomodel.instruments.load_instruments`).
    """
    out = []
    for table in ("actuators", "sensors"):
        entries = file.tables.get(table, [])
        for entry in entries if isinstance(entries, list) else []:
            if not isinstance(entry, dict):
                continue
            grids = [row[0] for row in entry.get("dofs", []) if isinstance(row, list) and row]
            grids += [g for row in entry.get("wheels", []) if isinstance(row, list) for g in row[:2]]
            out.append((table[:-1], str(entry.get("name", "?")),
                        [g for g in grids if isinstance(g, int) and not isinstance(g, bool)]))
    return out


def check_instruments_against_deck(file: StructureFile, deck: Deck, *, configuration: str = "") -> None:
    """A MaceError naming the structure file, the actuator or sensor and the grids when an instrument's DOFs
    name a grid ``deck`` (the configuration's: 0-g lacks the suspension's grids) does not have.

    Only the grids are checked here, before any solve; the rest of each entry is checked where the
    instruments are read (:func:`mace_fmu.iomodel.instruments.load_instruments`)."""
    problems = []
    for what, name, grids in instrument_grids(file):
        missing = sorted({g for g in grids if g not in deck.grids})
        if missing:
            problems.append(f"{what} {name!r} names grid {_ids_text(missing)}")
    if problems:
        where = " (the 0-g structure: its suspension's grids removed)" if configuration == "0g" else ""
        raise MaceError(f"{file.path}: " + "; ".join(problems) + f", which {deck.path}{where} does not have")


def check_spec_against_deck(spec: StructureSpec, deck: Deck) -> None:
    """A MaceError naming the structure file and the IDs when it names grids or elements the deck lacks."""
    elements = set().union(*(getattr(deck, table) for table in ELEMENT_TABLES))
    problems = []
    for what, ids, have in (("[suspension] grids", spec.suspension_grids, deck.grids),
                            ("[suspension] elements", spec.suspension_elements, elements)):
        missing = sorted(i for i in ids if i not in have)
        if missing:
            problems.append(f"{what} {_ids_text(missing)}")
    for name, grids in spec.components.items():
        missing = sorted(g for g in grids if g not in deck.grids)
        if missing:
            problems.append(f"[components] {name}: grids {_ids_text(missing)}")
    for m in spec.mechanisms:
        missing = [g for g in (m.dependent, m.independent) if g not in deck.grids]
        if missing:
            problems.append(f"[mechanisms] {m.name!r}: grids {missing}")
    if problems:
        raise MaceError(f"{spec.source}: names IDs that {deck.path} lacks: " + "; ".join(problems)
                        + " (is it the structure file of another deck?)")


def check_parameters_against_deck(file: StructureFile, deck: Deck) -> None:
    """A MaceError naming the structure file, its line, the ``[parameters]`` table and the card when an entry names
    a MAT1, CELAS2 or CONM2 ID ``deck`` lacks, with the IDs of that card the deck has.

    Without the check such an entry is silently no parameter at all (the card it was meant for keeps its default
    name, ``E_mat<ID>``). ``deck`` is the deck as read, before the suspension is removed for the 0-g structure (a
    suspension spring is named once, for both structures).
    """
    table = file.tables.get("parameters", {})
    if not isinstance(table, dict):
        return
    text = read_text(file.path, what="structure")
    have = {"materials": deck.mat1s, "springs": deck.celas2s, "masses": deck.conm2s}
    for key, card in PARAMETER_KEYS.items():
        for ident, name in dict(table.get(key, {})).items():
            if int(ident) not in have[key]:
                line = key_line(text, "parameters", key)
                ids = _ids_text(list(have[key])) if have[key] else "none"
                raise MaceError(f"{file.path}:{line}: [parameters] {key}: \"{ident}\" = {name!r} names {card} {ident}, "
                                f"which {deck.path} lacks (its {card} IDs: {ids})")
