"""Compile the C runtime of native FMUs into a shared library for a platform (gcc, mingw-w64).

The runtime does not depend on the model (the model is data), so one compilation serves every
FMU a process exports; it is cached per platform and source digest. The flags are portable:
no -march=native and no -ffast-math (the exact zero-order hold relies on IEEE arithmetic).
"""

from __future__ import annotations

import functools
from concurrent.futures import ThreadPoolExecutor
import hashlib
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from mace_fmu.errors import MaceError

SOURCE_DIR = Path(__file__).with_name("c")
#: the plant runtime's C files, in link order; the FMI headers and their licence go into sources/ too
C_FILES = ("mace_linalg.c", "mace_data.c", "mace_zoh.c", "mace_model.c", "mace_instance.c", "fmi2_api.c",
           "fmi3_api.c")
#: the sampled-data controller's: the same FMI layers over another implementation of mace_model.h
CONTROLLER_C_FILES = ("mace_linalg.c", "mace_data.c", "controller/mace_discrete.c", "mace_instance.c", "fmi2_api.c",
                      "fmi3_api.c")
CFLAGS = ("-std=c99", "-O3", "-fPIC", "-shared", "-fvisibility=hidden")


@dataclass(frozen=True)
class Platform:
    """A target of the runtime: its compiler and where FMI 2 and FMI 3 put its binary."""

    name: str
    compiler: str
    suffix: str
    fmi2_folder: str
    fmi3_folder: str
    extra_flags: tuple[str, ...] = ()


LINUX64 = Platform("linux64", "gcc", ".so", "linux64", "x86_64-linux", ("-lm",))
WIN64 = Platform("win64", "x86_64-w64-mingw32-gcc", ".dll", "win64", "x86_64-windows",
                 ("-static-libgcc", "-lm"))


def source_files(c_files: tuple[str, ...] = C_FILES) -> list[Path]:
    """Every file of a runtime that an FMU's sources/ folder carries (its C files, the headers, the licence).

    A host that builds from sources compiles every C file there, so each FMU carries exactly the C
    files of its own runtime (``C_FILES`` for plants, ``CONTROLLER_C_FILES`` for controllers).
    """
    shared = [p for p in SOURCE_DIR.iterdir() if p.suffix == ".h" or p.name.startswith("LICENSE")]
    return sorted(shared + [SOURCE_DIR / f for f in c_files], key=lambda p: p.name)


def _digest(c_files: tuple[str, ...]) -> str:
    h = hashlib.sha256()
    for path in source_files(c_files):
        h.update(path.name.encode() + b"\0" + path.read_bytes())
    return h.hexdigest()


def available(platform: Platform) -> bool:
    """Whether this machine has the platform's compiler."""
    return shutil.which(platform.compiler) is not None


@functools.lru_cache(maxsize=8)
def _compile_cached(platform: Platform, c_files: tuple[str, ...], digest: str) -> bytes:
    with tempfile.TemporaryDirectory(prefix="mace_fmu_cc_") as tmp:
        out = Path(tmp) / f"runtime{platform.suffix}"
        command = [platform.compiler, *CFLAGS, f"-I{SOURCE_DIR}", "-o", str(out),
                   *(str(SOURCE_DIR / f) for f in c_files), *platform.extra_flags]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            raise MaceError(f"compiling the native FMU runtime for {platform.name} failed:\n{done.stderr.strip()}")
        return out.read_bytes()


def compile_runtime(platform: Platform = LINUX64, *, c_files: tuple[str, ...] = C_FILES) -> bytes:
    """A runtime's shared library for ``platform`` (compiled once per process and source version).

    Parameters
    ----------
    platform : Platform
        Compiler, flags and binary folder names (default: linux64 with gcc; win64 with mingw-w64).
    c_files : tuple of str
        The runtime's C sources, in link order.

    Returns
    -------
    bytes
        The shared library (.so or .dll).

    Raises
    ------
    MaceError
        The compiler is missing or fails (its messages included).
    """
    if not available(platform):
        raise MaceError(f"no C compiler for {platform.name}: {platform.compiler} is not installed")
    return _compile_cached(platform, c_files, _digest(c_files))


def compile_runtimes(platforms: list[Platform], *, c_files: tuple[str, ...] = C_FILES) -> dict[Platform, bytes]:
    """The runtime (plant by default) for each of ``platforms``, the compilers running side by side."""
    with ThreadPoolExecutor(max_workers=max(1, len(platforms))) as pool:
        return dict(zip(platforms, pool.map(functools.partial(compile_runtime, c_files=c_files), platforms)))
