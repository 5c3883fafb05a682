"""Real eigenvectors, the eigenvalue summary and the grid geometry from a NASTRAN OP2 file (SOL 103).

Tables read (the layouts of MSC's DMAP Programmer's Guide, as pyNastran reads them):

- ``OUGV1``/``OUG1``/``BOUGV1`` (and any other displacement-type table): pairs of records, an IDENT of
  146 words (approach code 10 * 2 + device: real eigenvalues; table code 7: eigenvector; subcase in
  word 4, mode in word 5, eigenvalue in word 6; format code, words per point in words 9 and 10) and
  the data: 8 words per point (ID * 10 + device code, point type, T1 T2 T3 R1 R2 R3). ``BOUGV1`` holds
  the vectors in the basic system, the others in each grid's displacement (CD) system. SORT1, real.
- ``LAMA``: 7 words per mode (mode, extraction order, eigenvalue, radians, cycles, generalized mass,
  generalized stiffness); word 11 of its header record, the residual vector augmentation flag.
- ``GEOM1*``: GRID (4501, 45, 1: ID, CP, X1-3, CD, PS, SEID) and CORD1R/C/S, CORD2R/C/S.
- ``DYNAMICS``: EIGR (307, 3, 85) and EIGRL (308, 8, 348), the run's eigenvalue requests: how many roots (ND)
  or up to which frequency (V2) it asked for, and how it normalised the vectors (NORM).

The other tables are named in messages: a buckling run's (approach code 8, ``BLAMA``), a complex eigenvalue
run's (9, ``CLAMA``), a static run's (1) results are said to be what they are.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any
from pathlib import Path

import numpy as np

from mace_fmu.errors import MaceError
from mace_fmu.nastran_modes.file_modes import CoordCard, CoordKind, FileGeometry, FileModes, xyz
from mace_fmu.nastran_modes.fortran import Op2Records

IDENT_WORDS = 146
EIGENVECTOR_TABLE_CODE = 7
REAL_EIGENVALUES_APPROACH = 2
GRID_POINT = 1  #: word 2 of a point's entry: 1 a grid; scalar (2, 7) and extra points (3) are left out
#: GEOM1 record keys (word 1 of the 3-word key) of the cards read
GRID_KEY = 4501
CORD2_KEYS: dict[int, CoordKind] = {2101: "R", 2001: "C", 2201: "S"}
CORD1_KEYS: dict[int, CoordKind] = {1801: "R", 1701: "C", 1901: "S"}
#: DYNAMICS record keys of the real eigenvalue requests
EIGR_KEY, EIGRL_KEY = (307, 3, 85), (308, 8, 348)
#: what a vector table holds, by the approach code of its IDENT (word 1 // 10; pyNastran's op2_common.py)
APPROACHES = {1: "static displacements (SOL 101)", 2: "normal modes", 3: "differential stiffness displacements",
              4: "differential stiffness displacements", 5: "frequency response (SOL 108, 111)",
              6: "transient response (SOL 109, 112)", 7: "pre-buckling static displacements (SOL 105)",
              8: "buckling modes (SOL 105)", 9: "complex modes (SOL 107, 110)",
              10: "nonlinear static displacements (SOL 106)", 11: "geometric nonlinear static displacements",
              12: "transient (CONTRAN) results"}
#: the eigenvalue summary tables and what each holds
SUMMARIES = {"LAMA": "real eigenvalues", "BLAMA": "buckling eigenvalues", "CLAMA": "complex eigenvalues"}
#: the sort code (table code // 1000) bits: complex values, SORT2, random results (pyNastran's sort_bits.py)
COMPLEX_BIT, SORT2_BIT, RANDOM_BIT = 1, 2, 4


def _is_vector_table(name: str) -> bool:
    return name.startswith(("OUG", "BOUG", "OPHIG", "BOPHIG"))


def _wanted(name: str) -> bool:
    return _is_vector_table(name) or name == "LAMA" or name.startswith(("GEOM1", "DYNAMIC"))


def read_op2_modes(path: Path, *, subcase: int | None) -> FileModes:
    """The real eigenvectors of one subcase of the OP2 at ``path`` (the only one when ``subcase`` is None).

    MaceError (one line: file, table, record) for a truncated or corrupted file, a file without real
    eigenvectors (saying what it holds: a buckling, complex eigenvalue or static run's results), several
    subcases and none chosen, or SORT2 / complex eigenvectors.
    """
    records = Op2Records(path, path.read_bytes())
    endian = records.endian
    # subcase -> (table, record, mode, eigenvalue, IDs, types, values) per mode
    blocks: dict[int, list[tuple[Any, ...]]] = {}
    summaries: list[np.ndarray] = []
    grids: dict[int, tuple[int, tuple[float, float, float], int]] = {}
    coords: dict[int, CoordCard] = {}
    names: list[str] = []  # every table, in file order: what the file holds, for messages
    held: dict[str, set[str]] = {}  # what the vector tables hold other than normal modes -> their tables
    methods: list[dict[str, Any]] = []  # the run's EIGR/EIGRL requests
    augmented = False  # LAMA's residual vector augmentation flag
    has_geometry = False
    for table in records.tables(_wanted):
        names.append(table.name)
        if _is_vector_table(table.name):
            _read_vectors(records, table.name, table.records, endian, blocks, held)
        elif table.name == "LAMA":
            records.table = table.name
            summaries.append(_read_summary(records, table.records, endian))
            augmented |= _residual_flag(table.records, endian)
        elif table.name.startswith("DYNAMIC"):
            methods += _eigenvalue_requests(table.records, endian, table=table.name)
        elif table.name.startswith("GEOM1"):
            has_geometry = True
            records.table = table.name
            _read_geometry(records, table.records, endian, grids, coords)
    first = next((n for n in names if _is_vector_table(n)), "OUGV1")
    records.table, records.record = first, "its IDENT records"
    if not blocks:
        records.fail(_what_the_file_holds(names, held))
    if subcase is None:
        if len(blocks) > 1:
            records.fail(f"eigenvectors of subcases {sorted(blocks)} (expected one: choose it with subcase=)")
        subcase = next(iter(blocks))
    if subcase not in blocks:
        records.fail(f"no eigenvectors of subcase {subcase} (the file has subcases {sorted(blocks)})")
    found = _assemble(path, subcase, blocks[subcase], summaries,
                      FileGeometry(grids=grids, coords=coords) if has_geometry else None)
    return _with_request(found, methods, augmented=augmented)


def _what_the_file_holds(names: list[str], held: dict[str, set[str]]) -> str:
    """The problem of an OP2 without real eigenvectors: what its tables hold instead, and what to ask NASTRAN for."""
    summaries = [f"{SUMMARIES[n]} ({n})" for n in dict.fromkeys(names) if n in SUMMARIES]
    if held:
        what = "; ".join(f"{kind} in {', '.join(sorted(tables))}" for kind, tables in held.items())
        return (f"no real eigenvectors of a normal-modes run in the file: it holds {what}"
                + (f", and {', '.join(summaries)}" if summaries else "")
                + " (expected the OP2 of a SOL 103 run: its normal modes)")
    if "LAMA" in names:
        return ("the file has the eigenvalues (LAMA) but no eigenvectors (expected an OUGV1 table of the SOL 103 run: "
                "add DISPLACEMENT(PLOT)=ALL or VECTOR=ALL to the case control)")
    shown = ", ".join(list(dict.fromkeys(names))[:12]) + (" ..." if len(set(names)) > 12 else "")
    return (f"no eigenvectors in the file: its tables are {shown or 'none'}"
            + (f", with {', '.join(summaries)}" if summaries else "")
            + " (expected an OUGV1 table of a SOL 103 run: add DISPLACEMENT(PLOT)=ALL or VECTOR=ALL to the case "
              "control and PARAM,POST,-1 or -2)")


def _read_vectors(records: Op2Records, name: str, raw: tuple[bytes, ...], endian: str,
                  blocks: dict[int, list[tuple[Any, ...]]], held: dict[str, set[str]]) -> None:
    """Append (table, mode, eigenvalue, ids, types, values) of every real eigenvector of the table; what its other
    IDENTs hold (static displacements, buckling modes ...) goes into ``held``."""
    records.table = name
    for k in range(0, len(raw) - 1, 2):
        records.record = f"record {k + 3} (the IDENT of a vector)"
        ident = raw[k]
        if len(ident) != 4 * IDENT_WORDS:
            records.fail(f"the IDENT record has {len(ident) // 4} words (expected {IDENT_WORDS})")
        words = np.frombuffer(ident, dtype=endian + "i4")
        approach, table_code = int(words[0]) // 10, int(words[1])
        sort_code = table_code // 1000
        if approach != REAL_EIGENVALUES_APPROACH or table_code % 1000 != EIGENVECTOR_TABLE_CODE:
            kind = APPROACHES.get(approach, f"results of approach code {approach}")
            if sort_code & RANDOM_BIT:
                kind = "random response (SOL 111 with RANDOM, SOL 112)"
            held.setdefault(kind, set()).add(name)
            continue
        if sort_code & COMPLEX_BIT:
            records.fail("the eigenvectors are complex (expected real ones: the normal modes of a SOL 103 run)")
        if sort_code & SORT2_BIT:
            records.fail("the eigenvectors are in SORT2 (expected SORT1: the default, or SORT1 in the request)")
        num_wide, fmt = int(words[9]), int(words[8])
        if num_wide != 8 or fmt not in (0, 1):
            records.fail(f"eigenvectors of {num_wide} words per point in format {fmt} (expected real ones: "
                         "8 words, format 1)")
        subcase, mode = int(words[3]), int(words[4])
        eigenvalue = float(np.frombuffer(ident, dtype=endian + "f4")[5])
        records.record = f"record {k + 4} (the data of mode {mode})"
        data = raw[k + 1]
        if len(data) % 32:
            records.fail(f"the data record has {len(data) // 4} words (expected 8 per point)")
        ints = np.frombuffer(data, dtype=endian + "i4").reshape(-1, 8)
        floats = np.frombuffer(data, dtype=endian + "f4").reshape(-1, 8)
        found = blocks.setdefault(subcase, [])
        if found and found[0][0] != name:
            continue  # the same modes again in another table (BOUGV1 beside OUGV1): the first table's are kept
        found.append((name, records.record, mode, eigenvalue, ints[:, 0] // 10, ints[:, 1],
                      floats[:, 2:].astype(float)))


def _read_summary(records: Op2Records, raw: tuple[bytes, ...], endian: str) -> np.ndarray:
    """(n_modes, 7) rows of the eigenvalue summary: mode, order, eigenvalue, radians, cycles, mass, stiffness."""
    records.record = "record 4 (the eigenvalue summary)"
    if len(raw) < 2 or len(raw[1]) % 28:
        records.fail("the eigenvalue summary is missing or not 7 words per mode")
    ints = np.frombuffer(raw[1], dtype=endian + "i4").reshape(-1, 7)
    rows = np.frombuffer(raw[1], dtype=endian + "f4").reshape(-1, 7).astype(float)
    rows[:, :2] = ints[:, :2]
    return rows


def _residual_flag(raw: tuple[bytes, ...], endian: str) -> bool:
    """Whether a LAMA's header record (record 3) says the run augmented its modes with residual vectors (word 11,
    RSFLAG of MSC's DMAP Programmer's Guide, as pyNastran reads it)."""
    if not raw or len(raw[0]) < 44:
        return False
    return int(np.frombuffer(raw[0][:44], dtype=endian + "i4")[10]) != 0


def _eigenvalue_requests(raw: tuple[bytes, ...], endian: str, *, table: str) -> list[dict[str, Any]]:
    """The EIGR and EIGRL entries of a DYNAMICS table: card, SID, V2 [Hz] (None: not given), ND (0: not given),
    NORM ("MASS", "MAX" or "POINT"). EIGR: 18 words per entry; EIGRL: 13 words and its frequency segments, laid
    out in 27 words by the writers of the public files; a record of another length is read for its first entry."""
    found = []
    for record in raw:
        if len(record) < 12 or len(record) % 4:
            continue
        key = tuple(int(v) for v in np.frombuffer(record[:12], dtype=endian + "i4"))
        body = record[12:]
        if key == EIGR_KEY:
            stride = 72
        elif key == EIGRL_KEY:
            stride = 108 if len(body) % 108 == 0 else len(body)
        else:
            continue
        for start in range(0, len(body) - min(stride, 52) + 1, stride):
            entry = body[start:start + stride]
            ints = np.frombuffer(entry[:52], dtype=endian + "i4")
            reals = np.frombuffer(entry[:52], dtype=endian + "f4")
            if key == EIGR_KEY:  # SID, METHOD(2), F1, F2, NE, ND, 2 unused, NORM(2), G, C, ...
                v2 = float(reals[4]) or None
                nd, norm = int(ints[6]), entry[36:44]
                card = f"EIGR {int(ints[0])}"
            else:  # SID, V1, V2, ND, MSGLVL, MAXSET, SHFSCL, FLAG1, FLAG2 (0: V1, V2 given), NORM(2), ALPH, NUMS
                v2 = float(reals[2]) if int(ints[8]) == 0 and reals[2] > 0 else None
                nd, norm = int(ints[3]), entry[36:44]
                card = f"EIGRL {int(ints[0])}"
            name = norm.decode("latin-1").replace("\x00", " ").strip().upper() or "MASS"  # NORM's default: MASS
            found.append({"card": card, "v2": v2, "nd": max(nd, 0), "norm": name, "where": f"{card} in table {table}"})
    return found


def _with_request(found: FileModes, methods: list[dict[str, Any]], *, augmented: bool) -> FileModes:
    """``found`` with what the run's eigenvalue request says: how it normalised the vectors, and which vectors
    are residual vectors. NASTRAN returns at most ND eigenvectors, none above V2: a vector beyond them is a
    residual vector (PARAM,RESVEC) that the run appended and orthogonalised with the modes. With several
    requests in the file (one per subcase's METHOD) only a NORM they all share is taken."""
    norms = {m["norm"] for m in methods}
    run_norm = (methods[0]["norm"], methods[0]["where"] if len(methods) == 1 else
                "every EIGR/EIGRL of table DYNAMICS") if len(norms) == 1 else None
    residual: list[int] = []
    notes = list(found.notes)
    if len(methods) == 1:
        request = methods[0]
        hz = np.sign(found.eigenvalues) * np.sqrt(np.abs(found.eigenvalues)) / (2 * np.pi)
        beyond = np.zeros(len(found.mode_numbers), dtype=bool)
        if request["nd"]:
            beyond |= np.arange(len(beyond)) >= request["nd"]
        if request["v2"] is not None:
            beyond |= hz > request["v2"] * (1 + 1e-6)
        residual = [int(m) for m in found.mode_numbers[beyond]]
    elif augmented:
        notes.append("the run augmented its modes with residual vectors (LAMA's flag; PARAM,RESVEC) and the file "
                     "does not say which of the vectors they are")
    return replace(found, run_normalisation=run_norm, residual_vectors=tuple(residual), notes=tuple(notes))


def _read_geometry(records: Op2Records, raw: tuple[bytes, ...], endian: str,
                   grids: dict[int, tuple[int, tuple[float, float, float], int]],
                   coords: dict[int, CoordCard]) -> None:
    """GRIDs and coordinate systems of one GEOM1 table, single precision or double (NX, MSC 2014 and later)."""
    for k, record in enumerate(raw):
        records.record = f"record {k + 3}"
        if len(record) < 12 or len(record) % 4:
            continue
        key = int(np.frombuffer(record[:4], dtype=endian + "i4")[0])
        body = record[12:]
        if key == GRID_KEY:
            for i, x in _entries(records, body, endian, "GRID", ints_before=2, reals=3, ints_after=3):
                grids[int(i[0])] = (int(i[1]), (float(x[0]), float(x[1]), float(x[2])), int(i[2]))
        elif key in CORD2_KEYS:
            kind = CORD2_KEYS[key]
            for i, x in _entries(records, body, endian, f"CORD2{kind}", ints_before=4, reals=9, ints_after=0):
                points = tuple(xyz(list(x[3 * j:3 * j + 3])) for j in range(3))
                coords[int(i[0])] = CoordCard(id=int(i[0]), kind=kind, rid=int(i[3]),
                                              points=points, grids=None)
        elif key in CORD1_KEYS:
            if len(body) % 24:
                records.fail(f"CORD1{CORD1_KEYS[key]} entries of {len(body) // 4} words in all (expected 6 each)")
            for i in np.frombuffer(body, dtype=endian + "i4").reshape(-1, 6):
                coords[int(i[0])] = CoordCard(id=int(i[0]), kind=CORD1_KEYS[key], rid=None,
                                              points=None, grids=(int(i[3]), int(i[4]), int(i[5])))


def _entries(records: Op2Records, body: bytes, endian: str, card: str, *, ints_before: int, reals: int,
             ints_after: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """(integers, reals) of each entry of a GEOM1 record whose entries are integers, reals, integers; the reals
    single precision or double, whichever divides the record into entries with plausible IDs."""
    layouts = []
    for real in ("f4", "f8"):
        fields = [(f"i{j}", endian + "i4") for j in range(ints_before)]
        fields += [(f"x{j}", endian + real) for j in range(reals)]
        fields += [(f"i{ints_before + j}", endian + "i4") for j in range(ints_after)]
        dtype = np.dtype(fields)
        if len(body) % dtype.itemsize == 0:
            table = np.frombuffer(body, dtype=dtype)
            ids = table["i0"]
            if len(ids) and np.all(ids > 0) and np.all(np.isfinite([table[f"x{j}"] for j in range(reals)])):
                layouts.append(table)
    if not layouts:
        records.fail(f"{card} entries of {len(body) // 4} words in all (expected {ints_before + reals + ints_after} "
                     f"words each, or {ints_before + 2 * reals + ints_after} in double precision)")
    table = layouts[-1] if len(layouts) == 1 else _plausible(layouts)
    n_ints = ints_before + ints_after
    ints = np.column_stack([table[f"i{j}"] for j in range(n_ints)]).astype(int)
    values = np.column_stack([table[f"x{j}"] for j in range(reals)]).astype(float)
    return list(zip(ints, values))


def _plausible(layouts: list[np.ndarray]) -> np.ndarray:
    """Of two readings of the same bytes, the one whose IDs ascend (NASTRAN sorts GEOM1 entries by ID)."""
    for table in layouts:
        if np.all(np.diff(table["i0"]) > 0):
            return table
    return layouts[0]


def _assemble(path: Path, subcase: int, vectors: list[tuple[Any, ...]], summaries: list[np.ndarray],
              geometry: FileGeometry | None) -> FileModes:
    """One subcase's vectors on the grids of its first mode, with the summary that lists its modes."""
    table, _, _, _, ids, types, _ = vectors[0]
    keep = types == GRID_POINT
    skipped = tuple(int(i) for i in ids[~keep])
    grid_ids = ids[keep]
    modes, eigenvalues, columns = [], [], []
    for name, where, mode, eigenvalue, ids_m, _, values in vectors:
        if not np.array_equal(ids_m, ids):
            raise MaceError(f"{path}: table {name}, {where}: the points of mode {mode} differ from those of the "
                            f"first mode (expected the same {len(ids)} points in every mode)")
        modes.append(mode)
        eigenvalues.append(eigenvalue)
        columns.append(values[keep])
    mode_numbers = np.array(modes)
    summary = _matching_summary(summaries, mode_numbers, np.array(eigenvalues))
    if summary is None and not np.any(eigenvalues):
        raise MaceError(f"{path}: table {table}, its IDENT records: the eigenvalues of subcase {subcase} are not in "
                        "the file (every IDENT holds 0 and no LAMA table lists its modes: expected the OP2 of the "
                        "SOL 103 run, with its LAMA)")
    return FileModes(
        source=path, subcase=subcase, grid_ids=np.asarray(grid_ids, dtype=int),
        vectors=np.stack(columns, axis=2), frame="basic" if table.startswith("B") else "cd",
        mode_numbers=mode_numbers,
        eigenvalues=summary[:, 2] if summary is not None else np.array(eigenvalues),
        generalized_masses=summary[:, 5] if summary is not None else None,
        skipped_points=skipped, geometry=geometry, where=f"table {table}",
        eigenvalues_from="table LAMA" if summary is not None else f"table {table}, its IDENT records")


def _matching_summary(summaries: list[np.ndarray], modes: np.ndarray, eigenvalues: np.ndarray) -> np.ndarray | None:
    """The summary rows of ``modes`` from the LAMA that lists them with the eigenvalues of the vectors' IDENTs; when
    the IDENTs hold no eigenvalue (all 0, as some runs write them), the only LAMA that lists those modes."""
    candidates = []
    for rows in summaries:
        by_mode = {int(r[0]): r for r in rows}
        if all(int(m) in by_mode for m in modes):
            candidates.append(np.array([by_mode[int(m)] for m in modes]))
    if not np.any(eigenvalues):
        return candidates[0] if len(candidates) == 1 else None
    scale = np.abs(eigenvalues).max()
    for picked in candidates:
        if np.allclose(picked[:, 2], eigenvalues, rtol=1e-6, atol=1e-6 * scale):
            return picked
    return None
