"""The native runtime's layers (mace_fmu/fmu/native/c/README.md): each prefix is one layer, a file
calls only its own layer and the layers below it, and the sources compile without a warning (gcc, and zig's
clang for every platform the FMUs carry)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from mace_fmu.fmu.native import compile as runtime
from mace_fmu.fmu.native.compile import SOURCE_DIR
from mace_fmu.fmu.native.platforms import PLATFORMS

#: layer of each call prefix, from the bottom (numerics) up
LAYER_OF_PREFIX = {"ml": 0, "zoh": 0, "rs": 0, "mace": 1, "mi": 2}
#: layer of each source file
LAYER_OF_FILE = {"mace_linalg.c": 0, "mace_zoh.c": 0, "mace_resolve.c": 0, "mace_data.c": 1, "mace_model.c": 1,
                 "controller/mace_discrete.c": 1, "mace_instance.c": 2, "fmi2_api.c": 3, "fmi3_api.c": 3}
CALL = re.compile(r"\b(ml|zoh|rs|mi|mace)_[a-z0-9_]+\s*\(")
#: layer of each header: a file includes headers of its own layer and the layers below it only (the FMI
#: standard's headers are the entry points')
LAYER_OF_HEADER = {"mace_linalg.h": 0, "mace_zoh.h": 0, "mace_resolve.h": 0, "mace_data.h": 1, "mace_model.h": 1, "mace_instance.h": 2,
                   "fmi2Functions.h": 3, "fmi2FunctionTypes.h": 3, "fmi2TypesPlatform.h": 3,
                   "fmi3Functions.h": 3, "fmi3FunctionTypes.h": 3, "fmi3PlatformTypes.h": 3}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def _calls(path: Path) -> set[str]:
    text = re.sub(r"/\*.*?\*/|//[^\n]*|\"(?:\\.|[^\"\\])*\"", "", path.read_text(), flags=re.S)
    return set(CALL.findall(text))


def test_every_source_file_has_a_layer_and_calls_no_layer_above_it():
    sources = {p.relative_to(SOURCE_DIR).as_posix() for p in SOURCE_DIR.rglob("*.c")}
    assert sources == set(LAYER_OF_FILE)
    upward = [(name, prefix) for name, layer in LAYER_OF_FILE.items()
              for prefix in _calls(SOURCE_DIR / name) if LAYER_OF_PREFIX[prefix] > layer]
    assert upward == []
    # and the layers are used: the instance calls the model, the model the numerics
    assert "mace" in _calls(SOURCE_DIR / "mace_instance.c") and "zoh" in _calls(SOURCE_DIR / "mace_model.c")


def _includes(path: Path) -> list[str]:
    """The headers of ours a file includes (``#include "..."``; comments left out)."""
    return INCLUDE.findall(re.sub(r"/\*.*?\*/|//[^\n]*", "", path.read_text(), flags=re.S))


def test_every_file_includes_only_headers_of_its_layer_and_below():
    """The layers hold for the ``#include``s as for the calls: the numerics (mace_zoh.c) included mace_model.h for
    one constant, the error buffer's length, which now lives in the lowest header, mace_linalg.h."""
    headers = {p.relative_to(SOURCE_DIR).as_posix() for p in SOURCE_DIR.rglob("*.h")}
    assert headers == set(LAYER_OF_HEADER)
    layer_of = {**LAYER_OF_FILE, **LAYER_OF_HEADER}
    found = {name: _includes(SOURCE_DIR / name) for name in layer_of}
    assert {h for included in found.values() for h in included} <= set(LAYER_OF_HEADER)
    upward = [(name, header) for name, included in found.items() for header in included
              if LAYER_OF_HEADER[header] > layer_of[name]]
    assert upward == []
    assert "mace_model.h" not in found["mace_zoh.c"] and "mace_linalg.h" in found["mace_zoh.h"]


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
def test_the_runtime_compiles_without_a_warning_under_wall_wextra():
    files = [str(SOURCE_DIR / name) for name in LAYER_OF_FILE]
    done = subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-fsyntax-only",
                           f"-I{SOURCE_DIR}", *files], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


@pytest.mark.slow
@pytest.mark.parametrize("platform", PLATFORMS, ids=lambda p: p.name)
def test_the_runtime_compiles_without_a_warning_for_every_platform(platform, tmp_path):
    """The same -Wall -Wextra -Werror check with zig's clang for each target: its headers (mingw-w64's, macOS's)
    and its 32-bit `long` on Windows show what gcc on Linux does not. Each variant links alone (one FMI version's
    entry points need nothing of the other's: macOS's linker, like Windows', refuses an undefined symbol); for
    Windows the front end's check alone, since a link needs mingw-w64's C library, which zig builds for each of
    its installations and -O levels (90 s on a fresh machine: the package build's zig is another installation)
    and the wine test builds already; the package build links every variant for Windows."""
    zig = runtime.zig_command()
    if zig is None:
        pytest.skip("zig (the ziglang package) is not installed")
    variants = [(f"{kind}{version}", c_files) for kind, files in (("plant", runtime.C_FILES),
                                                                  ("controller", runtime.CONTROLLER_C_FILES))
                for version, c_files in files.items()]
    assert set().union(*(c_files for _, c_files in variants)) == set(LAYER_OF_FILE)
    # clang's warnings come from its front end, so any -O sees them all: the runtime's own
    flags = [*zig, "cc", "-target", platform.target, "-std=c99", runtime.OPTIMISATION, "-Wall", "-Wextra", "-Werror",
             f"-I{SOURCE_DIR}"]
    if "windows" in platform.target:  # each file to an object, no link
        builds = [(f, [*flags, "-c", "-o", str(tmp_path / f"{Path(f).stem}.obj"), str(SOURCE_DIR / f)])
                  for f in sorted(LAYER_OF_FILE)]
    else:
        builds = [(name, [*flags, "-shared", "-fPIC", "-o", str(tmp_path / f"{name}{platform.suffix}"),
                          *(str(SOURCE_DIR / f) for f in c_files), "-lm"]) for name, c_files in variants]
    for name, command in builds:
        done = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path)
        assert done.returncode == 0, (name, done.stderr)


def test_the_data_files_codes_are_the_runtimes_enums():
    """The block kinds, parameter kinds, counts and row kinds the data file carries as numbers (resource.py) are
    the C runtime's enums, in their order: one meaning per code on both sides."""
    from mace_fmu.fmu.native import resource

    source = (Path(SOURCE_DIR) / "mace_model.c").read_text()

    def enum(prefix: str) -> list[str]:
        body = next(m.group(1) for m in re.finditer(r"enum\s*\{([^}]*)\}", source) if f"{prefix}_" in m.group(1))
        return [name.split("=")[0].strip().removeprefix(f"{prefix}_").lower() for name in body.split(",")
                if name.strip() and not name.strip().startswith("N_")]

    assert enum("BLOCK") == list(resource.BLOCK_KINDS)
    assert list(resource.BLOCK_KINDS.values()) == list(range(len(resource.BLOCK_KINDS)))
    assert enum("PARAM") == list(resource.PARAMETER_KINDS)
    assert list(resource.PARAMETER_KINDS.values()) == list(range(len(resource.PARAMETER_KINDS)))
    assert enum("COUNT") == list(resource.COUNTS)
    rows = {name: int(value) for name, value in re.findall(r"#define ROW_(\w+) (\d+)", source)}
    assert rows == {"DISPLACEMENT": resource.ROW_DISPLACEMENT, "RATE": resource.ROW_RATE,
                    "ACCELERATION": resource.ROW_ACCELERATION}
