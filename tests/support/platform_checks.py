"""Checks of a native FMU's binaries for every platform, from the archive alone (tests/support/binaries.py
reads them): the folders each FMI version names, each binary's CPU, its exported symbols against its FMI
version's header in the FMU's own sources/, and sources/build_info.json against the binaries and sources."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import zipfile
from pathlib import Path

import fmpy
import pytest
from support.binaries import declared_fmi_functions, read_fat, read_library, read_macho

#: folder -> (CPU, file suffix) of each FMI version's binaries
FMI2_FOLDERS = {"linux64": ("x86_64", ".so"), "aarch64-linux": ("aarch64", ".so"), "win64": ("x86_64", ".dll"),
                "darwin64": ("x86_64+aarch64", ".dylib")}
FMI3_FOLDERS = {"x86_64-linux": ("x86_64", ".so"), "aarch64-linux": ("aarch64", ".so"),
                "x86_64-windows": ("x86_64", ".dll"), "x86_64-darwin": ("x86_64", ".dylib"),
                "aarch64-darwin": ("aarch64", ".dylib")}
#: FMI version -> what its binaries export beyond its FMI header: the one allowed extra is FMI 2's
#: maceRunRecord, the whole-record call the updating engine makes through ctypes (mace_fmu/updating/fmu/model.py,
#: which loads FMI 2 FMUs only); FMI 3 binaries export exactly fmi3Functions.h's functions
EXTENSIONS = {2: {"maceRunRecord"}, 3: set()}
#: files of sources/ written per FMU, not compiled
GENERATED = {"build_info.json", "buildDescription.xml"}
#: symbols zig's Mach-O linker defines and exports in every dylib (the image's own header)
MACHO_LINKER_SYMBOLS = {"_mh_dylib_header", "__dso_handle"}


def require_tool(path: str | None, what: str) -> str:
    """``path`` if the tool exists; else skip locally, but fail under CI (.ci/run exports MACE_REQUIRE_CROSS=1)."""
    if path and (shutil.which(path) or Path(path).exists()):
        return path
    message = f"{what} is not installed (.ci/run installs it)"
    if os.environ.get("MACE_REQUIRE_CROSS"):
        pytest.fail(message + "; MACE_REQUIRE_CROSS is set")
    pytest.skip(message)


def slices(data: bytes) -> dict[str, bytes]:
    """CPU -> thin image of a binary: itself, or each slice of a universal Mach-O file."""
    if data[:4] == b"\xca\xfe\xba\xbe":
        out = {}
        for piece in read_fat(data):
            assert piece.offset % (1 << piece.align) == 0, "a fat slice off its declared alignment"
            out[read_macho(piece.image)[0].cpu] = piece.image
        return out
    return {read_library(data).cpu: data}


def check_binaries(fmu: Path) -> dict[str, bytes]:
    """Assert what the docs promise of every binary of ``fmu``; returns its archive entries of binaries and sources."""
    md = fmpy.read_model_description(str(fmu))
    version = int(md.fmiVersion[0])
    identifier = (md.coSimulation or md.modelExchange).modelIdentifier
    with zipfile.ZipFile(fmu) as z:
        entries = {n: z.read(n) for n in z.namelist() if n.startswith(("binaries/", "sources/")) and not n.endswith("/")}
    folders = FMI2_FOLDERS if version == 2 else FMI3_FOLDERS
    expected = {f"binaries/{folder}/{identifier}{suffix}" for folder, (_, suffix) in folders.items()}
    assert {n for n in entries if n.startswith("binaries/")} == expected

    sources = {n.removeprefix("sources/"): data for n, data in entries.items() if n.startswith("sources/")}
    other = 5 - version  # the FMI version this FMU is not: none of its files, none of its functions
    assert not [n for n in sources if n.startswith(f"fmi{other}")], sorted(sources)
    sections = declared_fmi_functions(sources[f"fmi{version}Functions.h"].decode())
    every = set().union(*sections.values())  # all the header declares, as the runtime implements every one
    allowed = every | EXTENSIONS[version]
    promised = set(sections["common"])
    if md.coSimulation is not None:
        promised |= sections["co-simulation"]
    if md.modelExchange is not None:
        promised |= sections["model exchange"]
    assert len(promised) >= (34 if version == 2 else 64), promised  # the headers were read, not an empty set

    info = json.loads(sources["build_info.json"])
    recorded = {b["platform"]: b for b in info["binaries"]}
    assert len(recorded) == 5
    for folder, (cpus, _) in folders.items():
        entry = f"binaries/{folder}/{identifier}{folders[folder][1]}"
        thin = slices(entries[entry])
        assert sorted(thin) == sorted(cpus.split("+")), (entry, sorted(thin))
        for cpu, image in thin.items():
            library = read_library(image)
            extra = MACHO_LINKER_SYMBOLS if library.kind == "macho" else set()
            assert library.exports == allowed | extra, (entry, sorted(library.exports ^ (allowed | extra)))
            assert promised <= library.exports
            assert not [n for n in library.exports if n.startswith(f"fmi{other}")], entry
            if library.kind == "macho":
                assert read_macho(image)[1] == library.exports, "dyld's export trie differs from the symbol table"
            platform = next(p for p, b in recorded.items() if b["archive_entry"] == entry and p.startswith(cpu))
            assert hashlib.sha256(image).hexdigest() == recorded[platform]["sha256"], (entry, cpu)

    digest = hashlib.sha256()
    for name in sorted(n for n in sources if n not in GENERATED):  # the runtime's files, as compiled
        digest.update(name.encode() + b"\0" + sources[name])
    assert info["sources_sha256"] == digest.hexdigest()
    c_files = {n for n in sources if n.endswith(".c")}
    flags = set()
    for b in info["binaries"]:
        command = b["command"]
        target = command.index("-target")
        output = command.index("-o")
        assert {a for a in command if a.endswith(".c")} == c_files
        flags.add(tuple(command[:target] + command[target + 2:output] + command[output + 2:]))
    assert len(flags) == 1, f"the platforms were built with different flags or sources: {flags}"
    return entries
